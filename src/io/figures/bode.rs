//! Bode comparison: model frequency responses against the empirical (chirp) estimate.
use std::path::Path;

use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

use super::legend::{LegendEntry, Swatch, draw_legend};
use super::{
    Area, DrawResult, FigureError, chart_builder, check_len, house_style, padded_range, palette, render_chart,
};
use crate::core::control::bands::BodeBand;
use crate::core::numerics::tf::BodePoint;

/// The fill of a model's uncertainty band: light grey, under every curve.
const BAND_FILL: RGBColor = RGBColor(200, 200, 200);

/// Empirical points with at least this coherence are drawn filled, the others hollow and grey.
pub const GOOD_COHERENCE: f64 = 0.8;
const THIN_PX: u32 = 1;
const THICK_PX: u32 = 3;
/// Dash and gap of a dashed curve, pixels.
const DASH_PX: u32 = 8;
const GAP_PX: u32 = 5;

/// One model's frequency response.
#[derive(Clone, Debug, PartialEq)]
pub struct BodeCurve {
    pub name: String,
    pub points: Vec<BodePoint>,
    /// Drawn thick (the reduced models); the others thin (the segment models).
    pub emphasis: bool,
    /// The curve's own colour (a model's, the same in every figure), drawn at full strength; `None`
    /// takes the next series colour (thin curves, faded) or emphasis colour (thick ones) in turn.
    pub colour: Option<RGBColor>,
    /// Drawn dashed (the linear model and the simple references, as the app's traces draw them): a
    /// dashed curve over a thick one that it follows shows in the thick one's colour between dashes.
    pub dashed: bool,
}

/// The empirical frequency response with its coherence, one value per frequency.
#[derive(Clone, Debug, PartialEq)]
pub struct EmpiricalBode {
    pub omega_rad_s: Vec<f64>,
    pub mag_db: Vec<f64>,
    pub phase_deg: Vec<f64>,
    pub coherence: Vec<f64>,
}

#[derive(Clone, Copy)]
enum Panel {
    Magnitude,
    Phase,
}

impl Panel {
    fn of_point(self, p: &BodePoint) -> f64 {
        match self {
            Panel::Magnitude => p.mag_db,
            Panel::Phase => p.phase_deg,
        }
    }

    fn of_empirical(self, e: &EmpiricalBode) -> &[f64] {
        match self {
            Panel::Magnitude => &e.mag_db,
            Panel::Phase => &e.phase_deg,
        }
    }

    fn desc(self) -> &'static str {
        match self {
            Panel::Magnitude => "magnitude (dB)",
            Panel::Phase => "phase (deg)",
        }
    }
}

type BodeChart<'a, 'b> = ChartContext<'a, BitMapBackend<'b>, Cartesian2d<LogCoord<f64>, RangedCoordf64>>;

/// Draws magnitude (dB) over phase (deg) against a logarithmic ω axis (rad/s).
///
/// Curves with `emphasis` are drawn thick and first, the others thin and over them, so a thin curve
/// that follows a thick one still shows; the empirical estimate as points, filled where its
/// coherence reaches [`GOOD_COHERENCE`].
pub fn bode_png(
    path: &Path,
    title: &str,
    curves: &[BodeCurve],
    empirical: Option<&EmpiricalBode>,
) -> Result<(), FigureError> {
    bode_with_band_png(path, title, curves, empirical, None)
}

