//! How well the identification run fixes a finished model's parameters: one covariance of all of
//! them, and models drawn from it, for everything a controller designer reads off the model.
//!
//! **The parameters.** θ holds, in this order:
//! - the linear block's roots: `atanh` of each real pole's position, and of each pair's modulus
//!   with its angle (upper half-plane), so every value of θ is a stable model; then each zero's
//!   position (a pair's real and imaginary parts);
//! - the static map's coefficients (powers of the scaled variable);
//! - each effect's free parameters, in the unconstrained form its fit moves.
//!
//! The linear block's steady gain and offset are held: they only rescale the map's input, which
//! the map's coefficients already span, and a parameter the data cannot tell from another gives a
//! singular information matrix. Moving a root therefore moves the dynamics and never the steady
//! state.
//!
//! **The estimator: a sandwich of the fit's own estimating equations.** Every parameter but the
//! map's is fitted by output error on the identification run; the map's coefficients by least
//! squares on the means of the steady windows (`core::identification::reduce::steady_windows`).
//! The covariance stacks both sets of equations, `ψ = Σₖ cₖ eₖ` with `cₖ` the output's gradient
//! `Jₖ` for an output-error parameter and `wₖ Jₖ` for a map coefficient (`wₖ = 1/len` inside a
//! steady window of `len` samples, 0 elsewhere): `Σ = H⁻¹ S H⁻ᵀ`, `H = Σₖ cₖ Jₖᵀ`, `S` the
//! Newey–West long-run variance of the scores `cₖ eₖ` (bandwidth from the residual's correlation
//! time, as for the roots in `core::identification::uncertainty`, whose doc argues it).
//! - A simulated model's residual is autocorrelated over the spool's settling time; the sandwich
//!   holds whatever that correlation, where `σ²(JᵀJ)⁻¹` would count thousands of correlated samples
//!   as independent.
//! - Taking the map as fitted by output error on the whole run (the first version) credits it with
//!   the information of every transient sample: on a known Wiener system its steady-gain
//!   intervals covered the truth 80 % of the time, against 93 % with the map's own equations.
//! - The map's equations are means over the steady windows, and their block of `S` is widened to at
//!   least what the residual's autocovariance over the whole run gives such a mean (see
//!   `at_least_stationary` for why the windows' own residuals cannot).
//! - The coverage tests in `core::control::bands` and `tests/coverage.rs` (the paper's own
//!   shaft-speed model) check the result against the truth.
//!
//! A parameter the run does not move the output with (a rate limit the run never reaches) has no
//! information: it is held at its value and named in [`ParameterCovariance::held`], not allowed
//! to make the whole covariance singular.
use std::ops::Range;

use nalgebra::DMatrix;
use num_complex::Complex64;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use crate::core::effects::ExtendedModel;
use crate::core::identification::uncertainty::{bandwidth, long_run_variance};
use crate::core::numerics::tf::DiscreteTf;
use crate::core::run::Run;

/// A root whose imaginary part is below this share of its modulus (or of 1) is a real root: the
/// polynomial root finder returns a real root with an imaginary part of rounding size (~1e-12),
/// far below it, and a genuine pair this close to the axis has no oscillation a run could show.
const REAL_TOL: f64 = 1e-7;
/// Relative step of the central differences: large beside a simulation's rounding (~1e-12
/// relative over a run), small beside any parameter's interval.
const STEP: f64 = 1e-6;
/// A Jacobian column whose norm is below this share of the largest carries no information: the
/// output moves by less than a simulation's rounding when that parameter moves.
const NO_INFORMATION: f64 = 1e-9;

/// The covariance of a model's parameters, stored with the model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ParameterCovariance {
    /// One name per parameter, in the order of [`parameters`].
    pub names: Vec<String>,
    /// The parameter values the covariance is centred on.
    pub values: Vec<f64>,
    /// The covariance matrix, row by row.
    pub matrix: Vec<Vec<f64>>,
    /// Parameters the run carries no information on, held at their values (zero rows).
    #[serde(default)]
    pub held: Vec<String>,
    /// The Newey–West bandwidth used, samples.
    pub bandwidth_samples: usize,
    /// Samples of the identification run the covariance is estimated from.
    pub samples: usize,
}

