//! The app: session (saved), view state (transient) and derived cache, the frame layout, and the
//! one place where commands change the session.
use std::time::Instant;

use egui::RichText;

use super::command::Command;
use super::derived::Derived;
use super::file_dialog::{PendingPick, PickPoll};
use super::mapping_ui::{self, MappingDialog, MappingTarget};
use super::session::{LoadFailure, Role, SavedSession, Session, SessionRun, file_label};
use super::views::{self, Tab, ViewStates};
use super::{panels_ui, theme};

/// State that only matters while the app runs: nothing here is saved.
#[derive(Default)]
pub struct ViewState {
    pub tab: Tab,
    pub selected_run: Option<usize>,
    pub views: ViewStates,
    /// Files that could not be read, shown until dismissed.
    pub failures: Vec<LoadFailure>,
    pub mapping: Option<MappingDialog>,
    /// The latest message for the status bar.
    pub status: Option<String>,
    /// The duration of the previous frame's UI code, in ms.
    pub frame_ms: Option<f32>,
    /// The whole previous frame as eframe measured it (UI and tessellation), in ms.
    pub cpu_frame_ms: Option<f32>,
    /// A native file dialog is open.
    pub picker: Option<PendingPick>,
    pub open_dialog_requested: bool,
    pub quit_requested: bool,
}

pub struct App {
    pub session: Session,
    pub view: ViewState,
    pub cache: Derived,
}

impl App {
    pub fn new(session: Session) -> Self {
        let selected_run = if session.runs.is_empty() { None } else { Some(0) };
        Self { session, view: ViewState { selected_run, ..ViewState::default() }, cache: Derived::default() }
    }

    /// The app on a restored session, with the runs that failed to load shown as errors.
    pub fn with_failures(session: Session, failures: Vec<LoadFailure>) -> Self {
        let mut app = Self::new(session);
        if !failures.is_empty() {
            app.view.status = Some(format!("{} run file(s) could not be read", failures.len()));
        }
        app.view.failures = failures;
        app
    }

    /// Start on the saved session, else (nothing saved, or nothing of it could be read) on the
    /// bundled sample runs, else empty.
    pub fn startup(saved: Option<&SavedSession>) -> Self {
        let mut failures = Vec::new();
        if let Some(saved) = saved.filter(|s| !s.runs.is_empty()) {
            let (session, restore_failures) = Session::restore(saved);
            if !session.runs.is_empty() {
                return Self::with_failures(session, restore_failures);
            }
            failures = restore_failures;
        }
        match Session::bundled() {
            Some((session, mut bundled_failures)) => {
                failures.append(&mut bundled_failures);
                let mut app = Self::with_failures(session, failures);
                if app.view.failures.is_empty()
                    && let Some(dir) = super::bundled_sample_dir()
                {
                    app.view.status = Some(format!("Sample runs from {}", dir.display()));
                }
                app
            }
            None => Self::with_failures(Session::default(), failures),
        }
    }

    /// What is saved on close: the session's runs, plus files that failed to load and were not
    /// dismissed (e.g. moved away since last time), so that closing the app loses nothing.
    pub fn saved_session(&self) -> SavedSession {
        let mut saved = self.session.to_saved();
        saved
            .runs
            .extend(self.view.failures.iter().filter(|f| f.existing.is_none()).map(LoadFailure::source));
        saved
    }

