//! The Compare view's plots: every model over the measurement of one scored run, the chirp's
//! frequency response (measured points and each model's, all by the same Welch estimate) and the
//! Monte Carlo histograms with their normal fits.
use egui_plot::{Bar, BarChart, Line, LineStyle, MarkerShape, Plot, PlotPoints, Points};

use crate::core::compare::{Curve, FrequencyComparison, ModelKind, OutputComparison};
use crate::core::monte_carlo::MonteCarloResult;
use crate::ui::theme;
use crate::ui::views::compare::table::{
    MODELS, model_colour, paper_monte_carlo_std, run_title, significant_digits,
};
use crate::ui::widgets::plot as plot_util;

const Y_AXIS_WIDTH: f32 = 64.0;
/// Height of the traces and frequency-response row (keys included) when there is room for it.
pub const PLOT_HEIGHT: f32 = 320.0;
/// The least height that row shrinks to so the Monte Carlo row fits the window.
pub const MIN_PLOT_HEIGHT: f32 = 220.0;
const HISTOGRAM_HEIGHT: f32 = 125.0;

/// What the traces and frequency-response row shows: the output's comparison, the run the user
/// picked for the traces (the first scored run when none), the output's axis label and the row's
/// height with its keys.
pub struct Row<'a> {
    pub comparison: &'a OutputComparison,
    pub shown_run: Option<&'a str>,
    pub output_label: &'a str,
    pub height: f32,
    /// Per run name: the half-width of the 95 % band of the gray-box model's noiseless output
    /// from its parameter uncertainty.
    pub bands: &'a [(&'a str, &'a [f64])],
}

/// The traces (left) and the chirp's frequency response (right); returns the run the user picked.
pub fn traces_and_frequency_ui(ui: &mut egui::Ui, row: &Row<'_>) -> Option<String> {
    let mut picked = None;
    ui.columns(2, |columns| {
        if let [left, right] = columns {
            picked = traces_ui(left, row);
            match &row.comparison.frequency {
                Some(freq) => frequency_ui(right, row.comparison, freq, row.height),
                None => {
                    crate::ui::widgets::model::hint(
                        right,
                        "No chirp run, so no frequency-domain comparison.",
                    );
                }
            }
        }
    });
    picked
}

fn traces_ui(ui: &mut egui::Ui, row: &Row<'_>) -> Option<String> {
    let Row { comparison, shown_run, output_label, height, bands } = *row;
    let runs = &comparison.runs;
    let shown = shown_run.and_then(|name| runs.iter().find(|r| r.run.name == name)).or(runs.first());
    let Some(shown) = shown else {
        crate::ui::widgets::model::hint(ui, "No validation or chirp run to simulate the models on.");
        return None;
    };
    let mut picked = None;
    ui.horizontal(|ui| {
        let label = ui.label("Traces on run:");
        egui::ComboBox::from_id_salt(("compare_run", &comparison.output))
            .selected_text(run_title(shown))
            .show_ui(ui, |ui| {
                for run in runs {
                    if ui.selectable_label(run.run.name == shown.run.name, run_title(run)).clicked() {
                        picked = Some(run.run.name.clone());
                    }
                }
            })
            .response
            .labelled_by(label.id);
    });
    let Some(measured) = shown.run.output(&comparison.output) else { return picked };
    let t = &shown.run.t_secs;
    let series =
        |values: &[f64]| -> PlotPoints<'static> { t.iter().zip(values).map(|(t, v)| [*t, *v]).collect() };
    let models: Vec<_> =
        MODELS.iter().filter_map(|m| shown.models.iter().find(|r| r.model == *m).map(|r| (*m, r))).collect();
    let gray_box = models.iter().find(|(m, _)| *m == ModelKind::GrayBox).map(|(_, r)| r.y_hat.as_slice());
    let band = bands.iter().find(|(name, _)| *name == shown.run.name).and_then(|(_, half)| {
        plot_util::band_around(BAND_NAME, t, gray_box?, half, model_colour(ModelKind::GrayBox))
    });
    // The key sits above the plot: eight entries inside it covered the first minute of data.
    let key_top = ui.cursor().top();
    let kinds: Vec<ModelKind> = models.iter().map(|(m, _)| *m).collect();
    key_ui(ui, &kinds, band.is_some());
    let key_height = ui.cursor().top() - key_top;
    Plot::new(("compare_traces", &comparison.output, &shown.run.name))
        .height(height - ui.spacing().interact_size.y - key_height)
        .x_axis_label("time [s]")
        .y_axis_label(output_label)
        .y_axis_min_width(Y_AXIS_WIDTH)
        .x_grid_spacer(plot_util::grid_125_x)
        .y_grid_spacer(plot_util::grid_125_y)
        .show(ui, |plot_ui| {
            plot_ui.line(
                Line::new("measured", series(&measured.values)).color(theme::MEASURED).width(MEASURED_WIDTH),
            );
            if let Some(band) = band {
                plot_ui.add(band);
            }
            // The gray-box model last, on top.
            for (model, run) in models.iter().rev() {
                let (width, dashed) = trace_style(*model);
                let mut line =
                    Line::new(model.label(), series(&run.y_hat)).color(model_colour(*model)).width(width);
                if dashed {
                    line = line.style(LineStyle::Dashed { length: 8.0 });
                }
                plot_ui.line(line);
            }
        });
    picked
}

