//! The reduced model of one output: its roots, the Wiener model they give on the identification
//! range, and the polish that moves them by simulation error while keeping each inside its cluster.
//!
//! **Root groups.** The reduced linear block is a list of [`RootGroup`]s: one real root, or one
//! conjugate pair, each taken from a valid cluster (its centroid) or free (the direct output-error
//! fit of `core::identification::direct_fit`). For given roots the Wiener model is [`assemble`]d the one way the
//! whole crate uses: the unit-gain response is simulated, gain and offset come from least squares
//! on the identification range, and the static map is fitted to the steady-state points (the
//! pre-step baseline and the settled tail of every segment), its order chosen by leave-one-out
//! unless the output's settings fix it.
//!
//! **The polish keeps one story.** A high-order ARX fitted to noisy data is biased, so centroids sit
//! a little off the engine's roots; Levenberg–Marquardt then moves the roots to minimise the Wiener
//! model's simulation error on the identification range, with gain, offset and map re-solved by
//! least squares at every step (variable projection). Each root that came from a cluster is kept
//! inside that cluster's circle: it is written as centre + radius · tanh(ρ)/ρ · θ (θ ∈ ℝ² for a
//! pair, the real segment of the circle for a real root), so the optimiser moves freely and the
//! root cannot leave. The circle is the engineer's statement of where the segment models put the
//! root; the polish finds the best root inside it, and the z-plane, the cluster table and the model
//! tell the same story. A root that ends on the rim is reported ([`RootGroup::at_rim`]): the data
//! pull it further, and widening the circle lets them.
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use crate::core::identification::cluster::{ClusterEval, RootKind, natural_freq_and_damping};
use crate::core::identification::error::PipelineError;
use crate::core::identification::fits::{SegmentFits, output_values};
use crate::core::identification::settings::{OutputSettings, PolishRegion};
use crate::core::identification::static_map::{OrderSuggestion, fit_static_map, suggest_order};
use crate::core::identification::wiener::{
    LinearBlock, WienerError, WienerModel, linear_block_on, unit_gain_tf,
};
use crate::core::numerics::stats::mean;
use crate::core::numerics::tf::DiscreteTf;
use crate::core::run::Run;

/// A root whose distance from its circle's centre is at least this share of the radius is on the
/// rim: the tanh map has then used 98 % of its room, so the optimiser was stopped by the circle.
const RIM_SHARE: f64 = 0.98;
/// Largest |w| a starting point may have inside its circle (w = (z − c)/r), so atanh stays finite.
const MAX_START_SHARE: f64 = 0.995;

/// A circle a root is kept in.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Region {
    pub centre: Complex64,
    pub radius: f64,
}

/// One real root or one conjugate pair of the reduced linear block.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RootGroup {
    pub kind: RootKind,
    /// The root; in the closed upper half-plane for a pair (its conjugate is implied), real otherwise.
    pub root: Complex64,
    pub pair: bool,
    /// The circle the polish keeps the root in (its cluster's); `None` for a free root.
    pub region: Option<Region>,
    /// Index of the cluster the root came from, in the cluster list it was built from.
    pub cluster: Option<usize>,
}

impl RootGroup {
    /// A free real root at `x`.
    pub fn free_real(kind: RootKind, x: f64) -> Self {
        Self { kind, root: Complex64::new(x, 0.0), pair: false, region: None, cluster: None }
    }

    /// A free conjugate pair at `z` (and its conjugate).
    pub fn free_pair(kind: RootKind, z: Complex64) -> Self {
        let root = Complex64::new(z.re, z.im.abs());
        Self { kind, root, pair: true, region: None, cluster: None }
    }

    /// The group of a valid cluster: its centroid, kept inside its circle.
    pub fn of_cluster(index: usize, eval: &ClusterEval) -> Self {
        let pair = !eval.cluster.is_real_axis();
        let root = if pair { eval.centroid } else { Complex64::new(eval.centroid.re, 0.0) };
        Self {
            kind: eval.cluster.kind,
            root,
            pair,
            region: Some(Region { centre: eval.cluster.centre, radius: eval.cluster.radius }),
            cluster: Some(index),
        }
    }

    /// The group with its circle dropped when the polish may move it freely.
    pub fn within(self, region: PolishRegion) -> Self {
        match region {
            PolishRegion::WithinClusters => self,
            PolishRegion::Free => Self { region: None, ..self },
        }
    }

