//! The column-mapping dialog: pick which header column is time, input, output(s) and auxiliary
//! channels, then load again with that [`ColumnMap`].
use crate::core::run::RunRole;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};

use egui::RichText;

use crate::io::csv_run::{ColumnMap, LoadOptions};
use crate::ui::state::command::Command;
use crate::ui::state::session::file_label;
use crate::ui::theme;

// Guesses that pre-fill the dialog (names lower-cased): the canonical names of CONTRACT.md and
// the obvious variants. The user confirms or corrects them.
fn looks_like_time(name: &str) -> bool {
    name == "t" || name.starts_with("time")
}

fn looks_like_input(name: &str) -> bool {
    name.contains("fuel")
}

fn looks_like_output(name: &str) -> bool {
    ["rpm", "speed", "thrust"].iter().any(|word| name.contains(word))
}

/// What the dialog loads when confirmed.
#[derive(Clone, Debug, PartialEq)]
pub enum MappingTarget {
    /// A file that is not in the session yet.
    New { path: PathBuf, role: RunRole },
    /// Session run `index`, read again.
    Existing { index: usize, path: PathBuf },
}

impl MappingTarget {
    pub fn path(&self) -> &Path {
        match self {
            Self::New { path, .. } | Self::Existing { path, .. } => path,
        }
    }
}

/// The dialog's state (view state: nothing here is saved).
pub struct MappingDialog {
    pub target: MappingTarget,
    /// The header columns, or why they could not be read.
    pub headers: Result<Vec<String>, String>,
    pub time: Option<usize>,
    pub input: Option<usize>,
    pub outputs: Vec<bool>,
    pub aux: Vec<bool>,
    /// Keep every other numeric column as auxiliary (the loader's default) instead of `aux`.
    pub auto_aux: bool,
    pub sample_time_text: String,
    pub resample: bool,
    /// The options being edited; the fields the dialog does not show (window, quality) are kept.
    base: LoadOptions,
}

impl MappingDialog {
    /// Open on `target`, pre-filled from `current` where it names columns, else from the canonical
    /// names.
    pub fn new(target: MappingTarget, current: &LoadOptions) -> Self {
        let headers = read_header(target.path());
        let names: &[String] = headers.as_ref().map_or(&[], Vec::as_slice);
        let find = |wanted: &Option<String>, guess: fn(&str) -> bool| match wanted {
            Some(wanted) => names.iter().position(|h| h == wanted),
            None => names.iter().position(|h| guess(&h.to_lowercase())),
        };
        let flags = |wanted: &[String], guess: fn(&str) -> bool| -> Vec<bool> {
            names
                .iter()
                .map(|h| if wanted.is_empty() { guess(&h.to_lowercase()) } else { wanted.contains(h) })
                .collect()
        };
        let time = find(&current.map.time, looks_like_time);
        let input = find(&current.map.input, looks_like_input);
        let outputs = flags(&current.map.outputs, looks_like_output);
        let aux = flags(&current.map.aux, |_| false);
        let auto_aux = current.map.aux.is_empty();
        let sample_time_text = current.sample_time_secs.map(|dt| dt.to_string()).unwrap_or_default();
        let resample = current.resample;
        Self {
            target,
            headers,
            time,
            input,
            outputs,
            aux,
            auto_aux,
            sample_time_text,
            resample,
            base: current.clone(),
        }
    }

    /// The options the dialog describes, or what is still missing.
    pub fn options(&self) -> Result<LoadOptions, String> {
        let headers = self.headers.as_ref().map_err(Clone::clone)?;
        let name = |i: usize| headers.get(i).cloned();
        let input = self.input.and_then(name).ok_or("choose the input column")?;
        let picked = |flags: &[bool]| -> Vec<String> {
            flags.iter().zip(headers).filter(|(on, _)| **on).map(|(_, h)| h.clone()).collect()
        };
        let outputs = picked(&self.outputs);
        if outputs.is_empty() {
            return Err("choose at least one output column".into());
        }
        let time = self.time.and_then(name);
        let sample_time_secs = if time.is_some() {
            None
        } else {
            let dt: f64 = self
                .sample_time_text
                .trim()
                .parse()
                .map_err(|_| "without a time column, enter the sample time")?;
            if !(dt.is_finite() && dt > 0.0) {
                return Err("the sample time must be a positive number of seconds".into());
            }
            Some(dt)
        };
        let aux = if self.auto_aux { Vec::new() } else { picked(&self.aux) };
        Ok(LoadOptions {
            map: ColumnMap { time, input: Some(input), outputs, aux },
            sample_time_secs,
            resample: self.resample,
            ..self.base.clone()
        })
    }

    /// The command that loads with these options.
    fn command(&self, options: LoadOptions) -> Command {
        match &self.target {
            MappingTarget::New { path, role } => {
                Command::LoadRun { path: path.clone(), role: *role, options }
            }
            MappingTarget::Existing { index, .. } => Command::ReloadRun { index: *index, options },
        }
    }
}

