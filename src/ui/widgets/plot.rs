//! Helpers shared by the plots of several views.
use egui_plot::{GridInput, GridMark, uniform_grid_spacer};

/// Grid lines on a 1–2–5 sequence (egui_plot's default uses powers of ten only, which leaves a
/// short axis with a single labelled tick). Labelled lines at least `label_factor` `base_step_size`s
/// apart (egui_plot labels ticks that are far enough apart), thin lines between them, heavy lines
/// at the next 1–2–5 step above; each step divides the next.
pub fn steps_125(input: GridInput, label_factor: f64) -> [f64; 3] {
    let labelled = nice_125(label_factor * input.base_step_size);
    let exponent = labelled.log10().floor();
    let mantissa = (labelled / 10f64.powf(exponent)).round();
    match mantissa as i64 {
        2 => [labelled / 2.0, labelled, labelled * 5.0],
        5 => [labelled / 5.0, labelled, labelled * 2.0],
        _ => [labelled / 5.0, labelled, labelled * 5.0],
    }
}

/// A 1–2–5 grid spacer for [`egui_plot::Plot::y_grid_spacer`] (labels need ~20 points).
pub fn grid_125_y(input: GridInput) -> Vec<GridMark> {
    (uniform_grid_spacer(|i| steps_125(i, 3.0)))(input)
}

/// A 1–2–5 grid spacer for [`egui_plot::Plot::x_grid_spacer`] (labels need ~60 points).
pub fn grid_125_x(input: GridInput) -> Vec<GridMark> {
    (uniform_grid_spacer(|i| steps_125(i, 9.0)))(input)
}

/// A 1–2–5 grid spacer for both axes of an equal-aspect plot (the z-plane): same steps on x and y.
pub fn grid_125_equal(input: GridInput) -> Vec<GridMark> {
    (uniform_grid_spacer(|i| steps_125(i, 9.0)))(input)
}

/// About eight tick labels on a 1–2–5 step over the visible range, with the decimals that step
/// needs (egui_plot's default labels every line it has room for and takes the decimals from each
/// line's own step, which prints 0.5 as "0" on a heavy 0.5 line).
pub fn range_label(mark: GridMark, range: &std::ops::RangeInclusive<f64>) -> String {
    let span = (range.end() - range.start()).abs();
    let step = nice_125(span / 8.0);
    let nearest = (mark.value / step).round() * step;
    if (nearest - mark.value).abs() > 1e-6 * step {
        return String::new();
    }
    let decimals = (-step.log10()).ceil().clamp(0.0, 6.0) as usize;
    format!("{:.*}", decimals, nearest)
}

/// Margin egui_plot's tick labels keep each side of their text on a y axis, points.
const TICK_LABEL_MARGIN: f32 = 4.0;
/// The gap egui_plot leaves beside a rotated axis label, as a share of its line height.
const AXIS_LABEL_GAP: f32 = 0.25;

/// The width a y axis labelled by [`range_label`] needs for a trace spanning `lo..=hi` (the tick
/// labels at either end of the auto-fitted bounds, and the rotated axis label beside them), in
/// points. Plots stacked over one time axis take the largest of their widths, so their plotting
/// areas, and with them their time axes, line up.
pub fn y_axis_width(ui: &egui::Ui, lo: f64, hi: f64) -> f32 {
    if !(lo.is_finite() && hi.is_finite()) {
        return 0.0;
    }
    // egui_plot pads fitted bounds by a few percent; a tenth each side covers it.
    let pad = if hi > lo { 0.1 * (hi - lo) } else { 0.1 * lo.abs().max(1.0) };
    let (lo, hi) = (lo - pad, hi + pad);
    let step = nice_125((hi - lo) / 8.0);
    let ends = [(lo / step).ceil() * step, (hi / step).floor() * step];
    let font = egui::TextStyle::Body.resolve(ui.style());
    let widest = ends
        .iter()
        .map(|v| {
            let mark = GridMark { value: *v, step_size: step };
            let text = range_label(mark, &(lo..=hi));
            ui.painter().layout_no_wrap(text, font.clone(), egui::Color32::WHITE).size().x
        })
        .fold(0.0, f32::max);
    let axis_label = ui.text_style_height(&egui::TextStyle::Body) * (1.0 + AXIS_LABEL_GAP);
    widest + 2.0 * TICK_LABEL_MARGIN + axis_label
}

