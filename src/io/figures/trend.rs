//! An engine's health over its runs: one panel per delta, each run's value with its 95 % interval
//! as an error bar, the band it was judged against shaded behind it, flagged runs in red.
use std::path::Path;

use plotters::prelude::*;

use super::legend::{LegendEntry, Swatch, draw_legend};
use super::{
    Area, DrawResult, FigureError, LIGHT_LINES, chart_builder, draw_note, label_font, padded_range, palette,
    render, tick_label, titled_with_legend,
};

/// Pixels per panel (the figure is as tall as its panels need).
const PANEL_HEIGHT: u32 = 260;
const WIDTH: u32 = 1200;

/// One run's value of a delta.
#[derive(Clone, Debug, PartialEq)]
pub struct TrendPoint {
    /// Position on the x axis: the run's place in date order.
    pub x: f64,
    pub value: f64,
    pub ci95: Option<[f64; 2]>,
    /// The band the run was judged against, `[low, centre, high]`.
    pub band: Option<[f64; 3]>,
    pub flagged: bool,
}

/// One delta over the runs.
#[derive(Clone, Debug, PartialEq)]
pub struct TrendPanel {
    pub label: String,
    pub points: Vec<TrendPoint>,
}

/// Draws the panels one above the other to `path`; the x axis names run `i` by `x_labels[i]`.
pub fn trend_png(
    path: &Path,
    title: &str,
    x_desc: &str,
    x_labels: &[String],
    panels: &[TrendPanel],
) -> Result<(), FigureError> {
    let height = 120 + PANEL_HEIGHT * panels.len().max(1) as u32;
    render(path, (WIDTH, height), |root| {
        let (chart_area, legend_area) = titled_with_legend(root, title)?;
        if panels.is_empty() {
            return draw_note(&chart_area, "no health deltas");
        }
        for (area, panel) in chart_area.split_evenly((panels.len(), 1)).iter().zip(panels) {
            draw_panel(area, panel, x_desc, x_labels)?;
        }
        let entries = [
            LegendEntry::line("run, 95 % interval", palette::series(0), 2),
            LegendEntry::line("flagged run", palette::FIT, 2),
            LegendEntry::new("normal band (3.5σ)", Swatch::Bar(palette::GRID_BOLD)),
            LegendEntry::text("  (the engine's trend;"),
            LegendEntry::text("  wider for a run"),
            LegendEntry::text("  noisier than usual)"),
            LegendEntry::line("band centre", palette::REFERENCE, 1),
        ];
        draw_legend(&legend_area, &entries)
    })
}

fn draw_panel(area: &Area<'_>, panel: &TrendPanel, x_desc: &str, x_labels: &[String]) -> DrawResult {
    let xs = panel.points.iter().map(|p| p.x);
    let Some((x_lo, x_hi)) = padded_range(xs.chain([-0.5]), 0.05) else {
        return draw_note(area, "no runs");
    };
    let finite = |v: &f64| v.is_finite();
    let ys = panel
        .points
        .iter()
        .flat_map(|p| [Some(p.value), p.ci95.map(|c| c[0]), p.ci95.map(|c| c[1])])
        .flatten()
        .chain(panel.points.iter().flat_map(|p| p.band.into_iter().flatten()))
        .filter(finite);
    let Some((y_lo, y_hi)) = padded_range(ys, 0.08) else {
        return draw_note(area, &format!("{}: not fitted", panel.label));
    };
    let mut chart = chart_builder(area).build_cartesian_2d(x_lo..x_hi.max(0.5), y_lo..y_hi)?;
    chart
        .configure_mesh()
        .light_line_style(palette::GRID_LIGHT)
        .bold_line_style(palette::GRID_BOLD)
        .x_max_light_lines(0)
        .y_max_light_lines(LIGHT_LINES)
        .x_desc(x_desc)
        .y_desc(panel.label.as_str())
        .label_style(label_font())
        .y_label_formatter(&|v| tick_label(*v))
        .x_labels(x_labels.len().clamp(2, 20) + 1)
        .x_label_formatter(&|v| {
            let i = v.round();
            let whole = (v - i).abs() < 1e-6 && i >= 0.0;
            if whole { x_labels.get(i as usize).cloned().unwrap_or_default() } else { String::new() }
        })
        .draw()?;
    for p in &panel.points {
        let Some([low, centre, high]) = p.band.filter(|b| b.iter().all(finite)) else { continue };
        let (lo, hi, left, right) = (low.max(y_lo), high.min(y_hi), p.x - 0.45, p.x + 0.45);
        chart
            .draw_series([Rectangle::new([(left, lo), (right, hi)], palette::GRID_BOLD.mix(0.6).filled())])?;
        chart.draw_series(LineSeries::new(
            [(left, centre), (right, centre)],
            palette::REFERENCE.stroke_width(1),
        ))?;
    }
    for p in panel.points.iter().filter(|p| p.value.is_finite()) {
        let colour = if p.flagged { palette::FIT } else { palette::series(0) };
        if let Some([lo, hi]) = p.ci95.filter(|c| c.iter().all(finite)) {
            let (lo, hi) = (lo.max(y_lo), hi.min(y_hi));
            chart.draw_series(LineSeries::new([(p.x, lo), (p.x, hi)], colour.stroke_width(2)))?;
            for end in [lo, hi] {
                chart.draw_series(LineSeries::new(
                    [(p.x - 0.12, end), (p.x + 0.12, end)],
                    colour.stroke_width(2),
                ))?;
            }
        }
        chart.draw_series([Circle::new((p.x, p.value), 4, colour.filled())])?;
    }
    Ok(())
}
