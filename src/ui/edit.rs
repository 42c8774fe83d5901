//! Setup changes (segments, clusters, settings) with undo and redo: the part of `App::apply` that
//! records history.
use crate::ui::app::App;
use crate::ui::state::setup::ModelSetup;

impl App {
    /// Change the setup; a change that changes nothing is not recorded. Every real change can be
    /// undone and bumps the session revision.
    pub(super) fn edit_setup(&mut self, what: &str, change: impl FnOnce(&mut ModelSetup)) {
        let mut next = self.session.setup.clone();
        change(&mut next);
        if next == self.session.setup {
            return;
        }
        let before = std::mem::replace(&mut self.session.setup, next);
        self.view.history.record(before);
        self.session.revision += 1;
        self.view.status = Some(what.to_owned());
    }

    pub(super) fn undo(&mut self) {
        match self.view.history.undo(&self.session.setup) {
            Some(previous) => {
                self.session.setup = previous;
                self.session.revision += 1;
                self.view.status = Some("Undone".into());
            }
            None => self.view.status = Some("Nothing to undo".into()),
        }
    }

    pub(super) fn redo(&mut self) {
        match self.view.history.redo(&self.session.setup) {
            Some(next) => {
                self.session.setup = next;
                self.session.revision += 1;
                self.view.status = Some("Redone".into());
            }
            None => self.view.status = Some("Nothing to redo".into()),
        }
    }

    /// Describe a cluster change for the status bar.
    pub(super) fn clusters_status(output: &str, count: Option<usize>) -> String {
        match count {
            Some(n) => format!("{output}: {n} cluster(s) set"),
            None => format!("{output}: automatic cluster proposal"),
        }
    }
}