    /// The roots this group puts in the transfer function.
    pub fn roots(&self) -> Vec<Complex64> {
        if self.pair { vec![self.root, self.root.conj()] } else { vec![Complex64::new(self.root.re, 0.0)] }
    }

    /// Number of roots (1 or 2).
    pub fn count(&self) -> usize {
        if self.pair { 2 } else { 1 }
    }

    /// True when the polish left the root on the rim of its circle (see [`RIM_SHARE`]).
    pub fn at_rim(&self) -> bool {
        self.region.is_some_and(|r| r.radius > 0.0 && (self.root - r.centre).norm() >= RIM_SHARE * r.radius)
    }

    /// (ωn rad/s, ζ, τ s) of the root: τ for a real root in (0, 1), ωn and ζ always.
    pub fn s_plane(&self, dt_secs: f64) -> (f64, f64, Option<f64>) {
        let (omega, zeta) = natural_freq_and_damping(self.root, dt_secs);
        let tau = (!self.pair && self.root.re > 0.0 && self.root.re < 1.0)
            .then(|| -dt_secs / self.root.re.ln())
            .filter(|t| t.is_finite());
        (omega, zeta, tau)
    }

    /// Number of polish parameters: 0 for a real root pinned to a circle that only touches the axis.
    fn n_params(&self) -> usize {
        match (self.pair, self.region) {
            (true, _) => 2,
            (false, Some(r)) if real_half_width(r) <= 0.0 => 0,
            (false, _) => 1,
        }
    }

    /// The group's polish parameters.
    fn encode(&self) -> Vec<f64> {
        match (self.pair, self.region) {
            (true, None) => vec![self.root.re, self.root.im],
            (false, None) => vec![self.root.re],
            (true, Some(r)) => {
                let w = (self.root - r.centre) / r.radius.max(f64::MIN_POSITIVE);
                let rho = w.norm().min(MAX_START_SHARE);
                let scale = if rho > 0.0 { rho.atanh() / w.norm() } else { 1.0 };
                vec![w.re * scale, w.im * scale]
            }
            (false, Some(r)) => {
                let h = real_half_width(r);
                if h <= 0.0 {
                    return Vec::new();
                }
                let x = ((self.root.re - r.centre.re) / h).clamp(-MAX_START_SHARE, MAX_START_SHARE);
                vec![x.atanh()]
            }
        }
    }

    /// The group moved to the parameters `theta` (as many as [`RootGroup::n_params`]).
    fn decode(&self, theta: &[f64]) -> Option<Self> {
        let root = match (self.pair, self.region) {
            (true, None) => Complex64::new(*theta.first()?, theta.get(1)?.abs()),
            (false, None) => Complex64::new(*theta.first()?, 0.0),
            (true, Some(r)) => {
                let t = Complex64::new(*theta.first()?, *theta.get(1)?);
                let rho = t.norm();
                let shrink = if rho > 1e-12 { rho.tanh() / rho } else { 1.0 };
                let z = r.centre + t * (r.radius * shrink);
                Complex64::new(z.re, z.im.abs())
            }
            (false, Some(r)) => {
                let h = real_half_width(r);
                let x = if h > 0.0 { r.centre.re + h * theta.first()?.tanh() } else { r.centre.re };
                Complex64::new(x, 0.0)
            }
        };
        Some(Self { root, ..self.clone() })
    }
}

/// Half the length of the real axis inside a circle (0 when the circle does not reach the axis).
fn real_half_width(r: Region) -> f64 {
    (r.radius * r.radius - r.centre.im * r.centre.im).max(0.0).sqrt()
}

/// All roots of one kind in a list of groups.
pub fn roots_of(groups: &[RootGroup], kind: RootKind) -> Vec<Complex64> {
    let mut roots: Vec<Complex64> =
        groups.iter().filter(|g| g.kind == kind).flat_map(RootGroup::roots).collect();
    roots.sort_by(|a, b| a.arg().total_cmp(&b.arg()).then(a.norm().total_cmp(&b.norm())));
    roots
}

/// Number of roots of one kind.
pub fn count_of(groups: &[RootGroup], kind: RootKind) -> usize {
    groups.iter().filter(|g| g.kind == kind).map(RootGroup::count).sum()
}

/// The identification data a reduced model is fitted on: the run over the segments' range.
pub struct IdentData<'a> {
    pub fits: &'a SegmentFits,
    pub u: &'a [f64],
    pub y: &'a [f64],
    /// Index in the identification run of the first sample of `u` and `y`.
    pub start: usize,
    pub settings: &'a OutputSettings,
    /// Samples of `u` and `y` left out of every fit (a cross-validation fold's held-out segment).
    pub held_out: Option<std::ops::Range<usize>>,
    /// Input dead time of the reduced model, samples (besides what its roots give).
    pub delay: usize,
}

