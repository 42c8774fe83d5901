//! The gray-box identification of one output, end to end, split so that the expensive part (the
//! segment ARX fits) is done once and the live part (clusters → reduced model → static map →
//! validation → Bode → metrics) can run on every drag.
use serde::{Deserialize, Serialize};

use crate::core::identification::cluster::{self, Cluster, ClusterEval, RootKind};
use crate::core::identification::initial_state::{InitialState, fit_free_response};
use crate::core::identification::reduce::{self, IdentData, RootGroup};
use crate::core::identification::refine::Refinement;
use crate::core::identification::segment::Segment;
use crate::core::identification::static_map::{OrderSuggestion, StaticMap};
use crate::core::identification::structure::{self, Proposal};
use crate::core::identification::uncertainty::{self, RootInterval};
use crate::core::identification::wiener::{LinearBlock, WienerError, WienerModel};
use crate::core::numerics::metrics::{Metrics, metrics};
use crate::core::numerics::tf::BodePoint;
use crate::core::run::Run;

use crate::core::identification::error::PipelineError;
use crate::core::identification::fits::{SegmentFits, fit_segments_for, output_values};
use crate::core::identification::settings::OutputSettings;

/// The reduced model of one output: clusters, linear block, static map and how they were chosen.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GrayBoxModel {
    pub output: String,
    pub clusters: Vec<Cluster>,
    pub wiener: WienerModel,
    /// The roots of the linear block as the model uses them (polished), each with the cluster it
    /// came from; free roots when the model was fitted directly.
    #[serde(default)]
    pub roots: Vec<RootGroup>,
    /// Steady-state points (v, y) the static map was fitted to.
    pub steady_points: Vec<(f64, f64)>,
    pub static_suggestion: Option<OrderSuggestion>,
    /// Present when the roots were polished by simulation error.
    pub refinement: Option<Refinement>,
    /// Why the model was fitted directly rather than built from clusters, when it was.
    #[serde(default)]
    pub direct_fit: Option<String>,
    /// 95 % intervals of each root's s-plane figures, in the order of `roots` (see
    /// `core::identification::uncertainty`): filled by [`identify_output`], the path that reports
    /// them, not on the live path the app rebuilds on every drag; empty when the data do not fix
    /// the roots.
    #[serde(default)]
    pub root_intervals: Vec<RootInterval>,
}

/// Clusters → reduced linear block (each root polished inside its cluster) → static map.
pub fn build_gray_box(
    fits: &SegmentFits,
    ident: &Run,
    clusters: &[Cluster],
    settings: &OutputSettings,
) -> Result<(GrayBoxModel, Vec<ClusterEval>), PipelineError> {
    let evals = cluster::evaluate_clusters(clusters, &fits.roots, &settings.cluster, fits.dt_secs)?;
    let groups: Vec<RootGroup> = evals
        .iter()
        .enumerate()
        .filter(|(_, e)| e.valid)
        .map(|(i, e)| RootGroup::of_cluster(i, e).within(settings.polish))
        .collect();
    if groups.iter().all(|g| g.kind != RootKind::Pole) {
        return Err(PipelineError::Wiener(WienerError::NoPoles));
    }
    let data = IdentData::new(fits, ident, settings)?;
    let model = model_of_groups(&data, &groups, clusters, None)?;
    Ok((model, evals))
}

/// The Wiener model of root groups on the identification range: assembled with the static-map order
/// leave-one-out chooses (or the settings fix), then polished when the settings ask for it.
fn model_of_groups(
    data: &IdentData,
    groups: &[RootGroup],
    clusters: &[Cluster],
    direct_fit: Option<String>,
) -> Result<GrayBoxModel, PipelineError> {
    let first = reduce::assemble_groups(data, groups, data.settings.static_order)?;
    let order = first.wiener.map.order();
    let polished = if data.settings.refine { reduce::polish(data, groups, order) } else { None };
    let (assembled, roots, refinement) = match polished {
        Some(p) if p.refinement.rms_after < p.refinement.rms_before => {
            (p.assembled, p.groups, Some(p.refinement))
        }
        _ => (first.clone(), groups.to_vec(), None),
    };
    Ok(GrayBoxModel {
        root_intervals: Vec::new(),
        output: data.fits.output.clone(),
        clusters: clusters.to_vec(),
        wiener: assembled.wiener,
        roots,
        steady_points: assembled.steady_points,
        static_suggestion: first.suggestion,
        refinement,
        direct_fit,
    })
}

