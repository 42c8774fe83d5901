//! Distribution figures: histograms (Monte Carlo) and box plots (percentage errors).
use std::f64::consts::PI;
use std::ops::Range;
use std::path::Path;

use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, Ranged, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::legend::{LegendEntry, Swatch, draw_legend};
use super::{
    Area, DrawError, DrawResult, FigureError, LIGHT_LINES, chart_builder, desc_font, font, house_style,
    label_font, padded_range, palette, render_chart, sig, tick_label,
};
use crate::core::numerics::metrics::BoxStats;

const NORMAL_CURVE_POINTS: usize = 200;
/// Half the width of a box, in category units (one category is 1 wide).
const BOX_HALF_WIDTH: f64 = 0.3;
const CAP_HALF_WIDTH: f64 = 0.15;

/// Draws a histogram of the finite `samples` in `bins` equal bins, with the normal density
/// `fitted_normal = (mean, std)` scaled to counts over it.
pub fn histogram_png(
    path: &Path,
    title: &str,
    samples: &[f64],
    bins: usize,
    fitted_normal: Option<(f64, f64)>,
    x_label: &str,
) -> Result<(), FigureError> {
    if bins == 0 {
        let path = path.to_path_buf();
        return Err(FigureError::InvalidParameter { path, name: "bins", value: 0.0, expected: "at least 1" });
    }
    let samples: Vec<f64> = samples.iter().copied().filter(|v| v.is_finite()).collect();
    let normal = fitted_normal.filter(|(m, s)| m.is_finite() && s.is_finite() && *s > 0.0);
    let sample_range = padded_range(samples.iter().copied(), 0.0);
    render_chart(path, title, sample_range, "no samples", |chart_area, legend_area, (lo, hi)| {
        let width = (hi - lo) / bins as f64;
        let mut counts = vec![0usize; bins];
        for v in &samples {
            let i = (((v - lo) / width).floor().max(0.0) as usize).min(bins - 1);
            if let Some(c) = counts.get_mut(i) {
                *c += 1;
            }
        }
        let scale = samples.len() as f64 * width;
        let curve: Vec<(f64, f64)> = normal.map(|(m, s)| normal_curve(m, s, scale)).unwrap_or_default();
        let x_values =
            [lo, hi].into_iter().chain(normal.into_iter().flat_map(|(m, s)| [m - 3.0 * s, m + 3.0 * s]));
        let (x_lo, x_hi) = padded_range(x_values, 0.03).unwrap_or((lo, hi));
        let peak = counts.iter().map(|c| *c as f64).chain(curve.iter().map(|p| p.1)).fold(1.0, f64::max);
        let mut chart = chart_builder(chart_area).build_cartesian_2d(x_lo..x_hi, 0.0..1.08 * peak)?;
        house_style(chart.configure_mesh().x_desc(x_label).y_desc("count")).draw()?;
        let bars = counts.iter().enumerate().map(|(i, c)| {
            let x0 = lo + i as f64 * width;
            [(x0, 0.0), (x0 + width, *c as f64)]
        });
        chart.draw_series(bars.clone().map(|r| Rectangle::new(r, palette::FILL.mix(0.5).filled())))?;
        chart.draw_series(bars.map(|r| Rectangle::new(r, palette::FILL.stroke_width(1))))?;
        chart.draw_series(LineSeries::new(curve, palette::FIT.stroke_width(3)))?;
        let mut entries =
            vec![LegendEntry::new(format!("samples (n = {})", samples.len()), Swatch::Bar(palette::FILL))];
        if let Some((m, s)) = normal {
            entries.push(LegendEntry::line("fitted normal", palette::FIT, 3));
            entries.push(LegendEntry::text(format!("  mean = {}", sig(m, 4))));
            entries.push(LegendEntry::text(format!("  std = {}", sig(s, 3))));
        }
        draw_legend(legend_area, &entries)
    })
}

