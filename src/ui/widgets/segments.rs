//! The identification run's segments on its traces: shaded spans labelled A, B, …, the step inside
//! each (dashed) and boundaries that can be dragged. A boundary shared by two segments moves for
//! both. The segment fits are recomputed when the boundary is released (one undoable command).
use egui::{Align2, RichText};
use egui_plot::{LineStyle, PlotPoint, PlotUi, Span, Text, VLine};

use crate::core::identification::segment::Segment;
use crate::ui::state::command::Command;
use crate::ui::theme;

/// Pointer distance (screen points) that grabs a boundary.
const GRAB: f32 = 6.0;
/// A segment keeps at least this many samples before its step and after it.
const MIN_BASELINE: usize = 3;
const MIN_RESPONSE: usize = 10;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    Start,
    End,
}

/// A boundary being dragged: the segment edges at that sample, where it is now and its limits.
#[derive(Clone, Debug, PartialEq)]
pub struct EdgeDrag {
    pub edges: Vec<(usize, Side)>,
    pub sample: usize,
    lo: usize,
    hi: usize,
}

/// The segments of the run drawn, and how samples map to time. The segments index the
/// identification run, of which the run drawn may be a part (several runs joined end to end): it
/// starts at sample `offset` and holds `samples`; only the segments inside it are drawn.
pub struct SegmentOverlay<'a> {
    pub segments: &'a [Segment],
    pub offset: usize,
    pub t0_secs: f64,
    pub dt_secs: f64,
    pub samples: usize,
}

impl SegmentOverlay<'_> {
    fn time(&self, sample: usize) -> f64 {
        self.t0_secs + (sample as f64 - self.offset as f64) * self.dt_secs
    }

    fn sample(&self, t_secs: f64) -> usize {
        let k = ((t_secs - self.t0_secs) / self.dt_secs).round();
        self.offset + if k <= 0.0 { 0 } else { (k as usize).min(self.samples) }
    }

    /// Whether segment `s` lies in the run drawn.
    fn shows(&self, s: &Segment) -> bool {
        s.start >= self.offset && s.end <= self.offset + self.samples
    }

    /// Every edge sample with the edges there (a shared boundary is one entry).
    fn boundaries(&self) -> Vec<(usize, Vec<(usize, Side)>)> {
        let mut out: Vec<(usize, Vec<(usize, Side)>)> = Vec::new();
        for (i, s) in self.segments.iter().enumerate().filter(|(_, s)| self.shows(s)) {
            for (sample, side) in [(s.start, Side::Start), (s.end, Side::End)] {
                match out.iter_mut().find(|(k, _)| *k == sample) {
                    Some((_, edges)) => edges.push((i, side)),
                    None => out.push((sample, vec![(i, side)])),
                }
            }
        }
        out
    }

    /// Where the edges at `sample` may go: past neither a step nor a neighbour not moved with them.
    fn limits(&self, sample: usize, edges: &[(usize, Side)]) -> (usize, usize) {
        let moved = |i: usize, side: Side| edges.contains(&(i, side));
        let (mut lo, mut hi) = (self.offset, self.offset + self.samples);
        for &(i, side) in edges {
            let Some(s) = self.segments.get(i) else { continue };
            match side {
                Side::Start => {
                    hi = hi.min(s.step_at.saturating_sub(MIN_BASELINE));
                    if i > 0 && !moved(i - 1, Side::End) {
                        lo = lo.max(self.segments[i - 1].end.min(sample));
                    }
                }
                Side::End => {
                    lo = lo.max(s.step_at + MIN_RESPONSE);
                    if i + 1 < self.segments.len() && !moved(i + 1, Side::Start) {
                        hi = hi.min(self.segments[i + 1].start.max(sample));
                    }
                }
            }
        }
        (lo.min(sample), hi.max(sample))
    }

    /// The segments with the dragged edges moved.
    fn moved(&self, drag: &EdgeDrag) -> Vec<Segment> {
        let mut segments = self.segments.to_vec();
        for &(i, side) in &drag.edges {
            if let Some(s) = segments.get_mut(i) {
                match side {
                    Side::Start => s.start = drag.sample,
                    Side::End => s.end = drag.sample,
                }
            }
        }
        segments
    }
}

