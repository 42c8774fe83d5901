//! Where a model fails on one run, in four panels: the residual with the noise band and the worst
//! stretches, the error by regime, the residual's autocorrelation and its cross-correlation with the
//! input (99 % bounds), and the residual spectrum.
use std::path::Path;

use plotters::prelude::*;

use super::legend::{LegendEntry, Swatch, draw_legend};
use super::{
    Area, DrawResult, FIGURE_SIZE, FigureError, LIGHT_LINES, chart_builder, draw_note, label_font,
    padded_range, palette, render, tick_label, titled_with_legend,
};
use crate::core::residuals::{Correlogram, Regime, ResidualAnalysis};

const BAND: RGBColor = RGBColor(150, 150, 150);
const STRETCH: RGBColor = RGBColor(255, 200, 120);
const XCORR: RGBColor = RGBColor(255, 127, 14);

/// Draws the residual analysis of one run; `t_secs` is the run's time axis (one value per residual
/// sample).
pub fn residuals_png(
    path: &Path,
    title: &str,
    t_secs: &[f64],
    a: &ResidualAnalysis,
) -> Result<(), FigureError> {
    super::check_len(path, "residual", a.residual.len(), t_secs.len())?;
    let unit = if a.unit.is_empty() { String::new() } else { format!(" ({})", a.unit) };
    render(path, FIGURE_SIZE, |root| {
        let (chart_area, legend_area) = titled_with_legend(root, title)?;
        let panels = chart_area.split_evenly((2, 2));
        let [trace, regimes, correlation, spectrum] = panels.as_slice() else {
            return Ok(());
        };
        residual_panel(trace, t_secs, a, &unit)?;
        regime_panel(regimes, a, &unit)?;
        correlation_panel(correlation, a)?;
        spectrum_panel(spectrum, a)?;
        let mut entries = vec![
            LegendEntry::text("Residual (top left)"),
            LegendEntry::line("measured − model", palette::series(0), 1),
            LegendEntry::line(format!("±{:.0}σ noise band", a.band.band_sigmas), BAND, 2),
            LegendEntry::new("worst stretches", Swatch::Bar(STRETCH)),
            LegendEntry::text("RMSE by regime,"),
            LegendEntry::line("noise σ for scale", BAND, 2),
            LegendEntry::text("Correlations:"),
            LegendEntry::line("residual ACF", palette::series(0), 2),
        ];
        if a.input_xcorr.is_some() {
            entries.push(LegendEntry::line("residual–input CCF", XCORR, 2));
        }
        entries.push(LegendEntry::line("99 % bounds", BAND, 1));
        entries.push(LegendEntry::text("Spectrum (bottom right)"));
        entries.push(LegendEntry::line("largest peak", palette::FIT, 1));
        draw_legend(&legend_area, &entries)
    })
}

fn residual_panel(area: &Area<'_>, t_secs: &[f64], a: &ResidualAnalysis, unit: &str) -> DrawResult {
    let Some((t_lo, t_hi)) = padded_range(t_secs.iter().copied(), 0.0) else {
        return draw_note(area, "no samples");
    };
    let half = a.band.half_width;
    let values = a.residual.iter().copied().chain([half, -half]);
    let (y_lo, y_hi) = padded_range(values, 0.05).unwrap_or((-1.0, 1.0));
    let mut chart = chart_builder(area).build_cartesian_2d(t_lo..t_hi, y_lo..y_hi)?;
    chart
        .configure_mesh()
        .light_line_style(palette::GRID_LIGHT)
        .bold_line_style(palette::GRID_BOLD)
        .x_max_light_lines(LIGHT_LINES)
        .y_max_light_lines(LIGHT_LINES)
        .x_desc("time (s)")
        .y_desc(format!("residual{unit}"))
        .label_style(label_font())
        .y_label_formatter(&|v| tick_label(*v))
        .x_label_formatter(&|v| tick_label(*v))
        .draw()?;
    chart.draw_series(
        a.worst_stretches
            .iter()
            .map(|s| Rectangle::new([(s.start_secs, y_lo), (s.end_secs, y_hi)], STRETCH.mix(0.5).filled())),
    )?;
    for level in [half, -half] {
        chart.draw_series(LineSeries::new([(t_lo, level), (t_hi, level)], BAND.stroke_width(2)))?;
    }
    let points = t_secs.iter().zip(&a.residual).filter(|(_, r)| r.is_finite()).map(|(t, r)| (*t, *r));
    chart.draw_series(LineSeries::new(points, palette::series(0).stroke_width(1)))?;
    Ok(())
}

