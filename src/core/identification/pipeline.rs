//! The gray-box identification of one output, end to end, split so that the expensive part (the
//! segment ARX fits) is done once and the live part (clusters → reduced model → static map →
//! validation → Bode → metrics) can run on every drag.
use serde::{Deserialize, Serialize};

use crate::core::identification::arx::{self, ArxModel, ArxOrders, DeadTime, fit_arx};
use crate::core::identification::cluster::{
    self, Cluster, ClusterError, ClusterEval, ClusterSettings, RootKind, SegmentRoots,
};
use crate::core::identification::initial_state::{InitialState, fit_free_response};
use crate::core::identification::reduce::{self, IdentData, RootGroup};
use crate::core::identification::refine::Refinement;
use crate::core::identification::segment::{
    Segment, SegmentError, SegmentSettings, auto_segments, check_segments,
};
use crate::core::identification::static_map::{OrderSuggestion, StaticMap, StaticMapError};
use crate::core::identification::structure::{self, Proposal};
use crate::core::identification::wiener::{LinearBlock, WienerError, WienerModel};
use crate::core::numerics::metrics::{Metrics, MetricsError, metrics};
use crate::core::numerics::stats::mean;
use crate::core::numerics::tf::BodePoint;
use crate::core::run::Run;

/// Settings for identifying one output.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct OutputSettings {
    pub orders: ArxOrders,
    pub cluster: ClusterSettings,
    /// Static-map order; `None` lets the data choose (leave-one-out on the steady points).
    pub static_order: Option<usize>,
    pub max_static_order: usize,
    /// Length of the settled tail of each segment that gives its steady-state point.
    pub settle_secs: f64,
    /// Polish the cluster centroids by simulation error (see `core::identification::reduce`).
    pub refine: bool,
    /// Where the polish may move a root that came from a cluster.
    pub polish: PolishRegion,
    /// Estimate the input delay of the segment ARX models from the step segments (see
    /// [`arx::estimate_dead_time`]); when false, `orders.nk` is used.
    pub estimate_dead_time: bool,
    /// Input dead time of the reduced model built from given clusters, samples (the automatic
    /// proposal chooses its own, see `core::identification::structure`); `None` is none.
    pub dead_time_samples: Option<usize>,
    /// Where scored simulations (validation, chirp, diagnosis) start (see `core::identification::initial_state`).
    pub initial_state: InitialState,
}

/// Where the polish may move a root that came from a cluster.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PolishRegion {
    /// Inside the cluster's circle: the model's roots and the clusters tell one story.
    #[default]
    WithinClusters,
    /// Anywhere inside the unit circle (the cluster only gives the starting point).
    Free,
}

impl Default for OutputSettings {
    fn default() -> Self {
        Self {
            orders: ArxOrders::new(10, 2),
            // Prefer the low-frequency clusters (paper §5.1): above π/2 rad/sample (13.9 rad/s at
            // 8.85 Hz, the top of the chirp band) ARX on noisy data leaves a ring of noise-model
            // roots that recur in every segment but are not engine dynamics.
            cluster: ClusterSettings {
                nyquist_exclusion_rad: std::f64::consts::FRAC_PI_2,
                max_radius: 0.08,
                ..ClusterSettings::default()
            },
            static_order: None,
            max_static_order: 3,
            settle_secs: 6.0,
            refine: true,
            polish: PolishRegion::WithinClusters,
            estimate_dead_time: true,
            dead_time_samples: None,
            initial_state: InitialState::Estimated,
        }
    }
}

impl OutputSettings {
    /// The paper's orders for the SR-30 outputs: speed 19 poles / 3 zeros, thrust 21 / 19.
    pub fn for_output(name: &str) -> Self {
        let orders = match crate::core::run::Quantity::of(name) {
            Some(crate::core::run::Quantity::ShaftSpeed) => ArxOrders::new(19, 3),
            Some(crate::core::run::Quantity::Thrust) => ArxOrders::new(21, 19),
            None => ArxOrders::new(10, 2),
        };
        Self { orders, ..Self::default() }
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PipelineError {
    #[error("run '{run}' has no output column '{output}' (outputs: {available})")]
    MissingOutput { run: String, output: String, available: String },
    #[error("segmentation of '{run}': {source}")]
    Segment { run: String, source: SegmentError },
    #[error(
        "steps_from = \"{channel}\": the identification run '{run}' has no such channel (map it with aux={channel})"
    )]
    NoStepChannel { run: String, channel: String },
    #[error("only {fitted} of {segments} segment models could be fitted (need at least 2): {diagnostics}")]
    TooFewSegmentFits { fitted: usize, segments: usize, diagnostics: String },
    #[error(transparent)]
    Cluster(#[from] ClusterError),
    #[error(transparent)]
    Wiener(#[from] WienerError),
    #[error("static map: {0}")]
    StaticMap(#[from] StaticMapError),
    #[error("scoring run '{run}': {source}")]
    Metrics { run: String, source: MetricsError },
    #[error("no model can be fitted: {reason}")]
    NoModel { reason: String },
}

/// The ARX model of every segment, with the roots the clusters are drawn over.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SegmentFits {
    pub output: String,
    pub dt_secs: f64,
    pub segments: Vec<Segment>,
    pub models: Vec<ArxModel>,
    pub roots: Vec<SegmentRoots>,
    /// Segments that could not be fitted, and fits with rank deficiency.
    pub diagnostics: Vec<String>,
    /// The input dead time, when it was estimated from the segments.
    #[serde(default)]
    pub dead_time: Option<DeadTime>,
}

impl SegmentFits {
    /// The segment models' input delay, samples (1: none beyond the sampling).
    pub fn nk(&self) -> usize {
        self.models.first().map_or(1, |m| m.orders.nk)
    }
}

pub fn output_values<'a>(run: &'a Run, output: &str) -> Result<&'a [f64], PipelineError> {
    run.output(output).map(|c| c.values.as_slice()).ok_or_else(|| PipelineError::MissingOutput {
        run: run.name.clone(),
        output: output.to_owned(),
        available: run.outputs.iter().map(|c| c.name.as_str()).collect::<Vec<_>>().join(", "),
    })
}