/// Why a covariance cannot be estimated or drawn from.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CovarianceError {
    #[error("the run '{run}' has no output '{output}'")]
    NoOutput { run: String, output: String },
    #[error("the model of '{output}' has no usable linear block: {reason}")]
    BadLinearBlock { output: String, reason: String },
    #[error("the model of '{output}' cannot be simulated on '{run}': {reason}")]
    Simulation { output: String, run: String, reason: String },
    #[error("'{run}' has {samples} usable samples, too few for {params} parameters")]
    TooFewSamples { run: String, samples: usize, params: usize },
    #[error("moving the parameter '{name}' by {step:e} gives no model")]
    NoModel { name: String, step: f64 },
    #[error("the run does not fix the parameters {names:?} of '{output}' apart (singular information)")]
    Singular { output: String, names: Vec<String> },
    #[error("the covariance has {stored} parameters but the model has {model}: it belongs to another model")]
    Mismatch { stored: usize, model: usize },
}

/// How a root sits in θ: one coordinate for a real root, two for a pair.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Slot {
    Real,
    Pair,
}

/// Where each part of a model sits in θ, and what is held while θ moves (what an export needs to
/// rebuild a model from a parameter vector).
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    pub poles: Vec<Slot>,
    pub zeros: Vec<Slot>,
    /// Coefficients of the static map.
    pub map: usize,
    /// Free parameters of each effect, in signal-path order.
    pub effects: Vec<usize>,
    /// The linear block's steady gain G(1), held.
    pub steady_gain: f64,
    /// Input dead time of the linear block beyond its roots, samples, held.
    pub delay: usize,
    pub dt_secs: f64,
}

/// Real roots and upper pairs of a root list, with their coordinates: for poles (`bounded`)
/// `atanh` of a real pole's position and of a pair's modulus, with the pair's angle, so that every
/// parameter vector is a stable model and draws from the covariance never leave the unit circle;
/// for zeros, which may sit anywhere, the positions themselves.
fn split_roots(roots: &[Complex64], bounded: bool) -> (Vec<Slot>, Vec<f64>) {
    let mut slots = Vec::new();
    let mut x = Vec::new();
    for r in roots {
        let tol = REAL_TOL * r.norm().max(1.0);
        if r.im.abs() <= tol {
            slots.push(Slot::Real);
            x.push(if bounded { r.re.atanh() } else { r.re });
        } else if r.im > 0.0 {
            slots.push(Slot::Pair);
            x.extend(if bounded { [r.norm().atanh(), r.arg()] } else { [r.re, r.im] });
        }
    }
    (slots, x)
}

fn join_roots(slots: &[Slot], x: &[f64], bounded: bool) -> Vec<Complex64> {
    let mut at = 0;
    let mut roots = Vec::new();
    for s in slots {
        match s {
            Slot::Real => {
                roots.push(Complex64::new(if bounded { x[at].tanh() } else { x[at] }, 0.0));
                at += 1;
            }
            Slot::Pair => {
                let z = if bounded {
                    Complex64::from_polar(x[at].tanh(), x[at + 1])
                } else {
                    Complex64::new(x[at], x[at + 1])
                };
                roots.extend([z, z.conj()]);
                at += 2;
            }
        }
    }
    roots
}

fn slot_len(slots: &[Slot]) -> usize {
    slots.iter().map(|s| if *s == Slot::Pair { 2 } else { 1 }).sum()
}

