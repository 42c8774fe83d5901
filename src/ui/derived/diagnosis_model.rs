//! The model with its effects, as every view shows it, and what the Diagnosis view needs from the
//! cache.
//!
//! After the committed gray-box model of an output is built, the effects of its setup are added in
//! the order the user applied them, each refitted on the identification data
//! ([`diagnose::apply`], as `jetid --batch` does with `add_effects`), and the validation error is
//! recorded after every step (the error history). The scored runs are then simulated with the
//! extended model: their `gray_box` prediction is the model's, the one without effects is kept
//! beside it.
//!
//! While a cluster is dragged the preview shows the gray-box model **without** its effects (and
//! says so): refitting the effects every frame would be too slow, and the effect parameters fitted
//! for the previous Wiener part do not fit a moved one (the ambient correction, for one, changes
//! the units the gain is fitted in). The effects are refitted once the drag is committed.
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::core::diagnose;
use crate::core::diagnose::HistoryStep;
use crate::core::effects::{EffectId, ExtendedModel};
use crate::core::identification::pipeline::{self, OutputSettings, SegmentFits};
use crate::core::run::Run;

use crate::ui::derived::live_model::ModelKey;
use crate::ui::derived::model_cache::LiveModel;
use crate::ui::state::session::Role;

/// Every live model gets its own id, so that results computed for a model (the diagnosis, the
/// residual analysis) can tell when they are stale.
static NEXT_MODEL_ID: AtomicU64 = AtomicU64::new(1);

/// A new model id.
pub fn next_model_id() -> u64 {
    NEXT_MODEL_ID.fetch_add(1, Ordering::Relaxed)
}

/// The effects of one output's model.
#[derive(Clone, Debug, Default)]
pub struct EffectsOutcome {
    /// The effect ids the setup asks for, in the order they were applied.
    pub requested: Vec<EffectId>,
    /// The gray-box model with every requested effect added and refitted; `None` without effects,
    /// during a drag preview, or when an effect could not be added.
    pub model: Option<ExtendedModel>,
    /// Validation RMSPE (mean over the validation runs) after each step: base, +effect, …
    pub history: Vec<HistoryStep>,
    /// What went wrong (an effect that could not be added, a run the model cannot simulate).
    pub problems: Vec<String>,
    /// The model is a drag preview: the effects are left out until the drag is committed.
    pub left_out_for_preview: bool,
}

impl EffectsOutcome {
    /// True when the setup asks for effects but the model shown does not (fully) hold them.
    pub fn incomplete(&self) -> bool {
        !self.requested.is_empty() && (self.model.is_none() || !self.problems.is_empty())
    }
}

/// Add the effects `ids` to the committed `live` model and simulate the scored runs with the
/// result. `runs` are the scored runs, in the order of `live.runs`.
pub(super) fn apply_effects(
    live: &mut LiveModel,
    ids: &[EffectId],
    ident: &Run,
    fits: &SegmentFits,
    settings: &OutputSettings,
    runs: &[Arc<Run>],
) {
    let mut outcome = EffectsOutcome { requested: ids.to_vec(), ..EffectsOutcome::default() };
    if ids.is_empty() {
        if let Some(rmspe_pct) = live.mean_validation_rmspe() {
            outcome.history.push(HistoryStep { step: "base".into(), rmspe_pct });
        }
        live.effects = outcome;
        return;
    }
    let output = live.model.output.clone();
    let validation: Vec<&Run> = live
        .runs
        .iter()
        .zip(runs)
        .filter(|(scored, _)| scored.role == Role::Validation)
        .map(|(_, run)| run.as_ref())
        .collect();
    let base = ExtendedModel::from_gray_box(&live.model);
    let sequence = diagnose::apply_in_order(&base, ids, ident, fits, settings, &validation);
    outcome.history = sequence.history;
    outcome.problems = sequence.history_gaps;
    if let Some((id, err)) = sequence.failed {
        outcome.problems.push(format!("the effect {id} could not be added: {err}"));
        live.effects = outcome;
        return;
    }
    let model = sequence.model;
    for (scored, run) in live.runs.iter_mut().zip(runs) {
        let prediction = model
            .simulate_scored(run, settings.initial_state)
            .map_err(|e| e.to_string())
            .and_then(|y_hat| pipeline::score(run, &output, y_hat).map_err(|e| e.to_string()));
        match prediction {
            Ok(p) => scored.without_effects = Some(std::mem::replace(&mut scored.gray_box, p)),
            Err(err) => {
                outcome
                    .problems
                    .push(format!("run {}: {err}; the model without effects is shown for it", scored.name));
                scored.effects_error = Some(err);
            }
        }
    }
    outcome.model = Some(model);
    live.effects = outcome;
}

/// What a diagnosis of one output's current model needs (owned, for a worker thread).
#[derive(Clone)]
pub struct DiagnosisInput {
    /// The model the diagnosis is for.
    pub model: ModelKey,
    pub output: String,
    /// The model as the views show it (with its effects).
    pub current: ExtendedModel,
    pub ident: Arc<Run>,
    pub fits: Arc<SegmentFits>,
    pub validation: Vec<Arc<Run>>,
    pub settings: OutputSettings,
}

impl DiagnosisInput {
    /// Rank the catalog's effects on this model (see [`diagnose::diagnose`]).
    pub fn run(
        &self,
        progress: &mut dyn FnMut(f64) -> bool,
    ) -> Result<diagnose::DiagnosisReport, diagnose::DiagnoseError> {
        let validation: Vec<&Run> = self.validation.iter().map(AsRef::as_ref).collect();
        diagnose::diagnose_with_progress(
            &self.current,
            &self.ident,
            &self.fits,
            &validation,
            &self.settings,
            progress,
        )
    }
}
