//! The app: session (saved), view state (transient) and derived cache, the frame layout, and the
//! one place where commands change the session.
use std::time::Instant;

use crate::io::csv_run::LoadOptions;
use crate::ui::derived::Derived;
use crate::ui::derived::model_cache::IdentCache;
use crate::ui::file_dialog::{self, PickPurpose};
use crate::ui::mapping_ui::{self, MappingDialog, MappingTarget};
use crate::ui::panels_ui;
use crate::ui::path_prompt;
use crate::ui::state::command::{Command, FileAction};
use crate::ui::state::session::{LoadFailure, SavedSession, Session, SessionRun, file_label};
use crate::ui::state::{Tab, ViewState};
use crate::ui::views;

pub struct App {
    pub session: Session,
    pub view: ViewState,
    pub cache: Derived,
}

impl App {
    pub fn new(session: Session) -> Self {
        let selected_run = if session.runs.is_empty() { None } else { Some(0) };
        let view = ViewState {
            selected_run,
            native_dialogs: file_dialog::native_dialog_available(),
            ..ViewState::default()
        };
        Self { session, view, cache: Derived::default() }
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
                let mut app = Self::with_failures(session, restore_failures);
                // Say so: a user who expects the sample runs, or an empty app, should not have to
                // guess where these runs came from.
                app.view.restored_runs = Some(app.session.runs.len());
                return app;
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
                    let parts: Vec<_> = dir.components().rev().take(2).collect();
                    let short: std::path::PathBuf = parts.into_iter().rev().collect();
                    app.view.status = Some(format!("Bundled sample runs ({})", short.display()));
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
            Command::LoadRun { path, role, options } => self.load_run(&path, role, options),
            Command::ReloadRun { index, options } => self.reload_run(index, options),
            Command::RemoveRun(index) => self.remove_run(index),
            Command::SetRole(index, role) => self.set_role(index, role),
            Command::SetSegments(segments) => self.set_segments(segments),
            Command::SetClusters { output, clusters } => self.set_clusters(&output, clusters),
            Command::SetOutputSettings { output, settings } => {
                let status = format!("{output}: settings changed");
                self.edit_setup(&status, |setup| setup.output_mut(&output).settings = settings);
            }
            Command::ApplyEffect { output, trial } => self.apply_effect(&output, trial),
            Command::RemoveEffect { output, effect } => {
                let status = format!("{output}: effect {effect} removed");
                self.edit_setup(&status, |setup| setup.output_mut(&output).effects.retain(|e| *e != effect));
            }
            Command::SetAutoEffects { output, rounds } => self.set_auto_effects(&output, rounds),
            Command::Undo => self.undo(),
            Command::Redo => self.redo(),
            Command::StartFresh => self.start_fresh(),
            Command::ExportModel(path) => self.file_action_shown(FileAction::ExportModel, &path),
            Command::ImportModel(path) => self.file_action_shown(FileAction::ImportModel, &path),
            Command::SaveProject(path) => self.file_action_shown(FileAction::SaveProject, &path),
            Command::OpenProject(path) => self.file_action_shown(FileAction::OpenProject, &path),
            Command::OpenFleet(path) => self.file_action_shown(FileAction::OpenFleet, &path),
            Command::OpenRunDialog => self.view.dialog_requested = Some(PickPurpose::Runs),
            Command::ChooseFile(action) => self.view.dialog_requested = Some(PickPurpose::File(action)),
            Command::SubmitPath => self.submit_path(),
            Command::ClosePathPrompt => (self.view.path_prompt, self.view.status) = (None, None),
            Command::DismissError(index) => remove_at(&mut self.view.errors, index),
            Command::SelectOutput(name) => {
                // Cluster indices belong to one output.
                self.view.views.zplane.selected = None;
                self.view.output = Some(name);
            }
            Command::MapColumnsOfRun(index) => self.map_columns_of_run(index),
            Command::MapColumnsOfFailure(index) => self.map_columns_of_failure(index),
            Command::CloseMappingDialog => self.view.mapping = None,
            Command::DismissFailure(index) => remove_at(&mut self.view.failures, index),
            Command::DismissAllFailures => self.view.failures.clear(),
            Command::DismissRestoreNotice => self.view.restored_runs = None,
            Command::SelectRun(index) => {
                if index < self.session.runs.len() {
                    self.view.selected_run = Some(index);
                }
            }
            Command::ShowTab(tab) => self.view.tab = tab,
            Command::FocusTraces { run, t0_secs, t1_secs } => {
                self.view.views.traces.focus(run, t0_secs, t1_secs);
                self.view.tab = Tab::Traces;
            }
            Command::Quit => self.view.quit_requested = true,
        }
    }

    fn load_run(&mut self, path: &std::path::Path, role: crate::core::run::RunRole, options: LoadOptions) {
        match SessionRun::load(path, role, options) {
            Ok(run) => {
                self.view.status = Some(format!(
                    "Loaded {} ({} samples) as {}",
                    file_label(path),
                    run.run.len(),
                    role.label()
                ));
                self.view.failures.retain(|f| !(f.existing.is_none() && f.path == path));
                self.session.runs.push(run);
                self.view.selected_run = Some(self.session.runs.len() - 1);
                self.session.revision += 1;
            }
            Err(failure) => self.push_failure(*failure),
        }
    }

    fn remove_run(&mut self, index: usize) {
        if index < self.session.runs.len() {
            let removed = self.session.runs.remove(index);
            self.view.status = Some(format!("Removed {}", file_label(&removed.path)));
            self.after_remove(index);
            self.session.revision += 1;
        }
    }

    fn set_role(&mut self, index: usize, role: crate::core::run::RunRole) {
        if let Some(run) = self.session.runs.get_mut(index)
            && run.role != role
        {
            run.role = role;
            self.session.revision += 1;
        }
    }

    fn map_columns_of_run(&mut self, index: usize) {
        if let Some(run) = self.session.runs.get(index) {
            let target = MappingTarget::Existing { index, path: run.path.clone() };
            self.view.mapping = Some(MappingDialog::new(target, &run.options));
        }
    }

    fn map_columns_of_failure(&mut self, index: usize) {
        if let Some(failure) = self.view.failures.get(index) {
            let target = match failure.existing {
                Some(existing) => MappingTarget::Existing { index: existing, path: failure.path.clone() },
                None => MappingTarget::New { path: failure.path.clone(), role: failure.role },
            };
            self.view.mapping = Some(MappingDialog::new(target, &failure.options));
        }
    }

    /// Replace the session by the one of a first start (what is saved on close from then on). The
    /// tab and the way files are chosen stay.
    fn start_fresh(&mut self) {
        let mut fresh = Self::startup(None);
        fresh.session.revision = self.session.revision + 1;
        fresh.view.tab = self.view.tab;
        fresh.view.native_dialogs = self.view.native_dialogs;
        let what = if fresh.session.runs.is_empty() {
            "an empty session".to_owned()
        } else {
            format!("the bundled sample runs ({})", fresh.session.runs.len())
        };
        fresh.view.status = Some(format!("Started fresh on {what}"));
        *self = fresh;
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
        self.refresh();
        self.view.views.compare.poll();
        self.view.views.history.poll();

        let mut commands = shortcut_commands(ui);
        egui::Panel::top("menu_bar").show(ui, |ui| {
            commands.extend(panels_ui::menu_bar_ui(ui, &self.view.history));
        });
        if let Some(runs) = self.view.restored_runs {
            egui::Panel::top("restore_notice").show(ui, |ui| {
                commands.extend(panels_ui::restore_notice_ui(ui, runs));
            });
        }
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
        if let Some(prompt) = &mut self.view.path_prompt {
            commands.extend(path_prompt::path_prompt_ui(&ctx, prompt));
        }
        if !self.view.errors.is_empty() {
            commands.extend(panels_ui::errors_ui(&ctx, &self.view.errors));
        }

        for command in commands {
            self.apply(command);
        }
        // Recompute now rather than next frame, and draw the result in one more frame.
        if self.refresh() {
            ctx.request_repaint();
        }
        // The proposal's and the finishing model's jobs cannot reach the context: look for their
        // results. A proposal takes seconds, a finishing model a few frames: it is looked for sooner.
        if self.cache.ident.as_ref().is_some_and(IdentCache::is_finishing) {
            ctx.request_repaint_after(FINISH_POLL);
        } else if self.cache.ident.as_ref().is_some_and(IdentCache::is_proposing) {
            ctx.request_repaint_after(PROPOSAL_POLL);
        }
        if let Some(purpose) = self.view.dialog_requested.take() {
            self.open_picker(&ctx, purpose);
            // Draw the path field (or the "Choosing a file…" status) now, not at the next input.
            ctx.request_repaint();
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
        // The History view shows a fleet, not the session's runs.
        if self.session.runs.is_empty() && self.view.tab != Tab::History {
            panels_ui::empty_session_ui(ui);
            return commands;
        }
        commands.extend(views::tab_ui(ui, &self.session, &mut self.view, &self.cache));
        commands
    }

    /// Bring the derived cache up to date with the session and the drag in progress; true when
    /// anything was recomputed.
    pub fn refresh(&mut self) -> bool {
        let stale = self.cache.revision() != Some(self.session.revision);
        self.cache.refresh(&self.session);
        let proposed = self.cache.ident.as_mut().is_some_and(IdentCache::poll_jobs);
        let drag = self.view.views.zplane.preview_request();
        let preview_changed = self.cache.set_preview(drag.as_ref().map(|(o, c)| (o.as_str(), c.as_slice())));
        stale || proposed || preview_changed
    }

    /// [`Self::refresh`], then wait for the automatic proposals and the models finished in the
    /// background (tests, screenshots and the headless paths; never in a frame).
    pub fn settle(&mut self) {
        self.refresh();
        if let Some(ident) = self.cache.ident.as_mut() {
            ident.wait_for_jobs();
        }
        self.refresh();
    }

    /// The output the model views show: the chosen one, else the first one identified.
    pub fn selected_output(&self) -> Option<String> {
        views::selected_output(&self.view, &self.cache)
    }
}

