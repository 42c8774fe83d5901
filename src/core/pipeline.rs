//! The gray-box identification of one output, end to end, split so that the expensive part (the
//! segment ARX fits) is done once and the live part (clusters → reduced model → static map →
//! validation → Bode → metrics) can run on every drag.
use serde::{Deserialize, Serialize};

use crate::core::arx::{ArxModel, ArxOrders, fit_arx};
use crate::core::cluster::{
    self, Cluster, ClusterError, ClusterEval, ClusterSettings, RootKind, SegmentRoots,
};
use crate::core::metrics::{Metrics, MetricsError, metrics};
use crate::core::refine::{Refinement, refine_roots};
use crate::core::run::Run;
use crate::core::segment::{Segment, SegmentError, SegmentSettings, auto_segments, check_segments};
use crate::core::static_map::{OrderSuggestion, StaticMap, StaticMapError, fit_static_map, suggest_order};
use crate::core::tf::BodePoint;
use crate::core::wiener::{LinearBlock, WienerError, WienerModel, fit_linear_block};

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
    /// Polish the cluster centroids by simulation error (see `core::refine`).
    pub refine: bool,
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
        }
    }
}

impl OutputSettings {
    /// The paper's orders for the SR-30 outputs: speed 19 poles / 3 zeros, thrust 21 / 19.
    pub fn for_output(name: &str) -> Self {
        let orders = if name.contains("speed") || name.contains("rpm") {
            ArxOrders::new(19, 3)
        } else if name.contains("thrust") {
            ArxOrders::new(21, 19)
        } else {
            ArxOrders::new(10, 2)
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
}

pub fn output_values<'a>(run: &'a Run, output: &str) -> Result<&'a [f64], PipelineError> {
    run.output(output).map(|c| c.values.as_slice()).ok_or_else(|| PipelineError::MissingOutput {
        run: run.name.clone(),
        output: output.to_owned(),
        available: run.outputs.iter().map(|c| c.name.as_str()).collect::<Vec<_>>().join(", "),
    })
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

fn mean(x: &[f64]) -> f64 {
    if x.is_empty() { 0.0 } else { x.iter().sum::<f64>() / x.len() as f64 }
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
    })
}

/// The reduced model of one output: clusters, linear block, static map and how they were chosen.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GrayBoxModel {
    pub output: String,
    pub clusters: Vec<Cluster>,
    pub wiener: WienerModel,
    /// Steady-state points (v, y) the static map was fitted to.
    pub steady_points: Vec<(f64, f64)>,
    pub static_suggestion: Option<OrderSuggestion>,
    /// Present when the centroids were polished by simulation error.
    pub refinement: Option<Refinement>,
}

/// Range of the identification run the gain and static map are fitted on: first to last segment.
fn fit_range(fits: &SegmentFits) -> (usize, usize) {
    let start = fits.segments.first().map_or(0, |s| s.start);
    let end = fits.segments.last().map_or(0, |s| s.end);
    (start, end)
}

/// The Wiener model for given reduced roots, fitted on the identification range.
struct Assembled {
    wiener: WienerModel,
    steady_points: Vec<(f64, f64)>,
    suggestion: Option<OrderSuggestion>,
    residual: Vec<f64>,
}

fn assemble(
    fits: &SegmentFits,
    u: &[f64],
    y: &[f64],
    start: usize,
    poles: &[num_complex::Complex64],
    zeros: &[num_complex::Complex64],
    settings: &OutputSettings,
    static_order: Option<usize>,
) -> Result<Assembled, PipelineError> {
    let linear = fit_linear_block(poles, zeros, u, y, fits.dt_secs)?;
    let v = linear.simulate(u);
    let tail = ((settings.settle_secs / fits.dt_secs).round() as usize).max(3);
    let mut steady_points = Vec::with_capacity(fits.segments.len() + 1);
    if let Some(first) = fits.segments.first() {
        let b = first.step_at - start;
        steady_points.push((mean(&v[..b]), mean(&y[..b])));
    }
    for seg in &fits.segments {
        let (a, b) = seg.settled_tail(tail);
        steady_points.push((mean(&v[a - start..b - start]), mean(&y[a - start..b - start])));
    }
    let (vs, ys): (Vec<f64>, Vec<f64>) = steady_points.iter().copied().unzip();
    let (order, suggestion) = match static_order {
        Some(order) => (order, None),
        None => {
            let s = suggest_order(&vs, &ys, settings.max_static_order)?;
            (s.order, Some(s))
        }
    };
    let map = fit_static_map(&vs, &ys, order)?;
    let residual = v.iter().zip(y).map(|(vk, yk)| map.eval(*vk) - yk).collect();
    Ok(Assembled { wiener: WienerModel { linear, map }, steady_points, suggestion, residual })
}

