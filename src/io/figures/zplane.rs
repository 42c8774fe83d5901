//! The z-plane: every segment model's poles and zeros, the clusters and the unit circle.
use std::f64::consts::PI;
use std::path::Path;

use nalgebra::Complex;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::legend::{LegendEntry, Swatch, draw_legend};
use super::{
    Area, CHART_MARGIN, DrawResult, FigureError, X_LABEL_AREA, Y_LABEL_AREA, chart_builder, desc_font, font,
    house_style, palette, render, sig, tick_label, titled_with_legend,
};
use crate::core::identification::cluster::{ClusterEval, RootKind, SegmentRoots};

type Complex64 = Complex<f64>;

/// Picture size: the chart part is square, the legend panel sits to its right.
pub const ZPLANE_SIZE: (u32, u32) = (1150, 900);
/// The axes span −LIMIT..LIMIT on both axes.
const LIMIT: f64 = 1.1;
/// Angle rays are drawn for round frequencies between this fraction of Nyquist and Nyquist.
const LOWEST_RAY_FRACTION: f64 = 0.02;
/// Ray labels closer than this (radians) to the previous one are left out.
const MIN_LABEL_GAP_RAD: f64 = 0.07;
const CIRCLE_POINTS: usize = 180;

type ZChart<'a, 'b> = ChartContext<'a, BitMapBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Draws the z-plane of the segment models with the clusters.
///
/// `roots` hold each segment's poles (×) and zeros (○), coloured by segment; `evals` the clusters,
/// drawn as circles with their mirror images, solid when valid and dashed grey when not. The angle
/// rays are labelled with the frequency ω = angle / `dt_secs`.
pub fn zplane_png(
    path: &Path,
    title: &str,
    roots: &[SegmentRoots],
    evals: &[ClusterEval],
    dt_secs: f64,
) -> Result<(), FigureError> {
    zplane_with_regions_png(path, title, roots, evals, dt_secs, &ModelRoots::default())
}

/// The model's own poles and zeros, and the 95 % region of each (closed outlines in z, the upper
/// root of a pair; its mirror image is drawn too).
#[derive(Clone, Copy, Debug, Default)]
pub struct ModelRoots<'a> {
    pub poles: &'a [Complex64],
    pub zeros: &'a [Complex64],
    pub regions: &'a [Vec<[f64; 2]>],
}

/// [`zplane_png`] with the model's roots, large, and the 95 % region of each drawn over it, named
/// in the legend.
pub fn zplane_with_regions_png(
    path: &Path,
    title: &str,
    roots: &[SegmentRoots],
    evals: &[ClusterEval],
    dt_secs: f64,
    model: &ModelRoots<'_>,
) -> Result<(), FigureError> {
    let regions = model.regions;
    if !(dt_secs.is_finite() && dt_secs > 0.0) {
        return Err(FigureError::InvalidParameter {
            path: path.to_path_buf(),
            name: "dt_secs",
            value: dt_secs,
            expected: "finite and > 0",
        });
    }
    render(path, ZPLANE_SIZE, |root| {
        let (chart_region, legend_area) = titled_with_legend(root, title)?;
        let mut chart =
            chart_builder(&square(&chart_region)).build_cartesian_2d(-LIMIT..LIMIT, -LIMIT..LIMIT)?;
        house_style(chart.configure_mesh().x_desc("Re z").y_desc("Im z").x_labels(12).y_labels(12)).draw()?;
        draw_reference(&mut chart, dt_secs)?;
        for eval in evals {
            draw_cluster(&mut chart, eval, evals)?;
        }
        let mut outside = 0;
        for (j, segment) in roots.iter().enumerate() {
            outside += draw_roots(&mut chart, segment, palette::series(j))?;
        }
        for outline in regions {
            let finite: Vec<(f64, f64)> = outline
                .iter()
                .filter(|[x, y]| x.is_finite() && y.is_finite())
                .map(|[x, y]| (*x, *y))
                .collect();
            let mirrored: Vec<(f64, f64)> = finite.iter().map(|(x, y)| (*x, -*y)).collect();
            for line in [finite, mirrored] {
                chart.draw_series(LineSeries::new(line, palette::FIT.stroke_width(2)))?;
            }
        }
        let outside_model = draw_model_roots(&mut chart, model)?;
        if roots.iter().all(|s| s.poles.is_empty() && s.zeros.is_empty()) && evals.is_empty() {
            let style = desc_font().color(&palette::NOTE).pos(Pos::new(HPos::Center, VPos::Center));
            chart.plotting_area().draw(&Text::new("no roots or clusters", (0.0, 0.5), style))?;
        }
        let mut entries = legend_entries(roots, evals, dt_secs, outside + outside_model);
        if !(model.poles.is_empty() && model.zeros.is_empty()) {
            entries.push(LegendEntry::new("model's roots", Swatch::Cross(palette::FIT)));
        }
        if !regions.is_empty() {
            entries.push(LegendEntry::line("their 95 % regions", palette::FIT, 2));
        }
        draw_legend(&legend_area, &entries)
    })
}