/// The layout, names and values of a model's parameters.
fn layout(model: &ExtendedModel) -> Result<(Layout, Vec<String>, Vec<f64>), CovarianceError> {
    let bad = |reason: String| CovarianceError::BadLinearBlock { output: model.output.clone(), reason };
    let tf = &model.wiener.linear.tf;
    let (poles, zeros) = model.roots().map_err(|e| bad(e.to_string()))?;
    let steady_gain = tf.dc_gain().map_err(|e| bad(e.to_string()))?;
    let (pole_slots, pole_x) = split_roots(&poles, true);
    let (zero_slots, zero_x) = split_roots(&zeros, false);
    let mut names = Vec::new();
    for (i, s) in pole_slots.iter().enumerate() {
        match s {
            Slot::Real => names.push(format!("pole {} atanh(z)", i + 1)),
            Slot::Pair => names.extend([format!("pole {} atanh|z|", i + 1), format!("pole {} arg z", i + 1)]),
        }
    }
    for (i, s) in zero_slots.iter().enumerate() {
        match s {
            Slot::Real => names.push(format!("zero {} z", i + 1)),
            Slot::Pair => names.extend([format!("zero {} re", i + 1), format!("zero {} im", i + 1)]),
        }
    }
    let map = &model.wiener.map.coeffs_scaled;
    names.extend((0..map.len()).map(|k| format!("static map c{k}")));
    let mut values: Vec<f64> = pole_x.into_iter().chain(zero_x).chain(map.iter().copied()).collect();
    let mut effects = Vec::new();
    for block in &model.effects {
        let free = block.free_params();
        names.extend((0..free.len()).map(|k| format!("{}[{k}]", block.id())));
        effects.push(free.len());
        values.extend(free);
    }
    let layout = Layout {
        poles: pole_slots,
        zeros: zero_slots,
        map: map.len(),
        effects,
        steady_gain,
        delay: tf.input_delay(),
        dt_secs: tf.dt_secs,
    };
    Ok((layout, names, values))
}

/// Where a model's parameters sit in θ.
pub fn parameter_layout(model: &ExtendedModel) -> Result<Layout, CovarianceError> {
    Ok(layout(model)?.0)
}

/// The names and values of a model's parameters, in the order a covariance uses.
pub fn parameters(model: &ExtendedModel) -> Result<(Vec<String>, Vec<f64>), CovarianceError> {
    let (_, names, values) = layout(model)?;
    Ok((names, values))
}

/// The model with its parameters at `theta`; `None` where they give no model (a pole on or outside
/// the unit circle, a steady gain of zero, an effect parameter out of its range).
fn with_parameters(model: &ExtendedModel, layout: &Layout, theta: &[f64]) -> Option<ExtendedModel> {
    let (np, nz) = (slot_len(&layout.poles), slot_len(&layout.zeros));
    let poles = join_roots(&layout.poles, theta.get(..np)?, true);
    let zeros = join_roots(&layout.zeros, theta.get(np..np + nz)?, false);
    if poles.iter().any(|p| !p.norm().is_finite() || p.norm() >= 1.0) {
        return None;
    }
    let shape = DiscreteTf::from_zpk(&zeros, &poles, 1.0, layout.dt_secs).ok()?;
    let g = shape.dc_gain().ok()?;
    if !g.is_finite() || g.abs() < 1e-12 {
        return None;
    }
    let k = layout.steady_gain / g;
    let tf = DiscreteTf::new(shape.num_zinv.iter().map(|b| b * k).collect(), shape.den_zinv, layout.dt_secs)
        .ok()?
        .with_input_delay(layout.delay);
    let mut out = model.clone();
    out.wiener.linear.tf = tf;
    let mut at = np + nz;
    out.wiener.map.coeffs_scaled = theta.get(at..at + layout.map)?.to_vec();
    at += layout.map;
    for (block, &n) in out.effects.iter_mut().zip(&layout.effects) {
        *block = block.with_free_params(theta.get(at..at + n)?, layout.dt_secs)?;
        at += n;
    }
    Some(out)
}

/// Halvings of an effect's step back towards its fitted values before a draw is given up.
const MAX_HALVINGS: usize = 30;

