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
