//! The Data view: the selected run's input, outputs and (on demand) auxiliary channels against
//! time, one plot per channel, with linked time axes. The identification run also shows its
//! segments, whose boundaries can be dragged.
use std::collections::BTreeSet;

use egui::RichText;
use egui_plot::{Line, Plot, PlotPoints};

use crate::core::identification::segment::Segment;
use crate::ui::derived::{ChannelKind, Derived, Trace};
use crate::ui::state::command::Command;
use crate::ui::state::session::{Session, SessionRun};
use crate::ui::theme;
use crate::ui::widgets::plot as plot_util;
use crate::ui::widgets::segments::{self as segments_ui, EdgeDrag, SegmentOverlay};
use crate::workflow::runs::StepsFrom;

/// Height below which plots stop shrinking and the view scrolls instead.
const MIN_PLOT_HEIGHT: f32 = 110.0;
/// The narrowest y axis; every plot takes the width of the widest one so that the time axes line up.
const Y_AXIS_WIDTH: f32 = 64.0;

#[derive(Default)]
pub struct DataViewState {
    /// Auxiliary channels the user asked to see, by name (kept when switching runs).
    pub shown_aux: BTreeSet<String>,
    /// A segment boundary being dragged.
    pub segment_drag: Option<EdgeDrag>,
    /// The pointer was on a segment boundary last frame (the plots then do not pan).
    pub on_boundary: bool,
    /// Time ↔ screen of the top plot last frame (tests use it to find a boundary).
    pub last_transform: Option<egui_plot::PlotTransform>,
}

pub fn data_ui(
    ui: &mut egui::Ui,
    session: &Session,
    selected_run: Option<usize>,
    state: &mut DataViewState,
    cache: &Derived,
) -> Vec<Command> {
    let mut commands = Vec::new();
    let Some(index) = selected_run else {
        ui.label(RichText::new("Select a run in the list on the left.").color(theme::HINT));
        return commands;
    };
    let (Some(entry), Some(run_traces)) = (session.runs.get(index), cache.runs.get(index)) else {
        return commands;
    };

    header_ui(ui, entry);
    let part = cache.ident.as_ref().and_then(|ident| Some((ident, ident.part_start(index)?)));
    let ident = part.map(|(ident, _)| ident);
    if let Some(ident) = ident {
        let how = match (ident.segments_are_automatic(), ident.steps_from()) {
            (false, _) => "moved by hand".to_owned(),
            (true, StepsFrom::Input) => "detected from the input steps".to_owned(),
            (true, StepsFrom::Named(channel)) => format!("detected from the steps of {channel}"),
            (true, StepsFrom::Found(set_point)) => {
                format!("detected from the steps of {}, found to be a set-point", set_point.channel)
            }
        };
        commands.extend(segments_header_ui(ui, &ident.segments, ident.segments_are_automatic(), &how));
    }
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
    // The segments count samples of the identification run, which starts `window_start` samples
    // into the session's runs when a long run was cut to the part its model is fitted on.
    let in_session = part.and_then(|(ident, offset)| {
        let shift = ident.window_start();
        let moved = |s: &Segment| Segment {
            label: s.label.clone(),
            start: s.start + shift,
            step_at: s.step_at + shift,
            end: s.end + shift,
        };
        Some((ident.segments.as_ref().ok()?.iter().map(moved).collect::<Vec<_>>(), offset))
    });
    let overlay = in_session.as_ref().map(|(segments, offset)| SegmentOverlay {
        segments,
        offset: *offset,
        t0_secs: entry.run.t_secs.first().copied().unwrap_or(0.0),
        dt_secs: entry.run.dt_secs,
        samples: entry.run.len(),
    });
    commands.extend(plots_ui(ui, index, &shown, overlay.as_ref(), state));
    commands
}

