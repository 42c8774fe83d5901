//! The z-plane plots: the interactive detail plot (segment roots, clusters with draggable centre and
//! rim, the reduced model's roots) and the whole-circle overview.
//!
//! The plot's own pan, zoom and reset are off: the view keeps its own bounds (drag on empty space
//! pans, the wheel zooms about the pointer) so that pointer positions map to z through a transform
//! that does not move under a handle being dragged.
use egui::{Align2, Color32, Pos2, RichText};
use egui_plot::{
    Line, LineStyle, MarkerShape, Plot, PlotBounds, PlotPoint, PlotTransform, PlotUi, Points, Text,
};
use num_complex::Complex64;

use super::state::{ClusterDrag, Handle, ZPlaneViewState, ZoomView};
use crate::core::identification::cluster::{Cluster, RootKind};
use crate::core::identification::fits::SegmentFits;
use crate::ui::derived::LiveView;
use crate::ui::state::command::Command;
use crate::ui::theme;
use crate::ui::widgets::plot as plot_util;

/// Angle rays at these frequencies (rad/s), where below the Nyquist frequency.
const RAY_OMEGAS_RAD_S: [f64; 9] = [0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 15.0, 20.0, 25.0];
/// Circles of constant modulus |z|.
const MODULUS_CIRCLES: [f64; 4] = [0.25, 0.5, 0.75, 0.9];
/// Pointer distances (screen points) that grab a handle.
const CENTRE_GRAB: f32 = 9.0;
const RIM_GRAB: f32 = 6.0;
/// Smallest radius a rim drag leaves.
const MIN_RADIUS: f64 = 1e-4;
/// Ray labels closer than this (screen points) to the previous one are left out.
const LABEL_SPACING: f32 = 36.0;

/// Points on a circle (closed).
pub fn circle(centre: Complex64, radius: f64, n: usize) -> Vec<[f64; 2]> {
    (0..=n)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / n as f64;
            [centre.re + radius * a.cos(), centre.im + radius * a.sin()]
        })
        .collect()
}

fn folded(points: &[Complex64]) -> Vec<[f64; 2]> {
    points.iter().map(|z| [z.re, z.im]).collect()
}

/// The unit circle, modulus circles and the angle rays labelled in rad/s (angle · fs).
fn grid_ui(plot_ui: &mut PlotUi<'_>, dt_secs: f64, exclusion_rad: f64, labels: bool) {
    for r in MODULUS_CIRCLES {
        plot_ui.line(
            Line::new("", circle(Complex64::new(0.0, 0.0), r, 180))
                .color(theme::ZGRID)
                .width(0.6)
                .allow_hover(false),
        );
    }
    plot_ui.line(
        Line::new("", circle(Complex64::new(0.0, 0.0), 1.0, 2048))
            .color(theme::UNIT_CIRCLE)
            .width(1.4)
            .allow_hover(false),
    );
    plot_ui
        .line(Line::new("", vec![[-1.0, 0.0], [1.0, 0.0]]).color(theme::ZGRID).width(0.6).allow_hover(false));
    let nyquist_rad_s = std::f64::consts::PI / dt_secs;
    let mut last_label: Option<Pos2> = None;
    let rays = RAY_OMEGAS_RAD_S.iter().map(|w| (*w, false)).filter(|(w, _)| *w < 0.97 * nyquist_rad_s);
    for (omega, is_exclusion) in rays.chain([(exclusion_rad / dt_secs, true), (nyquist_rad_s, false)]) {
        let angle = omega * dt_secs;
        let (colour, style) = if is_exclusion {
            (theme::EXCLUSION, LineStyle::Dashed { length: 6.0 })
        } else {
            (theme::ZGRID, LineStyle::Solid)
        };
        for sign in [1.0, -1.0] {
            let tip = [angle.cos(), sign * angle.sin()];
            let ray = Line::new("", vec![[0.0, 0.0], tip]).color(colour).width(0.8).style(style);
            plot_ui.line(ray.allow_hover(false));
        }
        if !labels {
            continue;
        }
        // Labels just outside the circle, except the Nyquist one (inside, on the negative real axis).
        let is_nyquist = !is_exclusion && (omega - nyquist_rad_s).abs() < 1e-9;
        let r = if is_nyquist { 0.97 } else { 1.03 };
        let at = PlotPoint::new(r * angle.cos(), r * angle.sin());
        let screen = plot_ui.screen_from_plot(at);
        if !is_exclusion && last_label.is_some_and(|p| p.distance(screen) < LABEL_SPACING) {
            continue;
        }
        last_label = Some(screen);
        let text = if is_exclusion {
            format!("{omega:.1} rad/s (exclusion)")
        } else if is_nyquist {
            format!("{omega:.1} rad/s (Nyquist)")
        } else {
            format!("{omega} rad/s")
        };
        let anchor =
            if angle.cos() >= 0.0 || is_nyquist { Align2::LEFT_BOTTOM } else { Align2::RIGHT_BOTTOM };
        plot_ui.text(Text::new("", at, RichText::new(text).size(11.0)).color(colour).anchor(anchor));
    }
}