/// `scale` × the normal density over mean ± 4 std.
fn normal_curve(mean: f64, std: f64, scale: f64) -> Vec<(f64, f64)> {
    (0..=NORMAL_CURVE_POINTS)
        .map(|k| {
            let x = mean + std * (-4.0 + 8.0 * k as f64 / NORMAL_CURVE_POINTS as f64);
            let z = (x - mean) / std;
            (x, scale * (-0.5 * z * z).exp() / (std * (2.0 * PI).sqrt()))
        })
        .collect()
}

/// A category axis: category i spans [i, i + 1] and is labelled with its name at i + 0.5. Drawn
/// upwards, so the axis is reversed: the first name sits at the top.
struct CategoryAxis {
    names: Vec<String>,
}

impl Ranged for CategoryAxis {
    type FormatOption = NoDefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let n = self.names.len().max(1) as f64;
        (limit.0 as f64 + value / n * (limit.1 - limit.0) as f64).round() as i32
    }

    fn key_points<Hint: KeyPointHint>(&self, _hint: Hint) -> Vec<f64> {
        (0..self.names.len()).map(|i| i as f64 + 0.5).collect()
    }

    fn range(&self) -> Range<f64> {
        0.0..self.names.len().max(1) as f64
    }
}

impl ValueFormatter<f64> for CategoryAxis {
    fn format_ext(&self, value: &f64) -> String {
        let from_top = self.names.len() as f64 - value.floor() - 1.0;
        if from_top < 0.0 {
            return String::new();
        }
        self.names.get(from_top as usize).cloned().unwrap_or_default()
    }
}

/// Widest a box label may make the label area, as a share of the chart area's width.
const MAX_LABEL_SHARE: f64 = 0.5;

/// Draws one box per entry, one row each, the first at the top, labelled at the left with its
/// whole name (so a dozen long "model / run" names stay readable): q1–q3 box, median line,
/// whiskers, the minimum and maximum when they lie beyond the whiskers, and the number of points
/// outside the whiskers. Names of the form "group / name" are grouped: a line separates the groups.
pub fn boxplot_png(
    path: &Path,
    title: &str,
    boxes: &[(String, BoxStats)],
    value_label: &str,
) -> Result<(), FigureError> {
    let values =
        boxes.iter().flat_map(|(_, b)| [b.min, b.max, b.whisker_lo, b.whisker_hi, b.q1, b.q3, b.median]);
    // Room at the right for the "n outside" notes.
    let note_room = if boxes.iter().any(|(_, b)| b.outliers > 0) { NOTE_SHARE } else { 0.0 };
    let x_range = padded_range(values, 0.08).map(|(lo, hi)| (lo, hi + note_room * (hi - lo)));
    render_chart(path, title, x_range, "no data", |chart_area, legend_area, (x_lo, x_hi)| {
        let names = fitted_labels(chart_area, boxes.iter().map(|(n, _)| n.as_str()))?;
        let label_width = names.iter().map(|(_, w)| *w).max().unwrap_or(0);
        let axis = CategoryAxis { names: names.into_iter().map(|(n, _)| n).collect() };
        let mut chart = chart_builder(chart_area)
            .y_label_area_size(label_width + LABEL_GAP_PX)
            .build_cartesian_2d(x_lo..x_hi, axis)?;
        chart
            .configure_mesh()
            .disable_y_mesh()
            .x_desc(value_label)
            .x_label_formatter(&|v| tick_label(*v))
            .label_style(label_font())
            .axis_desc_style(desc_font())
            .bold_line_style(palette::GRID_BOLD)
            .light_line_style(palette::GRID_LIGHT)
            .max_light_lines(LIGHT_LINES)
            .draw()?;
        let centre = |i: usize| boxes.len().saturating_sub(i + 1) as f64 + 0.5;
        for i in group_starts(boxes) {
            let y = centre(i) + 0.5;
            chart.draw_series([PathElement::new(vec![(x_lo, y), (x_hi, y)], palette::REFERENCE.mix(0.4))])?;
        }
        for (i, (_, b)) in boxes.iter().enumerate() {
            draw_box(&mut chart, centre(i), b)?;
        }
        let entries = [
            LegendEntry::new("quartiles q1–q3", Swatch::Bar(palette::FILL)),
            LegendEntry::line("median", palette::MEASURED, 3),
            LegendEntry::line("whiskers", palette::MEASURED, 1),
            LegendEntry::new("min / max beyond", Swatch::Ring(palette::MEASURED)),
            LegendEntry::text("n outside: points beyond"),
            LegendEntry::text("  the whiskers"),
        ];
        draw_legend(legend_area, &entries)
    })
}