/// Ctrl+O opens run files, Ctrl+Q quits, Ctrl+Z undoes, Ctrl+Shift+Z and Ctrl+Y redo (Cmd on
/// macOS). Undo and redo are left to a text field that has the keyboard.
fn shortcut_commands(ui: &egui::Ui) -> Vec<Command> {
    use egui::{Key, Modifiers};
    let typing = ui.ctx().egui_wants_keyboard_input();
    // Ctrl+Shift+Z before Ctrl+Z: a shortcut without Shift also matches with Shift held.
    let shortcuts = [
        (Modifiers::COMMAND, Key::O, Command::OpenRunDialog, true),
        (Modifiers::COMMAND, Key::Q, Command::Quit, true),
        (Modifiers::COMMAND | Modifiers::SHIFT, Key::Z, Command::Redo, !typing),
        (Modifiers::COMMAND, Key::Y, Command::Redo, !typing),
        (Modifiers::COMMAND, Key::Z, Command::Undo, !typing),
    ];
    shortcuts
        .into_iter()
        .filter(|(modifiers, key, _, enabled)| {
            *enabled && ui.input_mut(|i| i.consume_shortcut(&egui::KeyboardShortcut::new(*modifiers, *key)))
        })
        .map(|(_, _, command, _)| command)
        .collect()
}

/// How often a frame looks for a finished automatic proposal while one is computed: quick enough
/// that the model appears without a felt delay (a tenth of a second is below what a user notices
/// after a second of waiting), slow enough to cost nothing while idle.
const PROPOSAL_POLL: std::time::Duration = std::time::Duration::from_millis(100);
/// How often a model being finished is looked for: about a frame at 60 Hz, so the polished model
/// follows the release with no visible wait (an idle frame costs well under a millisecond).
const FINISH_POLL: std::time::Duration = std::time::Duration::from_millis(16);

/// Remove item `index` of `items`, when there is one.
fn remove_at<T>(items: &mut Vec<T>, index: usize) {
    if index < items.len() {
        items.remove(index);
    }
}
