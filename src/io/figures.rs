//! PNG figures for the batch report: z-plane clusters, Bode comparison, static-map fit, validation
//! traces, histograms and box plots.
//!
//! Every function takes plain data and writes one PNG file. The file is written atomically: the
//! image is encoded in memory, written to a temporary file in the target directory and renamed
//! over the target, so a failed run never leaves a half-written picture behind.
//!
//! Drawing uses `plotters` with its pure-Rust bitmap backend and the embedded DejaVu Sans font
//! (`assets/fonts/`), so no system font library is needed. Empty data gives a chart with a
//! "no data" note rather than an error; inconsistent data (series of different lengths, zero
//! bins) gives a [`FigureError`]. Non-finite values are skipped.

mod bode;
mod legend;
pub mod palette;
mod residuals;
mod stats;
mod trend;
mod xy;
mod zplane;

use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, Ordering};

use plotters::coord::Shift;
use plotters::drawing::DrawingAreaErrorKind;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

pub use bode::{BodeCurve, EmpiricalBode, bode_png, bode_with_band_png};
pub use residuals::residuals_png;
pub use stats::{boxplot_png, histogram_png};
pub use trend::{TrendPanel, TrendPoint, trend_png};
pub use xy::{static_map_png, traces_png, traces_with_band_png};
pub use zplane::{ModelRoots, ZPLANE_SIZE, zplane_png, zplane_with_regions_png};

/// DejaVu Sans (Bitstream Vera licence, see `assets/fonts/DejaVuSans-LICENSE.txt`).
static FONT_TTF: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
/// The family name the font is registered under; plotters' default text styles use it.
const FONT_FAMILY: &str = "sans-serif";

/// Standard figure size in pixels.
pub const FIGURE_SIZE: (u32, u32) = (1200, 800);
/// Width of the legend panel at the right of every figure, in pixels.
const LEGEND_WIDTH: u32 = 250;
const TITLE_FONT_PX: f64 = 28.0;
const DESC_FONT_PX: f64 = 20.0;
const LABEL_FONT_PX: f64 = 16.0;
/// Space around each chart and the sizes of its axis label areas, in pixels.
const CHART_MARGIN: u32 = 15;
const X_LABEL_AREA: u32 = 50;
const Y_LABEL_AREA: u32 = 80;
/// Space above the title, in pixels.
const TITLE_TOP: u32 = 10;
/// Minor grid lines between two major ones.
const LIGHT_LINES: usize = 4;
/// Tick values closer to zero than this are rounding noise (a tick at 0 computed as −2e−16).
const ZERO_TICK: f64 = 1e-12;

#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    #[error("figure {}: cannot write the file: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    #[error("figure {}: cannot encode the PNG: {source}", path.display())]
    Encode { path: PathBuf, source: image::ImageError },
    #[error("figure {}: drawing failed: {message}", path.display())]
    Draw { path: PathBuf, message: String },
    #[error("figure {}: the path has no file name", path.display())]
    NoFileName { path: PathBuf },
    #[error("figure {}: {what} has {found} values, expected {expected}", path.display())]
    LengthMismatch { path: PathBuf, what: String, found: usize, expected: usize },
    #[error("figure {}: parameter `{name}` = {value} is out of range ({expected})", path.display())]
    InvalidParameter { path: PathBuf, name: &'static str, value: f64, expected: &'static str },
    #[error("the embedded figure font could not be loaded")]
    Font,
}

/// A drawing failure inside plotters, before the path is attached.
#[derive(Debug)]
pub(crate) struct DrawError(String);

impl<E: std::error::Error + Send + Sync> From<DrawingAreaErrorKind<E>> for DrawError {
    fn from(e: DrawingAreaErrorKind<E>) -> Self {
        Self(e.to_string())
    }
}

pub(crate) type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;
pub(crate) type DrawResult = Result<(), DrawError>;

