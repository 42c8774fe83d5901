//! The frame around the views: menu bar, run list, status bar, load-error window, empty-session
//! hint. Each returns the commands the user asked for.
use crate::core::run::RunRole;
use egui::RichText;

use crate::ui::state::ViewState;
use crate::ui::state::command::{Command, FileAction};
use crate::ui::state::session::{LoadFailure, Session, file_label};
use crate::ui::state::setup::History;
use crate::ui::theme;
use crate::ui::widgets::hint;

pub fn menu_bar_ui(ui: &mut egui::Ui, history: &History) -> Vec<Command> {
    let mut commands = Vec::new();
    egui::MenuBar::new().ui(ui, |ui| {
        ui.menu_button("File", |ui| {
            let items = [
                ("Open run…", Command::OpenRunDialog),
                ("Open project…", Command::ChooseFile(FileAction::OpenProject)),
                ("Open fleet manifest…", Command::ChooseFile(FileAction::OpenFleet)),
                ("Save project…", Command::ChooseFile(FileAction::SaveProject)),
                ("Import model (clusters)…", Command::ChooseFile(FileAction::ImportModel)),
                ("Export model…", Command::ChooseFile(FileAction::ExportModel)),
            ];
            for (label, command) in items {
                if ui.button(label).clicked() {
                    commands.push(command);
                    ui.close();
                }
            }
            ui.separator();
            if ui.button("Quit").clicked() {
                commands.push(Command::Quit);
                ui.close();
            }
        });
        ui.menu_button("Edit", |ui| {
            if ui.add_enabled(history.can_undo(), egui::Button::new("Undo").shortcut_text("Ctrl+Z")).clicked()
            {
                commands.push(Command::Undo);
                ui.close();
            }
            let redo = egui::Button::new("Redo").shortcut_text("Ctrl+Shift+Z");
            if ui.add_enabled(history.can_redo(), redo).clicked() {
                commands.push(Command::Redo);
                ui.close();
            }
        });
    });
    commands
}

/// The notice that the last session was restored, with the way back to a first start.
pub fn restore_notice_ui(ui: &mut egui::Ui, runs: usize) -> Vec<Command> {
    let mut commands = Vec::new();
    ui.horizontal(|ui| {
        let plural = if runs == 1 { "" } else { "s" };
        ui.label(
            RichText::new(format!("Restored the last session ({runs} run{plural}) —")).color(theme::WARNING),
        );
        let fresh = if super::bundled_sample_dir().is_some() {
            "Drops these runs and their setup for the bundled sample runs"
        } else {
            "Drops these runs and their setup for an empty session"
        };
        if ui.button("Start fresh").on_hover_text(fresh).clicked() {
            commands.push(Command::StartFresh);
        }
        if ui.button("Keep").on_hover_text("Hide this notice").clicked() {
            commands.push(Command::DismissRestoreNotice);
        }
    });
    commands
}

/// Model and project file errors, each with its whole message.
pub fn errors_ui(ctx: &egui::Context, errors: &[String]) -> Vec<Command> {
    let mut commands = Vec::new();
    egui::Window::new("Error")
        .id(egui::Id::unique("file_errors_window"))
        .collapsible(false)
        .default_width(560.0)
        .pivot(egui::Align2::CENTER_TOP)
        .default_pos(ctx.content_rect().center_top() + egui::vec2(0.0, 120.0))
        .show(ctx, |ui| {
            for (i, message) in errors.iter().enumerate() {
                ui.group(|ui| {
                    ui.set_width(ui.available_width());
                    ui.add(
                        egui::Label::new(RichText::new(message).monospace().color(theme::ERROR))
                            .wrap()
                            .selectable(true),
                    );
                    if ui.button("Dismiss").clicked() {
                        commands.push(Command::DismissError(i));
                    }
                });
            }
        });
    commands
}

pub fn status_bar_ui(ui: &mut egui::Ui, view: &ViewState) {
    ui.horizontal(|ui| {
        if let Some(message) = &view.status {
            ui.label(message);
        }
        ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
            if let Some(ms) = view.cpu_frame_ms.or(view.frame_ms) {
                ui.label(RichText::new(format!("frame {ms:.1} ms")).monospace().color(theme::HINT))
                    .on_hover_text("CPU time of the previous frame");
            }
        });
    });
}

