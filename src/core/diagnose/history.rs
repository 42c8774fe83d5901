//! The model's effects added one after another, each refitted on the identification data, with the
//! validation error after every step: the error history the batch reports and the app draws.
use serde::{Deserialize, Serialize};

use crate::core::effects::{EffectId, ExtendedModel};
use crate::core::identification::fits::SegmentFits;
use crate::core::identification::settings::OutputSettings;
use crate::core::run::Run;

use super::{
    DiagnoseError, DiagnosisKind, DiagnosisReport, Edit, TrialId, diagnose_with_progress, edit,
    validation_rmspe,
};

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
    /// The diagnosis of `model` on the validation runs, when the missing-physics loop ended on it
    /// (nothing further significant): the same report a diagnosis of the final model would give.
    pub final_diagnosis: Option<DiagnosisReport>,
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
    let mut sequence = EffectSequence {
        model: base.clone(),
        history: Vec::new(),
        history_gaps: Vec::new(),
        failed: None,
        final_diagnosis: None,
    };
    sequence.record("base", validation, settings);
    for &id in ids {
        match edit(&sequence.model, Edit::Add(id), ident, fits, settings) {
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

/// One round of the missing-physics loop: what the diagnosis ranked first among the significant
/// entries and was added, with its evidence.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AutoRound {
    /// The effect or structural refinement added.
    pub added: TrialId,
    /// Physics or structure.
    pub kind: DiagnosisKind,
    /// Validation RMSPE before and after, %.
    pub rmspe_before_pct: f64,
    pub rmspe_after_pct: f64,
    /// The evidence sentence the diagnosis gave for it.
    pub evidence: String,
    /// What made it significant: the witnesses' tests, in words (see [`super::Comparison::words`]).
    pub significance: String,
    /// When that round's diagnosis could not tell it from another explanation: both, with the
    /// numbers, why this one was taken and the experiment that would separate them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub attribution: Option<String>,
}

/// The missing-physics loop run on `sequence`'s model for up to `rounds` rounds: diagnose, add the
/// top significant entry (physics or structure, already refitted on the identification data by the
/// diagnosis), record the validation error, repeat. Stops early when nothing is significant; every
/// choice is made on `validation`, so held-out runs stay a fair test. Returns the rounds taken.
/// `progress` gets the fraction of the rounds done (0..=1); when it returns false the loop stops
/// with [`DiagnoseError::Cancelled`].
pub fn auto_effects(
    sequence: &mut EffectSequence,
    rounds: usize,
    ident: &Run,
    fits: &SegmentFits,
    settings: &OutputSettings,
    validation: &[&Run],
    progress: &mut dyn FnMut(f64) -> bool,
) -> Result<Vec<AutoRound>, DiagnoseError> {
    let mut taken = Vec::new();
    for round in 0..rounds {
        let mut round_progress = |f: f64| progress((round as f64 + f) / rounds as f64);
        let report =
            diagnose_with_progress(&sequence.model, ident, fits, validation, settings, &mut round_progress)?;
        let Some(top) = report.entries.iter().find(|d| d.significant) else {
            sequence.final_diagnosis = Some(report);
            break;
        };
        taken.push(AutoRound {
            added: top.effect,
            kind: top.kind,
            rmspe_before_pct: top.rmspe_before_pct,
            rmspe_after_pct: top.rmspe_after_pct,
            evidence: top.evidence.clone(),
            significance: top.significance_words(),
            attribution: report.attribution_note.clone(),
        });
        sequence.model = top.model.clone();
        sequence.record(&format!("+{} (auto)", top.effect), validation, settings);
    }
    Ok(taken)
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