/// [`bode_png`] with a 95 % band (of the reduced model, from its parameter uncertainty) shaded
/// under the curves, named in the legend.
pub fn bode_with_band_png(
    path: &Path,
    title: &str,
    curves: &[BodeCurve],
    empirical: Option<&EmpiricalBode>,
    band: Option<&BodeBand>,
) -> Result<(), FigureError> {
    if let Some(b) = band {
        check_len(path, "band magnitude", b.mag_db.len(), b.omega_rad_s.len())?;
        check_len(path, "band phase", b.phase_deg.len(), b.omega_rad_s.len())?;
    }
    if let Some(e) = empirical {
        let n = e.omega_rad_s.len();
        check_len(path, "empirical magnitude", e.mag_db.len(), n)?;
        check_len(path, "empirical phase", e.phase_deg.len(), n)?;
        check_len(path, "empirical coherence", e.coherence.len(), n)?;
    }
    let omegas = curves
        .iter()
        .flat_map(|c| c.points.iter().map(|p| p.omega_rad_s))
        .chain(empirical.iter().flat_map(|e| e.omega_rad_s.iter().copied()))
        .filter(|w| *w > 0.0);
    let omega_range = log_range(omegas);
    render_chart(
        path,
        title,
        omega_range,
        "no frequency response data",
        |chart_area, legend_area, (w_lo, w_hi)| {
            let (_, h) = chart_area.dim_in_pixel();
            let (top, bottom) = chart_area.split_vertically(h / 2);
            draw_panel(&top, Panel::Magnitude, (w_lo, w_hi), curves, empirical, band)?;
            draw_panel(&bottom, Panel::Phase, (w_lo, w_hi), curves, empirical, band)?;
            let mut entries = legend_entries(curves, empirical);
            if band.is_some() {
                entries.push(LegendEntry::new("95 % band (parameters)", Swatch::Bar(BAND_FILL)));
            }
            draw_legend(legend_area, &entries)
        },
    )
}

/// The positive finite range of `omegas`, widened to whole decades when it is a single value.
fn log_range(omegas: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = padded_range(omegas.filter(|w| *w > 0.0).map(f64::log10), 0.0)?;
    Some((10f64.powf(lo), 10f64.powf(hi)))
}

fn in_view(omega: f64, value: f64) -> bool {
    omega > 0.0 && omega.is_finite() && value.is_finite()
}

fn draw_panel(
    area: &Area<'_>,
    panel: Panel,
    (w_lo, w_hi): (f64, f64),
    curves: &[BodeCurve],
    empirical: Option<&EmpiricalBode>,
    band: Option<&BodeBand>,
) -> DrawResult {
    let values = curves
        .iter()
        .flat_map(|c| c.points.iter().filter(|p| p.omega_rad_s > 0.0).map(move |p| panel.of_point(p)))
        .chain(empirical.iter().flat_map(|e| {
            e.omega_rad_s.iter().zip(panel.of_empirical(e)).filter(|(w, _)| **w > 0.0).map(|(_, v)| *v)
        }));
    let (y_lo, y_hi) = padded_range(values, 0.05).unwrap_or((-1.0, 1.0));
    let mut chart = chart_builder(area).build_cartesian_2d((w_lo..w_hi).log_scale(), y_lo..y_hi)?;
    house_style(chart.configure_mesh().x_desc("ω (rad/s)").y_desc(panel.desc())).draw()?;
    if let Some(b) = band {
        let sides = match panel {
            Panel::Magnitude => &b.mag_db,
            Panel::Phase => &b.phase_deg,
        };
        // One quadrilateral per frequency step, clipped to the panel's range.
        let clip = |v: f64| v.clamp(y_lo, y_hi);
        let quads = (1..b.omega_rad_s.len()).filter_map(|k| {
            let (w0, w1) = (b.omega_rad_s[k - 1], b.omega_rad_s[k]);
            let ([l0, h0], [l1, h1]) = (sides[k - 1], sides[k]);
            let finite = [w0, w1, l0, h0, l1, h1].iter().all(|v| v.is_finite()) && w0 > 0.0;
            finite.then(|| {
                Polygon::new(
                    vec![(w0, clip(l0)), (w1, clip(l1)), (w1, clip(h1)), (w0, clip(h0))],
                    BAND_FILL.filled(),
                )
            })
        });
        chart.draw_series(quads)?;
    }
    // Thick curves first: a thin curve drawn under a thick one that it follows would vanish.
    for pass_emphasis in [true, false] {
        for (curve, color) in coloured(curves).filter(|(c, _)| c.emphasis == pass_emphasis) {
            draw_curve(&mut chart, panel, curve, color)?;
        }
    }
    if let Some(e) = empirical {
        draw_empirical(&mut chart, panel, e)?;
    }
    Ok(())
}

