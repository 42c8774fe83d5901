//! One output's model built from its cache: the committed model (the user's clusters or the
//! automatic proposal's model, polished and with its effects) and, while a cluster is dragged, the
//! [`Preview`] that runs the live path on the dragged clusters every frame without polishing the
//! centroids (`refine = false`) and without the effects.
//!
//! Everything a build needs is owned ([`ModelInputs`]), so the committed model can be finished on a
//! worker thread (see [`OutputCache`](super::model_cache::OutputCache)); the effects are added as in
//! [`diagnosis_model`](super::diagnosis_model).
use std::sync::Arc;

use crate::core::effects::EffectId;
use crate::core::identification::cluster::{self, Cluster, ClusterEval};
use crate::core::identification::pipeline::{
    LiveResult, OutputSettings, SegmentFits, live_update, live_update_proposed,
};
use crate::core::identification::structure::Proposal;
use crate::core::run::Run;
use crate::ui::derived::diagnosis_model::{self, EffectsOutcome};
use crate::ui::derived::ident_runs::ScoredSource;
use crate::ui::derived::live_model::{LiveModel, ScoredRun};
use crate::ui::derived::model_cache::IdentCache;

/// The model a cache builds: the user's clusters, or the automatic proposal's model.
pub(super) enum ModelSource {
    Clusters(Vec<Cluster>),
    Proposal(Arc<Proposal>),
}

impl ModelSource {
    pub(super) fn clusters(&self) -> Vec<Cluster> {
        match self {
            Self::Clusters(clusters) => clusters.clone(),
            Self::Proposal(proposal) => proposal.clusters.clone(),
        }
    }
}

/// Cluster evaluations and the model, as a cache keeps them.
pub(super) type Built = (Result<Vec<ClusterEval>, String>, Result<LiveModel, String>);

/// What building one output's model needs, owned so that a worker thread can do it.
pub(super) struct ModelInputs {
    pub(super) run: Arc<Run>,
    pub(super) fits: Result<Arc<SegmentFits>, String>,
    pub(super) scored: Vec<ScoredSource>,
    pub(super) omegas_rad_s: Arc<[f64]>,
    pub(super) effects: Vec<EffectId>,
}

impl ModelInputs {
    /// The model of `source` with `settings`, without its effects.
    pub(super) fn build(&self, source: &ModelSource, settings: &OutputSettings) -> Built {
        match source {
            ModelSource::Clusters(clusters) => self.evaluate(clusters, settings),
            ModelSource::Proposal(proposal) => self.evaluate_proposal(proposal, settings),
        }
    }

    /// [`Self::build`], then the effects added and refitted.
    pub(super) fn finish(&self, source: &ModelSource, settings: &OutputSettings) -> Built {
        let (evals, mut live) = self.build(source, settings);
        if let (Ok(live), Ok(fits)) = (&mut live, &self.fits) {
            let runs: Vec<Arc<Run>> = self.scored.iter().map(|s| Arc::clone(&s.run)).collect();
            diagnosis_model::apply_effects(live, &self.effects, &self.run, fits, settings, &runs);
        }
        (evals, live)
    }

    /// Cluster evaluations and the live path for `clusters` with `settings`: one core call, which
    /// evaluates the clusters once; only when it gives no model are the clusters evaluated alone, so
    /// that the z-plane still says which cluster fails.
    fn evaluate(&self, clusters: &[Cluster], settings: &OutputSettings) -> Built {
        let fits = match &self.fits {
            Ok(fits) => fits,
            Err(err) => return (Err(err.clone()), Err(err.clone())),
        };
        if clusters.is_empty() {
            let why = "there are no clusters; add a pole cluster or accept the automatic proposal".to_owned();
            return (Ok(Vec::new()), Err(why));
        }
        let runs: Vec<&Run> = self.scored.iter().map(|s| s.run.as_ref()).collect();
        match live_update(fits, &self.run, clusters, settings, &runs, &self.omegas_rad_s) {
            Ok(result) => self.split_result(result, settings),
            Err(err) => {
                let evals =
                    cluster::evaluate_clusters(clusters, &fits.roots, &settings.cluster, fits.dt_secs)
                        .map_err(|e| e.to_string());
                (evals, Err(err.to_string()))
            }
        }
    }

    /// The model of the automatic proposal (its clusters with its dead time, or its direct fit).
    fn evaluate_proposal(&self, proposal: &Proposal, settings: &OutputSettings) -> Built {
        let fits = match &self.fits {
            Ok(fits) => fits,
            Err(err) => return (Err(err.clone()), Err(err.clone())),
        };
        let runs: Vec<&Run> = self.scored.iter().map(|s| s.run.as_ref()).collect();
        match live_update_proposed(fits, &self.run, proposal, settings, &runs, &self.omegas_rad_s) {
            Ok(result) => self.split_result(result, settings),
            Err(err) => (Ok(Vec::new()), Err(err.to_string())),
        }
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
            id: diagnosis_model::next_model_id(),
            effects: EffectsOutcome { requested: self.effects.clone(), ..EffectsOutcome::default() },
            model: result.model,
            bode: result.bode,
            runs: scored,
            polish_requested: settings.refine,
            finishing: false,
        }
    }
}

/// The live path on clusters being dragged (not yet committed).
pub struct Preview {
    pub output: String,
    pub clusters: Vec<Cluster>,
    pub evals: Result<Vec<ClusterEval>, String>,
    pub live: Result<LiveModel, String>,
}

impl Preview {
    /// The live path on `clusters` for `output`, without polishing (fast enough for every frame).
    pub fn compute(ident: &IdentCache, output: &str, clusters: Vec<Cluster>) -> Option<Self> {
        let cache = ident.output(output)?;
        let (evals, mut live) = cache.inputs(&ident.run).evaluate(&clusters, &cache.preview_settings());
        if let Ok(live) = &mut live {
            live.effects.left_out_for_preview = !live.effects.requested.is_empty();
        }
        Some(Self { output: output.to_owned(), clusters, evals, live })
    }
}