impl<'a> IdentData<'a> {
    /// The range of `ident` from the first segment's start to the last segment's end.
    pub fn new(
        fits: &'a SegmentFits,
        ident: &'a Run,
        settings: &'a OutputSettings,
    ) -> Result<Self, PipelineError> {
        let y_all = output_values(ident, &fits.output)?;
        let start = fits.segments.first().map_or(0, |s| s.start);
        let end = fits.segments.last().map_or(0, |s| s.end).min(y_all.len()).min(ident.input.values.len());
        let (u, y) = match (ident.input.values.get(start..end), y_all.get(start..end)) {
            (Some(u), Some(y)) => (u, y),
            _ => (&ident.input.values[..0], &y_all[..0]),
        };
        Ok(Self {
            fits,
            u,
            y,
            start,
            settings,
            held_out: None,
            delay: settings.dead_time_samples.unwrap_or(0),
        })
    }

    /// The same data for a reduced model with `delay` samples of input dead time.
    pub fn with_delay(&self, delay: usize) -> Self {
        Self { delay, held_out: self.held_out.clone(), ..*self }
    }

    /// The same data with the samples `start..end` of the identification run held out.
    pub fn holding_out(&self, start: usize, end: usize) -> Self {
        let (a, b) = (start.saturating_sub(self.start), end.saturating_sub(self.start).min(self.u.len()));
        Self { held_out: Some(a..b.max(a)), delay: self.delay, ..*self }
    }

    /// Standard deviation of the output's measurement noise, read from the data: the median absolute
    /// first difference over the identification range, scaled to σ for Gaussian noise (Δy of white
    /// noise has σ√2, and its median absolute value is 0.6745 σ√2). The dynamics at these sample
    /// rates move the output little from one sample to the next except during the few seconds after
    /// each step, which the median ignores.
    pub fn noise_sigma(&self) -> f64 {
        let mut diffs: Vec<f64> = self.y.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
        if diffs.is_empty() {
            return 0.0;
        }
        diffs.sort_by(f64::total_cmp);
        let median = diffs[diffs.len() / 2];
        median / (0.674_489_75 * std::f64::consts::SQRT_2)
    }

    /// Whether sample `k` of `u` and `y` takes part in the fit.
    pub fn fits_sample(&self, k: usize) -> bool {
        self.held_out.as_ref().is_none_or(|out| !out.contains(&k))
    }
}

/// A Wiener model for given roots, fitted on the identification range, with its residual there.
#[derive(Clone, Debug)]
pub struct Assembled {
    pub wiener: WienerModel,
    /// Steady-state points (v, y) the static map was fitted to.
    pub steady_points: Vec<(f64, f64)>,
    pub suggestion: Option<OrderSuggestion>,
    /// Simulated minus measured output over the identification range.
    pub residual: Vec<f64>,
}

impl Assembled {
    /// Root-mean-square of the residual.
    pub fn rms(&self) -> f64 {
        rms(&self.residual)
    }
}

/// Root-mean-square of a residual (0 for an empty one).
pub fn rms(residual: &[f64]) -> f64 {
    (residual.iter().map(|r| r * r).sum::<f64>() / residual.len().max(1) as f64).sqrt()
}

/// Gain, offset and static map for these roots (see the module documentation). `static_order`
/// `None` lets leave-one-out choose within the settings' maximum.
pub fn assemble(
    data: &IdentData,
    poles: &[Complex64],
    zeros: &[Complex64],
    static_order: Option<usize>,
) -> Result<Assembled, PipelineError> {
    let one = assemble_each(data, &[(poles, zeros)], static_order).pop();
    one.unwrap_or(Err(PipelineError::Wiener(WienerError::TooFewSamples { samples: 0 })))
}

