//! The legend panel drawn at the right of a figure.
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{Area, DrawResult, label_font};

const ROW_PX: i32 = 26;
const TOP_PX: i32 = 30;
/// Left edge of the swatches; leaves room for chart text that spills past the plotting area.
const LEFT_PX: i32 = 20;
const SWATCH_PX: i32 = 30;
const MAX_LABEL_CHARS: usize = 24;
/// A remark has no swatch, so its text starts at the swatch's left edge and may run longer.
const MAX_REMARK_CHARS: usize = 28;

/// How an entry's sample is drawn.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Swatch {
    Line {
        color: RGBColor,
        width: u32,
        dashed: bool,
    },
    Cross(RGBColor),
    Ring(RGBColor),
    Dot(RGBColor),
    Bar(RGBColor),
    /// Text only (a heading or a remark).
    None,
}

#[derive(Clone, Debug)]
pub(crate) struct LegendEntry {
    pub label: String,
    pub swatch: Swatch,
}

impl LegendEntry {
    pub fn new(label: impl Into<String>, swatch: Swatch) -> Self {
        Self { label: label.into(), swatch }
    }

    pub fn line(label: impl Into<String>, color: RGBColor, width: u32) -> Self {
        Self::new(label, Swatch::Line { color, width, dashed: false })
    }

    pub fn text(label: impl Into<String>) -> Self {
        Self::new(label, Swatch::None)
    }
}

/// Draws the entries top-down; when they do not fit, the last row says how many were left out.
pub(crate) fn draw_legend(area: &Area<'_>, entries: &[LegendEntry]) -> DrawResult {
    let (_, h) = area.dim_in_pixel();
    let rows = ((h as i32 - TOP_PX) / ROW_PX).max(1) as usize;
    let shown = if entries.len() > rows { rows - 1 } else { entries.len() };
    for (row, entry) in entries.iter().take(shown).enumerate() {
        draw_entry(area, row, entry)?;
    }
    if shown < entries.len() {
        let more = LegendEntry::text(format!("… and {} more", entries.len() - shown));
        draw_entry(area, shown, &more)?;
    }
    Ok(())
}

fn draw_entry(area: &Area<'_>, row: usize, entry: &LegendEntry) -> DrawResult {
    let y = TOP_PX + ROW_PX * row as i32;
    let (x0, x1) = (LEFT_PX, LEFT_PX + SWATCH_PX);
    let xm = (x0 + x1) / 2;
    match entry.swatch {
        Swatch::Line { color, width, dashed: false } => {
            area.draw(&PathElement::new(vec![(x0, y), (x1, y)], color.stroke_width(width)))?;
        }
        Swatch::Line { color, width, dashed: true } => {
            for (a, b) in [(x0, x0 + 8), (x0 + 12, x0 + 20), (x0 + 24, x1)] {
                area.draw(&PathElement::new(vec![(a, y), (b, y)], color.stroke_width(width)))?;
            }
        }
        Swatch::Cross(color) => area.draw(&Cross::new((xm, y), 6, color.stroke_width(2)))?,
        Swatch::Ring(color) => area.draw(&Circle::new((xm, y), 6, color.stroke_width(2)))?,
        Swatch::Dot(color) => area.draw(&Circle::new((xm, y), 5, color.filled()))?,
        Swatch::Bar(color) => {
            area.draw(&Rectangle::new([(x0, y - 7), (x1, y + 7)], color.mix(0.6).filled()))?;
        }
        Swatch::None => {}
    }
    let text_x = match entry.swatch {
        Swatch::None => x0,
        _ => x1 + 10,
    };
    let style = label_font().pos(Pos::new(HPos::Left, VPos::Center));
    area.draw(&Text::new(shorten(entry), (text_x, y), style))?;
    Ok(())
}

impl LegendEntry {
    /// The most characters the label can show in the panel.
    fn max_chars(&self) -> usize {
        match self.swatch {
            Swatch::None => MAX_REMARK_CHARS,
            _ => MAX_LABEL_CHARS,
        }
    }

    /// Whether the label is shown whole (a longer one is cut).
    pub fn fits(&self) -> bool {
        self.label.chars().count() <= self.max_chars()
    }
}

/// Cuts a label that does not fit the panel, marking the cut.
fn shorten(entry: &LegendEntry) -> String {
    if entry.fits() {
        return entry.label.clone();
    }
    let mut s: String = entry.label.chars().take(entry.max_chars() - 1).collect();
    s.push('…');
    s
}