/// [`with_parameters`] for a draw: an effect whose drawn parameters leave its admissible range is
/// moved back towards its fitted values `centre` until it is inside, so a fit that ended on its
/// range's bound (as a scheduled time constant's ratio may) stays near the bound in the draws that
/// would push it out, as the fit itself would have.
fn drawn_model(
    model: &ExtendedModel,
    layout: &Layout,
    theta: &[f64],
    centre: &[f64],
) -> Option<ExtendedModel> {
    let mut theta = theta.to_vec();
    let mut at = slot_len(&layout.poles) + slot_len(&layout.zeros) + layout.map;
    for (block, &n) in model.effects.iter().zip(&layout.effects) {
        let mut t = 1.0;
        for _ in 0..MAX_HALVINGS {
            let slice: Vec<f64> = (at..at + n).map(|i| centre[i] + t * (theta[i] - centre[i])).collect();
            if block.with_free_params(&slice, layout.dt_secs).is_some() {
                theta[at..at + n].copy_from_slice(&slice);
                break;
            }
            t *= 0.5;
        }
        at += n;
    }
    with_parameters(model, layout, &theta)
}

/// The model with its parameters at `theta` (in the order of [`parameters`]); `None` where they
/// give no model.
pub fn model_at(model: &ExtendedModel, theta: &[f64]) -> Option<ExtendedModel> {
    let (layout, _, values) = layout(model).ok()?;
    (theta.len() == values.len()).then(|| with_parameters(model, &layout, theta))?
}

/// The covariance of `model`'s parameters from its fit to `run` (see the module documentation):
/// the static map's coefficients by least squares on the means of the `steady_windows` (run
/// indices; the map's own fit), every other parameter by output error over the whole run. With no
/// windows the map is taken as fitted by output error too.
pub fn estimate(
    model: &ExtendedModel,
    run: &Run,
    steady_windows: &[Range<usize>],
) -> Result<ParameterCovariance, CovarianceError> {
    let output = model.output.clone();
    let y = &run
        .output(&output)
        .ok_or_else(|| CovarianceError::NoOutput { run: run.name.clone(), output: output.clone() })?
        .values;
    let (layout, names, theta0) = layout(model)?;
    let simulate =
        |theta: &[f64]| -> Option<Vec<f64>> { with_parameters(model, &layout, theta)?.simulate(run).ok() };
    let sim = model.simulate(run).map_err(|e| CovarianceError::Simulation {
        output: output.clone(),
        run: run.name.clone(),
        reason: e.to_string(),
    })?;
    let kept: Vec<usize> =
        (0..y.len().min(sim.len())).filter(|&k| y[k].is_finite() && sim[k].is_finite()).collect();
    let n = theta0.len();
    if kept.len() <= 2 * n.max(1) {
        return Err(CovarianceError::TooFewSamples { run: run.name.clone(), samples: kept.len(), params: n });
    }
    let e: Vec<f64> = kept.iter().map(|&k| sim[k] - y[k]).collect();
    let mut jac: Vec<Vec<f64>> = Vec::with_capacity(n);
    for i in 0..n {
        let h = STEP * theta0[i].abs().max(1.0);
        let (mut up, mut down) = (theta0.clone(), theta0.clone());
        up[i] += h;
        down[i] -= h;
        // One-sided at a parameter's range bound (a fit that ended on it).
        let (su, sd, width) = match (simulate(&up), simulate(&down)) {
            (Some(su), Some(sd)) => (su, sd, 2.0 * h),
            (Some(su), None) => (su, sim.clone(), h),
            (None, Some(sd)) => (sim.clone(), sd, h),
            (None, None) => return Err(CovarianceError::NoModel { name: names[i].clone(), step: h }),
        };
        jac.push(kept.iter().map(|&k| (su[k] - sd[k]) / width).collect());
    }
    let map_rows = map_rows(&layout, steady_windows, &kept);
    let norms: Vec<f64> = jac.iter().map(|c| c.iter().map(|v| v * v).sum::<f64>().sqrt()).collect();
    let largest = norms.iter().copied().fold(0.0, f64::max);
    let informed: Vec<usize> =
        (0..n).filter(|&i| norms[i] > NO_INFORMATION * largest && norms[i].is_finite()).collect();
    let held: Vec<String> = (0..n).filter(|i| !informed.contains(i)).map(|i| names[i].clone()).collect();
    // The estimating equations' columns: the Jacobian itself for output-error parameters, the
    // Jacobian weighted to the steady windows' means for the map's.
    let equations: Vec<Vec<f64>> = informed
        .iter()
        .map(|&i| match (&map_rows.weights, map_rows.range.contains(&i)) {
            (Some(w), true) => jac[i].iter().zip(w).map(|(j, w)| j * w).collect(),
            _ => jac[i].clone(),
        })
        .collect();
    let m = informed.len();
    let slope: DMatrix<f64> =
        DMatrix::from_fn(m, m, |a, b| equations[a].iter().zip(&jac[informed[b]]).map(|(c, j)| c * j).sum());
    let singular = || CovarianceError::Singular {
        output: output.clone(),
        names: informed.iter().map(|&i| names[i].clone()).collect(),
    };
    let inverse = slope.try_inverse().ok_or_else(singular)?;
    let bandwidth_samples = bandwidth(&e);
    let mut scores = long_run_variance(&equations, &e, bandwidth_samples);
    let map_equations: Vec<usize> = (0..m).filter(|&a| map_rows.range.contains(&informed[a])).collect();
    at_least_stationary(
        &mut scores,
        &map_equations,
        &equations,
        &e,
        &window_positions(steady_windows, &kept),
    );
    let sandwich: DMatrix<f64> = &inverse * scores * inverse.transpose();
    if sandwich.iter().any(|v| !v.is_finite()) {
        return Err(singular());
    }
    let mut matrix = vec![vec![0.0; n]; n];
    for (a, &i) in informed.iter().enumerate() {
        for (b, &j) in informed.iter().enumerate() {
            matrix[i][j] = 0.5 * (sandwich[(a, b)] + sandwich[(b, a)]);
        }
    }
    Ok(ParameterCovariance { names, values: theta0, matrix, held, bandwidth_samples, samples: kept.len() })
}