/// [`assemble`] for each set of roots (poles, zeros), their simulations stepped side by side
/// ([`DiscreteTf::simulate_each_from_steady`]): what a finite-difference Jacobian's columns ask for.
/// Each result is the one [`assemble`] gives alone, bit for bit.
pub fn assemble_each(
    data: &IdentData,
    roots: &[(&[Complex64], &[Complex64])],
    static_order: Option<usize>,
) -> Vec<Result<Assembled, PipelineError>> {
    let dt = data.fits.dt_secs;
    let shapes: Vec<Result<DiscreteTf, WienerError>> = roots
        .iter()
        .map(|(poles, zeros)| Ok(unit_gain_tf(poles, zeros, dt)?.with_input_delay(data.delay)))
        .collect();
    let responses = simulate_ok(&shapes, data.u);
    let linears: Vec<Result<LinearBlock, WienerError>> = shapes
        .into_iter()
        .zip(responses)
        .map(|(shape, w)| linear_block_on(shape?, &w, data.y, data.held_out.clone()))
        .collect();
    let blocks: Vec<Result<DiscreteTf, WienerError>> =
        linears.iter().map(|l| l.as_ref().map(|l| l.tf.clone()).map_err(Clone::clone)).collect();
    let outputs = simulate_ok(&blocks, data.u);
    linears
        .into_iter()
        .zip(outputs)
        .map(|(linear, mut v)| {
            let linear = linear?;
            for x in &mut v {
                *x += linear.offset;
            }
            with_map(data, linear, v, static_order)
        })
        .collect()
}

/// Each block's response to `u` from its steady state (empty where there is no block), simulated
/// side by side.
fn simulate_ok(blocks: &[Result<DiscreteTf, WienerError>], u: &[f64]) -> Vec<Vec<f64>> {
    let ok: Vec<(&DiscreteTf, &[f64])> = blocks.iter().filter_map(|b| Some((b.as_ref().ok()?, u))).collect();
    let mut simulated = DiscreteTf::simulate_each_from_steady(&ok).into_iter();
    blocks.iter().map(|b| b.as_ref().ok().and_then(|_| simulated.next()).unwrap_or_default()).collect()
}

/// The static map on the steady points of `v` (the linear block's output), and the residual.
fn with_map(
    data: &IdentData,
    linear: LinearBlock,
    v: Vec<f64>,
    static_order: Option<usize>,
) -> Result<Assembled, PipelineError> {
    let steady_points: Vec<(f64, f64)> = steady_windows(data)
        .into_iter()
        .filter_map(|w| {
            let local = w.start - data.start..w.end - data.start;
            Some((mean(v.get(local.clone())?), mean(data.y.get(local)?)))
        })
        .collect();
    let (vs, ys): (Vec<f64>, Vec<f64>) = steady_points.iter().copied().unzip();
    let (order, suggestion) = match static_order {
        Some(order) => (order, None),
        None => {
            let s = suggest_order(&vs, &ys, data.settings.max_static_order)?;
            (s.order, Some(s))
        }
    };
    let map = fit_static_map(&vs, &ys, order)?;
    let residual = v.iter().zip(data.y).map(|(vk, yk)| map.eval(*vk) - yk).collect();
    Ok(Assembled { wiener: WienerModel { linear, map }, steady_points, suggestion, residual })
}

/// The windows of the identification run whose means are the static map's steady points, in run
/// indices: the hold before the first step, then each segment's settled tail (the last
/// `settle_secs`, at most half the segment after its step); windows that touch the held-out samples
/// or leave the data are left out.
pub fn steady_windows(data: &IdentData) -> Vec<std::ops::Range<usize>> {
    let fits = data.fits;
    let tail = ((data.settings.settle_secs / fits.dt_secs).round() as usize).max(3);
    let end = data.start + data.u.len().min(data.y.len());
    let usable = |a: usize, b: usize| -> Option<std::ops::Range<usize>> {
        let (la, lb) = (a.checked_sub(data.start)?, b.checked_sub(data.start)?);
        if data.held_out.as_ref().is_some_and(|out| out.start < lb && la < out.end) || b > end || a >= b {
            return None;
        }
        Some(a..b)
    };
    let mut windows = Vec::with_capacity(fits.segments.len() + 1);
    windows.extend(fits.segments.first().and_then(|first| usable(data.start, first.step_at)));
    for seg in &fits.segments {
        let (a, b) = seg.settled_tail(tail);
        windows.extend(usable(a, b));
    }
    windows
}

/// Assemble the model of a list of root groups.
pub fn assemble_groups(
    data: &IdentData,
    groups: &[RootGroup],
    static_order: Option<usize>,
) -> Result<Assembled, PipelineError> {
    assemble(data, &roots_of(groups, RootKind::Pole), &roots_of(groups, RootKind::Zero), static_order)
}

mod polish;
pub use polish::{Polished, polish, polish_with};

#[cfg(test)]
mod tests;