/// The smallest of 1, 2, 5 × 10ⁿ that is at least `value` (positive, finite).
pub fn nice_125(value: f64) -> f64 {
    if !(value.is_finite() && value > 0.0) {
        return 1.0;
    }
    let decade = 10f64.powf(value.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * decade)
        .find(|step| *step >= value * (1.0 - 1e-9))
        .unwrap_or(10.0 * decade)
}

/// Log-ω grid (x is log10 ω): decades labelled, 2…9 thin.
pub fn log_grid(input: GridInput) -> Vec<GridMark> {
    let (lo, hi) = input.bounds;
    let mut marks = Vec::new();
    let (first, last) = (lo.floor() as i32 - 1, hi.ceil() as i32 + 1);
    for decade in first..=last {
        let d = f64::from(decade);
        marks.push(GridMark { value: d, step_size: 1.0 });
        for k in 2..10 {
            marks.push(GridMark { value: d + f64::from(k).log10(), step_size: 0.1 });
        }
    }
    marks.retain(|m| m.value >= lo && m.value <= hi);
    marks
}

/// Labels at decades only: 0.1, 1, 10 …
pub fn log_label(mark: GridMark, _range: &std::ops::RangeInclusive<f64>) -> String {
    if (mark.value - mark.value.round()).abs() > 1e-6 {
        return String::new();
    }
    let omega = 10f64.powf(mark.value.round());
    if omega >= 1.0 { format!("{omega:.0}") } else { format!("{omega}") }
}

/// One panel of a Bode pair on a log-ω axis, its x axis and cursor linked with the other panel of
/// `group`: magnitude in dB, or phase in degrees.
pub fn bode_panel<'a>(
    id: impl std::hash::Hash + std::fmt::Debug,
    group: egui::Id,
    height: f32,
    phase: bool,
) -> egui_plot::Plot<'a> {
    egui_plot::Plot::new(id)
        .height(height)
        .link_axis(group, [true, false])
        .link_cursor(group, [true, false])
        .x_grid_spacer(log_grid)
        .x_axis_formatter(log_label)
        .y_grid_spacer(grid_125_y)
        .y_axis_label(if phase { "phase [deg]" } else { "magnitude [dB]" })
}

/// One key of a legend drawn outside a plot: a short stretch of the line as the plot draws it
/// (colour, width, solid or dashed), then its name. One widget, so a wrapping row never parts the
/// stretch from its name.
pub fn line_key_ui(ui: &mut egui::Ui, colour: egui::Color32, width: f32, dashed: bool, name: &str) {
    const STRETCH: f32 = 24.0;
    let rect = key_ui(ui, colour, name, STRETCH);
    let y = rect.center().y;
    let points = [egui::pos2(rect.left(), y), egui::pos2(rect.left() + STRETCH, y)];
    let stroke = egui::Stroke::new(width, colour);
    if dashed {
        ui.painter().extend(egui::Shape::dashed_line(&points, stroke, 6.0, 3.0));
    } else {
        ui.painter().line_segment(points, stroke);
    }
}

/// One key of a legend drawn outside a plot for points drawn as diamonds (egui_plot's own legend
/// draws every item as a dot, whatever its marker): a filled diamond, then its name.
pub fn diamond_key_ui(ui: &mut egui::Ui, colour: egui::Color32, name: &str) {
    const HALF: f32 = 5.0;
    let rect = key_ui(ui, colour, name, 2.0 * HALF);
    let c = egui::pos2(rect.left() + HALF, rect.center().y);
    let corners = vec![
        c + egui::vec2(0.0, -HALF),
        c + egui::vec2(HALF, 0.0),
        c + egui::vec2(0.0, HALF),
        c + egui::vec2(-HALF, 0.0),
    ];
    ui.painter().add(egui::Shape::convex_polygon(corners, colour, egui::Stroke::NONE));
}