/// Every segment model's poles (×) and zeros (○), one colour and legend entry per segment.
fn segment_roots_ui(plot_ui: &mut PlotUi<'_>, fits: &SegmentFits, size: f32) {
    for (i, roots) in fits.roots.iter().enumerate() {
        let name = format!("segment {}", roots.label);
        let colour = theme::segment_colour(i);
        plot_ui.points(
            Points::new(name.as_str(), folded(&roots.poles))
                .shape(MarkerShape::Cross)
                .radius(size)
                .color(colour)
                .allow_hover(false),
        );
        plot_ui.points(
            Points::new(name.as_str(), folded(&roots.zeros))
                .shape(MarkerShape::Circle)
                .filled(false)
                .radius(size * 0.85)
                .color(colour)
                .allow_hover(false),
        );
    }
}

/// Cluster circles (and their conjugate images), valid and invalid drawn differently.
fn clusters_ui(plot_ui: &mut PlotUi<'_>, clusters: &[Cluster], valid: &[bool], selected: Option<usize>) {
    for (i, cluster) in clusters.iter().enumerate() {
        let ok = valid.get(i).copied().unwrap_or(false);
        let (name, colour, style) = if ok {
            ("valid cluster", theme::CLUSTER_VALID, LineStyle::Solid)
        } else {
            ("invalid cluster", theme::CLUSTER_INVALID, LineStyle::Dashed { length: 5.0 })
        };
        let width = if selected == Some(i) { 3.0 } else { 1.8 };
        plot_ui.line(
            Line::new(name, circle(cluster.centre, cluster.radius, 96))
                .color(colour)
                .width(width)
                .style(style),
        );
        if !cluster.is_real_axis() {
            let image = Line::new(name, circle(cluster.centre.conj(), cluster.radius, 96))
                .color(colour.gamma_multiply(0.5))
                .width(1.0)
                .style(LineStyle::Dashed { length: 4.0 });
            plot_ui.line(image.allow_hover(false));
        }
        let kind = if cluster.kind == RootKind::Pole { "p" } else { "z" };
        let label_at = PlotPoint::new(cluster.centre.re, cluster.centre.im + cluster.radius);
        let label = RichText::new(format!("{kind}{}", i + 1)).size(12.0).strong();
        plot_ui.text(Text::new("", label_at, label).color(colour).anchor(Align2::CENTER_BOTTOM));
    }
}

/// Points on each 95 % region's outline (smooth at the size a region is drawn).
const REGION_POINTS: usize = 72;