/// Share of the value range added at the right for the "n outside" notes.
const NOTE_SHARE: f64 = 0.12;
/// Space between the labels and the axis, pixels.
const LABEL_GAP_PX: u32 = 20;

type BoxChart<'a, 'b> = ChartContext<'a, BitMapBackend<'b>, Cartesian2d<RangedCoordf64, CategoryAxis>>;

/// One horizontal box centred on `y`.
fn draw_box(chart: &mut BoxChart<'_, '_>, y: f64, b: &BoxStats) -> DrawResult {
    let line = |a: (f64, f64), c: (f64, f64), w: u32| {
        PathElement::new(vec![a, c], palette::MEASURED.stroke_width(w))
    };
    let (lo, hi) = (y - BOX_HALF_WIDTH, y + BOX_HALF_WIDTH);
    chart.draw_series([Rectangle::new([(b.q1, lo), (b.q3, hi)], palette::FILL.mix(0.3).filled())])?;
    chart.draw_series([Rectangle::new([(b.q1, lo), (b.q3, hi)], palette::FILL.stroke_width(2))])?;
    chart.draw_series([
        line((b.q3, y), (b.whisker_hi, y), 1),
        line((b.q1, y), (b.whisker_lo, y), 1),
        line((b.whisker_hi, y - CAP_HALF_WIDTH), (b.whisker_hi, y + CAP_HALF_WIDTH), 2),
        line((b.whisker_lo, y - CAP_HALF_WIDTH), (b.whisker_lo, y + CAP_HALF_WIDTH), 2),
        line((b.median, lo), (b.median, hi), 3),
    ])?;
    let extremes = [(b.min, b.min < b.whisker_lo), (b.max, b.max > b.whisker_hi)];
    let beyond = extremes.into_iter().filter(|(v, out)| *out && v.is_finite());
    chart.draw_series(beyond.map(|(v, _)| Circle::new((v, y), 5, palette::MEASURED.stroke_width(2))))?;
    if b.outliers > 0 && b.max.is_finite() {
        let style = font(14.0).color(&palette::NOTE).pos(Pos::new(HPos::Left, VPos::Center));
        let note = format!("{} outside", b.outliers);
        let at = EmptyElement::at((b.max.max(b.whisker_hi), y)) + Text::new(note, (12, 0), style);
        chart.plotting_area().draw(&at)?;
    }
    Ok(())
}

/// The indices where a new group starts: a box whose "group / …" prefix differs from the one before.
fn group_starts(boxes: &[(String, BoxStats)]) -> impl Iterator<Item = usize> + '_ {
    let group = |name: &str| name.split_once(" / ").map_or("", |(g, _)| g).to_owned();
    boxes
        .windows(2)
        .enumerate()
        .filter(move |(_, w)| match w {
            [a, b] => group(&a.0) != group(&b.0),
            _ => false,
        })
        .map(|(i, _)| i + 1)
}

/// Each label with its width in pixels, cut (and marked "…") where it would take more than
/// [`MAX_LABEL_SHARE`] of the chart area's width.
fn fitted_labels<'n>(
    area: &Area<'_>,
    names: impl Iterator<Item = &'n str>,
) -> Result<Vec<(String, u32)>, DrawError> {
    let (w, _) = area.dim_in_pixel();
    let limit = (MAX_LABEL_SHARE * f64::from(w)) as u32;
    let style = label_font();
    names
        .map(|name| {
            let mut text = name.to_owned();
            let mut width = area.estimate_text_size(&text, &style)?.0;
            while width > limit && text.chars().count() > 2 {
                let mut chars: Vec<char> = text.chars().collect();
                chars.truncate(chars.len() - 2);
                text = chars.into_iter().collect::<String>() + "…";
                width = area.estimate_text_size(&text, &style)?.0;
            }
            Ok((text, width))
        })
        .collect()
}