/// A legend key's widget: room for a mark `mark_width` wide, then `name` in `colour` (drawn here);
/// returns the whole key's rectangle, the mark to be drawn at its left.
fn key_ui(ui: &mut egui::Ui, colour: egui::Color32, name: &str, mark_width: f32) -> egui::Rect {
    const GAP: f32 = 4.0;
    let galley = egui::WidgetText::from(egui::RichText::new(name).color(colour)).into_galley(
        ui,
        Some(egui::TextWrapMode::Extend),
        f32::INFINITY,
        egui::TextStyle::Body,
    );
    let size = egui::vec2(mark_width + GAP + galley.size().x, galley.size().y);
    let (rect, response) = ui.allocate_exact_size(size, egui::Sense::hover());
    response.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Label, true, name));
    ui.painter().galley(egui::pos2(rect.left() + mark_width + GAP, rect.top()), galley, colour);
    rect
}

/// How opaque an uncertainty band is drawn: light enough that the lines over it stay readable.
const BAND_ALPHA: u8 = 60;

/// A 95 % uncertainty band between `lo` and `hi` over `x`, in `colour` washed out, without a
/// border; `None` when the three do not have one value each per x (a band that does not belong to
/// the curve it is drawn with) or nothing is finite. Non-finite points are left out.
pub fn band(
    name: &str,
    x: &[f64],
    lo: &[f64],
    hi: &[f64],
    colour: egui::Color32,
) -> Option<egui_plot::FilledArea> {
    if x.len() != lo.len() || x.len() != hi.len() {
        return None;
    }
    let kept: Vec<usize> =
        (0..x.len()).filter(|&k| x[k].is_finite() && lo[k].is_finite() && hi[k].is_finite()).collect();
    if kept.is_empty() {
        return None;
    }
    let pick = |v: &[f64]| -> Vec<f64> { kept.iter().map(|&k| v[k]).collect() };
    let fill = egui::Color32::from_rgba_unmultiplied(colour.r(), colour.g(), colour.b(), BAND_ALPHA);
    Some(
        egui_plot::FilledArea::new(name, &pick(x), &pick(lo), &pick(hi))
            .fill_color(fill)
            .stroke(egui::Stroke::NONE),
    )
}

/// [`band`] of `centre ± half`.
pub fn band_around(
    name: &str,
    x: &[f64],
    centre: &[f64],
    half: &[f64],
    colour: egui::Color32,
) -> Option<egui_plot::FilledArea> {
    if centre.len() != half.len() {
        return None;
    }
    let lo: Vec<f64> = centre.iter().zip(half).map(|(c, h)| c - h).collect();
    let hi: Vec<f64> = centre.iter().zip(half).map(|(c, h)| c + h).collect();
    band(name, x, &lo, &hi, colour)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_steps_are_125_and_not_smaller() {
        for (value, expected) in
            [(0.7, 1.0), (1.0, 1.0), (1.3, 2.0), (3.0, 5.0), (7.0, 10.0), (42.0, 50.0), (0.013, 0.02)]
        {
            let got = nice_125(value);
            assert!((got - expected).abs() < 1e-9 * expected, "{value} -> {got}, expected {expected}");
        }
    }

    #[test]
    fn each_step_divides_the_next() {
        for base in [0.003, 0.9, 1.7, 4.2, 33.0, 710.0] {
            let [a, b, c] = steps_125(GridInput { bounds: (0.0, 1.0), base_step_size: base }, 3.0);
            assert!(b >= 3.0 * base * (1.0 - 1e-9) && a < b && b < c);
            for (small, big) in [(a, b), (b, c)] {
                let ratio = big / small;
                assert!((ratio - ratio.round()).abs() < 1e-9, "{small} does not divide {big}");
            }
        }
    }
}
