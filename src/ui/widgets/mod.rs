//! Pieces every view may use: the model summary and output bar (`model`), plot helpers (`plot`),
//! the segment overlay (`segments`), and the grey hint line.
use egui::RichText;

use crate::ui::theme;

pub mod model;
pub mod plot;
pub mod segments;

/// `value` with the decimals that matter next to a measurement noise of standard deviation
/// `sigma` (a tenth of σ is the finest difference worth reading): whole rpm for a speed measured
/// to ±50 rpm, tenths of a newton for a thrust measured to ±1 N. `signed` puts a `+` on positive
/// values.
pub fn at_noise_precision(value: f64, sigma: f64, signed: bool) -> String {
    let resolution = sigma / 10.0;
    let decimals = if resolution.is_finite() && resolution > 0.0 {
        (-resolution.log10().floor()).clamp(0.0, 6.0) as usize
    } else {
        4
    };
    if signed { format!("{value:+.decimals$}") } else { format!("{value:.decimals$}") }
}

/// A grey line of explanation, or what a view shows when it has nothing to draw.
pub fn hint(ui: &mut egui::Ui, text: &str) {
    ui.label(RichText::new(text).color(theme::HINT));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_are_shown_to_a_tenth_of_the_noise() {
        // Speed: σ = 50.6 rpm.
        assert_eq!(at_noise_precision(3513.1167, 50.6, false), "3513");
        assert_eq!(at_noise_precision(3499.2341, 50.6, true), "+3499");
        // Thrust: σ = 1.3 N.
        assert_eq!(at_noise_precision(12.3456, 1.3, false), "12.3");
        // A small σ keeps the decimals; no σ falls back to four.
        assert_eq!(at_noise_precision(0.012345, 0.02, false), "0.012");
        assert_eq!(at_noise_precision(1.0, 0.0, false), "1.0000");
    }
}
