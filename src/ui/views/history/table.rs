//! The History view's lists: the engines with their flagged-run counts, and one engine's runs in
//! date order with their errors, health deltas (each with its 95 % interval) and flag in words.
use egui::RichText;

use crate::core::health::Estimate;
use crate::fleet::flags::plain;
use crate::ui::derived::fleet_history::{EngineHistory, FleetHistory};
use crate::ui::theme;

/// Background of a flagged run's row.
const FLAGGED_ROW: egui::Color32 = egui::Color32::from_rgba_premultiplied(90, 30, 28, 200);
/// A flag's words on its shaded row.
const FLAG_TEXT: egui::Color32 = egui::Color32::from_rgb(255, 200, 190);
/// The flag column's width: its first reason, cut.
const FLAG_WIDTH: f32 = 300.0;
/// Background of the selected run's row, and of the selected run's when it is flagged.
const SELECTED_ROW: egui::Color32 = egui::Color32::from_rgba_premultiplied(40, 60, 95, 200);
const SELECTED_FLAGGED_ROW: egui::Color32 = egui::Color32::from_rgba_premultiplied(130, 45, 40, 230);

/// The engine list; returns the engine clicked.
pub fn engines_ui(ui: &mut egui::Ui, fleet: &FleetHistory, selected: usize) -> Option<usize> {
    let mut clicked = None;
    ui.strong("Engines");
    for (i, engine) in fleet.engines.iter().enumerate() {
        let flagged = engine.flagged_runs();
        let text = format!("{}: {flagged} of {} runs flagged", engine.name, engine.runs.len());
        let text = if flagged > 0 { RichText::new(text).color(theme::WARNING) } else { RichText::new(text) };
        if ui.selectable_label(i == selected, text).clicked() {
            clicked = Some(i);
        }
    }
    clicked
}

/// `1.02 ± 0.01` (half the interval), `1.02` without one, "—" when not fitted.
pub fn estimate_text(estimate: Option<Estimate>, digits: i32) -> String {
    match estimate {
        None => "—".to_owned(),
        Some(Estimate { value, ci95: Some([lo, hi]) }) => {
            format!("{} ± {}", plain(value, digits), plain(0.5 * (hi - lo).abs(), 2))
        }
        Some(Estimate { value, ci95: None }) => plain(value, digits),
    }
}

/// The column headers of an engine's run table.
pub fn run_columns(engine: &EngineHistory) -> Vec<String> {
    let mut columns = ["run", "date", "flag", "input gain", "τ scale"].map(ToOwned::to_owned).to_vec();
    for (output, unit) in engine.outputs() {
        let unit = if unit.is_empty() || unit == "-" { String::new() } else { format!(" [{unit}]") };
        columns.push(format!("{output}\nRMSE{unit}"));
        columns.push(format!("{output}\nRMSPE [%]"));
        columns.push(format!("{output}\nmap shift{unit}"));
    }
    columns
}

/// An engine's runs, flagged rows shaded; returns the run clicked.
pub fn runs_ui(ui: &mut egui::Ui, engine: &EngineHistory, selected: Option<usize>) -> Option<usize> {
    let mut clicked = None;
    let flagged: Vec<bool> = engine.runs.iter().map(|r| r.flagged()).collect();
    let outputs = engine.outputs();
    egui::Grid::new(("history_runs", &engine.name))
        .striped(true)
        .spacing([12.0, 3.0])
        .with_row_color(move |row, _style| {
            // Row 0 is the header.
            let run = row.checked_sub(1)?;
            match (Some(run) == selected, flagged.get(run).copied().unwrap_or(false)) {
                (true, true) => Some(SELECTED_FLAGGED_ROW),
                (true, false) => Some(SELECTED_ROW),
                (false, true) => Some(FLAGGED_ROW),
                (false, false) => None,
            }
        })
        .show(ui, |ui| {
            for column in run_columns(engine) {
                ui.strong(column);
            }
            ui.end_row();
            for (i, run) in engine.runs.iter().enumerate() {
                if ui.selectable_label(Some(i) == selected, &run.run.name).clicked() {
                    clicked = Some(i);
                }
                ui.label(run.date_text());
                if run.flagged() {
                    let more = run.reasons.len().saturating_sub(1);
                    let first = run.reasons.first().map_or("", String::as_str);
                    let text = if more > 0 { format!("{first} (+{more} more)") } else { first.to_owned() };
                    let label = egui::Label::new(RichText::new(text).color(FLAG_TEXT))
                        .sense(egui::Sense::click())
                        .truncate();
                    // The whole reasons on hover and beside the comparison; the row stays one line.
                    let response = ui.scope(|ui| {
                        ui.set_max_width(FLAG_WIDTH);
                        ui.add(label).on_hover_text(run.reasons.join("\n"))
                    });
                    if response.inner.clicked() {
                        clicked = Some(i);
                    }
                } else {
                    ui.label(RichText::new("within the normal band").color(theme::OK));
                }
                ui.label(estimate_text(run.score.input_gain, 4));
                ui.label(estimate_text(run.score.tau_scale, 3));
                for (output, _) in &outputs {
                    match run.score.outputs.iter().find(|o| o.output == *output) {
                        Some(o) => {
                            ui.label(plain(o.rmse, 3));
                            ui.label(plain(o.rmspe_pct, 3));
                            ui.label(estimate_text(o.map_shift, 3));
                        }
                        None => {
                            for _ in 0..3 {
                                ui.label("—");
                            }
                        }
                    }
                }
                ui.end_row();
            }
        });
    clicked
}
