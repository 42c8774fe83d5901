//! The Compare view's tables: the paper's Table 1 (RMSPE and SE of every model on every scored run,
//! the paper's values beside, the best of each column highlighted) and the summary beside it
//! (−3 dB cut-offs, the input noise used, the Monte Carlo spreads).
use egui::{Color32, RichText};

use super::theme;
use crate::batch_compare::{
    GRAY_BOX, HAMMERSTEIN_WIENER, LINEAR, NNARX, OutputComparison, PAPER_MONTE_CARLO_STD,
};
use crate::core::numerics::noise_fit::Distribution;
use crate::io::report::{PAPER_TABLE1, paper_output_name};

/// The models in the order of the table's rows.
pub const MODELS: [&str; 4] = [GRAY_BOX, LINEAR, HAMMERSTEIN_WIENER, NNARX];

/// The model's name for people (and the paper's Table 1).
pub fn model_title(model: &str) -> &str {
    match model {
        GRAY_BOX => "gray-box",
        LINEAR => "linear",
        HAMMERSTEIN_WIENER => "Hammerstein–Wiener",
        NNARX => "NNARX",
        other => other,
    }
}

pub fn model_colour(model: &str) -> Color32 {
    match model {
        GRAY_BOX => theme::MODEL,
        LINEAR => theme::LINEAR,
        HAMMERSTEIN_WIENER => theme::HAMMERSTEIN_WIENER,
        NNARX => theme::NNARX,
        _ => theme::HINT,
    }
}

/// A row of the paper's Table 1 (see [`PAPER_TABLE1`]).
type PaperRow = (&'static str, &'static str, f64, f64, f64, f64);

/// One column of Table 1: a value per model of [`MODELS`] (`None`: not available).
#[derive(Clone, Debug, PartialEq)]
pub struct Table1Column {
    /// The run (or "paper", "paper chirp").
    pub group: String,
    /// "RMSPE %" or "SE".
    pub what: &'static str,
    pub values: [Option<f64>; 4],
}

impl Table1Column {
    /// The row of the smallest value.
    pub fn best(&self) -> Option<usize> {
        let present = self.values.iter().enumerate().filter_map(|(i, v)| v.map(|v| (i, v)));
        present.min_by(|a, b| a.1.total_cmp(&b.1)).map(|(i, _)| i)
    }
}

/// Table 1's columns: RMSPE and SE on every scored run (validation, then chirp), then the paper's
/// values when the output is one of the paper's (time-domain validation, then chirp).
pub fn table1_columns(comparison: &OutputComparison) -> Vec<Table1Column> {
    let mut columns = Vec::new();
    for run in &comparison.runs {
        let value = |model: &str, pick: fn(&crate::core::numerics::metrics::Metrics) -> f64| {
            run.models.iter().find(|m| m.model == model).and_then(|m| m.metrics.as_ref().ok()).map(pick)
        };
        let group = run_title(run);
        columns.push(Table1Column {
            group: group.clone(),
            what: "RMSPE %",
            values: MODELS.map(|m| value(m, |x| x.rmspe_pct)),
        });
        columns.push(Table1Column { group, what: "SE", values: MODELS.map(|m| value(m, |x| x.se)) });
    }
    if let Some(paper_output) = paper_output_name(&comparison.output) {
        let paper = |model: &str| {
            PAPER_TABLE1.iter().find(|(o, m, ..)| *o == paper_output && *m == model_title(model))
        };
        // The paper's row is (output, model, RMSPE, SE, RMSPE chirp, SE chirp).
        let picks = [
            ("paper", "RMSPE %", 0),
            ("paper", "SE", 1),
            ("paper chirp", "RMSPE %", 2),
            ("paper chirp", "SE", 3),
        ];
        for (group, what, k) in picks {
            let pick = |t: &PaperRow| [t.2, t.3, t.4, t.5].get(k).copied();
            columns.push(Table1Column {
                group: group.to_owned(),
                what,
                values: MODELS.map(|m| paper(m).and_then(pick)),
            });
        }
    }
    columns
}

/// The run's name, with "(chirp)" when the name does not say so.
pub fn run_title(run: &crate::batch_compare::RunComparison) -> String {
    if run.is_chirp && !run.run.name.to_lowercase().contains("chirp") {
        format!("{} (chirp)", run.run.name)
    } else {
        run.run.name.clone()
    }
}

/// Five significant digits, as the paper prints them.
pub fn significant(value: f64) -> String {
    significant_digits(value, 5)
}

