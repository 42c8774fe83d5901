//! Every colour the app draws with lives here, so that views stay consistent and a later theme
//! change is one edit.
use egui::Color32;

/// The input channel (fuel flow).
pub const INPUT: Color32 = Color32::from_rgb(230, 140, 40);

/// Output channels, in order; the palette repeats if a run has more outputs.
pub const OUTPUTS: [Color32; 3] =
    [Color32::from_rgb(70, 150, 230), Color32::from_rgb(90, 190, 110), Color32::from_rgb(200, 110, 200)];

/// Auxiliary channels (ambient conditions, EGT, …).
pub const AUX: [Color32; 4] = [
    Color32::from_rgb(160, 160, 170),
    Color32::from_rgb(190, 170, 110),
    Color32::from_rgb(120, 180, 180),
    Color32::from_rgb(180, 130, 130),
];

/// Error text (load failures).
pub const ERROR: Color32 = Color32::from_rgb(235, 90, 80);

/// Hints and secondary text.
pub const HINT: Color32 = Color32::from_rgb(150, 150, 150);

/// The colour of output number `index`.
pub fn output_colour(index: usize) -> Color32 {
    OUTPUTS[index % OUTPUTS.len()]
}

/// The colour of auxiliary channel number `index`.
pub fn aux_colour(index: usize) -> Color32 {
    AUX[index % AUX.len()]
}

/// Successful or valid things (valid clusters, "valid" in tables).
pub const OK: Color32 = Color32::from_rgb(90, 200, 120);

/// Warnings that are not errors (a preview without root polishing, stale inputs).
pub const WARNING: Color32 = Color32::from_rgb(230, 180, 60);

/// One colour per identification segment (A, B, …); the palette repeats after eight.
pub const SEGMENTS: [Color32; 8] = [
    Color32::from_rgb(90, 160, 240),
    Color32::from_rgb(240, 130, 60),
    Color32::from_rgb(110, 200, 110),
    Color32::from_rgb(220, 90, 150),
    Color32::from_rgb(170, 130, 230),
    Color32::from_rgb(60, 200, 200),
    Color32::from_rgb(230, 210, 80),
    Color32::from_rgb(200, 150, 110),
];

/// The colour of identification segment number `index`.
pub fn segment_colour(index: usize) -> Color32 {
    SEGMENTS[index % SEGMENTS.len()]
}

/// The shading of segment `index` behind the run traces (alternating, faint).
pub fn segment_fill(index: usize) -> Color32 {
    segment_colour(index).gamma_multiply(0.14)
}

/// A segment boundary that can be dragged, and the step inside a segment.
pub const SEGMENT_EDGE: Color32 = Color32::from_rgb(225, 205, 120);
pub const SEGMENT_EDGE_ACTIVE: Color32 = Color32::from_rgb(255, 240, 170);
pub const SEGMENT_STEP: Color32 = Color32::from_rgb(130, 130, 130);

/// Cluster circles on the z-plane.
pub const CLUSTER_VALID: Color32 = Color32::from_rgb(90, 220, 120);
pub const CLUSTER_INVALID: Color32 = Color32::from_rgb(240, 80, 70);
/// The handles (centre, rim) of the selected cluster.
pub const HANDLE: Color32 = Color32::from_rgb(255, 255, 255);

/// The unit circle and the z-plane grid (angle rays, modulus circles).
pub const UNIT_CIRCLE: Color32 = Color32::from_rgb(210, 210, 210);
pub const ZGRID: Color32 = Color32::from_rgb(90, 90, 90);
/// The angle above which clusters are excluded (near the Nyquist angle).
pub const EXCLUSION: Color32 = Color32::from_rgb(200, 120, 60);
/// The rectangle of the detail view drawn on the overview.
pub const VIEWPORT: Color32 = Color32::from_rgb(240, 200, 60);

/// The reduced (gray-box) model: its poles and zeros, its Bode curve, its simulated output.
pub const REDUCED: Color32 = Color32::from_rgb(255, 255, 255);
/// The gray-box model's simulated output over a measurement.
pub const MODEL: Color32 = Color32::from_rgb(240, 90, 80);
/// The linear block alone (the "linear" baseline model).
pub const LINEAR: Color32 = Color32::from_rgb(180, 180, 90);
/// The black-box baselines of the Compare view.
pub const HAMMERSTEIN_WIENER: Color32 = Color32::from_rgb(170, 130, 230);
pub const NNARX: Color32 = Color32::from_rgb(90, 200, 190);
/// The simple references: greys and muted tones, drawn thin and dashed under the models.
pub const ARX: Color32 = Color32::from_rgb(150, 150, 150);
pub const HAMMERSTEIN_ARX: Color32 = Color32::from_rgb(205, 140, 95);
pub const STATIC_CUBIC: Color32 = Color32::from_rgb(120, 160, 120);
/// Measurements drawn under a model.
pub const MEASURED: Color32 = Color32::from_rgb(70, 150, 230);
/// Static-map steady-state points and the chirp's empirical frequency response.
pub const STEADY_POINT: Color32 = Color32::from_rgb(240, 180, 60);
pub const EMPIRICAL: Color32 = Color32::from_rgb(240, 180, 60);

/// The gray-box model without its effects, drawn beside the model with them.
pub const WITHOUT_EFFECTS: Color32 = Color32::from_rgb(200, 150, 230);

/// A colour along a blue (0) to red (1) ramp: operating points from the bottom to the top of the
/// range.
pub fn ramp(t: f32) -> Color32 {
    let t = t.clamp(0.0, 1.0);
    let mix = |a: u8, b: u8| (a as f32 + (b as f32 - a as f32) * t).round() as u8;
    Color32::from_rgb(mix(70, 240), mix(150, 90), mix(230, 80))
}