    /// Carry out one command. Session changes bump `session.revision`; failures leave the session
    /// untouched and are shown.
    pub fn apply(&mut self, command: Command) {
        match command {
            Command::LoadRun { path, role, options } => match SessionRun::load(&path, role, options) {
                Ok(run) => {
                    self.view.status = Some(format!(
                        "Loaded {} ({} samples) as {}",
                        file_label(&path),
                        run.run.len(),
                        role.label()
                    ));
                    self.view.failures.retain(|f| !(f.existing.is_none() && f.path == path));
                    self.session.runs.push(run);
                    self.view.selected_run = Some(self.session.runs.len() - 1);
                    self.session.revision += 1;
                }
                Err(failure) => self.push_failure(*failure),
            },
            Command::ReloadRun { index, options } => self.reload_run(index, options),
            Command::RemoveRun(index) => {
                if index < self.session.runs.len() {
                    let removed = self.session.runs.remove(index);
                    self.view.status = Some(format!("Removed {}", file_label(&removed.path)));
                    self.after_remove(index);
                    self.session.revision += 1;
                }
            }
            Command::SetRole(index, role) => {
                if let Some(run) = self.session.runs.get_mut(index)
                    && run.role != role
                {
                    run.role = role;
                    self.session.revision += 1;
                }
            }
            Command::OpenRunDialog => self.view.open_dialog_requested = true,
            Command::MapColumnsOfRun(index) => {
                if let Some(run) = self.session.runs.get(index) {
                    let target = MappingTarget::Existing { index, path: run.path.clone() };
                    self.view.mapping = Some(MappingDialog::new(target, &run.options));
                }
            }
            Command::MapColumnsOfFailure(index) => {
                if let Some(failure) = self.view.failures.get(index) {
                    let target = match failure.existing {
                        Some(existing) => {
                            MappingTarget::Existing { index: existing, path: failure.path.clone() }
                        }
                        None => MappingTarget::New { path: failure.path.clone(), role: failure.role },
                    };
                    self.view.mapping = Some(MappingDialog::new(target, &failure.options));
                }
            }
            Command::CloseMappingDialog => self.view.mapping = None,
            Command::DismissFailure(index) => {
                if index < self.view.failures.len() {
                    self.view.failures.remove(index);
                }
            }
            Command::DismissAllFailures => self.view.failures.clear(),
            Command::SelectRun(index) => {
                if index < self.session.runs.len() {
                    self.view.selected_run = Some(index);
                }
            }
            Command::ShowTab(tab) => self.view.tab = tab,
            Command::Quit => self.view.quit_requested = true,
        }
    }

    fn reload_run(&mut self, index: usize, options: crate::io::csv_run::LoadOptions) {
        let Some((path, role)) = self.session.runs.get(index).map(|r| (r.path.clone(), r.role)) else {
            self.view.status = Some("That run is no longer in the session".into());
            return;
        };
        match SessionRun::load(&path, role, options) {
            Ok(run) => {
                self.view.status =
                    Some(format!("Reloaded {} ({} samples)", file_label(&run.path), run.run.len()));
                self.view.failures.retain(|f| f.existing != Some(index));
                if let Some(slot) = self.session.runs.get_mut(index) {
                    *slot = run;
                }
                self.session.revision += 1;
            }
            Err(failure) => self.push_failure(LoadFailure { existing: Some(index), ..*failure }),
        }
    }

    fn push_failure(&mut self, failure: LoadFailure) {
        self.view.status = Some(format!("Could not load {}", file_label(&failure.path)));
        // One entry per file and target: a retry replaces the previous message.
        self.view.failures.retain(|f| !(f.path == failure.path && f.existing == failure.existing));
        self.view.failures.push(failure);
    }

    /// Keep indices into the run list valid after run `removed` is gone.
    fn after_remove(&mut self, removed: usize) {
        let shift = |i: usize| {
            if i > removed {
                Some(i - 1)
            } else if i == removed {
                None
            } else {
                Some(i)
            }
        };
        self.view.selected_run = match self.view.selected_run {
            Some(i) if i == removed => {
                if self.session.runs.is_empty() {
                    None
                } else {
                    Some(removed.min(self.session.runs.len() - 1))
                }
            }
            Some(i) => shift(i),
            None => None,
        };
        for failure in &mut self.view.failures {
            failure.existing = failure.existing.and_then(shift);
        }
        if let Some(dialog) = &mut self.view.mapping
            && let MappingTarget::Existing { index, .. } = &mut dialog.target
        {
            match shift(*index) {
                Some(i) => *index = i,
                None => self.view.mapping = None,
            }
        }
    }