/// Clusters → reduced linear block → static map (the live path's model building).
pub fn build_gray_box(
    fits: &SegmentFits,
    ident: &Run,
    clusters: &[Cluster],
    settings: &OutputSettings,
) -> Result<(GrayBoxModel, Vec<ClusterEval>), PipelineError> {
    let evals = cluster::evaluate_clusters(clusters, &fits.roots, &settings.cluster, fits.dt_secs)?;
    let poles = cluster::valid_reduced_roots(&evals, RootKind::Pole);
    let zeros = cluster::valid_reduced_roots(&evals, RootKind::Zero);
    let y_all = output_values(ident, &fits.output)?;
    let (start, end) = fit_range(fits);
    let (u, y) = (&ident.input.values[start..end], &y_all[start..end]);
    let first = assemble(fits, u, y, start, &poles, &zeros, settings, settings.static_order)?;
    let order = Some(first.wiener.map.order());
    let suggestion = first.suggestion.clone();
    let refined = if settings.refine {
        refine_roots(&poles, &zeros, |p, z| {
            assemble(fits, u, y, start, p, z, settings, order).ok().map(|a| a.residual)
        })
    } else {
        None
    };
    let (assembled, refinement) = match refined {
        Some((p, z, info)) if info.rms_after < info.rms_before => {
            (assemble(fits, u, y, start, &p, &z, settings, order)?, Some(info))
        }
        _ => (first, None),
    };
    let model = GrayBoxModel {
        output: fits.output.clone(),
        clusters: clusters.to_vec(),
        wiener: assembled.wiener,
        steady_points: assembled.steady_points,
        static_suggestion: suggestion,
        refinement,
    };
    Ok((model, evals))
}

/// Automatic clusters for these fits.
pub fn auto_clusters(fits: &SegmentFits, settings: &OutputSettings) -> Result<Vec<Cluster>, PipelineError> {
    Ok(cluster::propose_clusters(&fits.roots, &settings.cluster, fits.dt_secs)?)
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
    pub predictions: Vec<RunPrediction>,
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
    let predictions = validation
        .iter()
        .map(|run| predict_wiener(&model.wiener, run, &fits.output))
        .collect::<Result<Vec<_>, _>>()?;
    let bode = model.wiener.linear.tf.bode_response(omegas_rad_s);
    Ok(LiveResult { model, evals, predictions, bode })
}

/// Segments → fits → clusters (given or automatic) → model, for one output.
pub struct Identified {
    pub fits: SegmentFits,
    pub model: GrayBoxModel,
    pub evals: Vec<ClusterEval>,
}

pub fn identify_output(
    ident: &Run,
    output: &str,
    settings: &OutputSettings,
    segments: &[Segment],
    clusters: Option<&[Cluster]>,
) -> Result<Identified, PipelineError> {
    let fits = fit_segments(ident, output, segments, settings.orders)?;
    let clusters = match clusters {
        Some(c) => c.to_vec(),
        None => auto_clusters(&fits, settings)?,
    };
    let (model, evals) = build_gray_box(&fits, ident, &clusters, settings)?;
    Ok(Identified { fits, model, evals })
}

/// The static map as the paper prints it: β0, β1, … (for reports).
pub fn static_map_beta(map: &StaticMap) -> Vec<f64> {
    map.beta()
}