/// The part of `region` whose plotting area is square, centred.
fn square<'a>(region: &Area<'a>) -> Area<'a> {
    let (w, h) = region.dim_in_pixel();
    let avail_w = w.saturating_sub(Y_LABEL_AREA + 2 * CHART_MARGIN);
    let avail_h = h.saturating_sub(X_LABEL_AREA + 2 * CHART_MARGIN);
    let side = avail_w.min(avail_h);
    let (extra_w, extra_h) = (avail_w - side, avail_h - side);
    region.margin(extra_h / 2, extra_h - extra_h / 2, extra_w / 2, extra_w - extra_w / 2)
}

fn circle_points(centre: Complex64, radius: f64) -> Vec<(f64, f64)> {
    (0..=CIRCLE_POINTS)
        .map(|k| {
            let a = 2.0 * PI * k as f64 / CIRCLE_POINTS as f64;
            (centre.re + radius * a.cos(), centre.im + radius * a.sin())
        })
        .collect()
}

/// Axes, angle rays with their frequency labels and the unit circle.
fn draw_reference(chart: &mut ZChart<'_, '_>, dt_secs: f64) -> DrawResult {
    let axis = palette::REFERENCE.stroke_width(1);
    chart.draw_series(LineSeries::new([(-LIMIT, 0.0), (LIMIT, 0.0)], axis))?;
    chart.draw_series(LineSeries::new([(0.0, -LIMIT), (0.0, LIMIT)], axis))?;
    let mut last_label: Option<f64> = None;
    for omega in ray_omegas(dt_secs) {
        let angle = omega * dt_secs;
        let (c, s) = (angle.cos(), angle.sin());
        for sign in [1.0, -1.0] {
            chart.draw_series(LineSeries::new([(0.0, 0.0), (c, sign * s)], palette::RAY.stroke_width(1)))?;
        }
        if last_label.is_some_and(|prev| angle - prev < MIN_LABEL_GAP_RAD) {
            continue;
        }
        last_label = Some(angle);
        let h = if c > 0.3 {
            HPos::Left
        } else if c < -0.3 {
            HPos::Right
        } else {
            HPos::Center
        };
        let v = if s > 0.3 { VPos::Bottom } else { VPos::Center };
        let style = font(14.0).color(&palette::NOTE).pos(Pos::new(h, v));
        let at = (1.03 * c, 1.03 * s);
        chart.plotting_area().draw(&Text::new(format!("{} rad/s", tick_label(omega)), at, style))?;
    }
    chart.draw_series(LineSeries::new(
        circle_points(Complex64::new(0.0, 0.0), 1.0),
        palette::REFERENCE.stroke_width(2),
    ))?;
    Ok(())
}

/// Round frequencies (1, 2, 5 × 10ᵏ rad/s) from [`LOWEST_RAY_FRACTION`] of Nyquist up to Nyquist.
fn ray_omegas(dt_secs: f64) -> Vec<f64> {
    let nyquist = PI / dt_secs;
    let lo = LOWEST_RAY_FRACTION * nyquist;
    let first_decade = lo.log10().floor() as i32;
    let last_decade = nyquist.log10().ceil() as i32;
    let mut out = Vec::new();
    for k in first_decade..=last_decade {
        for m in [1.0, 2.0, 5.0] {
            let omega = m * 10f64.powi(k);
            if omega >= lo && omega < 0.99 * nyquist {
                out.push(omega);
            }
        }
    }
    out
}