/// Each steady window as the positions in `kept` (the run's samples the covariance uses) it covers.
fn window_positions(steady_windows: &[Range<usize>], kept: &[usize]) -> Vec<Vec<usize>> {
    steady_windows
        .iter()
        .map(|w| (0..kept.len()).filter(|&p| w.contains(&kept[p])).collect::<Vec<usize>>())
        .filter(|positions| !positions.is_empty())
        .collect()
}

/// Widen the map equations' block of the scores' variance `scores` to at least what a stationary
/// residual gives them: `Σ_w Σ_{k,l∈w} cₖ cₗᵀ γ_{|k−l|}` over the steady windows `windows`, with
/// `γ` the residual `e`'s autocovariance over the whole run.
///
/// Why: a map coefficient's equation is a weighted mean of the residual over each steady window,
/// so its variance is that of the windows' mean errors. The Newey–West sum over the window's own
/// residuals cannot give it: with a bandwidth as long as the window it collapses to the squared
/// window mean, which the map's fit itself has pulled towards zero (a handful of windows for three
/// or four coefficients); with the residual's short bandwidth it misses the part that is
/// correlated over the spool's settling time, the measured input's noise filtered by the model,
/// which is a small share of the residual's variance but not of a window mean's. On the paper's own
/// shaft-speed model with a tenth of its sensor noise, the steady gains' 95 % intervals covered the
/// truth 78 % of the time before this (87 % with the fuel noise left out). The residual's
/// autocovariance over the whole run sees that correlation wherever it is; the whole run also
/// carries the transients' model error, so the bound is on the side of wider intervals. Only the
/// part of the bound above the sandwich's own block is added (its positive part), so the result
/// stays a covariance and no interval narrows.
fn at_least_stationary(
    scores: &mut DMatrix<f64>,
    map_equations: &[usize],
    equations: &[Vec<f64>],
    e: &[f64],
    windows: &[Vec<usize>],
) {
    let q = map_equations.len();
    let longest = windows.iter().map(Vec::len).max().unwrap_or(0);
    if q == 0 || longest == 0 || e.is_empty() {
        return;
    }
    let n = e.len();
    let mean = e.iter().sum::<f64>() / n as f64;
    let gamma: Vec<f64> = (0..longest.min(n))
        .map(|lag| e[lag..].iter().zip(e).map(|(a, b)| (a - mean) * (b - mean)).sum::<f64>() / n as f64)
        .collect();
    let mut bound = DMatrix::<f64>::zeros(q, q);
    for positions in windows {
        for (i, &a) in map_equations.iter().enumerate() {
            for (j, &b) in map_equations.iter().enumerate().take(i + 1) {
                let mut sum = 0.0;
                for &k in positions {
                    for &l in positions {
                        sum += equations[a][k] * equations[b][l] * gamma[k.abs_diff(l).min(gamma.len() - 1)];
                    }
                }
                bound[(i, j)] += sum;
                if i != j {
                    bound[(j, i)] += sum;
                }
            }
        }
    }
    let own = DMatrix::from_fn(q, q, |i, j| scores[(map_equations[i], map_equations[j])]);
    let eigen = (bound - own).symmetric_eigen();
    let clipped = eigen.eigenvalues.map(|v| v.max(0.0));
    let extra = &eigen.eigenvectors * DMatrix::from_diagonal(&clipped) * eigen.eigenvectors.transpose();
    for (i, &a) in map_equations.iter().enumerate() {
        for (j, &b) in map_equations.iter().enumerate() {
            scores[(a, b)] += extra[(i, j)];
        }
    }
}

