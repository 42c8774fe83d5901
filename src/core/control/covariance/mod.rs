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
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use crate::core::effects::ExtendedModel;
use crate::core::numerics::tf::DiscreteTf;

/// A root whose imaginary part is below this share of its modulus (or of 1) is a real root: the
/// polynomial root finder returns a real root with an imaginary part of rounding size (~1e-12),
/// far below it, and a genuine pair this close to the axis has no oscillation a run could show.
const REAL_TOL: f64 = 1e-7;

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
    /// The output is read off the shaft speed's model, whose parameters are estimated on the speed,
    /// but the run does not measure exactly one shaft speed.
    #[error(
        "'{output}' is read off the shaft speed's model, whose parameters' uncertainty is estimated on \
         the speed, but run '{run}' does not measure exactly one shaft speed"
    )]
    ReadOff { output: String, run: String },
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

/// The model with its parameters at `theta` (in the order of [`parameters`]); `None` where they
/// give no model.
pub fn model_at(model: &ExtendedModel, theta: &[f64]) -> Option<ExtendedModel> {
    let (layout, _, values) = layout(model).ok()?;
    (theta.len() == values.len()).then(|| with_parameters(model, &layout, theta))?
}

mod draws;
mod estimate;
mod map_equations;

pub use estimate::estimate;
