//! Setup changes (segments, clusters, settings, effects and the missing-physics loop) with undo
//! and redo: the part of `App::apply` that records history.
use crate::core::diagnose::TrialId;
use crate::core::identification::cluster::Cluster;
use crate::core::identification::segment::Segment;
use crate::ui::app::App;
use crate::ui::state::setup::{ModelSetup, OutputSetup};

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

    /// The segments of the identification run; `None` detects them again. The Data view's segments
    /// are every output's from then on.
    pub(super) fn set_segments(&mut self, segments: Option<Vec<Segment>>) {
        let status = if segments.is_some() { "Segments changed" } else { "Segments detected again" };
        self.edit_setup(status, |setup| {
            setup.segments = segments;
            setup.outputs.values_mut().for_each(|o| o.segments = None);
        });
    }

    /// The clusters of an output; `None` follows the automatic proposal (see [`carry_dead_time`]).
    pub(super) fn set_clusters(&mut self, output: &str, clusters: Option<Vec<Cluster>>) {
        let status = Self::clusters_status(output, clusters.as_ref().map(Vec::len));
        let proposed = self.cache.output(output).and_then(|o| o.proposal.dead_time_samples());
        self.edit_setup(&status, |setup| carry_dead_time(setup.output_mut(output), clusters, proposed));
    }

    /// The rounds of an output's missing-physics loop (0: off).
    pub(super) fn set_auto_effects(&mut self, output: &str, rounds: usize) {
        let status = match rounds {
            0 => format!("{output}: the missing-physics loop is off"),
            n => format!("{output}: the missing-physics loop runs {n} round(s)"),
        };
        self.edit_setup(&status, |setup| setup.output_mut(output).auto_effects = rounds);
    }

    /// Add what a trial adds to an output's setup (undoable): its catalog effect. A refinement
    /// of the linear block or the map is no block: it is an error shown, with where to make it.
    pub(super) fn apply_effect(&mut self, output: &str, trial: TrialId) {
        let Some(effect) = trial.as_effect() else {
            let err = anyhow::anyhow!(
                "{trial} changes the linear block or the static map itself: add or move a cluster on the \
                 z-plane, or raise the map's order in the output's settings"
            );
            return self.push_error(&err.context(format!("adding {trial} to {output}")));
        };
        let status = format!("{output}: effect {effect} applied");
        self.edit_setup(&status, |setup| {
            let effects = &mut setup.output_mut(output).effects;
            if !effects.contains(&effect) {
                effects.push(effect);
            }
        });
    }

    /// Describe a cluster change for the status bar.
    pub(super) fn clusters_status(output: &str, count: Option<usize>) -> String {
        match count {
            Some(n) => format!("{output}: {n} cluster(s) set"),
            None => format!("{output}: automatic cluster proposal"),
        }
    }
}

/// Set an output's clusters. Leaving the automatic proposal for edited clusters carries the
/// proposal's dead time into the settings (unless one is set), so the edited model keeps the delay
/// the proposal found and the saved project builds the same model in the batch; going back to the
/// proposal drops a dead time that came from it.
fn carry_dead_time(setup: &mut OutputSetup, clusters: Option<Vec<Cluster>>, proposed: Option<usize>) {
    match (&setup.clusters, &clusters) {
        (None, Some(_)) if setup.settings.dead_time_samples.is_none() => {
            setup.settings.dead_time_samples = proposed;
        }
        (Some(_), None) if setup.settings.dead_time_samples == proposed => {
            setup.settings.dead_time_samples = None;
        }
        _ => {}
    }
    setup.clusters = clusters;
}