/// Which parameters are the map's, and each kept sample's weight in the map's least squares
/// (`1/len` inside a steady window of `len` samples, 0 elsewhere); no weights without windows.
struct MapRows {
    range: Range<usize>,
    weights: Option<Vec<f64>>,
}

fn map_rows(layout: &Layout, steady_windows: &[Range<usize>], kept: &[usize]) -> MapRows {
    let start = slot_len(&layout.poles) + slot_len(&layout.zeros);
    let range = start..start + layout.map;
    if steady_windows.is_empty() {
        return MapRows { range, weights: None };
    }
    let weight =
        |k: usize| steady_windows.iter().find(|w| w.contains(&k)).map_or(0.0, |w| 1.0 / w.len() as f64);
    MapRows { range, weights: Some(kept.iter().map(|&k| weight(k)).collect()) }
}

impl ParameterCovariance {
    /// The standard deviation of each parameter.
    pub fn std_devs(&self) -> Vec<f64> {
        (0..self.values.len()).map(|i| self.matrix[i][i].max(0.0).sqrt()).collect()
    }

    /// A square root `L` of the covariance (`L Lᵀ = Σ`): the Cholesky factor, or from the
    /// eigenvalues (negative rounding clamped to zero) when the matrix is only semi-definite.
    fn root(&self) -> DMatrix<f64> {
        let n = self.values.len();
        let sigma = DMatrix::from_fn(n, n, |i, j| self.matrix[i][j]);
        if let Some(ch) = sigma.clone().cholesky() {
            return ch.l();
        }
        let eig = sigma.symmetric_eigen();
        let scale = DMatrix::from_diagonal(&eig.eigenvalues.map(|l| l.max(0.0).sqrt()));
        &eig.eigenvectors * scale
    }

    /// `n` parameter vectors drawn from the normal distribution of the covariance, reproducibly
    /// from `seed`.
    pub fn draw_parameters(&self, n: usize, seed: u64) -> Vec<Vec<f64>> {
        let root = self.root();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let dim = self.values.len();
        (0..n)
            .map(|_| {
                let z = nalgebra::DVector::from_fn(dim, |_, _| StandardNormal.sample(&mut rng));
                let dx = &root * z;
                self.values.iter().zip(dx.iter()).map(|(v, d)| v + d).collect()
            })
            .collect()
    }

    /// `n` models drawn from the covariance around `model` (whose parameters it must describe);
    /// draws that give no model (an effect parameter out of its range, a zero at z = 1) are left out, so fewer
    /// than `n` may come back.
    pub fn draw_models(
        &self,
        model: &ExtendedModel,
        n: usize,
        seed: u64,
    ) -> Result<Vec<ExtendedModel>, CovarianceError> {
        let (layout, _, values) = layout(model)?;
        if values.len() != self.values.len() {
            return Err(CovarianceError::Mismatch { stored: self.values.len(), model: values.len() });
        }
        Ok(self
            .draw_parameters(n, seed)
            .iter()
            .filter_map(|theta| drawn_model(model, &layout, theta, &self.values))
            .collect())
    }
}
