//! The Compare view's tables: the paper's Table 1 (RMSPE and SE of every model on every scored run,
//! the paper's values beside, the best of each column highlighted) and the summary beside it
//! (−3 dB cut-offs, the input noise used, the Monte Carlo spreads).
use crate::core::run::Quantity;
use egui::{Color32, RichText};

use crate::core::compare::{Curve, ModelKind, OutputComparison, PaperRow, RunComparison};
use crate::core::numerics::noise_fit::Distribution;
use crate::ui::theme;

/// The models in the order of the table's rows.
pub const MODELS: [ModelKind; ModelKind::ALL.len()] = ModelKind::ALL;

pub fn model_colour(model: ModelKind) -> Color32 {
    match model {
        ModelKind::GrayBox => theme::MODEL,
        ModelKind::Linear => theme::LINEAR,
        ModelKind::HammersteinWiener => theme::HAMMERSTEIN_WIENER,
        ModelKind::Nnarx => theme::NNARX,
        ModelKind::Arx => theme::ARX,
        ModelKind::HammersteinArx => theme::HAMMERSTEIN_ARX,
        ModelKind::StaticCubic => theme::STATIC_CUBIC,
    }
}

/// A curve keyed by report name ("measured" or a model's): its label and colour.
pub fn curve_style(curve: Curve) -> (&'static str, Color32) {
    match curve {
        Curve::Model(kind) => (kind.label(), model_colour(kind)),
        Curve::Measured => (curve.label(), theme::EMPIRICAL),
    }
}

/// One column of Table 1: a value per model of [`MODELS`] (`None`: not available).
#[derive(Clone, Debug, PartialEq)]
pub struct Table1Column {
    /// The run (or "paper", "paper chirp").
    pub group: String,
    /// "RMSPE %" or "SE".
    pub what: &'static str,
    pub values: [Option<f64>; ModelKind::ALL.len()],
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
        let value = |model: ModelKind, pick: fn(&crate::core::numerics::metrics::Metrics) -> f64| {
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
    if let Some(paper_output) = Quantity::of(&comparison.output) {
        let paper = |model: ModelKind| model.paper_table1(paper_output);
        let picks = [
            ("paper", "RMSPE %", 0),
            ("paper", "SE", 1),
            ("paper chirp", "RMSPE %", 2),
            ("paper chirp", "SE", 3),
        ];
        for (group, what, k) in picks {
            let pick = |t: PaperRow| [t.rmspe_pct, t.se, t.rmspe_chirp_pct, t.se_chirp].get(k).copied();
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
pub fn run_title(run: &RunComparison) -> String {
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
        let grid = egui::Grid::new(("compare_table1", &comparison.output)).striped(true).spacing([14.0, 3.0]).show(
            ui,
            |ui| {
                ui.label("");
                for column in &columns {
                    if column.what == "RMSPE %" {
                        group_label_ui(ui, &column.group);
                    } else {
                        ui.label("");
                    }
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
                    ui.label(RichText::new(model.label()).color(model_colour(*model)));
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
        // The notes wrap at the table's width: wider, they would push the summary beside the
        // table out of the view.
        ui.set_max_width(grid.response.rect.width());
        if Quantity::of(&comparison.output).is_some() {
            crate::ui::widgets::model::hint(
                ui,
                "The paper's values are from its SR-30 bench data (a mean over its validation test); ours from \
                 this session's runs.",
            );
        }
    });
}

/// Characters of a run's name shown above its two columns: a grid cell cannot span both, so a longer
/// name would widen the RMSPE column alone and push the SE column away from it (the JetCat's run
/// names are 34 characters). The whole name shows on hover.
const GROUP_CHARS: usize = 14;

fn group_label_ui(ui: &mut egui::Ui, group: &str) {
    ui.label(RichText::new(crate::ui::widgets::model::clipped(group, GROUP_CHARS)).strong())
        .on_hover_text(group);
}

/// The models that fail on a run (fit below 50 %), one line each with why; nothing when none does.
fn failures_ui(ui: &mut egui::Ui, comparison: &OutputComparison) {
    let failing: Vec<String> = comparison
        .runs
        .iter()
        .flat_map(|run| {
            run.models.iter().filter_map(move |m| {
                let failure = m.metrics.as_ref().ok()?.failure()?;
                let why = m.failure_reasons.join("; ");
                Some(format!("• {} on '{}': {failure}: {why}", m.model.label(), run_title(run)))
            })
        })
        .collect();
    if !failing.is_empty() {
        ui.add_space(6.0);
        ui.label(
            RichText::new("Fails (explains less than half of the output's variation):").color(theme::WARNING),
        );
        for line in &failing {
            ui.add(egui::Label::new(RichText::new(line).color(theme::WARNING)).wrap());
        }
    }
}

/// The models that fail, the −3 dB cut-offs and the input noise the Monte Carlo study used.
pub fn summary_ui(ui: &mut egui::Ui, comparison: &OutputComparison) {
    if let Some(freq) = &comparison.frequency {
        ui.label(RichText::new(format!("−3 dB cut-off on '{}' [rad/s]", freq.run)).strong());
        // The measurement first, then the models in the order of the tables.
        let order = |c: &Curve| match c {
            Curve::Measured => 0,
            Curve::Model(kind) => {
                1 + ModelKind::ALL.iter().position(|k| k == kind).unwrap_or(ModelKind::ALL.len())
            }
        };
        let mut curves: Vec<Curve> = freq.cutoff_rad_s.keys().copied().collect();
        curves.sort_by_key(order);
        ui.horizontal_wrapped(|ui| {
            for curve in curves {
                let cut = freq.cutoff_rad_s.get(&curve).copied().flatten();
                let text = cut.map_or("not in band".to_owned(), |c| format!("{c:.3}"));
                let (label, colour) = curve_style(curve);
                ui.label(RichText::new(format!("{label} {text}")).color(colour));
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
    failures_ui(ui, comparison);
}

/// The paper's Monte Carlo standard deviation for `model` on `output`, when it has one.
pub fn paper_monte_carlo_std(output: &str, model: ModelKind) -> Option<f64> {
    model.paper_monte_carlo_std(Quantity::of(output)?)
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
