//! The in-app path field, used instead of a native file dialog where none can appear (see
//! [`crate::ui::file_dialog`]): a small window with the path, prefilled, OK and Cancel. A file that
//! cannot be read or written keeps the window open with the error, so the path can be corrected.
use std::path::{Path, PathBuf};

use egui::RichText;

use crate::ui::file_dialog::PickPurpose;
use crate::ui::state::command::{Command, FileAction};
use crate::ui::theme;

/// The window's state (view state: nothing here is saved).
pub struct PathPrompt {
    pub purpose: PickPurpose,
    /// The path as typed.
    pub text: String,
    /// Why the last OK failed.
    pub error: Option<String>,
    /// Why this window is shown instead of the system's dialog, when the system's was tried.
    pub note: Option<String>,
}

impl PathPrompt {
    /// Prefilled with a file in `dir`: the usual name to read, or for a save a name that is not
    /// taken yet, so that pressing OK does not replace a file unasked.
    pub fn new(purpose: PickPurpose, dir: &Path) -> Self {
        let path = match purpose {
            PickPurpose::Runs => dir.join(""),
            PickPurpose::File(action) => {
                let (stem, extension) = default_name(action);
                if writes(action) {
                    free_path(dir, stem, extension)
                } else {
                    dir.join(format!("{stem}.{extension}"))
                }
            }
        };
        Self { purpose, text: path.display().to_string(), error: None, note: None }
    }

    pub fn path(&self) -> PathBuf {
        PathBuf::from(self.text.trim())
    }

    pub fn title(&self) -> &'static str {
        match self.purpose {
            PickPurpose::Runs => "Open run",
            PickPurpose::File(FileAction::ExportModel) => "Export model",
            PickPurpose::File(FileAction::ImportModel) => "Import model",
            PickPurpose::File(FileAction::SaveProject) => "Save project",
            PickPurpose::File(FileAction::OpenProject) => "Open project",
            PickPurpose::File(FileAction::OpenFleet) => "Open fleet manifest",
        }
    }

    fn writes(&self) -> bool {
        matches!(self.purpose, PickPurpose::File(action) if writes(action))
    }
}

/// The file name a dialog for `action` proposes, as stem and extension.
pub fn default_name(action: FileAction) -> (&'static str, &'static str) {
    match action {
        FileAction::ExportModel | FileAction::ImportModel => ("model", "json"),
        FileAction::SaveProject | FileAction::OpenProject => ("project", "toml"),
        FileAction::OpenFleet => ("manifest", "toml"),
    }
}

fn writes(action: FileAction) -> bool {
    matches!(action, FileAction::ExportModel | FileAction::SaveProject)
}

/// `dir/stem.extension`, else the first of `dir/stem-2.extension`, `dir/stem-3.extension`, … that
/// does not exist.
fn free_path(dir: &Path, stem: &str, extension: &str) -> PathBuf {
    let first = dir.join(format!("{stem}.{extension}"));
    if !first.exists() {
        return first;
    }
    (2..1000).map(|n| dir.join(format!("{stem}-{n}.{extension}"))).find(|p| !p.exists()).unwrap_or(first)
}

/// The window; returns [`Command::SubmitPath`] on OK (or Enter) and [`Command::ClosePathPrompt`]
/// on Cancel (or Escape).
pub fn path_prompt_ui(ctx: &egui::Context, prompt: &mut PathPrompt) -> Vec<Command> {
    let mut commands = Vec::new();
    egui::Window::new(prompt.title())
        .id(egui::Id::unique("path_prompt_window"))
        .collapsible(false)
        .resizable(false)
        .min_width(540.0)
        .pivot(egui::Align2::CENTER_TOP)
        .default_pos(ctx.content_rect().center_top() + egui::vec2(0.0, 120.0))
        .show(ctx, |ui| {
            if let Some(note) = &prompt.note {
                ui.label(RichText::new(note).color(theme::HINT));
            }
            let label = ui.label("Path");
            let field = ui
                .add(egui::TextEdit::singleline(&mut prompt.text).desired_width(520.0))
                .labelled_by(label.id);
            if field.changed() {
                prompt.error = None;
            }
            let entered = field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
            if prompt.writes() && prompt.path().is_file() {
                ui.label(RichText::new("A file of this name exists: OK replaces it.").color(theme::WARNING));
            }
            if let Some(error) = &prompt.error {
                ui.add(
                    egui::Label::new(RichText::new(error).monospace().color(theme::ERROR))
                        .wrap()
                        .selectable(true),
                );
            }
            ui.horizontal(|ui| {
                let ok = ui.add_enabled(!prompt.text.trim().is_empty(), egui::Button::new("OK"));
                if ok.clicked() || (entered && ok.enabled()) {
                    commands.push(Command::SubmitPath);
                }
                if ui.button("Cancel").clicked() || ui.input(|i| i.key_pressed(egui::Key::Escape)) {
                    commands.push(Command::ClosePathPrompt);
                }
            });
        });
    commands
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn a_save_is_prefilled_with_a_name_that_is_not_taken() {
        let dir = tempfile::tempdir().unwrap();
        let save = PickPurpose::File(FileAction::SaveProject);
        assert_eq!(PathPrompt::new(save, dir.path()).path(), dir.path().join("project.toml"));
        std::fs::write(dir.path().join("project.toml"), "").unwrap();
        std::fs::write(dir.path().join("project-2.toml"), "").unwrap();
        assert_eq!(PathPrompt::new(save, dir.path()).path(), dir.path().join("project-3.toml"));
        // Opening proposes the existing file.
        let open = PickPurpose::File(FileAction::OpenProject);
        assert_eq!(PathPrompt::new(open, dir.path()).path(), dir.path().join("project.toml"));
    }
}