/// The reduced model's poles and zeros, large and on top, each with the 95 % region its parameter
/// uncertainty gives (an ellipse for a pair and its mirror image, a bar along the axis for a real
/// root) once the model is finished.
fn reduced_roots_ui(plot_ui: &mut PlotUi<'_>, view: &LiveView<'_>) {
    let Ok(live) = view.live else { return };
    if let Ok(u) = &live.uncertainty {
        let colour = if u.refitted_block(&live.model.wiener.linear.tf).is_some() {
            theme::MODEL
        } else {
            theme::REDUCED
        };
        for region in &u.roots {
            let outline = region.outline(REGION_POINTS);
            let mirrored: Vec<[f64; 2]> = outline.iter().map(|[x, y]| [*x, -*y]).collect();
            for points in [outline, mirrored] {
                if points.iter().all(|[x, y]| x.is_finite() && y.is_finite()) {
                    plot_ui.line(
                        Line::new("95 % region of the roots (parameters)", points).color(colour).width(1.2),
                    );
                }
            }
        }
    }
    let tf = &live.model.wiener.linear.tf;
    let refitted = live.uncertainty.as_ref().ok().and_then(|u| u.refitted_block(tf));
    if let Some(block) = refitted {
        roots_ui(plot_ui, REFITTED_NAME, &block.poles, &block.zeros, theme::MODEL);
    }
    let poles = tf.poles().unwrap_or_default();
    let zeros = tf.zeros().unwrap_or_default();
    roots_ui(plot_ui, "reduced model", &poles, &zeros, theme::REDUCED);
}

/// The legend entry of the finished model's roots when the effects' refit moved them (their 95 %
/// regions are drawn around them, not around the reduced model's).
pub const REFITTED_NAME: &str = "model with effects";

/// Poles as crosses and zeros as rings, large.
fn roots_ui(plot_ui: &mut PlotUi<'_>, name: &str, poles: &[Complex64], zeros: &[Complex64], colour: Color32) {
    plot_ui.points(Points::new(name, folded(poles)).shape(MarkerShape::Cross).radius(8.0).color(colour));
    plot_ui.points(
        Points::new(name, folded(zeros)).shape(MarkerShape::Circle).filled(false).radius(7.0).color(colour),
    );
}

fn handles_ui(plot_ui: &mut PlotUi<'_>, cluster: &Cluster) {
    let c = cluster.centre;
    plot_ui.points(
        Points::new("", vec![[c.re, c.im]]).shape(MarkerShape::Square).radius(4.0).color(theme::HANDLE),
    );
    plot_ui.points(
        Points::new("", vec![[c.re + cluster.radius, c.im]])
            .shape(MarkerShape::Circle)
            .radius(4.0)
            .color(theme::HANDLE),
    );
}

/// Which handle (if any) of which cluster is at `pos`; the selected cluster is tried first.
pub fn hit_test(
    transform: &PlotTransform,
    clusters: &[Cluster],
    selected: Option<usize>,
    pos: Pos2,
) -> Option<(usize, Handle)> {
    let order = selected.into_iter().chain((0..clusters.len()).filter(|i| Some(*i) != selected));
    for i in order {
        let Some(cluster) = clusters.get(i) else { continue };
        let centre = transform.position_from_point(&PlotPoint::new(cluster.centre.re, cluster.centre.im));
        let radius_px = (cluster.radius * transform.dpos_dvalue_x().abs()) as f32;
        let d = centre.distance(pos);
        if d <= CENTRE_GRAB.min(0.5 * radius_px).max(3.0) {
            return Some((i, Handle::Centre));
        }
        if (d - radius_px).abs() <= RIM_GRAB {
            return Some((i, Handle::Rim));
        }
    }
    None
}

/// Move the dragged handle to the pointer at `pointer` (z-plane coordinates).
fn drag_to(drag: &mut ClusterDrag, pointer: PlotPoint) {
    let c = &drag.current;
    drag.current = match drag.handle {
        Handle::Centre => {
            let centre = Complex64::new(pointer.x + drag.grab_offset[0], pointer.y + drag.grab_offset[1]);
            Cluster::new(c.kind, centre, c.radius)
        }
        Handle::Rim => {
            let d = Complex64::new(pointer.x, pointer.y) - c.centre;
            let d_mirror = Complex64::new(pointer.x, pointer.y) - c.centre.conj();
            Cluster::new(c.kind, c.centre, d.norm().min(d_mirror.norm()).max(MIN_RADIUS))
        }
    };
}

/// The detail plot; returns the cluster change committed when a drag ends.
/// What both z-plane plots draw of the view: the segment fits, the exclusion angle beyond which
/// roots are not engine dynamics, and which clusters are valid (none while they cannot be evaluated).
fn drawn<'a>(view: &'a LiveView<'_>) -> Option<(&'a SegmentFits, f64, Vec<bool>)> {
    let fits = view.output.fits.as_ref().ok()?;
    let exclusion_rad = view.output.setup.settings.cluster.nyquist_exclusion_rad;
    let valid = view.evals.as_ref().map(|e| e.iter().map(|e| e.valid).collect()).unwrap_or_default();
    Some((fits, exclusion_rad, valid))
}