/// The signal steps are found on: the run's input, or the channel `steps_from` names (a set-point
/// on closed-loop data, a command when the input sensor drops out).
pub fn step_signal<'a>(run: &'a Run, steps_from: Option<&str>) -> Result<&'a [f64], PipelineError> {
    match steps_from {
        None => Ok(&run.input.values),
        Some(name) => run
            .channel(name)
            .map(|c| c.values.as_slice())
            .ok_or_else(|| PipelineError::NoStepChannel { run: run.name.clone(), channel: name.to_owned() }),
    }
}

/// Segments of the identification run: the user's if given (checked), else detected.
pub fn segments_for(
    run: &Run,
    given: Option<&[Segment]>,
    settings: &SegmentSettings,
) -> Result<Vec<Segment>, PipelineError> {
    let wrap = |source| PipelineError::Segment { run: run.name.clone(), source };
    match given {
        Some(segments) => {
            check_segments(segments, run.len()).map_err(wrap)?;
            Ok(segments.to_vec())
        }
        None => auto_segments(&run.input.values, run.dt_secs, settings).map_err(wrap),
    }
}

/// Fit one ARX model per segment on deviations from the segment's starting steady state.
pub fn fit_segments(
    run: &Run,
    output: &str,
    segments: &[Segment],
    orders: ArxOrders,
) -> Result<SegmentFits, PipelineError> {
    let y = output_values(run, output)?;
    let u = &run.input.values;
    let mut models = Vec::new();
    let mut roots = Vec::new();
    let mut fitted_segments = Vec::new();
    let mut diagnostics = Vec::new();
    for seg in segments {
        let (u0, y0) = (mean(&u[seg.start..seg.step_at]), mean(&y[seg.start..seg.step_at]));
        let du: Vec<f64> = u[seg.start..seg.end].iter().map(|v| v - u0).collect();
        let dy: Vec<f64> = y[seg.start..seg.end].iter().map(|v| v - y0).collect();
        match fit_arx(&du, &dy, orders, run.dt_secs) {
            Ok(model) => {
                if model.rank < orders.n_params() {
                    diagnostics.push(format!(
                        "segment {}: rank {} of {} (condition {:.2e}); minimum-norm solution used",
                        seg.label,
                        model.rank,
                        orders.n_params(),
                        model.cond
                    ));
                }
                roots.push(SegmentRoots {
                    label: seg.label.clone(),
                    poles: model.poles.clone(),
                    zeros: model.zeros.clone(),
                });
                models.push(model);
                fitted_segments.push(seg.clone());
            }
            Err(err) => diagnostics.push(format!("segment {}: {err}", seg.label)),
        }
    }
    if models.len() < 2 {
        return Err(PipelineError::TooFewSegmentFits {
            fitted: models.len(),
            segments: segments.len(),
            diagnostics: diagnostics.join("; "),
        });
    }
    Ok(SegmentFits {
        output: output.to_owned(),
        dt_secs: run.dt_secs,
        segments: fitted_segments,
        models,
        roots,
        diagnostics,
        dead_time: None,
    })
}

/// Longest input dead time searched, s: fuel-line and valve delays of small engines are well under
/// it, and the step segments (tens of seconds) show several times this much response after it.
pub const MAX_DEAD_TIME_SECS: f64 = 2.5;

/// [`fit_segments`] with the output's settings: the input dead time estimated from the segments
/// first when the settings ask for it (see [`arx::estimate_dead_time`]), else `orders.nk`.
pub fn fit_segments_for(
    run: &Run,
    output: &str,
    segments: &[Segment],
    settings: &OutputSettings,
) -> Result<SegmentFits, PipelineError> {
    if !settings.estimate_dead_time {
        return fit_segments(run, output, segments, settings.orders);
    }
    let y = output_values(run, output)?;
    let u = &run.input.values;
    let deviations: Vec<(Vec<f64>, Vec<f64>)> = segments
        .iter()
        .filter(|seg| seg.start < seg.step_at && seg.end <= y.len() && seg.end <= u.len())
        .map(|seg| {
            let (u0, y0) = (mean(&u[seg.start..seg.step_at]), mean(&y[seg.start..seg.step_at]));
            (
                u[seg.start..seg.end].iter().map(|v| v - u0).collect(),
                y[seg.start..seg.end].iter().map(|v| v - y0).collect(),
            )
        })
        .collect();
    let max_nk = ((MAX_DEAD_TIME_SECS / run.dt_secs).round() as usize).clamp(1, 50);
    let dead_time = arx::estimate_dead_time(&deviations, settings.orders.na, max_nk);
    let nk = dead_time.as_ref().map_or(settings.orders.nk, |d| d.nk);
    let mut fits = fit_segments(run, output, segments, ArxOrders { nk, ..settings.orders })?;
    fits.dead_time = dead_time;
    Ok(fits)
}

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
    let (model, evals) = source.build(&fits, ident, settings)?;
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