/// The traces' key: the measurement, each model as its trace is drawn, and the band when there is one.
fn key_ui(ui: &mut egui::Ui, models: &[ModelKind], band: bool) {
    ui.horizontal_wrapped(|ui| {
        ui.spacing_mut().item_spacing.x = 4.0;
        plot_util::line_key_ui(ui, theme::MEASURED, MEASURED_WIDTH, false, "measured");
        for model in models {
            let (width, dashed) = trace_style(*model);
            ui.add_space(6.0);
            plot_util::line_key_ui(ui, model_colour(*model), width, dashed, model.label());
        }
        if band {
            ui.add_space(6.0);
            let colour = model_colour(ModelKind::GrayBox).gamma_multiply(0.6);
            plot_util::line_key_ui(ui, colour, 8.0, false, BAND_NAME);
        }
    });
}

const MEASURED_WIDTH: f32 = 2.0;
/// The key of the gray-box model's band.
const BAND_NAME: &str = "gray-box: 95 % band (parameters)";

/// A model's trace: width and whether dashed (the linear model and the simple references are, so
/// the nonlinear models stand out).
fn trace_style(model: ModelKind) -> (f32, bool) {
    let width = if model.is_reference() { 1.0 } else { 1.3 };
    (width, model == ModelKind::Linear || model.is_reference())
}

fn frequency_ui(ui: &mut egui::Ui, comparison: &OutputComparison, freq: &FrequencyComparison, height: f32) {
    ui.label(format!("Frequency response on '{}' (one Welch estimate for all)", freq.run)).on_hover_text(
        "Each model's simulation of the chirp input goes through the same Welch estimate as the measurement.",
    );
    let group = egui::Id::unique(("compare_freq_axis", &comparison.output));
    let models: Vec<ModelKind> =
        MODELS.iter().copied().filter(|m| freq.responses.contains_key(&Curve::Model(*m))).collect();
    // The key sits above the plots, as the traces' does: egui_plot's legend would draw the chirp's
    // diamonds as a dot, and inside a Bode plot every corner has a curve at some ω.
    let key_top = ui.cursor().top();
    ui.horizontal_wrapped(|ui| {
        ui.spacing_mut().item_spacing.x = 4.0;
        if freq.responses.contains_key(&Curve::Measured) {
            plot_util::diamond_key_ui(ui, theme::EMPIRICAL, "measured (chirp)");
        }
        for model in &models {
            ui.add_space(6.0);
            plot_util::line_key_ui(ui, model_colour(*model), 1.5, false, model.label());
        }
    });
    let key_height = ui.cursor().top() - key_top;
    let height = (height - ui.spacing().interact_size.y - ui.spacing().item_spacing.y - key_height) / 2.0;
    for phase in [false, true] {
        // Short axis labels: each panel is half the row, shorter than "magnitude [dB]" on a window
        // that also shows the table and the Monte Carlo row.
        let mut plot =
            plot_util::bode_panel(("compare_freq", phase, &comparison.output), group, height, phase)
                .y_axis_label(if phase { "phase [°]" } else { "gain [dB]" })
                .y_axis_min_width(Y_AXIS_WIDTH)
                .show_axes([phase, true]);
        if phase {
            plot = plot.x_axis_label("ω [rad/s]");
        }
        plot.show(ui, |plot_ui| {
            if let Some(measured) = freq.responses.get(&Curve::Measured) {
                let values = if phase { &measured.phase_deg } else { &measured.mag_db };
                for ((omega, y), coherence) in
                    measured.omega_rad_s.iter().zip(values).zip(&measured.coherence)
                {
                    let weight = coherence.clamp(0.15, 1.0) as f32;
                    plot_ui.points(
                        Points::new("measured (chirp)", vec![[omega.log10(), *y]])
                            .shape(MarkerShape::Diamond)
                            .radius(1.5 + 2.5 * weight)
                            .color(theme::EMPIRICAL.gamma_multiply(weight)),
                    );
                }
            }
            // The gray-box model last, on top.
            for model in models.iter().rev() {
                let Some(response) = freq.responses.get(&Curve::Model(*model)) else { continue };
                let values = if phase { &response.phase_deg } else { &response.mag_db };
                let points: PlotPoints<'_> =
                    response.omega_rad_s.iter().zip(values).map(|(w, y)| [w.log10(), *y]).collect();
                plot_ui.line(Line::new(model.label(), points).color(model_colour(*model)).width(1.5));
            }
        });
    }
}

