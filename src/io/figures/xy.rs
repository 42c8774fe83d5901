//! Line and scatter figures: the static-map fit and the validation traces.
use std::path::Path;

use plotters::prelude::*;

use super::legend::{LegendEntry, Swatch, draw_legend};
use super::{
    Area, DrawResult, FigureError, chart_builder, check_len, draw_note, house_style, padded_range, palette,
    render_chart,
};

/// Share of the traces figure's height given to the traces; the residual panel gets the rest.
const TRACE_SHARE: f64 = 0.62;
/// Line widths: measured data and residuals (noisy) thin, model traces thicker.
const MEASURED_PX: u32 = 1;
const MODEL_PX: u32 = 2;

/// Draws the steady-state points and the fitted static map.
pub fn static_map_png(
    path: &Path,
    title: &str,
    points: &[(f64, f64)],
    curve: &[(f64, f64)],
    x_label: &str,
    y_label: &str,
) -> Result<(), FigureError> {
    let finite = |(x, y): &(f64, f64)| x.is_finite() && y.is_finite();
    let points: Vec<(f64, f64)> = points.iter().copied().filter(finite).collect();
    let mut curve: Vec<(f64, f64)> = curve.iter().copied().filter(finite).collect();
    curve.sort_by(|a, b| a.0.total_cmp(&b.0));
    let all = || points.iter().chain(&curve);
    let ranges = padded_range(all().map(|p| p.0), 0.04).zip(padded_range(all().map(|p| p.1), 0.06));
    render_chart(
        path,
        title,
        ranges,
        "no steady-state data",
        |chart_area, legend_area, ((x_lo, x_hi), (y_lo, y_hi))| {
            let mut chart = chart_builder(chart_area).build_cartesian_2d(x_lo..x_hi, y_lo..y_hi)?;
            house_style(chart.configure_mesh().x_desc(x_label).y_desc(y_label)).draw()?;
            chart.draw_series(points.iter().map(|p| Circle::new(*p, 5, palette::MEASURED.filled())))?;
            chart.draw_series(LineSeries::new(curve.iter().copied(), palette::FIT.stroke_width(3)))?;
            let entries = [
                LegendEntry::new(
                    format!("steady state (n = {})", points.len()),
                    Swatch::Dot(palette::MEASURED),
                ),
                LegendEntry::line("fitted static map", palette::FIT, 3),
            ];
            draw_legend(legend_area, &entries)
        },
    )
}

/// Draws the measured trace with the model traces over it and, below, the residual of the first
/// model (measured − model). The first model is the one the figure is about: it is drawn last, on
/// top of the others. Every trace must have one value per entry of `t_secs`.
pub fn traces_png(
    path: &Path,
    title: &str,
    t_secs: &[f64],
    measured: &[f64],
    models: &[(String, Vec<f64>)],
    y_label: &str,
) -> Result<(), FigureError> {
    traces_with_band_png(path, title, t_secs, measured, models, None, y_label)
}

/// A band as the two slices it is drawn between; none when it is empty.
fn as_band((lo, hi): &(Vec<f64>, Vec<f64>)) -> Option<(&[f64], &[f64])> {
    (!lo.is_empty()).then_some((lo.as_slice(), hi.as_slice()))
}

/// A band's fill: the first model's colour washed out towards white, so the lines stay readable
/// over it.
fn band_colour() -> RGBColor {
    let c = palette::series(0);
    let wash = |v: u8| (f64::from(v) + 0.72 * (255.0 - f64::from(v))).round() as u8;
    RGBColor(wash(c.0), wash(c.1), wash(c.2))
}

/// [`traces_png`] with the 95 % band of the first model's noiseless output from its parameter
/// uncertainty (`band`: the half-width at each sample), shaded around its trace and, in the
/// residual panel, around zero with its edges drawn over the residual: a residual beyond them is a
/// miss the parameters' uncertainty does not explain (noise, or something the model lacks).
pub fn traces_with_band_png(
    path: &Path,
    title: &str,
    t_secs: &[f64],
    measured: &[f64],
    models: &[(String, Vec<f64>)],
    band: Option<&[f64]>,
    y_label: &str,
) -> Result<(), FigureError> {
    check_len(path, "measured trace", measured.len(), t_secs.len())?;
    for (name, y) in models {
        check_len(path, &format!("model trace `{name}`"), y.len(), t_secs.len())?;
    }
    if let Some(half) = band {
        check_len(path, "uncertainty band", half.len(), t_secs.len())?;
    }
    let residual: Option<(&str, Vec<f64>)> =
        models.first().map(|(name, y)| (name.as_str(), measured.iter().zip(y).map(|(m, y)| m - y).collect()));
    let around = |centre: &[f64], sign: f64| -> Vec<f64> {
        band.map_or_else(Vec::new, |half| centre.iter().zip(half).map(|(c, h)| c + sign * h).collect())
    };
    let first = models.first().map_or(&[][..], |(_, y)| y.as_slice());
    let zeros = vec![0.0; t_secs.len()];
    let (trace_band, residual_band) =
        ((around(first, -1.0), around(first, 1.0)), (around(&zeros, -1.0), around(&zeros, 1.0)));
    let t_range = padded_range(t_secs.iter().copied(), 0.0);
    render_chart(path, title, t_range, "no samples", |chart_area, legend_area, t_range| {
        let (_, h) = chart_area.dim_in_pixel();
        let (top, bottom) = chart_area.split_vertically((TRACE_SHARE * h as f64) as u32);
        let mut series: Vec<(&[f64], RGBColor, u32)> = vec![(measured, palette::MEASURED, MEASURED_PX)];
        series.extend(
            models.iter().enumerate().rev().map(|(i, (_, y))| (y.as_slice(), palette::series(i), MODEL_PX)),
        );
        draw_lines(&top, t_secs, t_range, &series, as_band(&trace_band), false, y_label)?;
        let mut entries = vec![LegendEntry::line("measured", palette::MEASURED, MEASURED_PX + 1)];
        entries.extend(
            models
                .iter()
                .enumerate()
                .map(|(i, (n, _))| LegendEntry::line(n.clone(), palette::series(i), MODEL_PX)),
        );
        if band.is_some() {
            entries.push(LegendEntry::new("95 % band (parameters)", Swatch::Bar(band_colour())));
        }
        match &residual {
            Some((name, r)) => {
                draw_lines(
                    &bottom,
                    t_secs,
                    t_range,
                    &[(r, palette::series(0), MEASURED_PX)],
                    as_band(&residual_band),
                    true,
                    &format!("residual {}", unit_of(y_label)),
                )?;
                entries.push(LegendEntry::text("lower panel: residual"));
                entries.push(LegendEntry::line(
                    format!("measured − {name}"),
                    palette::series(0),
                    MEASURED_PX + 1,
                ));
                if band.is_some() {
                    entries.push(LegendEntry::line("± 95 % band (parameters)", palette::FIT, 1));
                }
            }
            None => draw_note(&bottom, "no model trace: no residual")?,
        }
        draw_legend(legend_area, &entries)
    })
}