/// The header line of a CSV file, split on commas (quotes and a byte-order mark removed).
pub fn read_header(path: &Path) -> Result<Vec<String>, String> {
    let file = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut line = String::new();
    BufReader::new(file).read_line(&mut line).map_err(|e| format!("{}: {e}", path.display()))?;
    let line = line.trim_start_matches('\u{feff}').trim_end_matches(['\r', '\n']);
    if line.trim().is_empty() {
        return Err(format!("{}: the file has no header line", path.display()));
    }
    Ok(line.split(',').map(|h| h.trim().trim_matches('"').to_owned()).collect())
}

/// Draw the dialog; returns the commands it asks for (load, close).
pub fn mapping_ui(ctx: &egui::Context, dialog: &mut MappingDialog) -> Vec<Command> {
    let mut commands = Vec::new();
    let mut open = true;
    egui::Window::new(format!("Column mapping: {}", file_label(dialog.target.path())))
        .id(egui::Id::unique("column_mapping_dialog"))
        .open(&mut open)
        .collapsible(false)
        .resizable(true)
        .default_width(460.0)
        .pivot(egui::Align2::CENTER_CENTER)
        .default_pos(ctx.content_rect().center())
        .show(ctx, |ui| {
            ui.label(RichText::new(dialog.target.path().display().to_string()).small().color(theme::HINT));
            let headers = match &dialog.headers {
                Ok(headers) => headers.clone(),
                Err(message) => {
                    ui.colored_label(theme::ERROR, message);
                    if ui.button("Close").clicked() {
                        commands.push(Command::CloseMappingDialog);
                    }
                    return;
                }
            };
            roles_grid_ui(ui, dialog, &headers);
            ui.separator();
            let options = dialog.options();
            if let Err(message) = &options {
                ui.colored_label(theme::ERROR, message);
            }
            ui.horizontal(|ui| {
                if ui.add_enabled(options.is_ok(), egui::Button::new("Load")).clicked()
                    && let Ok(options) = options
                {
                    commands.push(dialog.command(options));
                    commands.push(Command::CloseMappingDialog);
                }
                if ui.button("Cancel").clicked() {
                    commands.push(Command::CloseMappingDialog);
                }
            });
        });
    if !open {
        commands.push(Command::CloseMappingDialog);
    }
    commands
}

fn roles_grid_ui(ui: &mut egui::Ui, dialog: &mut MappingDialog, headers: &[String]) {
    ui.horizontal(|ui| {
        let label = ui.label("Time:");
        column_combo_ui(ui, "mapping_time", &mut dialog.time, headers, "(none: fixed sample time)")
            .labelled_by(label.id);
    });
    if dialog.time.is_none() {
        ui.horizontal(|ui| {
            let label = ui.label("Sample time [s]:");
            ui.add(egui::TextEdit::singleline(&mut dialog.sample_time_text).desired_width(80.0))
                .labelled_by(label.id);
        });
    }
    ui.horizontal(|ui| {
        let label = ui.label("Input:");
        column_combo_ui(ui, "mapping_input", &mut dialog.input, headers, "(choose)").labelled_by(label.id);
    });
    ui.checkbox(&mut dialog.resample, "Resample a non-uniform time axis");
    ui.checkbox(&mut dialog.auto_aux, "Keep every other numeric column as an auxiliary channel");
    ui.label("Outputs and auxiliary channels:");
    egui::ScrollArea::vertical().max_height(300.0).show(ui, |ui| {
        egui::Grid::new("mapping_grid").striped(true).num_columns(3).show(ui, |ui| {
            ui.strong("column");
            ui.strong("output");
            ui.strong("aux");
            ui.end_row();
            for (i, header) in headers.iter().enumerate() {
                let used = Some(i) == dialog.time || Some(i) == dialog.input;
                ui.label(header);
                if let (Some(out), Some(aux)) = (dialog.outputs.get_mut(i), dialog.aux.get_mut(i)) {
                    ui.add_enabled(!used, egui::Checkbox::new(out, ""))
                        .on_hover_text(format!("{header} is an output"));
                    ui.add_enabled(!used && !*out && !dialog.auto_aux, egui::Checkbox::new(aux, ""))
                        .on_hover_text(format!("{header} is an auxiliary channel"));
                    if used || *out {
                        *aux = false;
                    }
                    if used {
                        *out = false;
                    }
                }
                ui.end_row();
            }
        });
    });
}

fn column_combo_ui(
    ui: &mut egui::Ui,
    salt: &str,
    choice: &mut Option<usize>,
    headers: &[String],
    none: &str,
) -> egui::Response {
    let selected = choice.and_then(|i| headers.get(i)).map_or(none, String::as_str);
    egui::ComboBox::from_id_salt(salt)
        .selected_text(selected)
        .width(220.0)
        .show_ui(ui, |ui| {
            ui.selectable_value(choice, None, none);
            for (i, header) in headers.iter().enumerate() {
                ui.selectable_value(choice, Some(i), header);
            }
        })
        .response
}