/// Height of the Monte Carlo row: its title, each histogram's title and the histograms.
pub fn monte_carlo_height(ui: &egui::Ui, comparison: &OutputComparison) -> f32 {
    let line = ui.text_style_height(&egui::TextStyle::Body) + ui.spacing().item_spacing.y;
    if comparison.monte_carlo.is_empty() { line } else { 2.0 * line + HISTOGRAM_HEIGHT }
}

/// One histogram per model with its normal fit, side by side.
pub fn monte_carlo_ui(ui: &mut egui::Ui, comparison: &OutputComparison, unit: &str) {
    if comparison.monte_carlo.is_empty() {
        let why = if comparison.noise.is_none() {
            "Monte Carlo skipped: there is no steady run to fit the input noise on."
        } else {
            "Monte Carlo skipped: no model could be studied (see the notes above)."
        };
        ui.label(egui::RichText::new(why).color(theme::WARNING));
        return;
    }
    let unit = crate::core::run::bracketed_unit(unit);
    ui.label(
        egui::RichText::new(format!(
            "Monte Carlo error propagation: noisy − nominal output{unit}, 100 runs of 20 s at the steady input level"
        ))
        .strong(),
    );
    let shown: Vec<(ModelKind, &MonteCarloResult)> = ModelKind::MONTE_CARLO
        .iter()
        .filter_map(|m| comparison.monte_carlo.get(m).map(|r| (*m, r)))
        .collect();
    ui.columns(shown.len(), |columns| {
        for (ui, (model, result)) in columns.iter_mut().zip(&shown) {
            histogram_ui(ui, &comparison.output, *model, result);
        }
    });
}

fn histogram_ui(ui: &mut egui::Ui, output: &str, model: ModelKind, result: &MonteCarloResult) {
    let colour = model_colour(model);
    let paper = paper_monte_carlo_std(output, model).map_or(String::new(), |s| format!(" (paper {s})"));
    let std = significant_digits(result.std_difference, 4);
    let title = format!("{}: std {std}{paper}", model.label());
    ui.add(egui::Label::new(egui::RichText::new(title).color(colour)).truncate());
    let histogram = &result.histogram;
    let total = histogram.counts.iter().sum::<usize>().max(1) as f64;
    let width = histogram.edges.windows(2).next().map_or(1.0, |e| e[1] - e[0]);
    // Samples per bin (of every run), and the fitted normal scaled to the same: its pdf times the
    // number of samples times the bin width.
    let bars: Vec<Bar> = histogram
        .centres()
        .iter()
        .zip(&histogram.counts)
        .map(|(x, count)| Bar::new(*x, *count as f64).width(width))
        .collect();
    let (lo, hi) =
        (histogram.edges.first().copied().unwrap_or(-1.0), histogram.edges.last().copied().unwrap_or(1.0));
    let pdf: PlotPoints<'_> = (0..=120)
        .map(|k| {
            let x = lo + (hi - lo) * f64::from(k) / 120.0;
            [x, result.normal_fit.pdf(x) * total * width]
        })
        .collect();
    Plot::new(("compare_mc", output, model.report_name()))
        .height(HISTOGRAM_HEIGHT)
        .x_grid_spacer(plot_util::grid_125_x)
        .y_grid_spacer(plot_util::grid_125_y)
        .y_axis_label("samples")
        .allow_scroll(false)
        .show(ui, |plot_ui| {
            plot_ui.bar_chart(BarChart::new(model.label(), bars).color(colour.gamma_multiply(0.6)));
            plot_ui.line(Line::new("normal fit", pdf).color(theme::REDUCED).width(1.5));
        });
}