fn ensure_font() -> Result<(), FigureError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED
        .get_or_init(|| plotters::style::register_font(FONT_FAMILY, FontStyle::Normal, FONT_TTF).is_ok());
    if ok { Ok(()) } else { Err(FigureError::Font) }
}

/// Draws a `size` picture with `draw` and writes it to `path` as PNG, atomically.
pub(crate) fn render(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(&Area<'_>) -> DrawResult,
) -> Result<(), FigureError> {
    ensure_font()?;
    let (w, h) = size;
    let mut pixels = vec![255u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, size).into_drawing_area();
        let drawn = root
            .fill(&palette::BACKGROUND)
            .map_err(DrawError::from)
            .and_then(|()| draw(&root))
            .and_then(|()| root.present().map_err(DrawError::from));
        drawn.map_err(|DrawError(message)| FigureError::Draw { path: path.to_path_buf(), message })?;
    }
    let mut png = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut png),
        &pixels,
        w,
        h,
        image::ExtendedColorType::Rgb8,
    )
    .map_err(|source| FigureError::Encode { path: path.to_path_buf(), source })?;
    write_atomically(path, &png)
}

/// Writes `bytes` to a temporary file beside `path`, then renames it over `path`.
fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), FigureError> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let Some(file_name) = path.file_name() else {
        return Err(FigureError::NoFileName { path: path.to_path_buf() });
    };
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let tmp = dir.join(format!(".{}.{}-{n}.tmp", file_name.to_string_lossy(), std::process::id()));
    let io_err = |source| FigureError::Io { path: path.to_path_buf(), source };
    std::fs::write(&tmp, bytes).and_then(|()| std::fs::rename(&tmp, path)).map_err(|source| {
        // Best effort: the write or rename error is the one worth reporting.
        let _ = std::fs::remove_file(&tmp);
        io_err(source)
    })
}

pub(crate) fn font(size_px: f64) -> TextStyle<'static> {
    TextStyle::from((FONT_FAMILY, size_px).into_font()).color(&palette::TEXT)
}

pub(crate) fn title_font() -> TextStyle<'static> {
    font(TITLE_FONT_PX)
}

pub(crate) fn desc_font() -> TextStyle<'static> {
    font(DESC_FONT_PX)
}

pub(crate) fn label_font() -> TextStyle<'static> {
    font(LABEL_FONT_PX)
}

/// Draws the title and splits the rest into the chart area (left) and the legend panel (right).
pub(crate) fn titled_with_legend<'a>(
    root: &Area<'a>,
    title: &str,
) -> Result<(Area<'a>, Area<'a>), DrawError> {
    let body = root.margin(TITLE_TOP, 0, 0, 0).titled(title, title_font())?;
    let (w, _) = body.dim_in_pixel();
    Ok(body.split_horizontally(w.saturating_sub(LEGEND_WIDTH)))
}

/// Draws a standard figure to `path`: the title, then `draw` on the chart area and the legend panel
/// at its right with the data's `range`; without a range (nothing to draw), a `no_data` note in the
/// chart area instead.
pub(crate) fn render_chart<R>(
    path: &Path,
    title: &str,
    range: Option<R>,
    no_data: &str,
    draw: impl FnOnce(&Area<'_>, &Area<'_>, R) -> DrawResult,
) -> Result<(), FigureError> {
    render(path, FIGURE_SIZE, |root| {
        let (chart_area, legend_area) = titled_with_legend(root, title)?;
        match range {
            Some(range) => draw(&chart_area, &legend_area, range),
            None => draw_note(&chart_area, no_data),
        }
    })
}

/// A chart builder with the standard margin and label-area sizes.
pub(crate) fn chart_builder<'a, 'b>(area: &'a Area<'b>) -> ChartBuilder<'a, 'b, BitMapBackend<'b>> {
    let mut builder = ChartBuilder::on(area);
    builder.margin(CHART_MARGIN).x_label_area_size(X_LABEL_AREA).y_label_area_size(Y_LABEL_AREA);
    builder
}