/// `value` with `n` significant digits (at most six decimals).
pub fn significant_digits(value: f64, n: i32) -> String {
    let magnitude = if !value.is_finite() || value.abs() < f64::MIN_POSITIVE {
        0
    } else {
        value.abs().log10().floor() as i32
    };
    let decimals = (n - 1 - magnitude).clamp(0, 6) as usize;
    format!("{value:.decimals$}")
}

pub fn table1_ui(ui: &mut egui::Ui, comparison: &OutputComparison, unit: &str) {
    let columns = table1_columns(comparison);
    ui.vertical(|ui| {
        ui.label(RichText::new("Table 1: RMSPE % and SE of each model (best of each column in green)").strong());
        egui::Grid::new(("compare_table1", &comparison.output)).striped(true).spacing([14.0, 3.0]).show(
            ui,
            |ui| {
                ui.label("");
                for column in &columns {
                    let first = column.what == "RMSPE %";
                    ui.label(RichText::new(if first { column.group.as_str() } else { "" }).strong());
                }
                ui.end_row();
                ui.label(RichText::new("model").strong());
                for column in &columns {
                    let what = match (column.what, unit.is_empty()) {
                        ("SE", false) => format!("SE [{unit}]"),
                        (what, _) => what.to_owned(),
                    };
                    ui.label(RichText::new(what).strong());
                }
                ui.end_row();
                for (row, model) in MODELS.iter().enumerate() {
                    ui.label(RichText::new(model_title(model)).color(model_colour(model)));
                    for column in &columns {
                        let text = column.values.get(row).copied().flatten().map_or("–".to_owned(), significant);
                        let best = column.best() == Some(row);
                        let cell = if best { RichText::new(text).color(theme::OK).strong() } else { text.into() };
                        ui.label(cell);
                    }
                    ui.end_row();
                }
            },
        );
        if paper_output_name(&comparison.output).is_some() {
            super::model_ui::hint(
                ui,
                "The paper's values are from its SR-30 bench data (a mean over its validation test); ours from \
                 this session's runs.",
            );
        }
    });
}

/// The −3 dB cut-offs and the input noise the Monte Carlo study used.
pub fn summary_ui(ui: &mut egui::Ui, comparison: &OutputComparison) {
    if let Some(freq) = &comparison.frequency {
        ui.label(RichText::new(format!("−3 dB cut-off on '{}' [rad/s]", freq.run)).strong());
        let mut names: Vec<&String> = freq.cutoff_rad_s.keys().collect();
        names.sort_by_key(|n| (n.as_str() != "measured", MODELS.iter().position(|m| m == n)));
        ui.horizontal_wrapped(|ui| {
            for name in names {
                let cut = freq.cutoff_rad_s.get(name).copied().flatten();
                let text = cut.map_or("not in band".to_owned(), |c| format!("{c:.3}"));
                let colour = if name == "measured" { theme::EMPIRICAL } else { model_colour(name) };
                ui.label(RichText::new(format!("{} {text}", model_title(name))).color(colour));
            }
        });
        ui.add_space(6.0);
    }
    match &comparison.noise {
        Some(noise) => {
            ui.label(RichText::new("Input noise of the Monte Carlo study").strong());
            let text = match &noise.used {
                Some(d) => format!(
                    "{} fitted to {} of '{}' ({} samples; the best log-likelihood of {} families)",
                    distribution_text(d),
                    noise.channel,
                    noise.run,
                    noise.report.n,
                    noise.report.fits.len()
                ),
                None => format!("no distribution could be fitted to {} of '{}'", noise.channel, noise.run),
            };
            ui.add(egui::Label::new(text).wrap());
        }
        None => {
            ui.label(
                RichText::new("No steady run: no noise fit, no Monte Carlo study.").color(theme::WARNING),
            );
        }
    }
}

/// The paper's Monte Carlo standard deviation for `model` on `output`, when it has one.
pub fn paper_monte_carlo_std(output: &str, model: &str) -> Option<f64> {
    let paper = paper_output_name(output)?;
    let row = PAPER_MONTE_CARLO_STD.iter().find(|(m, ..)| *m == model)?;
    Some(if paper == "thrust" { row.2 } else { row.1 })
}

/// "normal (mean = 5.43, std = 0.00327)".
pub fn distribution_text(distribution: &Distribution) -> String {
    let params: Vec<String> = distribution
        .params()
        .iter()
        .map(|(name, value)| format!("{name} = {}", significant(*value)))
        .collect();
    format!("{} ({})", distribution.family().name(), params.join(", "))
}