/// A z-plane plot the pointer does not pan or zoom (the view moves it on drags and the wheel
/// itself), with the unit circle round.
fn still_plot<'a>(id: (&str, &str)) -> Plot<'a> {
    Plot::new(id)
        .data_aspect(1.0)
        .allow_drag(false)
        .allow_zoom(false)
        .allow_scroll(false)
        .allow_boxed_zoom(false)
        .allow_double_click_reset(false)
}

pub fn main_plot_ui(
    ui: &mut egui::Ui,
    view: &LiveView<'_>,
    state: &mut ZPlaneViewState,
    height: f32,
) -> Option<Command> {
    let output = view.output.name.as_str();
    let (fits, exclusion_rad, valid) = drawn(view)?;
    let dt_secs = fits.dt_secs;
    // The pointer readout has a row of its own under the plot, so it never covers roots.
    let readout_height = ui.text_style_height(&egui::TextStyle::Monospace) + ui.spacing().item_spacing.y;
    let plot = still_plot(("zplane", output))
        .height(height - readout_height)
        .allow_axis_zoom_drag(false)
        .show_crosshair(false)
        .x_axis_label("Re z")
        .y_axis_label("Im z")
        .x_grid_spacer(plot_util::grid_125_equal)
        .y_grid_spacer(plot_util::grid_125_equal)
        .x_axis_formatter(plot_util::range_label)
        .y_axis_formatter(plot_util::range_label);
    let selected = state.selected;
    let response = plot.show(ui, |plot_ui| {
        let committed = interact(plot_ui, output, view.clusters, state);
        plot_ui.set_plot_bounds(state.zoom.get(output).copied().unwrap_or(ZoomView::WHOLE).bounds());
        let clusters: Vec<Cluster> = match &state.drag {
            Some(drag) => drag.preview(),
            None => view.clusters.to_vec(),
        };
        grid_ui(plot_ui, dt_secs, exclusion_rad, true);
        segment_roots_ui(plot_ui, fits, 5.0);
        clusters_ui(plot_ui, &clusters, &valid, state.selected.or(selected));
        reduced_roots_ui(plot_ui, view);
        if let Some(cluster) = state.selected.and_then(|i| clusters.get(i)) {
            handles_ui(plot_ui, cluster);
        }
        committed
    });
    state.last_transform = Some(response.transform);
    let hovering_handle = response
        .response
        .hover_pos()
        .and_then(|pos| hit_test(&response.transform, view.clusters, state.selected, pos));
    if state.drag.is_some() || hovering_handle.is_some() {
        ui.ctx().set_cursor_icon(egui::CursorIcon::Grab);
    }
    let pointer = response.response.hover_pos().map(|pos| response.transform.value_from_position(pos));
    let readout = pointer.map_or_else(String::new, |p| pointer_text(Complex64::new(p.x, p.y), dt_secs));
    ui.label(RichText::new(readout).monospace().color(theme::HINT));
    response.inner
}

/// Where the pointer is on the z-plane, and the frequency of a root there.
fn pointer_text(z: Complex64, dt_secs: f64) -> String {
    format!(
        "pointer: z = {:.4} {:+.4}i   |z| = {:.4}   ω = {:.3} rad/s",
        z.re,
        z.im,
        z.norm(),
        z.arg().abs() / dt_secs
    )
}