fn segments_header_ui(
    ui: &mut egui::Ui,
    segments: &Result<
        Vec<crate::core::identification::segment::Segment>,
        crate::ui::derived::live_model::Unavailable,
    >,
    automatic: bool,
    how: &str,
) -> Option<Command> {
    let mut command = None;
    ui.horizontal_wrapped(|ui| {
        match segments {
            Ok(segments) => {
                ui.label(RichText::new(format!("{} segments, {how}", segments.len())).strong());
                ui.label(
                    RichText::new("drag a boundary (yellow line) to move it; the fits are redone on release")
                        .color(theme::HINT),
                );
            }
            Err(err) => {
                ui.label(RichText::new(format!("Segments: {err}")).color(theme::ERROR));
            }
        }
        if !automatic
            && ui
                .button("Detect again")
                .on_hover_text("Replace the segments by those detected from the input")
                .clicked()
        {
            command = Some(Command::SetSegments(None));
        }
    });
    command
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

fn plots_ui(
    ui: &mut egui::Ui,
    run_index: usize,
    traces: &[&Trace],
    overlay: Option<&SegmentOverlay<'_>>,
    state: &mut DataViewState,
) -> Vec<Command> {
    let mut commands = Vec::new();
    let on_boundary = std::mem::take(&mut state.on_boundary) || state.segment_drag.is_some();
    let count = traces.len().max(1) as f32;
    let spacing = ui.spacing().item_spacing.y;
    let available = ui.available_height() - spacing * (count - 1.0);
    let height = (available / count).max(MIN_PLOT_HEIGHT);
    // One y-axis width for all: egui_plot widens an axis to its widest tick label, which would
    // shift each plot's time axis by the difference.
    let y_axis_width = traces
        .iter()
        .map(|t| {
            let (lo, hi) = value_range(t);
            plot_util::y_axis_width(ui, lo, hi)
        })
        .fold(Y_AXIS_WIDTH, f32::max);
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
                .y_axis_min_width(y_axis_width)
                .x_grid_spacer(plot_util::grid_125_x)
                .y_grid_spacer(plot_util::grid_125_y)
                .y_axis_formatter(plot_util::range_label)
                // Time tick labels only under the bottom plot: the axes are linked.
                .show_axes([last, true])
                .allow_drag(!on_boundary);
            if last {
                plot = plot.x_axis_label("time [s]");
            }
            let shown = plot.show(ui, |plot_ui| {
                if let Some(overlay) = overlay {
                    let dragged = segments_ui::interact_segments(
                        plot_ui,
                        overlay,
                        &mut state.segment_drag,
                        &mut state.on_boundary,
                    );
                    commands.extend(dragged);
                    let label_y = (i == 0).then(|| label_height(trace));
                    segments_ui::draw_segments(plot_ui, overlay, state.segment_drag.as_ref(), label_y);
                }
                plot_ui.line(
                    Line::new(trace.name.as_str(), PlotPoints::from(trace.points.as_slice()))
                        .color(trace_colour(trace.kind))
                        .width(1.5),
                );
            });
            if i == 0 {
                state.last_transform = Some(shown.transform);
            }
        }
    });
    if state.on_boundary {
        ui.ctx().set_cursor_icon(egui::CursorIcon::ResizeHorizontal);
    }
    commands
}

/// The lowest and highest finite sample of the trace (infinite when there is none).
fn value_range(trace: &Trace) -> (f64, f64) {
    trace
        .points
        .iter()
        .filter(|p| p.y.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p.y), hi.max(p.y)))
}

/// A little above the highest sample of the trace.
fn label_height(trace: &Trace) -> f64 {
    let (lo, hi) = value_range(trace);
    if lo.is_finite() { hi + 0.12 * (hi - lo).max(1e-9) } else { 0.0 }
}

fn trace_colour(kind: ChannelKind) -> egui::Color32 {
    match kind {
        ChannelKind::Input => theme::INPUT,
        ChannelKind::Output(i) => theme::output_colour(i),
        ChannelKind::Aux(i) => theme::aux_colour(i),
    }
}
