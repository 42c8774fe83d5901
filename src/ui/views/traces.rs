//! The Traces view: each validation (and chirp) run's measured output with the gray-box model
//! (with its effects, when it has any; optionally the model without them and the linear block
//! alone) simulated from the input, the residual below, and the metrics of every run. The
//! Diagnosis view can send it to a time window (a worst stretch); "Reset zoom" shows the whole run.
use egui::RichText;
use egui_plot::{Legend, Line, LineStyle, Plot, PlotPoints};

use crate::core::identification::pipeline::RunPrediction;
use crate::ui::derived::Derived;
use crate::ui::derived::live_model::ScoredRun;
use crate::ui::state::session::Session;
use crate::ui::theme;
use crate::ui::widgets::model as model_ui;
use crate::ui::widgets::plot as plot_util;

const Y_AXIS_WIDTH: f32 = 64.0;

#[derive(Default)]
pub struct TracesViewState {
    /// The scored run shown (its index in the session).
    pub run: Option<usize>,
    pub show_linear: bool,
    /// Also draw the gray-box model without its effects.
    pub show_without_effects: bool,
    /// The time window asked for (`t0, t1` in s), e.g. a worst stretch from the Diagnosis view.
    pub focus_window: Option<(f64, f64)>,
    /// The focus window still has to be set on the plots.
    focus_pending: bool,
    /// The plots go back to showing the whole run on the next frame.
    reset_pending: bool,
}

impl TracesViewState {
    /// Show session run `run` zoomed to `t0_secs..=t1_secs`.
    pub fn focus(&mut self, run: usize, t0_secs: f64, t1_secs: f64) {
        self.run = Some(run);
        self.focus_window = Some((t0_secs.min(t1_secs), t0_secs.max(t1_secs)));
        self.focus_pending = true;
    }

    /// Forget the focus window and show the whole run again.
    pub fn reset_zoom(&mut self) {
        self.focus_window = None;
        self.focus_pending = false;
        self.reset_pending = true;
    }
}

/// The range of `values` over the samples whose time lies in `window`, padded by 5 %.
fn range_in_window(
    t_secs: &[f64],
    values: impl Iterator<Item = f64>,
    window: (f64, f64),
) -> Option<(f64, f64)> {
    let (lo, hi) = t_secs
        .iter()
        .zip(values)
        .filter(|(t, v)| **t >= window.0 && **t <= window.1 && v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (_, v)| (lo.min(v), hi.max(v)));
    if !(lo.is_finite() && hi.is_finite()) {
        return None;
    }
    let pad = 0.05 * (hi - lo).max(1e-9 * hi.abs().max(1.0));
    Some((lo - pad, hi + pad))
}

fn series(t_secs: &[f64], values: impl Iterator<Item = f64>) -> PlotPoints<'static> {
    t_secs.iter().zip(values).map(|(t, v)| [*t, v]).collect()
}

pub fn traces_ui(
    ui: &mut egui::Ui,
    output: &str,
    state: &mut TracesViewState,
    session: &Session,
    cache: &Derived,
) {
    let Some(view) = cache.live_view(output) else { return };
    for note in &view.output.notes {
        model_ui::hint(ui, note);
    }
    if !model_ui::model_state_ui(ui, &view) {
        return;
    }
    let Ok(live) = view.live else { return };
    if live.runs.is_empty() {
        model_ui::hint(ui, "Give a run the role validation or chirp to see the model against it.");
        return;
    }
    egui::CollapsingHeader::new(RichText::new("Metrics").strong()).default_open(true).show(ui, |ui| {
        model_ui::metrics_table_ui(ui, "traces_metrics", &live.runs);
    });
    let shown = state.run.and_then(|i| live.runs.iter().find(|r| r.index == i)).or(live.runs.first());
    let Some(scored) = shown else { return };
    controls_ui(ui, state, &live.runs, scored);
    if let Some(err) = &scored.effects_error {
        model_ui::error_ui(ui, &format!("The model's effects cannot be simulated on this run: {err}"));
    }
    let Some(entry) = session.runs.get(scored.index) else { return };
    let Some(measured) = entry.run.output(output) else { return };
    let shown = Shown {
        t: &entry.run.t_secs,
        measured: &measured.values,
        scored,
        linear: scored.linear.as_ref().ok().filter(|_| state.show_linear),
        without: scored.without_effects.as_ref().filter(|_| state.show_without_effects),
        model_name: if scored.without_effects.is_some() { "gray-box + effects" } else { "gray-box model" },
        focus: state.focus_window.filter(|_| state.focus_pending),
        reset: std::mem::take(&mut state.reset_pending),
        band: live
            .runs
            .iter()
            .position(|r| r.index == scored.index)
            .and_then(|i| live.uncertainty.as_ref().ok()?.run_bands.get(i)?.as_deref().ok()),
    };
    state.focus_pending = false;
    let spacing = ui.spacing().item_spacing.y;
    let available = ui.available_height() - spacing;
    let group = egui::Id::unique(("traces_time_axis", output, scored.index));
    output_plot_ui(ui, &shown, (output, &view.output.label()), group, (available * 0.65).max(140.0));
    residual_plot_ui(ui, &shown, (output, &view.output.unit), group, (available * 0.35).max(100.0));
}