/// Pointer handling: select, drag a handle (live preview, commit on release), pan, zoom.
fn interact(
    plot_ui: &mut PlotUi<'_>,
    output: &str,
    clusters: &[Cluster],
    state: &mut ZPlaneViewState,
) -> Option<Command> {
    let response = plot_ui.response().clone();
    let transform = *plot_ui.transform();
    let (press_origin, scroll) = plot_ui.ctx().input(|i| (i.pointer.press_origin(), i.smooth_scroll_delta.y));
    if response.clicked()
        && let Some(pos) = response.interact_pointer_pos()
    {
        state.selected = hit_test(&transform, clusters, state.selected, pos).map(|(i, _)| i).or_else(|| {
            let p = transform.value_from_position(pos);
            let z = Complex64::new(p.x, p.y);
            clusters
                .iter()
                .position(|c| (z - c.centre).norm() <= c.radius || (z - c.centre.conj()).norm() <= c.radius)
        });
    }
    if response.drag_started_by(egui::PointerButton::Primary) {
        let origin = press_origin.or(response.interact_pointer_pos());
        let hit =
            origin.and_then(|pos| hit_test(&transform, clusters, state.selected, pos).map(|h| (pos, h)));
        match hit {
            Some((pos, (index, handle))) => {
                let grab = transform.value_from_position(pos);
                let cluster = clusters.get(index)?;
                state.selected = Some(index);
                state.drag = Some(ClusterDrag {
                    output: output.to_owned(),
                    index,
                    handle,
                    base: clusters.to_vec(),
                    current: cluster.clone(),
                    grab_offset: [cluster.centre.re - grab.x, cluster.centre.im - grab.y],
                });
            }
            None => state.panning = true,
        }
    }
    let zoom = state.zoom.entry(output.to_owned()).or_insert(ZoomView::WHOLE);
    if state.panning && response.dragged() {
        let [dx, dy] = transform.dpos_dvalue();
        let delta = response.drag_delta();
        zoom.centre[0] -= f64::from(delta.x) / dx;
        zoom.centre[1] -= f64::from(delta.y) / dy;
    }
    if response.hovered()
        && scroll.abs() > 0.0
        && let Some(pos) = response.hover_pos()
    {
        let p = transform.value_from_position(pos);
        zoom.zoom_about([p.x, p.y], (-f64::from(scroll) * 0.002).exp());
    }
    // Escape drops the drag: nothing is committed.
    if state.drag.is_some() && plot_ui.ctx().input(|i| i.key_pressed(egui::Key::Escape)) {
        state.drag = None;
    }
    if let Some(drag) = &mut state.drag
        && (response.dragged() || response.drag_stopped())
        && let Some(pos) = response.interact_pointer_pos()
    {
        drag_to(drag, transform.value_from_position(pos));
    }
    if response.drag_stopped() {
        state.panning = false;
        if let Some(drag) = state.drag.take() {
            let changed = drag.base.get(drag.index) != Some(&drag.current);
            return changed.then(|| Command::SetClusters {
                output: drag.output.clone(),
                clusters: Some(drag.preview()),
            });
        }
    }
    None
}

/// The whole unit circle with the detail view's rectangle; a click centres the detail view there.
pub fn overview_ui(ui: &mut egui::Ui, view: &LiveView<'_>, state: &mut ZPlaneViewState, side: f32) {
    let output = view.output.name.as_str();
    let Some((fits, exclusion_rad, valid)) = drawn(view) else { return };
    let detail = state.last_transform.map(|t| *t.bounds());
    let response = still_plot(("zplane_overview", output))
        .width(side)
        .height(side)
        .show_axes(false)
        .show_grid(false)
        .show_crosshair(false)
        .show(ui, |plot_ui| {
            plot_ui.set_plot_bounds(PlotBounds::from_min_max([-1.12, -1.12], [1.12, 1.12]));
            grid_ui(plot_ui, fits.dt_secs, exclusion_rad, false);
            segment_roots_ui(plot_ui, fits, 2.0);
            clusters_ui(plot_ui, view.clusters, &valid, None);
            if let Some(b) = detail {
                let (lo, hi) = (b.min(), b.max());
                let rect =
                    vec![[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]], [lo[0], lo[1]]];
                plot_ui.line(Line::new("", rect).color(theme::VIEWPORT).width(1.2));
            }
        });
    if response.response.clicked()
        && let Some(pos) = response.response.interact_pointer_pos()
    {
        let p = response.transform.value_from_position(pos);
        if let Some(zoom) = state.zoom.get_mut(output) {
            zoom.centre = [p.x, p.y];
        }
    }
    response
        .response
        .on_hover_text("The whole unit circle; the yellow box is the detail view. Click to move it.");
}