/// One cluster circle and its mirror image, labelled P1, P2, … / Z1, Z2, … in `evals` order.
fn draw_cluster(chart: &mut ZChart<'_, '_>, eval: &ClusterEval, evals: &[ClusterEval]) -> DrawResult {
    let cluster = &eval.cluster;
    let (centre, radius) = (cluster.centre, cluster.radius);
    if !(centre.re.is_finite() && centre.im.is_finite() && radius.is_finite() && radius >= 0.0) {
        return Ok(());
    }
    let mut centres = vec![centre];
    if centre.im.abs() > 1e-12 {
        centres.push(centre.conj());
    }
    for c in centres {
        let points = circle_points(c, radius);
        if eval.valid {
            chart.draw_series(LineSeries::new(points, palette::VALID_CLUSTER.stroke_width(2)))?;
        } else {
            chart.draw_series(DashedLineSeries::new(points, 6, 5, palette::MUTED.stroke_width(2)))?;
        }
    }
    let number = evals
        .iter()
        .take_while(|e| !std::ptr::eq(*e, eval))
        .filter(|e| e.cluster.kind == cluster.kind)
        .count()
        + 1;
    let letter = match cluster.kind {
        RootKind::Pole => 'P',
        RootKind::Zero => 'Z',
    };
    let color = if eval.valid { palette::VALID_CLUSTER } else { palette::MUTED };
    let style = font(15.0).color(&color).pos(Pos::new(HPos::Left, VPos::Bottom));
    let at = (centre.re + 0.72 * radius, centre.im.abs() + 0.72 * radius);
    chart.plotting_area().draw(&Text::new(format!("{letter}{number}"), at, style))?;
    Ok(())
}

/// Draws a segment's poles and zeros inside the view; returns how many fell outside it.
fn draw_roots(
    chart: &mut ZChart<'_, '_>,
    segment: &SegmentRoots,
    color: RGBColor,
) -> Result<usize, super::DrawError> {
    draw_marks(chart, &segment.poles, &segment.zeros, color.stroke_width(2), 6)
}

/// The model's own roots: larger and heavier than the segments' so that they show among them.
fn draw_model_roots(chart: &mut ZChart<'_, '_>, model: &ModelRoots<'_>) -> Result<usize, super::DrawError> {
    draw_marks(chart, model.poles, model.zeros, palette::FIT.stroke_width(3), 9)
}

/// Poles as crosses and zeros as rings of `size` pixels; returns how many lie off the view.
fn draw_marks(
    chart: &mut ZChart<'_, '_>,
    poles: &[Complex64],
    zeros: &[Complex64],
    style: ShapeStyle,
    size: i32,
) -> Result<usize, super::DrawError> {
    let inside = |z: &&Complex64| z.re.abs() <= LIMIT && z.im.abs() <= LIMIT;
    let shown_poles: Vec<(f64, f64)> = poles.iter().filter(inside).map(|z| (z.re, z.im)).collect();
    let shown_zeros: Vec<(f64, f64)> = zeros.iter().filter(inside).map(|z| (z.re, z.im)).collect();
    let outside = poles.len() + zeros.len() - shown_poles.len() - shown_zeros.len();
    chart.draw_series(shown_poles.into_iter().map(|p| Cross::new(p, size, style)))?;
    chart.draw_series(shown_zeros.into_iter().map(|p| Circle::new(p, size - 1, style)))?;
    Ok(outside)
}

fn legend_entries(
    roots: &[SegmentRoots],
    evals: &[ClusterEval],
    dt_secs: f64,
    outside: usize,
) -> Vec<LegendEntry> {
    let mut entries = vec![
        LegendEntry::new("pole", Swatch::Cross(palette::MEASURED)),
        LegendEntry::new("zero", Swatch::Ring(palette::MEASURED)),
    ];
    if !evals.is_empty() {
        let valid = Swatch::Line { color: palette::VALID_CLUSTER, width: 2, dashed: false };
        let invalid = Swatch::Line { color: palette::MUTED, width: 2, dashed: true };
        entries.push(LegendEntry::new("valid cluster", valid));
        entries.push(LegendEntry::new("invalid cluster", invalid));
    }
    // Short enough for the legend panel: a cut number would be worse than a terse wording.
    entries.push(LegendEntry::text(format!("rays: ω = angle / {} s", sig(dt_secs, 4))));
    entries.push(LegendEntry::text(format!("Nyquist: {} rad/s", sig(PI / dt_secs, 4))));
    if outside > 0 {
        entries.push(LegendEntry::text(format!("{outside} roots off the view")));
    }
    if !roots.is_empty() {
        entries.push(LegendEntry::text("segments:"));
    }
    for (j, segment) in roots.iter().enumerate() {
        entries.push(LegendEntry::new(segment.label.clone(), Swatch::Cross(palette::series(j))));
    }
    entries
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_legend_remarks_are_shown_whole() {
        // The sample runs' sample time, and more roots off the view than any run has had.
        let entries = legend_entries(&[], &[], 0.113_094, 1234);
        let labels: Vec<&str> = entries.iter().map(|e| e.label.as_str()).collect();
        assert!(labels.contains(&"rays: ω = angle / 0.1131 s"), "{labels:?}");
        assert!(labels.contains(&"1234 roots off the view"), "{labels:?}");
        for entry in &entries {
            assert!(entry.fits(), "cut in the legend: {}", entry.label);
        }
    }
}