fn regime_panel(area: &Area<'_>, a: &ResidualAnalysis, unit: &str) -> DrawResult {
    let rows: Vec<(&'static str, f64)> = Regime::ALL
        .iter()
        .filter_map(|regime| a.regimes.row(*regime).and_then(|r| r.rmse).map(|v| (short_label(*regime), v)))
        .filter(|(_, v)| v.is_finite())
        .collect();
    if rows.is_empty() {
        return draw_note(area, "no regime has samples");
    }
    let peak = rows.iter().map(|(_, v)| *v).fold(a.band.sigma, f64::max).max(f64::MIN_POSITIVE);
    let n = rows.len() as i32;
    let mut chart = chart_builder(area).build_cartesian_2d((0..n - 1).into_segmented(), 0.0..1.15 * peak)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .light_line_style(palette::GRID_LIGHT)
        .bold_line_style(palette::GRID_BOLD)
        .y_max_light_lines(LIGHT_LINES)
        .x_labels(rows.len())
        .x_label_formatter(&|x| match x {
            SegmentValue::CenterOf(i) => {
                usize::try_from(*i).ok().and_then(|i| rows.get(i)).map(|r| r.0.to_owned()).unwrap_or_default()
            }
            _ => String::new(),
        })
        .y_desc(format!("RMSE{unit}"))
        .label_style(label_font())
        .y_label_formatter(&|v| tick_label(*v))
        .draw()?;
    chart.draw_series(rows.iter().zip(0..n).map(|((_, v), i)| {
        let mut bar = Rectangle::new(
            [(SegmentValue::Exact(i), 0.0), (SegmentValue::Exact(i + 1), *v)],
            palette::FILL.filled(),
        );
        bar.set_margin(0, 0, 6, 6);
        bar
    }))?;
    // The noise σ for scale: a model error at the noise level is as good as the sensor allows.
    chart.draw_series(LineSeries::new(
        [(SegmentValue::Exact(0), a.band.sigma), (SegmentValue::Last, a.band.sigma)],
        BAND.stroke_width(2),
    ))?;
    Ok(())
}

/// A regime's label short enough for a bar.
fn short_label(regime: Regime) -> &'static str {
    match regime {
        Regime::Run => "run",
        Regime::Steady => "steady",
        Regime::Transient => "trans.",
        Regime::Accelerating => "accel.",
        Regime::Decelerating => "decel.",
        Regime::Low => "low",
        Regime::Mid => "mid",
        Regime::High => "high",
    }
}

fn correlation_panel(area: &Area<'_>, a: &ResidualAnalysis) -> DrawResult {
    let dt = a.dt_secs;
    let as_secs = |c: &Correlogram| -> Vec<(f64, f64)> {
        c.lags_samples
            .iter()
            .zip(&c.values)
            .map(|(l, v)| (*l as f64 * dt, *v))
            .filter(|p| p.1.is_finite())
            .collect()
    };
    let acf = as_secs(&a.autocorrelation);
    let ccf = a.input_xcorr.as_ref().map(|x| as_secs(&x.correlogram)).unwrap_or_default();
    let Some((x_lo, x_hi)) = padded_range(acf.iter().chain(&ccf).map(|p| p.0), 0.0) else {
        return draw_note(area, "no correlation");
    };
    let bound = a.autocorrelation.bound_99;
    let mut chart = chart_builder(area).build_cartesian_2d(x_lo..x_hi, -1.05..1.05)?;
    chart
        .configure_mesh()
        .light_line_style(palette::GRID_LIGHT)
        .bold_line_style(palette::GRID_BOLD)
        .x_max_light_lines(LIGHT_LINES)
        .x_desc("lag (s)")
        .y_desc("correlation")
        .label_style(label_font())
        .y_label_formatter(&|v| tick_label(*v))
        .x_label_formatter(&|v| tick_label(*v))
        .draw()?;
    for level in [bound, -bound] {
        chart.draw_series(LineSeries::new([(x_lo, level), (x_hi, level)], BAND.stroke_width(1)))?;
    }
    if let Some(x) = &a.input_xcorr {
        let b = x.correlogram.bound_99;
        if (b - bound).abs() > 1e-9 {
            for level in [b, -b] {
                chart.draw_series(LineSeries::new(
                    [(x_lo, level), (x_hi, level)],
                    XCORR.mix(0.5).stroke_width(1),
                ))?;
            }
        }
        chart.draw_series(LineSeries::new(ccf, XCORR.stroke_width(2)))?;
    }
    chart.draw_series(LineSeries::new(acf, palette::series(0).stroke_width(2)))?;
    Ok(())
}

fn spectrum_panel(area: &Area<'_>, a: &ResidualAnalysis) -> DrawResult {
    let s = &a.spectrum;
    let points: Vec<(f64, f64)> = s
        .freq_hz
        .iter()
        .zip(&s.psd_per_hz)
        .filter(|(f, p)| **f > 0.0 && f.is_finite() && **p > 0.0 && p.is_finite())
        .map(|(f, p)| (*f, 10.0 * p.log10()))
        .collect();
    let (Some((f_lo, f_hi)), Some((d_lo, d_hi))) =
        (padded_range(points.iter().map(|p| p.0), 0.0), padded_range(points.iter().map(|p| p.1), 0.05))
    else {
        return draw_note(area, "no spectrum");
    };
    let mut chart = chart_builder(area).build_cartesian_2d((f_lo..f_hi).log_scale(), d_lo..d_hi)?;
    chart
        .configure_mesh()
        .light_line_style(palette::GRID_LIGHT)
        .bold_line_style(palette::GRID_BOLD)
        .x_desc("frequency (Hz)")
        .y_desc("residual PSD (dB)")
        .label_style(label_font())
        .y_label_formatter(&|v| tick_label(*v))
        .x_label_formatter(&|v| tick_label(*v))
        .draw()?;
    chart.draw_series(LineSeries::new(points, palette::series(0).stroke_width(2)))?;
    if s.peak_freq_hz > 0.0 && s.peak_freq_hz.is_finite() && s.peak_freq_hz > f_lo {
        chart.draw_series(LineSeries::new(
            [(s.peak_freq_hz, d_lo), (s.peak_freq_hz, d_hi)],
            palette::FIT.stroke_width(1),
        ))?;
    }
    Ok(())
}
