//! Where a model fails on one run, in four panels: the residual with the noise band and the worst
//! stretches, the error by regime, the residual's autocorrelation and its cross-correlation with the
//! input (99 % bounds), and the residual spectrum.
use std::path::Path;

use plotters::prelude::*;

use super::legend::{LegendEntry, Swatch, draw_legend};
use super::{
    Area, DrawError, DrawResult, FIGURE_SIZE, FigureError, LIGHT_LINES, chart_builder, draw_note, label_font,
    padded_range, palette, render, sig, tick_label, titled_with_legend,
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
        let peak_drawn = spectrum_panel(spectrum, a)?;
        let mut entries = vec![
            LegendEntry::text("Residual (top left)"),
            LegendEntry::line("measured − model", palette::series(0), 1),
        ];
        if a.band.applies() {
            entries.push(LegendEntry::line(format!("±{:.0}σ noise band", a.band.band_sigmas), BAND, 2));
        }
        entries.push(LegendEntry::new("worst stretches", Swatch::Bar(STRETCH)));
        if a.band.applies() {
            entries.push(LegendEntry::text("RMSE by regime,"));
            entries.push(LegendEntry::line("noise σ for scale", BAND, 2));
        } else {
            // The band is not drawn: σ, estimated from the run, does not apply to this residual.
            entries.push(LegendEntry::text("No noise band: σ estimated"));
            entries.push(LegendEntry::text("  from the run does not"));
            entries.push(LegendEntry::text("  apply (see the report)"));
        }
        entries.push(LegendEntry::text("Correlations:"));
        entries.push(LegendEntry::line("residual ACF", palette::series(0), 2));
        if a.input_xcorr.is_some() {
            entries.push(LegendEntry::line("residual–input CCF", XCORR, 2));
        }
        entries.push(LegendEntry::line("99 % bounds", BAND, 1));
        if peak_drawn {
            entries.push(LegendEntry::text("Spectrum (bottom right)"));
            entries.push(LegendEntry::new(
                format!("largest peak {} Hz", sig(a.spectrum.peak_freq_hz, 2)),
                Swatch::Ring(palette::FIT),
            ));
        }
        draw_legend(&legend_area, &entries)
    })
}

fn residual_panel(area: &Area<'_>, t_secs: &[f64], a: &ResidualAnalysis, unit: &str) -> DrawResult {
    let Some((t_lo, t_hi)) = padded_range(t_secs.iter().copied(), 0.0) else {
        return draw_note(area, "no samples");
    };
    let half = a.band.applies().then_some(a.band.half_width);
    let values = a.residual.iter().copied().chain(half.into_iter().flat_map(|h| [h, -h]));
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
    for level in half.into_iter().flat_map(|h| [h, -h]) {
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
    let sigma = a.band.applies().then_some(a.band.sigma);
    let peak = rows.iter().map(|(_, v)| *v).fold(sigma.unwrap_or(0.0), f64::max).max(f64::MIN_POSITIVE);
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
    if let Some(sigma) = sigma {
        chart.draw_series(LineSeries::new(
            [(SegmentValue::Exact(0), sigma), (SegmentValue::Last, sigma)],
            BAND.stroke_width(2),
        ))?;
    }
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

/// The residual PSD in dB re 1 (unit)²/Hz, with its largest peak ringed (and marked by a vertical
/// line); returns whether the peak was drawn.
fn spectrum_panel(area: &Area<'_>, a: &ResidualAnalysis) -> Result<bool, DrawError> {
    let s = &a.spectrum;
    let db = |p: f64| 10.0 * p.log10();
    let points: Vec<(f64, f64)> = s
        .freq_hz
        .iter()
        .zip(&s.psd_per_hz)
        .filter(|(f, p)| **f > 0.0 && f.is_finite() && **p > 0.0 && p.is_finite())
        .map(|(f, p)| (*f, db(*p)))
        .collect();
    let (Some((f_lo, f_hi)), Some((d_lo, d_hi))) =
        (padded_range(points.iter().map(|p| p.0), 0.0), padded_range(points.iter().map(|p| p.1), 0.05))
    else {
        draw_note(area, "no spectrum")?;
        return Ok(false);
    };
    let mut chart = chart_builder(area).build_cartesian_2d((f_lo..f_hi).log_scale(), d_lo..d_hi)?;
    chart
        .configure_mesh()
        .light_line_style(palette::GRID_LIGHT)
        .bold_line_style(palette::GRID_BOLD)
        .x_desc("frequency (Hz)")
        .y_desc(psd_label(&a.unit))
        .label_style(label_font())
        .y_label_formatter(&|v| tick_label(*v))
        .x_label_formatter(&|v| tick_label(*v))
        .draw()?;
    chart.draw_series(LineSeries::new(points.iter().copied(), palette::series(0).stroke_width(2)))?;
    // The peak is a bin of the curve; it may be the lowest drawn, on the panel's left edge, where a
    // vertical line would hide under the axis: the ring shows wherever it is.
    let peak =
        points.iter().find(|(f, _)| (f - s.peak_freq_hz).abs() <= 1e-9 * s.peak_freq_hz.abs().max(1.0));
    let Some(&(f_peak, d_peak)) = peak else { return Ok(false) };
    chart.draw_series(LineSeries::new(
        [(f_peak, d_lo), (f_peak, d_hi)],
        palette::FIT.mix(0.6).stroke_width(1),
    ))?;
    chart.draw_series([Circle::new((f_peak, d_peak), 7, palette::FIT.stroke_width(2))])?;
    Ok(true)
}

/// The PSD axis: what 0 dB is. The Welch estimate is one-sided, in the output's unit² per Hz.
fn psd_label(unit: &str) -> String {
    if unit.is_empty() {
        "residual PSD (dB re 1 /Hz)".to_owned()
    } else {
        format!("residual PSD (dB re 1 {unit}²/Hz)")
    }
}
