//! The user's identification decisions: the segments of the identification run and, per output,
//! its settings, clusters and applied effects. This is the part of the session that undo and redo
//! step through.
use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::core::effects::EffectId;
use crate::core::identification::cluster::Cluster;
use crate::core::identification::segment::Segment;
use crate::core::identification::settings::OutputSettings;

/// Segments, and per output its settings, clusters and effects.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ModelSetup {
    /// Segments of the identification run (sample indices); `None`: detected from the input.
    pub segments: Option<Vec<Segment>>,
    /// Detect the steps on this channel of the identification run rather than on its input (a
    /// project's `steps_from`: closed-loop data, or an input sensor with dropouts).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steps_from: Option<String>,
    /// By output column name. An output without an entry uses [`OutputSetup::for_output`].
    pub outputs: BTreeMap<String, OutputSetup>,
    /// The outputs to model (a project's `outputs`); empty: every output of the identification run.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub modelled: Vec<String>,
}

/// What the user decided for one output.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OutputSetup {
    pub settings: OutputSettings,
    /// `None`: the automatic proposal for the current segment fits (it follows the fits when the
    /// segments or orders change); `Some`: the user's clusters, kept as they are.
    #[serde(default)]
    pub clusters: Option<Vec<Cluster>>,
    /// Effects of the missing-physics catalog added to the model, by id, in the order the user
    /// applied them (each refitted on the identification data in turn).
    #[serde(default)]
    pub effects: Vec<EffectId>,
    /// Rounds of the missing-physics loop run after them (a project's `auto_effects`): diagnose,
    /// add the top significant effect or refinement, repeat (see `workflow::model::add_effects`).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub auto_effects: usize,
    /// This output's own segments, when a project gives the outputs different ones (`None`: the
    /// setup's segments, which the Data view shows and edits).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub segments: Option<Vec<Segment>>,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

impl OutputSetup {
    /// The defaults for an output of this name (the paper's ARX orders, automatic clusters).
    pub fn for_output(name: &str) -> Self {
        Self {
            settings: OutputSettings::for_output(name),
            clusters: None,
            effects: Vec::new(),
            auto_effects: 0,
            segments: None,
        }
    }
}

impl ModelSetup {
    /// The setup of an output (its defaults when the user has not changed anything).
    pub fn output(&self, name: &str) -> OutputSetup {
        self.outputs.get(name).cloned().unwrap_or_else(|| OutputSetup::for_output(name))
    }

    /// Whether the output `name` is modelled (the project's `outputs`, else every output).
    pub fn is_modelled(&self, name: &str) -> bool {
        self.modelled.is_empty() || self.modelled.iter().any(|o| o == name)
    }

    /// The setup of an output, to change it.
    pub fn output_mut(&mut self, name: &str) -> &mut OutputSetup {
        self.outputs.entry(name.to_owned()).or_insert_with(|| OutputSetup::for_output(name))
    }
}

/// Undo and redo of [`ModelSetup`] changes: whole snapshots (a setup is a few kB).
#[derive(Debug, Default)]
pub struct History {
    undo: Vec<ModelSetup>,
    redo: Vec<ModelSetup>,
}

impl History {
    /// Steps kept; the oldest are dropped beyond this.
    const LIMIT: usize = 200;

    /// Remember the setup as it was before a change; a new change clears the redo list.
    pub fn record(&mut self, before: ModelSetup) {
        self.undo.push(before);
        if self.undo.len() > Self::LIMIT {
            self.undo.remove(0);
        }
        self.redo.clear();
    }

    /// The setup to go back to, given the current one (which becomes redoable).
    pub fn undo(&mut self, current: &ModelSetup) -> Option<ModelSetup> {
        let previous = self.undo.pop()?;
        self.redo.push(current.clone());
        Some(previous)
    }

    /// The setup to go forward to, given the current one (which becomes undoable).
    pub fn redo(&mut self, current: &ModelSetup) -> Option<ModelSetup> {
        let next = self.redo.pop()?;
        self.undo.push(current.clone());
        Some(next)
    }

    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }

    /// Forget everything (a new project replaces the session).
    pub fn clear(&mut self) {
        self.undo.clear();
        self.redo.clear();
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn setup_with_order(na: usize) -> ModelSetup {
        let mut setup = ModelSetup::default();
        setup.output_mut("y").settings.orders.na = na;
        setup
    }

    #[test]
    fn undo_and_redo_walk_the_snapshots() {
        let mut history = History::default();
        let (a, b, c) = (setup_with_order(1), setup_with_order(2), setup_with_order(3));
        history.record(a.clone());
        history.record(b.clone());
        assert_eq!(history.undo(&c), Some(b.clone()));
        assert_eq!(history.undo(&b), Some(a.clone()));
        assert_eq!(history.undo(&a), None);
        assert_eq!(history.redo(&a), Some(b.clone()));
        assert_eq!(history.redo(&b), Some(c.clone()));
        assert!(!history.can_redo());
        // A new change after an undo drops the redo list.
        history.undo(&c);
        history.record(b);
        assert!(!history.can_redo());
    }
}
