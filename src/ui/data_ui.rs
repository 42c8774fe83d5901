//! The Data view: the selected run's input, outputs and (on demand) auxiliary channels against
//! time, one plot per channel, with linked time axes.
use std::collections::BTreeSet;

use egui::RichText;
use egui_plot::{Line, Plot, PlotPoints};

use super::command::Command;
use super::derived::{ChannelKind, Derived, Trace};
use super::plot_util;
use super::session::{Session, SessionRun};
use super::theme;

/// Height below which plots stop shrinking and the view scrolls instead.
const MIN_PLOT_HEIGHT: f32 = 110.0;
/// Same y-axis width on every plot so that the time axes line up.
const Y_AXIS_WIDTH: f32 = 64.0;

#[derive(Default)]
pub struct DataViewState {
    /// Auxiliary channels the user asked to see, by name (kept when switching runs).
    pub shown_aux: BTreeSet<String>,
}

pub fn data_ui(
    ui: &mut egui::Ui,
    session: &Session,
    selected_run: Option<usize>,
    state: &mut DataViewState,
    cache: &Derived,
) -> Vec<Command> {
    let commands = Vec::new();
    let Some(index) = selected_run else {
        ui.label(RichText::new("Select a run in the list on the left.").color(theme::HINT));
        return commands;
    };
    let (Some(entry), Some(run_traces)) = (session.runs.get(index), cache.runs.get(index)) else {
        return commands;
    };

    header_ui(ui, entry);
    let aux: Vec<&Trace> = run_traces.aux().collect();
    if !aux.is_empty() {
        aux_toggles_ui(ui, &aux, state);
    }
    ui.separator();

    let shown: Vec<&Trace> = run_traces
        .input()
        .chain(run_traces.outputs())
        .chain(aux.iter().copied().filter(|t| state.shown_aux.contains(&t.name)))
        .collect();
    plots_ui(ui, index, &shown);
    commands
}

fn header_ui(ui: &mut egui::Ui, entry: &SessionRun) {
    let run = &entry.run;
    let duration_secs = match (run.t_secs.first(), run.t_secs.last()) {
        (Some(first), Some(last)) => last - first,
        _ => 0.0,
    };
    ui.horizontal_wrapped(|ui| {
        ui.heading(entry.display_name());
        ui.label(RichText::new(entry.role.label()).strong());
        ui.label(format!(
            "{} samples · dt {:.4} s ({:.1} Hz) · {:.1} s",
            run.len(),
            run.dt_secs,
            if run.dt_secs > 0.0 { 1.0 / run.dt_secs } else { 0.0 },
            duration_secs
        ));
    })
    .response
    .on_hover_text(entry.path.display().to_string());
}

fn aux_toggles_ui(ui: &mut egui::Ui, aux: &[&Trace], state: &mut DataViewState) {
    ui.horizontal_wrapped(|ui| {
        ui.label("Auxiliary channels:");
        for trace in aux {
            let mut shown = state.shown_aux.contains(&trace.name);
            if ui.checkbox(&mut shown, trace.axis_label()).changed() {
                if shown {
                    state.shown_aux.insert(trace.name.clone());
                } else {
                    state.shown_aux.remove(&trace.name);
                }
            }
        }
    });
}

fn plots_ui(ui: &mut egui::Ui, run_index: usize, traces: &[&Trace]) {
    let count = traces.len().max(1) as f32;
    let spacing = ui.spacing().item_spacing.y;
    let available = ui.available_height() - spacing * (count - 1.0);
    let height = (available / count).max(MIN_PLOT_HEIGHT);
    // Plot ids include the run so each run opens fitted to its own data.
    let x_group = egui::Id::unique(("data_time_axis", run_index));
    egui::ScrollArea::vertical().auto_shrink([false, false]).show(ui, |ui| {
        for (i, trace) in traces.iter().enumerate() {
            let last = i + 1 == traces.len();
            let mut plot = Plot::new(("data_plot", run_index, trace.name.as_str()))
                .height(height)
                .link_axis(x_group, [true, false])
                .link_cursor(x_group, [true, false])
                .y_axis_label(trace.axis_label())
                .y_axis_min_width(Y_AXIS_WIDTH)
                .x_grid_spacer(plot_util::grid_125_x)
                .y_grid_spacer(plot_util::grid_125_y)
                // Time tick labels only under the bottom plot: the axes are linked.
                .show_axes([last, true]);
            if last {
                plot = plot.x_axis_label("time [s]");
            }
            plot.show(ui, |plot_ui| {
                plot_ui.line(
                    Line::new(trace.name.as_str(), PlotPoints::from(trace.points.as_slice()))
                        .color(trace_colour(trace.kind))
                        .width(1.5),
                );
            });
        }
    });
}

fn trace_colour(kind: ChannelKind) -> egui::Color32 {
    match kind {
        ChannelKind::Input => theme::INPUT,
        ChannelKind::Output(i) => theme::output_colour(i),
        ChannelKind::Aux(i) => theme::aux_colour(i),
    }
}