/// Each curve with its colour: its own, or else thin curves take the series colours in their order
/// (matching the segment colours of the z-plane), emphasised ones the emphasis colours in theirs.
fn coloured(curves: &[BodeCurve]) -> impl Iterator<Item = (&BodeCurve, RGBColor)> {
    let (mut thin, mut thick) = (0, 0);
    curves.iter().map(move |c| {
        let color = if let Some(colour) = c.colour {
            colour
        } else if c.emphasis {
            thick += 1;
            palette::emphasis(thick - 1)
        } else {
            thin += 1;
            palette::series(thin - 1)
        };
        (c, color)
    })
}

fn draw_curve(chart: &mut BodeChart<'_, '_>, panel: Panel, curve: &BodeCurve, color: RGBColor) -> DrawResult {
    let points: Vec<(f64, f64)> = curve
        .points
        .iter()
        .map(|p| (p.omega_rad_s, panel.of_point(p)))
        .filter(|(w, v)| in_view(*w, *v))
        .collect();
    let style = line_style(curve, color);
    if curve.dashed {
        chart.draw_series(DashedLineSeries::new(points, DASH_PX, GAP_PX, style))?;
    } else {
        chart.draw_series(LineSeries::new(points, style))?;
    }
    Ok(())
}

/// Thick for emphasised curves; thin ones faded in a series colour, or at full strength and a
/// little wider in their own colour (the models of a comparison, few and each to be told apart).
fn line_style(curve: &BodeCurve, color: RGBColor) -> ShapeStyle {
    match (curve.emphasis, curve.colour.is_some()) {
        (true, _) => color.stroke_width(THICK_PX),
        (false, true) => color.stroke_width(THIN_PX + 1),
        (false, false) => color.mix(0.7).stroke_width(THIN_PX),
    }
}

fn draw_empirical(chart: &mut BodeChart<'_, '_>, panel: Panel, e: &EmpiricalBode) -> DrawResult {
    let points = e
        .omega_rad_s
        .iter()
        .zip(panel.of_empirical(e))
        .zip(&e.coherence)
        .filter(|((w, v), _)| in_view(**w, **v))
        .map(|((w, v), c)| ((*w, *v), *c >= GOOD_COHERENCE));
    chart.draw_series(points.map(|(p, good)| {
        if good {
            Circle::new(p, 4, palette::MEASURED.filled())
        } else {
            Circle::new(p, 4, palette::MUTED.stroke_width(1))
        }
    }))?;
    Ok(())
}

fn legend_entries(curves: &[BodeCurve], empirical: Option<&EmpiricalBode>) -> Vec<LegendEntry> {
    let mut entries = Vec::new();
    if empirical.is_some() {
        entries.push(LegendEntry::new(
            format!("empirical, coh. ≥ {GOOD_COHERENCE}"),
            Swatch::Dot(palette::MEASURED),
        ));
        entries.push(LegendEntry::new(
            format!("empirical, coh. < {GOOD_COHERENCE}"),
            Swatch::Ring(palette::MUTED),
        ));
    }
    for pass_emphasis in [true, false] {
        for (curve, color) in coloured(curves).filter(|(c, _)| c.emphasis == pass_emphasis) {
            let width = if curve.emphasis { THICK_PX } else { THIN_PX + 1 };
            entries.push(LegendEntry::new(
                curve.name.clone(),
                Swatch::Line { color, width, dashed: curve.dashed },
            ));
        }
    }
    entries
}