/// The automatic proposal for these fits: candidate clusters, which of them the model keeps and
/// why, or the direct fit when none gives a model (see `core::identification::structure`).
pub fn propose(
    fits: &SegmentFits,
    ident: &Run,
    settings: &OutputSettings,
) -> Result<Proposal, PipelineError> {
    structure::propose(fits, ident, settings)
}

/// The model of an automatic proposal: built from its clusters, or its direct fit.
pub fn build_proposed(
    fits: &SegmentFits,
    ident: &Run,
    proposal: &Proposal,
    settings: &OutputSettings,
) -> Result<(GrayBoxModel, Vec<ClusterEval>), PipelineError> {
    match &proposal.direct {
        Some(direct) => {
            let data = IdentData::new(fits, ident, settings)?;
            let model = model_of_groups(&data, &direct.groups, &[], Some(direct.note.clone()))?;
            Ok((model, Vec::new()))
        }
        None => {
            let settings =
                OutputSettings { dead_time_samples: Some(proposal.dead_time.in_model()), ..settings.clone() };
            build_gray_box(fits, ident, &proposal.clusters, &settings)
        }
    }
}

/// A model's simulation of one run and its metrics.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunPrediction {
    pub run: String,
    pub y_hat: Vec<f64>,
    pub metrics: Metrics,
}

/// Simulate a linear block alone (the "linear" model) on a run.
pub fn predict_linear(block: &LinearBlock, run: &Run, output: &str) -> Result<RunPrediction, PipelineError> {
    score(run, output, block.simulate(&run.input.values))
}

/// Simulate the Wiener model on a run from its input alone.
pub fn predict_wiener(model: &WienerModel, run: &Run, output: &str) -> Result<RunPrediction, PipelineError> {
    score(run, output, model.simulate(&run.input.values).1)
}

/// Simulate the Wiener model on a run to score it, started as `initial` says (see
/// `core::identification::initial_state`); the same numbers as the comparison's gray-box row.
pub fn predict_scored(
    model: &WienerModel,
    run: &Run,
    output: &str,
    initial: InitialState,
) -> Result<RunPrediction, PipelineError> {
    let y = output_values(run, output)?;
    let v = model.linear.simulate(&run.input.values);
    let y_hat = match initial {
        InitialState::Steady => v.iter().map(|x| model.map.eval(*x)).collect(),
        InitialState::Estimated => {
            let poles = model.linear.tf.poles().unwrap_or_default();
            let through_map = |v: &[f64]| v.iter().map(|x| model.map.eval(*x)).collect::<Vec<f64>>();
            through_map(&fit_free_response(&poles, &v, y, through_map))
        }
    };
    score(run, output, y_hat)
}

pub fn score(run: &Run, output: &str, y_hat: Vec<f64>) -> Result<RunPrediction, PipelineError> {
    let y = output_values(run, output)?;
    let m = metrics(y, &y_hat).map_err(|source| PipelineError::Metrics { run: run.name.clone(), source })?;
    Ok(RunPrediction { run: run.name.clone(), y_hat, metrics: m })
}

/// Everything the app redraws after a cluster change.
#[derive(Clone, Debug, PartialEq)]
pub struct LiveResult {
    pub model: GrayBoxModel,
    pub evals: Vec<ClusterEval>,
    /// The gray-box model on every validation run, started as `settings.initial_state` says.
    pub predictions: Vec<RunPrediction>,
    /// The linear block alone on every validation run, started the same way.
    pub linear: Vec<RunPrediction>,
    pub bode: Vec<BodePoint>,
}

/// The live path: clusters → model → simulation and metrics of every validation run → Bode.
pub fn live_update(
    fits: &SegmentFits,
    ident: &Run,
    clusters: &[Cluster],
    settings: &OutputSettings,
    validation: &[&Run],
    omegas_rad_s: &[f64],
) -> Result<LiveResult, PipelineError> {
    let (model, evals) = build_gray_box(fits, ident, clusters, settings)?;
    live_result(model, evals, fits, settings, validation, omegas_rad_s)
}

