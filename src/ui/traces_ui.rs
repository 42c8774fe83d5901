//! The Traces view: each validation (and chirp) run's measured output with the gray-box model
//! (and optionally the linear block alone) simulated from the input, the residual below, and the
//! metrics of every run.
use egui::RichText;
use egui_plot::{Legend, Line, LineStyle, Plot, PlotPoints};

use super::derived::Derived;
use super::model_ui;
use super::plot_util;
use super::session::Session;
use super::theme;

const Y_AXIS_WIDTH: f32 = 64.0;

#[derive(Default)]
pub struct TracesViewState {
    /// The scored run shown (its index in the session).
    pub run: Option<usize>,
    pub show_linear: bool,
}

/// The run's name, and its role when the name does not say it.
pub fn run_label(run: &super::model_cache::ScoredRun) -> String {
    if run.name.eq_ignore_ascii_case(run.role.label()) {
        run.name.clone()
    } else {
        format!("{} ({})", run.name, run.role.label())
    }
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
    ui.horizontal(|ui| {
        let label = ui.label("Run:");
        egui::ComboBox::from_id_salt("traces_run")
            .selected_text(run_label(scored))
            .show_ui(ui, |ui| {
                for run in &live.runs {
                    if ui.selectable_label(run.index == scored.index, run_label(run)).clicked() {
                        state.run = Some(run.index);
                    }
                }
            })
            .response
            .labelled_by(label.id);
        ui.checkbox(&mut state.show_linear, "Show the linear block alone");
    });
    let Some(entry) = session.runs.get(scored.index) else { return };
    let Some(measured) = entry.run.output(output) else { return };
    let t = &entry.run.t_secs;
    let linear = scored.linear.as_ref().ok().filter(|_| state.show_linear);
    let spacing = ui.spacing().item_spacing.y;
    let available = ui.available_height() - spacing;
    let group = egui::Id::unique(("traces_time_axis", output, scored.index));
    Plot::new(("traces_output", output, scored.index))
        .height((available * 0.65).max(140.0))
        .link_axis(group, [true, false])
        .link_cursor(group, [true, false])
        .y_axis_label(view.output.label())
        .y_axis_min_width(Y_AXIS_WIDTH)
        .x_grid_spacer(plot_util::grid_125_x)
        .y_grid_spacer(plot_util::grid_125_y)
        .show_axes([false, true])
        .legend(Legend::default().position(egui_plot::Corner::LeftTop).follow_insertion_order(true))
        .show(ui, |plot_ui| {
            plot_ui.line(
                Line::new("measured", series(t, measured.values.iter().copied()))
                    .color(theme::MEASURED)
                    .width(1.5),
            );
            if let Some(linear) = linear {
                let line = Line::new("linear block", series(t, linear.y_hat.iter().copied()));
                plot_ui.line(line.color(theme::LINEAR).width(1.2).style(LineStyle::Dashed { length: 8.0 }));
            }
            let gray = Line::new("gray-box model", series(t, scored.gray_box.y_hat.iter().copied()));
            plot_ui.line(gray.color(theme::MODEL).width(1.5));
        });
    Plot::new(("traces_residual", output, scored.index))
        .height((available * 0.35).max(100.0))
        .link_axis(group, [true, false])
        .link_cursor(group, [true, false])
        .x_axis_label("time [s]")
        .y_axis_label(format!("residual y − ŷ [{}]", view.output.unit))
        .y_axis_min_width(Y_AXIS_WIDTH)
        .x_grid_spacer(plot_util::grid_125_x)
        .y_grid_spacer(plot_util::grid_125_y)
        .show(ui, |plot_ui| {
            let residual = |y_hat: &[f64]| series(t, measured.values.iter().zip(y_hat).map(|(y, yh)| y - yh));
            if let Some(linear) = linear {
                let line = Line::new("linear block", residual(&linear.y_hat));
                plot_ui.line(line.color(theme::LINEAR).width(1.0).style(LineStyle::Dashed { length: 8.0 }));
            }
            plot_ui.line(
                Line::new("gray-box model", residual(&scored.gray_box.y_hat)).color(theme::MODEL).width(1.2),
            );
        });
}