/// The run chooser, the extra curves and the zoom.
fn controls_ui(ui: &mut egui::Ui, state: &mut TracesViewState, runs: &[ScoredRun], scored: &ScoredRun) {
    ui.horizontal(|ui| {
        let label = ui.label("Run:");
        egui::ComboBox::from_id_salt("traces_run")
            .selected_text(scored.label())
            .show_ui(ui, |ui| {
                for run in runs {
                    if ui.selectable_label(run.index == scored.index, run.label()).clicked() {
                        state.run = Some(run.index);
                    }
                }
            })
            .response
            .labelled_by(label.id);
        ui.checkbox(&mut state.show_linear, "Show the linear block alone");
        if scored.without_effects.is_some() {
            ui.checkbox(&mut state.show_without_effects, "Show the model without its effects");
        }
        if let Some((t0, t1)) = state.focus_window {
            ui.label(RichText::new(format!("Showing {t0:.1}–{t1:.1} s")).color(theme::WARNING));
            if ui.button("Reset zoom").clicked() {
                state.reset_zoom();
            }
        }
    });
}

/// What both plots of one run draw.
struct Shown<'a> {
    t: &'a [f64],
    measured: &'a [f64],
    scored: &'a ScoredRun,
    linear: Option<&'a RunPrediction>,
    without: Option<&'a RunPrediction>,
    model_name: &'static str,
    /// The window to zoom to on this frame.
    focus: Option<(f64, f64)>,
    /// Show the whole run again on this frame.
    reset: bool,
    /// Half-width of the 95 % band of the model's noiseless output from its parameter uncertainty.
    band: Option<&'a [f64]>,
}

impl Shown<'_> {
    fn residual_of(&self, y_hat: &[f64]) -> Vec<f64> {
        self.measured.iter().zip(y_hat).map(|(y, yh)| y - yh).collect()
    }
}

/// The legend entry of the model's uncertainty band: around its trace above, around zero below (a
/// residual beyond it is a miss the parameters' uncertainty does not explain).
const BAND_NAME: &str = "95 % band of the model (parameters)";