/// Spans, steps, boundaries and (with `label_y`, in plot units) the segment letters. The labels
/// sit at a height taken from the data, not from the plot bounds, which they would push up.
pub fn draw_segments(
    plot_ui: &mut PlotUi<'_>,
    overlay: &SegmentOverlay<'_>,
    drag: Option<&EdgeDrag>,
    label_y: Option<f64>,
) {
    let segments = match drag {
        Some(drag) => overlay.moved(drag),
        None => overlay.segments.to_vec(),
    };
    for (i, s) in segments.iter().enumerate().filter(|(_, s)| overlay.shows(s)) {
        let span = Span::new("", overlay.time(s.start)..=overlay.time(s.end))
            .fill(theme::segment_fill(i))
            .border_width(0.0);
        plot_ui.span(span);
        let step = VLine::new("", overlay.time(s.step_at)).color(theme::SEGMENT_STEP).width(1.0);
        plot_ui.vline(step.style(LineStyle::Dashed { length: 4.0 }).allow_hover(false));
        if let Some(top) = label_y {
            let mid = 0.5 * (overlay.time(s.start) + overlay.time(s.end));
            let label = RichText::new(&s.label).size(15.0).strong().color(theme::segment_colour(i));
            plot_ui.text(
                Text::new("", PlotPoint::new(mid, top), label).anchor(Align2::CENTER_TOP).allow_hover(false),
            );
        }
    }
    let active = drag.map(|d| d.sample);
    let shown = SegmentOverlay { segments: &segments, ..*overlay };
    for (sample, _) in shown.boundaries() {
        let (colour, width) = if Some(sample) == active {
            (theme::SEGMENT_EDGE_ACTIVE, 2.5)
        } else {
            (theme::SEGMENT_EDGE, 1.2)
        };
        plot_ui.vline(VLine::new("", overlay.time(sample)).color(colour).width(width).allow_hover(false));
    }
}

/// The boundary near the pointer x (screen), if any.
fn boundary_at(
    plot_ui: &PlotUi<'_>,
    overlay: &SegmentOverlay<'_>,
    x: f32,
) -> Option<(usize, Vec<(usize, Side)>)> {
    let transform = plot_ui.transform();
    overlay
        .boundaries()
        .into_iter()
        .map(|(sample, edges)| {
            ((transform.position_from_point_x(overlay.time(sample)) - x).abs(), sample, edges)
        })
        .filter(|(d, _, _)| *d <= GRAB)
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, sample, edges)| (sample, edges))
}

/// Start, follow and finish a boundary drag; `hovered` is set when the pointer is on a boundary.
/// Returns the new segments when a drag ends somewhere else than it started.
pub fn interact_segments(
    plot_ui: &mut PlotUi<'_>,
    overlay: &SegmentOverlay<'_>,
    drag: &mut Option<EdgeDrag>,
    hovered: &mut bool,
) -> Option<Command> {
    let response = plot_ui.response().clone();
    if let Some(pos) = response.hover_pos()
        && boundary_at(plot_ui, overlay, pos.x).is_some()
    {
        *hovered = true;
    }
    if response.drag_started_by(egui::PointerButton::Primary) {
        let origin = plot_ui.ctx().input(|i| i.pointer.press_origin()).or(response.interact_pointer_pos());
        if let Some((sample, edges)) = origin.and_then(|pos| boundary_at(plot_ui, overlay, pos.x)) {
            let (lo, hi) = overlay.limits(sample, &edges);
            *drag = Some(EdgeDrag { edges, sample, lo, hi });
        }
    }
    let mine = drag.as_ref().is_some_and(|d| d.edges.iter().all(|(i, _)| *i < overlay.segments.len()));
    if !mine {
        return None;
    }
    if (response.dragged() || response.drag_stopped())
        && let (Some(d), Some(pos)) = (drag.as_mut(), response.interact_pointer_pos())
    {
        let t = plot_ui.transform().value_from_position(pos).x;
        d.sample = overlay.sample(t).clamp(d.lo, d.hi);
        *hovered = true;
    }
    if response.drag_stopped() {
        let finished = drag.take()?;
        let segments = overlay.moved(&finished);
        return (segments != overlay.segments).then_some(Command::SetSegments(Some(segments)));
    }
    None
}