    /// The whole app in `ui` (the window's root). Usable without eframe, e.g. in tests.
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        let started = Instant::now();
        self.poll_picker();
        self.cache.refresh(&self.session);

        let mut commands = shortcut_commands(ui);
        egui::Panel::top("menu_bar").show(ui, |ui| commands.extend(panels_ui::menu_bar_ui(ui)));
        egui::Panel::bottom("status_bar").show(ui, |ui| panels_ui::status_bar_ui(ui, &self.view));
        egui::Panel::left("runs_panel").resizable(true).default_size(250.0).min_size(180.0).show(ui, |ui| {
            commands.extend(panels_ui::runs_panel_ui(ui, &self.session, self.view.selected_run))
        });
        egui::CentralPanel::default().show(ui, |ui| commands.extend(self.central_ui(ui)));

        let ctx = ui.ctx().clone();
        if !self.view.failures.is_empty() {
            commands.extend(panels_ui::failures_ui(&ctx, &self.view.failures));
        }
        if let Some(dialog) = &mut self.view.mapping {
            commands.extend(mapping_ui::mapping_ui(&ctx, dialog));
        }

        for command in commands {
            self.apply(command);
        }
        if std::mem::take(&mut self.view.open_dialog_requested) {
            self.open_picker(&ctx);
        }
        if self.view.quit_requested {
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        }
        self.view.frame_ms = Some(started.elapsed().as_secs_f32() * 1000.0);
    }

    fn central_ui(&mut self, ui: &mut egui::Ui) -> Vec<Command> {
        let mut commands = Vec::new();
        ui.horizontal(|ui| {
            for tab in Tab::ALL {
                if ui.selectable_label(self.view.tab == tab, tab.label()).clicked() {
                    commands.push(Command::ShowTab(tab));
                }
            }
        });
        ui.separator();
        if self.session.runs.is_empty() {
            panels_ui::empty_session_ui(ui);
            return commands;
        }
        commands.extend(views::tab_ui(
            ui,
            self.view.tab,
            &self.session,
            self.view.selected_run,
            &mut self.view.views,
            &self.cache,
        ));
        commands
    }

    fn open_picker(&mut self, ctx: &egui::Context) {
        if self.view.picker.is_some() {
            return;
        }
        let start_dir = self
            .view
            .selected_run
            .and_then(|i| self.session.runs.get(i))
            .and_then(|r| r.path.parent().map(ToOwned::to_owned));
        let ctx = ctx.clone();
        self.view.picker = Some(PendingPick::open_runs(start_dir, move || ctx.request_repaint()));
        self.view.status = Some("Choosing run files…".into());
    }

    fn poll_picker(&mut self) {
        let Some(picker) = &self.view.picker else { return };
        let PickPoll::Done(paths) = picker.poll() else { return };
        self.view.picker = None;
        self.view.status = None;
        for path in paths {
            let role = Role::guess_from_path(&path, &self.session);
            self.apply(Command::load(path, role));
        }
    }
}

/// Ctrl+O opens run files, Ctrl+Q quits (Cmd on macOS).
fn shortcut_commands(ui: &egui::Ui) -> Vec<Command> {
    let shortcuts = [(egui::Key::O, Command::OpenRunDialog), (egui::Key::Q, Command::Quit)];
    shortcuts
        .into_iter()
        .filter(|(key, _)| {
            ui.input_mut(|i| i.consume_shortcut(&egui::KeyboardShortcut::new(egui::Modifiers::COMMAND, *key)))
        })
        .map(|(_, command)| command)
        .collect()
}

/// The hint shown when a view has nothing to draw.
pub(super) fn hint(ui: &mut egui::Ui, text: &str) {
    ui.label(RichText::new(text).color(theme::HINT));
}