/// The measured output with the model (and the extra curves) over time.
fn output_plot_ui(
    ui: &mut egui::Ui,
    shown: &Shown<'_>,
    (output, label): (&str, &str),
    group: egui::Id,
    height: f32,
) {
    let (t, scored) = (shown.t, shown.scored);
    Plot::new(("traces_output", output, scored.index))
        .height(height)
        .link_axis(group, [true, false])
        .link_cursor(group, [true, false])
        .y_axis_label(label)
        .y_axis_min_width(Y_AXIS_WIDTH)
        .x_grid_spacer(plot_util::grid_125_x)
        .y_grid_spacer(plot_util::grid_125_y)
        .show_axes([false, true])
        .legend(Legend::default().position(egui_plot::Corner::LeftTop).follow_insertion_order(true))
        .reset_if(shown.reset)
        .show(ui, |plot_ui| {
            if let Some(window) = shown.focus {
                plot_ui.set_plot_bounds_x(window.0..=window.1);
                let both = shown.measured.iter().chain(&scored.gray_box.y_hat).copied();
                let t_twice: Vec<f64> = t.iter().chain(t).copied().collect();
                if let Some((lo, hi)) = range_in_window(&t_twice, both, window) {
                    plot_ui.set_plot_bounds_y(lo..=hi);
                }
            }
            plot_ui.line(
                Line::new("measured", series(t, shown.measured.iter().copied()))
                    .color(theme::MEASURED)
                    .width(1.5),
            );
            if let Some(linear) = shown.linear {
                let line = Line::new("linear block", series(t, linear.y_hat.iter().copied()));
                plot_ui.line(line.color(theme::LINEAR).width(1.2).style(LineStyle::Dashed { length: 8.0 }));
            }
            if let Some(without) = shown.without {
                let line = Line::new("without effects", series(t, without.y_hat.iter().copied()));
                plot_ui.line(
                    line.color(theme::WITHOUT_EFFECTS).width(1.2).style(LineStyle::Dashed { length: 6.0 }),
                );
            }
            if let Some(band) = shown
                .band
                .and_then(|h| plot_util::band_around(BAND_NAME, t, &scored.gray_box.y_hat, h, theme::MODEL))
            {
                plot_ui.add(band);
            }
            let gray = Line::new(shown.model_name, series(t, scored.gray_box.y_hat.iter().copied()));
            plot_ui.line(gray.color(theme::MODEL).width(1.5));
        });
}

/// The residual of the model (and of the extra curves) over time.
fn residual_plot_ui(
    ui: &mut egui::Ui,
    shown: &Shown<'_>,
    (output, unit): (&str, &str),
    group: egui::Id,
    height: f32,
) {
    let (t, scored) = (shown.t, shown.scored);
    let model_residual = shown.residual_of(&scored.gray_box.y_hat);
    Plot::new(("traces_residual", output, scored.index))
        .height(height)
        .link_axis(group, [true, false])
        .link_cursor(group, [true, false])
        .x_axis_label("time [s]")
        .y_axis_label(format!("residual y − ŷ{}", crate::core::run::bracketed_unit(unit)))
        .y_axis_min_width(Y_AXIS_WIDTH)
        .x_grid_spacer(plot_util::grid_125_x)
        .y_grid_spacer(plot_util::grid_125_y)
        .reset_if(shown.reset)
        .show(ui, |plot_ui| {
            if let Some(window) = shown.focus {
                plot_ui.set_plot_bounds_x(window.0..=window.1);
                if let Some((lo, hi)) = range_in_window(t, model_residual.iter().copied(), window) {
                    plot_ui.set_plot_bounds_y(lo..=hi);
                }
            }
            if let Some(band) = shown
                .band
                .and_then(|h| plot_util::band_around(BAND_NAME, t, &vec![0.0; h.len()], h, theme::MODEL))
            {
                plot_ui.add(band);
            }
            let residual = |y_hat: &[f64]| series(t, shown.residual_of(y_hat).into_iter());
            if let Some(without) = shown.without {
                let line = Line::new("without effects", residual(&without.y_hat));
                plot_ui.line(
                    line.color(theme::WITHOUT_EFFECTS).width(1.0).style(LineStyle::Dashed { length: 6.0 }),
                );
            }
            if let Some(linear) = shown.linear {
                let line = Line::new("linear block", residual(&linear.y_hat));
                plot_ui.line(line.color(theme::LINEAR).width(1.0).style(LineStyle::Dashed { length: 8.0 }));
            }
            plot_ui.line(
                Line::new(shown.model_name, series(t, model_residual.iter().copied()))
                    .color(theme::MODEL)
                    .width(1.2),
            );
        });
}

/// `Plot::reset` when `reset` is true (egui_plot has no conditional form).
trait ResetIf {
    fn reset_if(self, reset: bool) -> Self;
}

impl ResetIf for Plot<'_> {
    fn reset_if(self, reset: bool) -> Self {
        if reset { self.reset() } else { self }
    }
}
