//! Pieces every view may use: the model summary and output bar (`model`), plot helpers (`plot`),
//! the segment overlay (`segments`), and the grey hint line.
use egui::RichText;

use crate::ui::theme;

pub mod model;
pub mod plot;
pub mod segments;

/// A grey line of explanation, or what a view shows when it has nothing to draw.
pub fn hint(ui: &mut egui::Ui, text: &str) {
    ui.label(RichText::new(text).color(theme::HINT));
}
