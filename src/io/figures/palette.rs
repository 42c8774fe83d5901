//! Every colour the figures use.
use plotters::style::RGBColor;

use crate::core::compare::ModelKind;

pub const BACKGROUND: RGBColor = RGBColor(255, 255, 255);
pub const TEXT: RGBColor = RGBColor(30, 30, 30);
pub const NOTE: RGBColor = RGBColor(120, 120, 120);
/// Major and minor grid lines.
pub const GRID_BOLD: RGBColor = RGBColor(210, 210, 210);
pub const GRID_LIGHT: RGBColor = RGBColor(238, 238, 238);
/// Axes, the unit circle and other reference lines drawn over the grid.
pub const REFERENCE: RGBColor = RGBColor(90, 90, 90);
/// The z-plane angle rays.
pub const RAY: RGBColor = RGBColor(190, 190, 190);
/// Measured data: traces, steady-state points, empirical Bode points.
pub const MEASURED: RGBColor = RGBColor(20, 20, 20);
/// Data the figure plays down: invalid clusters, low-coherence points.
pub const MUTED: RGBColor = RGBColor(160, 160, 160);
/// Valid clusters.
pub const VALID_CLUSTER: RGBColor = RGBColor(0, 0, 0);
/// A fitted curve drawn over measured points (static map, normal fit).
pub const FIT: RGBColor = RGBColor(214, 39, 40);
/// Bars and boxes.
pub const FILL: RGBColor = RGBColor(31, 119, 180);
/// Series colours (segments, models), used in turn (Tableau 10).
pub const SERIES: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// The reduced model over the segment models' Bode curves: black, apart from every series colour
/// the segments take (as the app draws it in white on its dark plots).
pub const REDUCED: RGBColor = RGBColor(0, 0, 0);

/// Colours of emphasised curves (the reduced models over the thin segment curves), used in turn.
pub const EMPHASIS: [RGBColor; 5] = [
    RGBColor(200, 0, 0),
    RGBColor(0, 60, 190),
    RGBColor(0, 130, 60),
    RGBColor(140, 0, 160),
    RGBColor(210, 110, 0),
];

/// The `i`-th emphasis colour, cycling.
pub fn emphasis(i: usize) -> RGBColor {
    EMPHASIS[i % EMPHASIS.len()]
}

/// The `i`-th series colour, cycling.
pub fn series(i: usize) -> RGBColor {
    SERIES[i % SERIES.len()]
}

/// Each model's colour in the figures that compare models: the gray-box in the first emphasis
/// colour (it is drawn thick), every other model in a hue clearly apart from it and from each other
/// (no second red: the linear model, whose curve often follows the gray-box's, is blue).
pub fn model(kind: ModelKind) -> RGBColor {
    match kind {
        ModelKind::GrayBox => EMPHASIS[0],
        ModelKind::Linear => RGBColor(31, 119, 180),
        ModelKind::HammersteinWiener => RGBColor(148, 103, 189),
        ModelKind::Nnarx => RGBColor(0, 150, 160),
        ModelKind::Arx => RGBColor(127, 127, 127),
        ModelKind::HammersteinArx => RGBColor(140, 86, 75),
        ModelKind::StaticCubic => RGBColor(44, 160, 44),
    }
}