/// Writes `text` in the middle of `area` (used for "no data").
pub(crate) fn draw_note(area: &Area<'_>, text: &str) -> DrawResult {
    let (w, h) = area.dim_in_pixel();
    let style = desc_font().color(&palette::NOTE).pos(Pos::new(HPos::Center, VPos::Center));
    area.draw(&Text::new(text.to_owned(), (w as i32 / 2, h as i32 / 2), style))?;
    Ok(())
}

/// The range of the finite values, padded by `pad` of its width; a single value or a zero-width
/// range is widened so the axis is still drawable. `None` when no value is finite or the padded
/// range overflows.
pub(crate) fn padded_range(values: impl IntoIterator<Item = f64>, pad: f64) -> Option<(f64, f64)> {
    let (lo, hi) =
        values.into_iter().filter(|v| v.is_finite()).fold(None, |acc: Option<(f64, f64)>, v| match acc {
            None => Some((v, v)),
            Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
        })?;
    let width = hi - lo;
    if width <= f64::EPSILON * (lo.abs() + hi.abs()) {
        let half = if lo.abs() > 0.0 { 0.1 * lo.abs() } else { 1.0 };
        return Some((lo - half, hi + half));
    }
    let (lo, hi) = (lo - pad * width, hi + pad * width);
    // Values near ±f64::MAX overflow the padding; such an axis cannot be drawn.
    (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
}

/// A number for an axis tick: few digits, no trailing zeros; rounding noise around zero is zero.
/// The house style of every chart's axes: tick labels, fonts and the grid. Axis descriptions and
/// label counts stay with each chart.
pub(crate) fn house_style<'m, 'a, 'b, X, Y, DB>(
    mesh: &'m mut plotters::chart::MeshStyle<'a, 'b, X, Y, DB>,
) -> &'m mut plotters::chart::MeshStyle<'a, 'b, X, Y, DB>
where
    X: plotters::coord::ranged1d::Ranged<ValueType = f64> + plotters::coord::ranged1d::ValueFormatter<f64>,
    Y: plotters::coord::ranged1d::Ranged<ValueType = f64> + plotters::coord::ranged1d::ValueFormatter<f64>,
    DB: DrawingBackend,
{
    mesh.x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .label_style(label_font())
        .axis_desc_style(desc_font())
        .bold_line_style(palette::GRID_BOLD)
        .light_line_style(palette::GRID_LIGHT)
        .max_light_lines(LIGHT_LINES)
}

fn tick(v: &f64) -> String {
    tick_label(*v)
}

pub(crate) fn tick_label(v: f64) -> String {
    let a = v.abs();
    if a < ZERO_TICK {
        return "0".to_owned();
    }
    if !(1e-3..1e6).contains(&a) {
        return format!("{v:.1e}");
    }
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".to_owned() } else { s.to_owned() }
}

/// An axis label with its unit as the figures write it, "thrust_n (N)" like "time (s)"; the name
/// alone when the unit is unknown or is the name ("rpm", not "rpm (rpm)").
pub fn with_unit(name: &str, unit: &str) -> String {
    if crate::core::run::name_is_unit(name, unit) { name.to_owned() } else { format!("{name} ({unit})") }
}

/// `v` with `digits` significant digits, for numbers quoted in legends.
pub(crate) fn sig(v: f64, digits: usize) -> String {
    let a = v.abs();
    if a < ZERO_TICK || !v.is_finite() {
        return tick_label(v);
    }
    if !(1e-3..1e6).contains(&a) {
        return format!("{v:.*e}", digits.saturating_sub(1));
    }
    let magnitude = a.log10().floor() as i64;
    let decimals = (digits as i64 - 1 - magnitude).max(0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_owned() } else { s }
}

/// Fails unless `found == expected`.
pub(crate) fn check_len(path: &Path, what: &str, found: usize, expected: usize) -> Result<(), FigureError> {
    if found == expected {
        Ok(())
    } else {
        Err(FigureError::LengthMismatch { path: path.to_path_buf(), what: what.to_owned(), found, expected })
    }
}