/// [`live_update`] for the model of an automatic proposal (see [`build_proposed`]).
pub fn live_update_proposed(
    fits: &SegmentFits,
    ident: &Run,
    proposal: &Proposal,
    settings: &OutputSettings,
    validation: &[&Run],
    omegas_rad_s: &[f64],
) -> Result<LiveResult, PipelineError> {
    let (model, evals) = build_proposed(fits, ident, proposal, settings)?;
    live_result(model, evals, fits, settings, validation, omegas_rad_s)
}

/// What the app redraws for a built model: its simulation and the linear block's of every run
/// (started as `settings.initial_state` says), and its Bode at `omegas_rad_s`.
pub fn live_result(
    model: GrayBoxModel,
    evals: Vec<ClusterEval>,
    fits: &SegmentFits,
    settings: &OutputSettings,
    validation: &[&Run],
    omegas_rad_s: &[f64],
) -> Result<LiveResult, PipelineError> {
    let initial = settings.initial_state;
    let predictions = validation
        .iter()
        .map(|run| predict_scored(&model.wiener, run, &fits.output, initial))
        .collect::<Result<Vec<_>, _>>()?;
    let linear = validation
        .iter()
        .map(|run| {
            let y = output_values(run, &fits.output)?;
            score(run, &fits.output, model.wiener.linear.simulate_scored(&run.input.values, y, initial))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let bode = model.wiener.linear.tf.bode_response(omegas_rad_s);
    Ok(LiveResult { model, evals, predictions, linear, bode })
}

/// Where a model's structure comes from: clusters the user (or a project) gives, or the automatic
/// proposal for the segment fits (its clusters with its dead time, or its direct fit).
#[derive(Clone, Debug, PartialEq)]
pub enum ModelSource {
    Clusters(Vec<Cluster>),
    Proposal(std::sync::Arc<Proposal>),
}

impl ModelSource {
    /// The clusters the model is drawn from (the proposal's kept clusters).
    pub fn clusters(&self) -> Vec<Cluster> {
        match self {
            Self::Clusters(clusters) => clusters.clone(),
            Self::Proposal(proposal) => proposal.clusters.clone(),
        }
    }

    /// The model of this source on the identification range (see [`build_gray_box`] and
    /// [`build_proposed`]).
    pub fn build(
        &self,
        fits: &SegmentFits,
        ident: &Run,
        settings: &OutputSettings,
    ) -> Result<(GrayBoxModel, Vec<ClusterEval>), PipelineError> {
        match self {
            Self::Clusters(clusters) => build_gray_box(fits, ident, clusters, settings),
            Self::Proposal(proposal) => build_proposed(fits, ident, proposal, settings),
        }
    }
}

/// Segments → fits → clusters (given or automatic) → model, for one output.
#[derive(Clone)]
pub struct Identified {
    pub fits: SegmentFits,
    pub model: GrayBoxModel,
    pub evals: Vec<ClusterEval>,
    /// The automatic proposal, when the clusters were not given.
    pub proposal: Option<Proposal>,
}

/// The model of one output: the segment fits, then the given clusters or the automatic proposal,
/// then the model of that [`ModelSource`].
pub fn identify_output(
    ident: &Run,
    output: &str,
    settings: &OutputSettings,
    segments: &[Segment],
    clusters: Option<&[Cluster]>,
) -> Result<Identified, PipelineError> {
    let fits = fit_segments_for(ident, output, segments, settings)?;
    let source = match clusters {
        Some(c) => ModelSource::Clusters(c.to_vec()),
        None => ModelSource::Proposal(std::sync::Arc::new(propose(&fits, ident, settings)?)),
    };
    let (mut model, evals) = source.build(&fits, ident, settings)?;
    let data = IdentData::new(&fits, ident, settings)?.with_delay(model.wiener.linear.tf.input_delay());
    model.root_intervals = uncertainty::of_roots(&data, &model.roots, model.wiener.map.order())
        .map(|u| u.intervals)
        .unwrap_or_default();
    let proposal = match source {
        ModelSource::Proposal(p) => Some(std::sync::Arc::unwrap_or_clone(p)),
        ModelSource::Clusters(_) => None,
    };
    Ok(Identified { fits, model, evals, proposal })
}

/// The static map as the paper prints it: β0, β1, … (for reports).
pub fn static_map_beta(map: &StaticMap) -> Vec<f64> {
    map.beta()
}
