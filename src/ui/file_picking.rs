//! Choosing a file: the native dialog on a worker thread while the frame goes on, and the in-app
//! path field where no native dialog can appear; what is chosen becomes a command.
use crate::ui::app::App;
use crate::ui::file_dialog::{PendingPick, PickPoll, PickPurpose};
use crate::ui::path_prompt::PathPrompt;
use crate::ui::state::command::{Command, FileAction};
use crate::ui::state::session::guess_role;

impl App {
    /// A file action whose failure goes to the error window.
    pub(super) fn file_action_shown(&mut self, action: FileAction, path: &std::path::Path) {
        if let Err(err) = self.file_action(action, path) {
            self.push_error(&err);
        }
    }

    /// Use the in-app path field's path. A model or project file that fails keeps the field open
    /// with the error; a run file that fails goes to the load-failure window like any other.
    pub(super) fn submit_path(&mut self) {
        let Some(mut prompt) = self.view.path_prompt.take() else { return };
        let path = prompt.path();
        match prompt.purpose {
            PickPurpose::Runs => {
                let role = guess_role(&path, &self.session);
                self.apply(Command::load(path, role));
            }
            PickPurpose::File(action) => {
                if let Err(err) = self.file_action(action, &path) {
                    self.view.status = Some(format!("{} failed", prompt.title()));
                    prompt.error = Some(format!("{err:#}"));
                    self.view.path_prompt = Some(prompt);
                }
            }
        }
    }

    /// The folder a file dialog starts in: the selected run's.
    pub(super) fn start_dir(&self) -> Option<std::path::PathBuf> {
        self.view
            .selected_run
            .and_then(|i| self.session.runs.get(i))
            .and_then(|r| r.path.parent().map(ToOwned::to_owned))
    }

    /// The in-app path field for `purpose`, starting in the selected run's folder (else the
    /// working folder).
    pub(super) fn open_path_prompt(&mut self, purpose: PickPurpose, note: Option<String>) {
        let dir = self.start_dir().or_else(|| std::env::current_dir().ok()).unwrap_or_default();
        let mut prompt = PathPrompt::new(purpose, &dir);
        prompt.note = note;
        self.view.status = Some(format!("{}: type the path", prompt.title()));
        self.view.path_prompt = Some(prompt);
    }

    pub(super) fn open_picker(&mut self, ctx: &egui::Context, purpose: PickPurpose) {
        if self.view.picker.is_some() || self.view.path_prompt.is_some() {
            return;
        }
        if !self.view.native_dialogs {
            return self.open_path_prompt(purpose, None);
        }
        let start_dir = self.start_dir();
        let ctx = ctx.clone();
        let repaint = move || ctx.request_repaint();
        self.view.picker = Some(match purpose {
            PickPurpose::Runs => PendingPick::open_runs(start_dir, repaint),
            PickPurpose::File(action) => PendingPick::open_file(action, start_dir, repaint),
        });
        self.view.status = Some("Choosing a file…".into());
    }

    pub(super) fn poll_picker(&mut self) {
        let Some(picker) = &self.view.picker else { return };
        let purpose = picker.purpose;
        let paths = match picker.poll() {
            PickPoll::Waiting => return,
            PickPoll::Done(paths) => paths,
            PickPoll::NoDialog => {
                // No dialog came up; ask here from now on.
                self.view.picker = None;
                self.view.native_dialogs = false;
                let note = "The system's file dialog could not be opened.".to_owned();
                return self.open_path_prompt(purpose, Some(note));
            }
        };
        self.view.picker = None;
        self.view.status = None;
        for path in paths {
            let command = match purpose {
                PickPurpose::Runs => Command::load(path.clone(), guess_role(&path, &self.session)),
                PickPurpose::File(action) => action.command(path),
            };
            self.apply(command);
        }
    }
}
