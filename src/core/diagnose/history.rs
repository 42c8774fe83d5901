//! The model's effects added one after another, each refitted on the identification data, with the
//! validation error after every step: the error history the batch reports and the app draws.
use serde::{Deserialize, Serialize};

use crate::core::effects::{EffectId, ExtendedModel};
use crate::core::identification::pipeline::{OutputSettings, SegmentFits};
use crate::core::run::Run;

use super::{DiagnoseError, apply, validation_rmspe};

/// The mean validation RMSPE of the model after one step ("base", "+thermal_soak", …).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HistoryStep {
    pub step: String,
    pub rmspe_pct: f64,
}

/// The model after adding a list of effects in order.
#[derive(Clone, Debug)]
pub struct EffectSequence {
    /// The model after the last effect that could be added.
    pub model: ExtendedModel,
    /// The validation error after each step, base first; a step whose error cannot be computed
    /// (or with no validation run) has none.
    pub history: Vec<HistoryStep>,
    /// Why a step has no validation error, in words.
    pub history_gaps: Vec<String>,
    /// The effect that could not be added, and why; the effects after it were not tried.
    pub failed: Option<(EffectId, DiagnoseError)>,
}

/// Add `ids` to `base` in order, each refitted on the identification data (`ident`, `fits`), and
/// score the model on `validation` after every step.
pub fn apply_in_order(
    base: &ExtendedModel,
    ids: &[EffectId],
    ident: &Run,
    fits: &SegmentFits,
    settings: &OutputSettings,
    validation: &[&Run],
) -> EffectSequence {
    let mut sequence =
        EffectSequence { model: base.clone(), history: Vec::new(), history_gaps: Vec::new(), failed: None };
    sequence.record("base", validation, settings);
    for &id in ids {
        match apply(&sequence.model, id, ident, fits, settings) {
            Ok(next) => sequence.model = next,
            Err(err) => {
                sequence.failed = Some((id, err));
                break;
            }
        }
        sequence.record(&format!("+{id}"), validation, settings);
    }
    sequence
}

impl EffectSequence {
    fn record(&mut self, step: &str, validation: &[&Run], settings: &OutputSettings) {
        if validation.is_empty() {
            return;
        }
        match validation_rmspe(&self.model, validation, settings.initial_state) {
            Ok(rmspe_pct) => self.history.push(HistoryStep { step: step.to_owned(), rmspe_pct }),
            Err(e) => self.history_gaps.push(format!("no validation error after {step}: {e}")),
        }
    }
}
