//! One output's model built from its cache: the committed model (the user's clusters or the
//! automatic proposal's model, polished, with its effects and the missing-physics loop) and, while a
//! cluster is dragged, the [`Preview`] that builds the model of the dragged clusters every frame
//! without polishing the centroids (`refine = false`) and without the effects. Each step is the
//! workflow's ([`crate::workflow::model`]), as in the batch.
//!
//! Everything a build needs is owned ([`ModelInputs`]), so the committed model can be finished on a
//! worker thread (see `model_cache::OutputCache`), with the loop's progress.
//!
//! While a cluster is dragged the preview shows the gray-box model **without** its effects (and
//! says so): refitting the effects every frame would be too slow, and the effect parameters fitted
//! for the previous Wiener part do not fit a moved one (the ambient correction, for one, changes
//! the units the gain is fitted in). The effects are refitted once the drag is committed.
use std::sync::Arc;

use crate::core::effects::ExtendedModel;
use crate::core::identification::cluster::{self, Cluster, ClusterEval};
use crate::core::identification::fits::SegmentFits;
use crate::core::identification::pipeline::{self, LiveResult, live_result};
use crate::core::identification::settings::OutputSettings;
use crate::core::run::{Run, RunRole};
use crate::ui::derived::ident_runs::ScoredSource;
use crate::ui::derived::live_model::{EffectsOutcome, LiveModel, ScoredRun, Unavailable, next_model_id};
use crate::ui::derived::uncertainty;
use crate::workflow::model::{self, EffectPlan, ModelSource};

/// Cluster evaluations and the model, as a cache keeps them.
pub(super) type Built = (Result<Vec<ClusterEval>, Unavailable>, Result<LiveModel, Unavailable>);

/// What building one output's model needs, owned so that a worker thread can do it.
pub(super) struct ModelInputs {
    pub(super) run: Arc<Run>,
    pub(super) fits: Result<Arc<SegmentFits>, Unavailable>,
    pub(super) scored: Vec<ScoredSource>,
    pub(super) omegas_rad_s: Arc<[f64]>,
    pub(super) effects: EffectPlan,
    /// The shaft speed's finished model, whose spool blocks this output's model shares (see
    /// [`model::share_spool`]); `None` for the speed itself or without one.
    pub(super) spool: Option<Arc<ExtendedModel>>,
}

impl ModelInputs {
    /// The model of `source` with `settings`, without its effects. For clusters that give no model
    /// the clusters are still evaluated, so that the z-plane says which cluster fails.
    pub(super) fn build(&self, source: &ModelSource, settings: &OutputSettings) -> Built {
        let fits = match &self.fits {
            Ok(fits) => fits,
            Err(err) => return (Err(err.clone()), Err(err.clone())),
        };
        if let ModelSource::Clusters(clusters) = source
            && clusters.is_empty()
        {
            return (Ok(Vec::new()), Err(Unavailable::NoClusters));
        }
        let runs: Vec<&Run> = self.scored.iter().map(|s| s.run.as_ref()).collect();
        let live = source
            .build(fits, &self.run, settings)
            .and_then(|(model, evals)| live_result(model, evals, fits, settings, &runs, &self.omegas_rad_s));
        match (live, source) {
            (Ok(result), _) => self.split_result(result, settings),
            (Err(err), ModelSource::Clusters(clusters)) => {
                let evals =
                    cluster::evaluate_clusters(clusters, &fits.roots, &settings.cluster, fits.dt_secs)
                        .map_err(|e| Unavailable::Pipeline(e.into()));
                (evals, Err(err.into()))
            }
            (Err(err), ModelSource::Proposal(_)) => (Ok(Vec::new()), Err(err.into())),
        }
    }

    /// [`Self::build`], then the effects added and refitted and the missing-physics loop run
    /// (`progress` gets the loop's fraction done; false cancels it).
    pub(super) fn finish(
        &self,
        source: &ModelSource,
        settings: &OutputSettings,
        progress: &mut dyn FnMut(f64) -> bool,
    ) -> Built {
        let (evals, mut live) = self.build(source, settings);
        if let (Ok(live), Ok(fits)) = (&mut live, &self.fits) {
            self.add_effects(live, fits, settings, progress);
            let runs: Vec<&Run> = self.scored.iter().map(|s| s.run.as_ref()).collect();
            live.uncertainty =
                uncertainty::of(&live.current_model(), fits, &self.run, settings, &runs, &self.omegas_rad_s);
        }
        (evals, live)
    }

