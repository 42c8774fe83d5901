//! The committed or previewed model of one output as every view shows it: the gray-box model, its
//! effects (added by hand and by the missing-physics loop, see [`crate::workflow::model`]), its
//! Bode and its simulation of every scored run.
use std::sync::atomic::{AtomicU64, Ordering};

use crate::core::diagnose::{AutoRound, HistoryStep};
use crate::core::effects::{EffectRecord, ExtendedModel};
use crate::core::identification::error::PipelineError;
use crate::core::identification::pipeline::{GrayBoxModel, RunPrediction};
use crate::core::identification::wiener::WienerModel;
use crate::core::numerics::tf::BodePoint;
use crate::core::run::RunRole;
use crate::ui::derived::jobs::JobError;
use crate::workflow::EffectPlan;

/// Why a derived value (the segments, the segment fits, the model, what a diagnosis needs) is not
/// there; the views show it as it reads.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Unavailable {
    #[error("not computed yet")]
    NotYet,
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
    /// Segments detected on a channel other than the input could not be found.
    #[error("{source} (steps detected on {channel})")]
    StepsOn { channel: String, source: PipelineError },
    #[error("no segments: {0}")]
    NoSegments(Box<Unavailable>),
    #[error("no segment fits: {0}")]
    NoFits(Box<Unavailable>),
    #[error("the automatic proposal is being computed")]
    Proposing,
    #[error("the automatic cluster proposal failed: {0}")]
    ProposalFailed(String),
    #[error("there are no clusters; add a pole cluster or accept the automatic proposal")]
    NoClusters,
    #[error("the model could not be finished: {0}")]
    NotFinished(JobError),
    #[error("no model: {0}")]
    NoModel(Box<Unavailable>),
    #[error("the model is being finished (centroids polished, effects refitted); a moment")]
    Finishing,
    #[error("the model's effects could not be added: {0}")]
    EffectsNotAdded(String),
    #[error("no identification run")]
    NoIdentificationRun,
    #[error("give a run the role validation: the effects are scored on validation runs")]
    NoValidationRun,
}

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
    /// What the setup asks for: effects by hand, in the order they were applied, then the rounds of
    /// the missing-physics loop.
    pub requested: EffectPlan,
    /// The gray-box model with every effect added and refitted; `None` without effects, during a
    /// drag preview, or when an effect could not be added.
    pub model: Option<ExtendedModel>,
    /// Validation RMSPE (mean over the validation runs) after each step: base, +effect, …
    pub history: Vec<HistoryStep>,
    /// What each round of the loop added.
    pub rounds: Vec<AutoRound>,
    /// What was done about sample-alternating poles, in words: the trials the loop refused, the
    /// effects added by hand whose fit gave such a pole up or keeps it.
    pub admissibility: Vec<String>,
    /// What the loop did, in words (the batch's notes).
    pub notes: Vec<String>,
    /// The shaft speed's spool blocks offered to this output's model, and what came of each.
    pub shared: Vec<crate::core::diagnose::SharedBlock>,
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

/// A model's simulation of one scored run.
#[derive(Clone, Debug)]
pub struct ScoredRun {
    /// Index of the run in the session.
    pub index: usize,
    pub name: String,
    pub role: RunRole,
    /// The model's simulation: the gray-box model with its effects, when it has any.
    pub gray_box: RunPrediction,
    /// The gray-box model without its effects (only when effects are in the model).
    pub without_effects: Option<RunPrediction>,
    /// Why the model with effects could not be simulated on this run (`gray_box` is then the
    /// model without effects).
    pub effects_error: Option<String>,
    /// The linear block alone (the "linear" baseline).
    pub linear: Result<RunPrediction, PipelineError>,
}

impl ScoredRun {
    /// The run's name, and its role when the name does not say it.
    pub fn label(&self) -> String {
        if self.name.eq_ignore_ascii_case(self.role.label()) {
            self.name.clone()
        } else {
            format!("{} ({})", self.name, self.role.label())
        }
    }
}

/// The live path's result for one set of clusters.
#[derive(Clone, Debug)]
pub struct LiveModel {
    /// Tells this model from every other one (see [`next_model_id`]).
    pub id: u64,
    pub model: GrayBoxModel,
    /// The effects added to the model, the model with them and the error history.
    pub effects: EffectsOutcome,
    /// Bode of the reduced linear block at the cache's frequency grid.
    pub bode: Vec<BodePoint>,
    pub runs: Vec<ScoredRun>,
    /// The centroids were polished by simulation error (asked for in the settings, not while
    /// dragging).
    pub polish_requested: bool,
    /// The committed model's first look: not polished and without its effects, shown while the
    /// finished model is computed on a worker thread.
    pub finishing: bool,
    /// The bands of the finished model's parameter uncertainty (`Err`: why there are none; a drag
    /// preview and a model being finished have none yet).
    pub uncertainty: Result<std::sync::Arc<crate::ui::derived::uncertainty::ModelUncertainty>, String>,
}

/// A model by value: its Wiener part and its effects with their fitted parameters. A model built
/// again from the same setup (after an Undo, say) has a new [`LiveModel::id`] but the same key, so
/// a result computed for it is still current.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelKey {
    wiener: WienerModel,
    effects: Vec<EffectRecord>,
}

impl LiveModel {
    pub fn key(&self) -> ModelKey {
        let model = self.current_model();
        ModelKey { effects: model.records(), wiener: model.wiener }
    }

    /// Mean gray-box RMSPE over the validation runs (the figure of merit shown while dragging);
    /// the model's effects included.
    pub fn mean_validation_rmspe(&self) -> Option<f64> {
        let values: Vec<f64> = self
            .runs
            .iter()
            .filter(|r| r.role == RunRole::Validation)
            .map(|r| r.gray_box.metrics.rmspe_pct)
            .collect();
        (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
    }

    /// The model as the views show it: with its effects when they could be added.
    pub fn current_model(&self) -> ExtendedModel {
        self.effects.model.clone().unwrap_or_else(|| ExtendedModel::from_gray_box(&self.model))
    }
}