pub fn runs_panel_ui(ui: &mut egui::Ui, session: &Session, selected: Option<usize>) -> Vec<Command> {
    let mut commands = Vec::new();
    ui.add_space(4.0);
    ui.heading("Runs");
    ui.add_space(4.0);
    if session.runs.is_empty() {
        hint(ui, "No runs loaded.");
    }
    egui::ScrollArea::vertical().auto_shrink([false, true]).show(ui, |ui| {
        for (i, run) in session.runs.iter().enumerate() {
            let name = run.display_name();
            let response = ui
                .selectable_label(selected == Some(i), RichText::new(&name).strong())
                .on_hover_text(run.path.display().to_string());
            if response.clicked() {
                commands.push(Command::SelectRun(i));
            }
            response.context_menu(|ui| {
                if ui.button("Map columns…").clicked() {
                    commands.push(Command::MapColumnsOfRun(i));
                    ui.close();
                }
                if ui.button("Remove").clicked() {
                    commands.push(Command::RemoveRun(i));
                    ui.close();
                }
            });
            ui.horizontal(|ui| {
                let label = ui.label("role");
                egui::ComboBox::from_id_salt(("run_role", i))
                    .selected_text(run.role.label())
                    .width(130.0)
                    .show_ui(ui, |ui| {
                        for role in RunRole::ALL {
                            if ui.selectable_label(run.role == role, role.label()).clicked() {
                                commands.push(Command::SetRole(i, role));
                            }
                        }
                    })
                    .response
                    .labelled_by(label.id);
            });
            ui.add_space(6.0);
        }
        ui.separator();
        if ui.button("Open run…").clicked() {
            commands.push(Command::OpenRunDialog);
        }
    });
    commands
}

pub fn failures_ui(ctx: &egui::Context, failures: &[LoadFailure]) -> Vec<Command> {
    let mut commands = Vec::new();
    let mut open = true;
    egui::Window::new("Could not load run")
        .id(egui::Id::unique("load_failures_window"))
        .open(&mut open)
        .collapsible(false)
        .default_width(560.0)
        .pivot(egui::Align2::CENTER_TOP)
        .default_pos(ctx.content_rect().center_top() + egui::vec2(0.0, 80.0))
        .show(ctx, |ui| {
            ui.label("The session was not changed.");
            egui::ScrollArea::vertical().max_height(400.0).show(ui, |ui| {
                for (i, failure) in failures.iter().enumerate() {
                    ui.group(|ui| failure_ui(ui, i, failure, &mut commands));
                }
            });
            if failures.len() > 1 && ui.button("Dismiss all").clicked() {
                commands.push(Command::DismissAllFailures);
            }
        });
    if !open {
        commands.push(Command::DismissAllFailures);
    }
    commands
}

fn failure_ui(ui: &mut egui::Ui, i: usize, failure: &LoadFailure, commands: &mut Vec<Command>) {
    ui.set_width(ui.available_width());
    ui.strong(file_label(&failure.path)).on_hover_text(failure.path.display().to_string());
    ui.add(
        egui::Label::new(RichText::new(&failure.message).monospace().color(theme::ERROR))
            .wrap()
            .selectable(true),
    );
    ui.horizontal(|ui| {
        let mut map = ui.button("Map columns…");
        if failure.column_problem {
            map = map.highlight();
        }
        if map.on_hover_text("Choose which columns are time, input, outputs and auxiliary channels").clicked()
        {
            commands.push(Command::MapColumnsOfFailure(i));
        }
        if ui.button("Dismiss").clicked() {
            commands.push(Command::DismissFailure(i));
        }
    });
}

pub fn empty_session_ui(ui: &mut egui::Ui) {
    ui.add_space(24.0);
    ui.vertical_centered(|ui| {
        ui.heading("No runs loaded");
        ui.add_space(8.0);
        hint(ui, "Open a run file (CSV) with File > Open run… (Ctrl+O).");
        if super::bundled_sample_dir().is_none() {
            hint(
                ui,
                "The bundled sample runs (sample_runs/sr30/*.csv) were not found; \
                 `jetid simulate --test ident --out ident.csv` makes one.",
            );
        }
    });
}