/// The "(unit)" at the end of an axis label, or "" when there is none.
fn unit_of(label: &str) -> &str {
    match label.rfind('(') {
        Some(i) if label.ends_with(')') => label.get(i..).unwrap_or(""),
        _ => "",
    }
}

/// One panel of traces against time.
fn draw_lines(
    area: &Area<'_>,
    t_secs: &[f64],
    (t_lo, t_hi): (f64, f64),
    series: &[(&[f64], RGBColor, u32)],
    band: Option<(&[f64], &[f64])>,
    edges: bool,
    y_desc: &str,
) -> DrawResult {
    let band_values = band.into_iter().flat_map(|(lo, hi)| lo.iter().chain(hi.iter()).copied());
    let values = series.iter().flat_map(|(y, _, _)| y.iter().copied()).chain(band_values);
    let (y_lo, y_hi) = padded_range(values, 0.05).unwrap_or((-1.0, 1.0));
    let mut chart = chart_builder(area).build_cartesian_2d(t_lo..t_hi, y_lo..y_hi)?;
    house_style(chart.configure_mesh().x_desc("time (s)").y_desc(y_desc)).draw()?;
    if let Some((lo, hi)) = band {
        // One quadrilateral per sample step: a single polygon would join the band across a gap.
        let finite = |k: usize| [t_secs[k], lo[k], hi[k]].iter().all(|v| v.is_finite());
        let quads =
            (1..t_secs.len().min(lo.len()).min(hi.len())).filter(|&k| finite(k - 1) && finite(k)).map(|k| {
                let (a, b) = (t_secs[k - 1], t_secs[k]);
                Polygon::new(
                    vec![(a, lo[k - 1]), (b, lo[k]), (b, hi[k]), (a, hi[k - 1])],
                    band_colour().filled(),
                )
            });
        chart.draw_series(quads)?;
    }
    for (y, color, width) in series {
        let points: Vec<(f64, f64)> = t_secs.iter().zip(y.iter()).map(|(t, y)| (*t, *y)).collect();
        // Separate two-point paths: plotters joins a wide polyline with mitres, which spike at
        // the sharp turns of a noisy trace. A non-finite value leaves a gap.
        let pieces = points.windows(2).filter_map(|w| match w {
            [a, b] if [a.0, a.1, b.0, b.1].iter().all(|v| v.is_finite()) => Some(vec![*a, *b]),
            _ => None,
        });
        chart.draw_series(pieces.map(|piece| PathElement::new(piece, color.stroke_width(*width))))?;
    }
    if let (Some((lo, hi)), true) = (band, edges) {
        for edge in [lo, hi] {
            let points = t_secs.iter().zip(edge).filter(|(t, y)| t.is_finite() && y.is_finite());
            chart
                .draw_series(LineSeries::new(points.map(|(t, y)| (*t, *y)), palette::FIT.stroke_width(1)))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// Pixels of exactly `colour` left of the legend panel.
    fn pixels_of(image: &image::RgbImage, colour: RGBColor) -> usize {
        let chart_width = image.width() - super::super::LEGEND_WIDTH;
        image
            .enumerate_pixels()
            .filter(|(x, _, p)| *x < chart_width && p.0 == [colour.0, colour.1, colour.2])
            .count()
    }

    #[test]
    fn the_first_model_is_drawn_on_top_of_the_others() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("traces.png");
        let t: Vec<f64> = (0..200).map(f64::from).collect();
        let measured = vec![0.0; t.len()];
        // Two models with the same trace: only the one on top shows.
        let models =
            vec![("gray-box".to_owned(), vec![1.0; t.len()]), ("other".to_owned(), vec![1.0; t.len()])];
        traces_png(&path, "order", &t, &measured, &models, "y (N)").unwrap();
        let image = image::open(&path).unwrap().to_rgb8();
        assert!(pixels_of(&image, palette::series(0)) > 100, "the first model's line is visible");
        assert_eq!(pixels_of(&image, palette::series(1)), 0, "the other model is under it");
    }
}
