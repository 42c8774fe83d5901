//! The committed or previewed model of one output as every view shows it: the gray-box model, its
//! effects, its Bode and its simulation of every scored run.
use crate::core::effects::EffectRecord;
use crate::core::identification::pipeline::{GrayBoxModel, RunPrediction};
use crate::core::identification::wiener::WienerModel;
use crate::core::numerics::tf::BodePoint;
use crate::ui::derived::diagnosis_model::EffectsOutcome;
use crate::ui::state::session::Role;

/// A model's simulation of one scored run.
#[derive(Clone, Debug)]
pub struct ScoredRun {
    /// Index of the run in the session.
    pub index: usize,
    pub name: String,
    pub role: Role,
    /// The model's simulation: the gray-box model with its effects, when it has any.
    pub gray_box: RunPrediction,
    /// The gray-box model without its effects (only when effects are in the model).
    pub without_effects: Option<RunPrediction>,
    /// Why the model with effects could not be simulated on this run (`gray_box` is then the
    /// model without effects).
    pub effects_error: Option<String>,
    /// The linear block alone (the "linear" baseline).
    pub linear: Result<RunPrediction, String>,
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
    /// Tells this model from every other one (see [`crate::ui::derived::diagnosis_model::next_model_id`]).
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
            .filter(|r| r.role == Role::Validation)
            .map(|r| r.gray_box.metrics.rmspe_pct)
            .collect();
        (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
    }

    /// The model as the views show it: with its effects when they could be added.
    pub fn current_model(&self) -> crate::core::effects::ExtendedModel {
        self.effects
            .model
            .clone()
            .unwrap_or_else(|| crate::core::effects::ExtendedModel::from_gray_box(&self.model))
    }
}