    /// Add the effects of the plan to the committed `live` model ([`model::add_effects`], as the
    /// batch does) and simulate the scored runs with the result.
    fn add_effects(
        &self,
        live: &mut LiveModel,
        fits: &SegmentFits,
        settings: &OutputSettings,
        progress: &mut dyn FnMut(f64) -> bool,
    ) {
        let plan = &self.effects;
        let mut outcome = EffectsOutcome { requested: plan.clone(), ..EffectsOutcome::default() };
        if plan.is_empty() && self.spool.is_none() {
            if let Some(rmspe_pct) = live.mean_validation_rmspe() {
                outcome.history.push(crate::core::diagnose::HistoryStep { step: "base".into(), rmspe_pct });
            }
            live.effects = outcome;
            return;
        }
        let output = live.model.output.clone();
        let validation: Vec<&Run> = self
            .scored
            .iter()
            .filter(|scored| scored.role == RunRole::Validation)
            .map(|scored| scored.run.as_ref())
            .collect();
        let mut effects =
            model::add_effects(&live.model, plan, &self.run, fits, settings, &validation, progress);
        if let Some(spool) = &self.spool {
            model::share_spool(&mut effects, spool, settings, &self.run, &validation);
        }
        outcome.history = effects.sequence.history.clone();
        outcome.rounds = effects.rounds.clone();
        outcome.admissibility = effects.sequence.admissibility.clone();
        outcome.notes = effects.notes(&output, plan);
        outcome.shared = effects.shared.clone();
        if let Err(err) = effects.check(&output) {
            outcome.problems.push(err.to_string());
            live.effects = outcome;
            return;
        }
        let model = effects.sequence.model;
        for (scored, source) in live.runs.iter_mut().zip(&self.scored) {
            let run = &source.run;
            let prediction = model
                .simulate_scored(run, settings.initial_state)
                .map_err(|e| e.to_string())
                .and_then(|y_hat| pipeline::score(run, &output, y_hat).map_err(|e| e.to_string()));
            match prediction {
                Ok(p) => scored.without_effects = Some(std::mem::replace(&mut scored.gray_box, p)),
                Err(err) => {
                    outcome.problems.push(format!(
                        "run {}: {err}; the model without effects is shown for it",
                        scored.name
                    ));
                    scored.effects_error = Some(err);
                }
            }
        }
        outcome.model = Some(model);
        live.effects = outcome;
    }

    /// The core's live result as the cache keeps it: the evaluations apart, the model with its runs.
    fn split_result(&self, mut result: LiveResult, settings: &OutputSettings) -> Built {
        let evals = std::mem::take(&mut result.evals);
        (Ok(evals), Ok(self.live_model(result, settings)))
    }

    fn live_model(&self, result: LiveResult, settings: &OutputSettings) -> LiveModel {
        let scored = self
            .scored
            .iter()
            .zip(result.predictions.into_iter().zip(result.linear))
            .map(|(source, (gray_box, linear))| ScoredRun {
                index: source.index,
                name: source.run.name.clone(),
                role: source.role,
                linear: Ok(linear),
                gray_box,
                without_effects: None,
                effects_error: None,
            })
            .collect();
        LiveModel {
            id: next_model_id(),
            effects: EffectsOutcome { requested: self.effects.clone(), ..EffectsOutcome::default() },
            model: result.model,
            bode: result.bode,
            runs: scored,
            polish_requested: settings.refine,
            finishing: false,
            uncertainty: Err("the parameter uncertainty is computed once the model is finished".to_owned()),
        }
    }
}

/// The live path on clusters being dragged (not yet committed).
pub struct Preview {
    pub output: String,
    pub clusters: Vec<Cluster>,
    pub evals: Result<Vec<ClusterEval>, Unavailable>,
    pub live: Result<LiveModel, Unavailable>,
}

impl Preview {
    /// The model of `clusters` for `output` from `inputs`, without polishing (fast enough for every
    /// frame) and without the effects.
    pub(super) fn compute(
        inputs: &ModelInputs,
        output: &str,
        clusters: Vec<Cluster>,
        settings: &OutputSettings,
    ) -> Self {
        let (evals, mut live) = inputs.build(&ModelSource::Clusters(clusters.clone()), settings);
        if let Ok(live) = &mut live {
            live.effects.left_out_for_preview = !live.effects.requested.is_empty();
        }
        Self { output: output.to_owned(), clusters, evals, live }
    }
}
