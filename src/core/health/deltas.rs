//! Health deltas: what a run needs, beyond its engine's reference model, to be explained. Fitted by
//! output error (the one Levenberg–Marquardt loop) from the reference itself (no delta), on every
//! output of the run at once:
//! - **input gain** `g` (u → g·u, shared by every output): the fuel the engine turns into speed per
//!   unit of the logged input. A meter that reads 2 % high, or an engine that needs 2 % more fuel for
//!   the same speed, shows as g ≈ 1/1.02.
//! - **time-constant scale** `s` (shared): every pole's continuous time constant times s — a real
//!   pole p → p^(1/s), a pair's modulus^(1/s) and angle/s — the DC gain kept. Fitted as ln s, so its
//!   interval is positive.
//! - **map shift** `d` per output: added to the output's static map (in the output's units).
//!
//! **The input offset is held at zero, not fitted.** An offset c (u → g·u + c) moves every output's
//! steady state by f′(v)·k·c, where k is the linear block's DC gain and f′ the map's slope: over an
//! operating range where f′ changes little this is a constant shift of each output, the same
//! signature as the map shifts. Two outputs do not separate it either (two steady intercepts for
//! three unknowns c, d₁, d₂); only the maps' curvature does, weakly, which makes c and the d's
//! correlated near ±1 and both intervals uselessly wide. So the offset is reported inside the map
//! shifts (an offset of the fuel meter reads as "speed map X rpm high" on every output alike), and
//! the gain, which the slope of the steady curve fixes on its own, is fitted.
//!
//! **Intervals.** The residuals of a simulated model are autocorrelated (a map error persists through
//! a hold), so the plain Gauss–Newton covariance σ²(JᵀJ)⁻¹ is too narrow. The sandwich
//! (JᵀJ)⁻¹ S (JᵀJ)⁻¹ is used instead, with S the Newey–West long-run variance of the scores summed
//! over the outputs at each sample (`core::identification::uncertainty`, the same estimator as the
//! model's own parameter intervals), and the 95 % interval is the estimate ± 1.96 standard errors.
use num_complex::Complex64;

use crate::core::effects::ExtendedModel;
use crate::core::identification::initial_state::InitialState;
use crate::core::identification::uncertainty::{bandwidth, long_run_variance};
use crate::core::numerics::lm::{Damping, Jacobian, LeastSquares, LmError, LmSettings, StepSolver};
use crate::core::numerics::lm::{minimise, no_progress};
use crate::core::numerics::poly::poly_from_roots;
use crate::core::numerics::tf::DiscreteTf;
use crate::core::run::Run;

/// Two-sided 95 % normal quantile.
pub(crate) const Z95: f64 = 1.959_963_984_540_054;
/// Central-difference step of the covariance's Jacobian, in the parameters' own scale (the gain,
/// ln s and the map shifts over the output's range are all of order one): small against any
/// change the data can resolve, large against the simulation's rounding (≈1e-12 relative).
const COV_STEP: f64 = 1e-5;
/// Fewest samples per fitted parameter: below this the long-run variance has too few lags to
/// average over (the bandwidth is at least 4 samples, the run must hold several bandwidths).
const SAMPLES_PER_PARAMETER: usize = 20;

/// The deltas applied to a reference (the reference itself: gain 1, offset 0, scale 1, no shift).
#[derive(Clone, Debug, PartialEq)]
pub struct Deltas {
    pub input_gain: f64,
    pub input_offset: f64,
    pub tau_scale: f64,
    /// Per output of the reference, in its order, in the output's units.
    pub map_shift: Vec<f64>,
}

impl Deltas {
    /// No change: the reference as it is, for `outputs` outputs.
    pub fn none(outputs: usize) -> Self {
        Self { input_gain: 1.0, input_offset: 0.0, tau_scale: 1.0, map_shift: vec![0.0; outputs] }
    }
}

/// A fitted delta and its 95 % interval (`None` when the data do not fix it).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Estimate {
    pub value: f64,
    pub ci95: Option<[f64; 2]>,
}

impl Estimate {
    /// The standard error the interval stands for (half its width over 1.96).
    pub fn std_error(&self) -> Option<f64> {
        self.ci95.map(|[lo, hi]| (hi - lo) / (2.0 * Z95))
    }
}

/// The deltas of one run against its engine's reference.
#[derive(Clone, Debug, PartialEq)]
pub struct HealthFit {
    pub input_gain: Estimate,
    pub tau_scale: Estimate,
    /// Per output of the reference, in the output's units.
    pub map_shift: Vec<Estimate>,
    /// Each output's simulation with the fitted deltas.
    pub fitted: Vec<Vec<f64>>,
    /// The Newey–West bandwidth of the intervals, samples.
    pub bandwidth_samples: usize,
}

impl HealthFit {
    pub fn deltas(&self) -> Deltas {
        Deltas {
            input_gain: self.input_gain.value,
            input_offset: 0.0,
            tau_scale: self.tau_scale.value,
            map_shift: self.map_shift.iter().map(|e| e.value).collect(),
        }
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HealthError {
    #[error("no output model to fit the health deltas of")]
    NoOutputs,
    #[error("the run '{run}' does not hold the output '{output}'")]
    MissingOutput { run: String, output: String },
    #[error("run '{run}' has {samples} samples: too few to fit {parameters} health deltas ({needed} needed)")]
    TooShort { run: String, samples: usize, parameters: usize, needed: usize },
    #[error("the reference of '{output}' cannot be simulated on run '{run}': {reason}")]
    Simulation { run: String, output: String, reason: String },
    #[error("the time constants cannot be scaled: {reason}")]
    Scale { reason: String },
    #[error("fitting the health deltas of run '{run}': {source}")]
    Fit {
        run: String,
        #[source]
        source: LmError,
    },
}

/// `tf` with every pole's continuous time constant multiplied by `s` (a real pole p → p^(1/s), a
/// pair's modulus^(1/s) and angle/s) and its numerator rescaled so the DC gain stays. Poles on the
/// negative real axis (a sample-alternating mode, no time constant) and at the origin stay.
pub fn scale_time_constants(tf: &DiscreteTf, s: f64) -> Result<DiscreteTf, HealthError> {
    let bad = |reason: String| HealthError::Scale { reason };
    if !(s.is_finite() && s > 0.0) {
        return Err(bad(format!("the scale {s} is not a positive number")));
    }
    let poles = tf.poles().map_err(|e| bad(e.to_string()))?;
    let moved: Vec<Complex64> = poles
        .iter()
        .map(|p| {
            let (r, angle) = p.to_polar();
            let alternating = p.im.abs() <= 1e-12 * r && p.re < 0.0;
            if r <= 0.0 || alternating { *p } else { Complex64::from_polar(r.powf(1.0 / s), angle / s) }
        })
        .collect();
    let mut den = poly_from_roots(&moved);
    // The denominator in z⁻¹ keeps its length (trailing zeros stand for poles at the origin).
    den.resize(tf.den_zinv.len().max(den.len()), 0.0);
    let (old, new): (f64, f64) = (tf.den_zinv.iter().sum(), den.iter().sum());
    if old.abs() <= 1e-12 * tf.den_zinv.iter().map(|a| a.abs()).sum::<f64>() {
        return Err(bad("the linear block has no steady state (a pole at z = 1)".into()));
    }
    let num = tf.num_zinv.iter().map(|b| b * new / old).collect();
    DiscreteTf::new(num, den, tf.dt_secs).map_err(|e| bad(e.to_string()))
}

/// The reference `model` with `deltas` on `run` (its map shift `shift` in the output's units).
pub fn simulate_with(
    model: &ExtendedModel,
    run: &Run,
    deltas: &Deltas,
    shift: f64,
    initial: InitialState,
) -> Result<Vec<f64>, HealthError> {
    let failed = |reason: String| HealthError::Simulation {
        run: run.name.clone(),
        output: model.output.clone(),
        reason,
    };
    let mut moved = model.clone();
    let one = (deltas.tau_scale - 1.0).abs() <= f64::EPSILON;
    if !one {
        moved.wiener.linear.tf = scale_time_constants(&model.wiener.linear.tf, deltas.tau_scale)?;
    }
    let mut driven = run.clone();
    let (g, c) = (deltas.input_gain, deltas.input_offset);
    driven.input.values.iter_mut().for_each(|u| *u = g * *u + c);
    let y = moved.simulate_scored(&driven, initial).map_err(|e| failed(e.to_string()))?;
    Ok(y.into_iter().map(|v| v + shift).collect())
}

/// What one output contributes to the fit: its model, measurement, range and error scale.
struct OutputData<'a> {
    model: &'a ExtendedModel,
    y: &'a [f64],
    /// The output's range on the run (the map shift is fitted over it, so every parameter is O(1)).
    range: f64,
    /// Its residual's scale: the reference's RMSE on the run (each output weighs in its own error).
    scale: f64,
}

/// Parameters θ = [g, ln s, d₁/range₁, …].
fn deltas_of(theta: &[f64], outputs: &[OutputData<'_>]) -> (Deltas, Vec<f64>) {
    let shifts: Vec<f64> = outputs.iter().enumerate().map(|(i, o)| theta[2 + i] * o.range).collect();
    let deltas = Deltas {
        input_gain: theta[0],
        input_offset: 0.0,
        tau_scale: theta[1].exp(),
        map_shift: shifts.clone(),
    };
    (deltas, shifts)
}

/// Each output's simulation at θ, `None` where one cannot be simulated or is not finite.
fn simulate_all(
    theta: &[f64],
    outputs: &[OutputData<'_>],
    run: &Run,
    initial: InitialState,
) -> Option<Vec<Vec<f64>>> {
    if !(theta[0].is_finite() && theta[0] > 0.0) {
        return None;
    }
    let (deltas, shifts) = deltas_of(theta, outputs);
    outputs
        .iter()
        .zip(&shifts)
        .map(|(o, &d)| {
            let y = simulate_with(o.model, run, &deltas, d, initial).ok()?;
            y.iter().all(|v| v.is_finite()).then_some(y)
        })
        .collect()
}

/// The scaled residuals of every output, one per sample and output.
fn residuals(sims: &[Vec<f64>], outputs: &[OutputData<'_>]) -> Vec<Vec<f64>> {
    sims.iter()
        .zip(outputs)
        .map(|(s, o)| s.iter().zip(o.y).map(|(a, b)| (a - b) / o.scale).collect())
        .collect()
}

/// Fit the health deltas of `run` against the reference `models` (one per output, in order), every
/// output of the reference being measured on the run.
pub fn fit_deltas(
    models: &[ExtendedModel],
    run: &Run,
    initial: InitialState,
) -> Result<HealthFit, HealthError> {
    if models.is_empty() {
        return Err(HealthError::NoOutputs);
    }
    let parameters = 2 + models.len();
    let needed = SAMPLES_PER_PARAMETER * parameters;
    if run.len() < needed {
        return Err(HealthError::TooShort { run: run.name.clone(), samples: run.len(), parameters, needed });
    }
    let none = Deltas::none(models.len());
    let mut outputs = Vec::with_capacity(models.len());
    for model in models {
        let Some(channel) = run.output(&model.output) else {
            return Err(HealthError::MissingOutput { run: run.name.clone(), output: model.output.clone() });
        };
        let y = channel.values.as_slice();
        let (lo, hi) = y.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
        let range = if hi > lo { hi - lo } else { hi.abs().max(1.0) };
        let reference = simulate_with(model, run, &none, 0.0, initial)?;
        let rmse =
            (reference.iter().zip(y).map(|(a, b)| (a - b) * (a - b)).sum::<f64>() / y.len() as f64).sqrt();
        // A perfect reference (noiseless data) still needs a scale: a millionth of the range.
        let scale = if rmse.is_finite() && rmse > 1e-6 * range { rmse } else { 1e-6 * range };
        outputs.push(OutputData { model, y, range, scale });
    }
    let stacked = |theta: &[f64]| -> Option<Vec<f64>> {
        let sims = simulate_all(theta, &outputs, run, initial)?;
        Some(residuals(&sims, &outputs).concat())
    };
    let mut problem: LeastSquares<_, LmError> =
        LeastSquares::new(stacked, Jacobian::default(), StepSolver::QrOnce);
    let settings = LmSettings { max_iterations: 40, cost_tol: 1e-9, damping: Damping::marquardt(16) };
    let mut theta0 = vec![1.0, 0.0];
    theta0.extend(std::iter::repeat_n(0.0, models.len()));
    let fitted = minimise(&mut problem, &theta0, &settings, &mut no_progress)
        .map_err(|source| HealthError::Fit { run: run.name.clone(), source })?;
    let theta = fitted.theta;
    let sims = simulate_all(&theta, &outputs, run, initial).ok_or_else(|| HealthError::Simulation {
        run: run.name.clone(),
        output: models[0].output.clone(),
        reason: "the fitted deltas give no finite simulation".into(),
    })?;
    let (cov, bandwidth_samples) = covariance(&theta, &sims, &outputs, run, initial).unzip();
    let se = |i: usize| cov.as_ref().map(|c: &nalgebra::DMatrix<f64>| c[(i, i)].max(0.0).sqrt());
    let interval = |value: f64, i: usize, scale: f64| Estimate {
        value: value * scale,
        ci95: se(i).map(|e| [(value - Z95 * e) * scale, (value + Z95 * e) * scale]),
    };
    let tau = Estimate {
        value: theta[1].exp(),
        ci95: se(1).map(|e| [(theta[1] - Z95 * e).exp(), (theta[1] + Z95 * e).exp()]),
    };
    Ok(HealthFit {
        input_gain: interval(theta[0], 0, 1.0),
        tau_scale: tau,
        map_shift: outputs.iter().enumerate().map(|(i, o)| interval(theta[2 + i], 2 + i, o.range)).collect(),
        fitted: sims,
        bandwidth_samples: bandwidth_samples.unwrap_or(0),
    })
}

/// The sandwich covariance of θ and its Newey–West bandwidth; `None` when the information matrix
/// is singular (a delta the run does not excite, e.g. the time constants of a run without a step).
fn covariance(
    theta: &[f64],
    sims: &[Vec<f64>],
    outputs: &[OutputData<'_>],
    run: &Run,
    initial: InitialState,
) -> Option<(nalgebra::DMatrix<f64>, usize)> {
    let e = residuals(sims, outputs);
    let n = theta.len();
    // Jacobian columns per output by central differences.
    let mut jac: Vec<Vec<Vec<f64>>> = Vec::with_capacity(n);
    for i in 0..n {
        let (mut up, mut down) = (theta.to_vec(), theta.to_vec());
        up[i] += COV_STEP;
        down[i] -= COV_STEP;
        let (su, sd) =
            (simulate_all(&up, outputs, run, initial)?, simulate_all(&down, outputs, run, initial)?);
        let (ru, rd) = (residuals(&su, outputs), residuals(&sd, outputs));
        jac.push(
            ru.iter()
                .zip(&rd)
                .map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y) / (2.0 * COV_STEP)).collect())
                .collect(),
        );
    }
    let samples = run.len();
    let information: nalgebra::DMatrix<f64> = nalgebra::DMatrix::from_fn(n, n, |a, b| {
        (0..outputs.len())
            .map(|o| jac[a][o].iter().zip(&jac[b][o]).map(|(x, y)| x * y).sum::<f64>())
            .sum::<f64>()
    });
    // The scores summed over the outputs at each sample, so the long-run variance keeps the
    // outputs' correlation at equal times and lags (a spool error shows on speed and thrust alike).
    let scores: Vec<Vec<f64>> = (0..n)
        .map(|a| (0..samples).map(|k| (0..outputs.len()).map(|o| jac[a][o][k] * e[o][k]).sum()).collect())
        .collect();
    let lags = e.iter().map(|r| bandwidth(r)).max().unwrap_or(0);
    let ones = vec![1.0; samples];
    let inverse = information.try_inverse()?;
    let sandwich: nalgebra::DMatrix<f64> = &inverse * long_run_variance(&scores, &ones, lags) * &inverse;
    sandwich.iter().all(|v| v.is_finite()).then_some((sandwich, lags))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::core::identification::static_map::StaticMap;
    use crate::core::identification::wiener::{LinearBlock, WienerModel};
    use crate::core::run::Channel;

    fn tf() -> DiscreteTf {
        // Poles 0.9 and a pair at 0.7 ± 0.2i; unit DC gain.
        let poles = [Complex64::new(0.9, 0.0), Complex64::new(0.7, 0.2), Complex64::new(0.7, -0.2)];
        let den = poly_from_roots(&poles);
        let dc: f64 = den.iter().sum();
        DiscreteTf::new(vec![0.0, dc], den, 0.1).unwrap()
    }

    #[test]
    fn scaled_time_constants_keep_the_gain_and_stretch_every_pole() {
        let s = 1.5;
        let scaled = scale_time_constants(&tf(), s).unwrap();
        assert!((scaled.dc_gain().unwrap() - 1.0).abs() < 1e-12);
        let tau = |p: Complex64| -0.1 / p.norm().ln();
        let (before, after) = (tf().poles().unwrap(), scaled.poles().unwrap());
        for (a, b) in before.iter().zip(&after) {
            assert!((tau(*b) / tau(*a) - s).abs() < 1e-9, "{a} → {b}");
            assert!((b.arg() - a.arg() / s).abs() < 1e-9);
        }
        let back = scale_time_constants(&scaled, 1.0 / s).unwrap();
        for (a, b) in back.den_zinv.iter().zip(&tf().den_zinv) {
            assert!((a - b).abs() < 1e-12);
        }
        assert!(scale_time_constants(&tf(), 0.0).is_err());
    }

    fn model(map: &[f64]) -> ExtendedModel {
        let wiener = WienerModel {
            linear: LinearBlock { tf: tf(), offset: 0.0 },
            map: StaticMap { coeffs_scaled: map.to_vec(), ..StaticMap::identity() },
        };
        ExtendedModel::new("shaft_speed_rpm", wiener)
    }

    /// Steps through the range, like a test-bench run.
    fn run_with(y: Vec<f64>, u: Vec<f64>) -> Run {
        let n = u.len();
        Run {
            name: "r".into(),
            dt_secs: 0.1,
            t_secs: (0..n).map(|k| k as f64 * 0.1).collect(),
            input: Channel { name: "fuel_flow_gph".into(), unit: "gal/h".into(), values: u },
            outputs: vec![Channel { name: "shaft_speed_rpm".into(), unit: "rpm".into(), values: y }],
            aux: Vec::new(),
        }
    }

    fn steps() -> Vec<f64> {
        (0..1200).map(|k| [2.0, 5.0, 3.0, 7.0, 4.0, 6.0][(k / 200) % 6]).collect()
    }

    #[test]
    fn recovers_known_deltas_and_covers_them() {
        let reference = model(&[10_000.0, 9_000.0, -300.0]);
        let u = steps();
        let truth = Deltas { input_gain: 0.95, input_offset: 0.0, tau_scale: 1.3, map_shift: vec![-400.0] };
        let placeholder = run_with(vec![1.0; u.len()], u.clone());
        let clean = simulate_with(&reference, &placeholder, &truth, -400.0, InitialState::Steady).unwrap();
        // Noise with a slow wander, as a model's residual has.
        let mut state = 0.0;
        let y: Vec<f64> = clean
            .iter()
            .enumerate()
            .map(|(k, v)| {
                state = 0.9 * state + 30.0 * ((k as f64 * 1.7).sin() + (k as f64 * 0.37).cos());
                v + state
            })
            .collect();
        let fit = fit_deltas(&[reference], &run_with(y, u), InitialState::Steady).unwrap();
        assert!((fit.input_gain.value - 0.95).abs() < 0.01, "{fit:?}");
        assert!((fit.tau_scale.value - 1.3).abs() < 0.1, "{fit:?}");
        assert!((fit.map_shift[0].value + 400.0).abs() < 150.0, "{fit:?}");
        let [lo, hi] = fit.input_gain.ci95.unwrap();
        assert!(lo < fit.input_gain.value && fit.input_gain.value < hi);
        assert!(fit.bandwidth_samples >= 4);
    }

    #[test]
    fn errors_name_the_run() {
        let reference = model(&[0.0, 1.0]);
        let short = run_with(vec![1.0; 10], vec![1.0; 10]);
        assert!(matches!(
            fit_deltas(std::slice::from_ref(&reference), &short, InitialState::Steady),
            Err(HealthError::TooShort { .. })
        ));
        let mut other = reference;
        other.output = "thrust_n".into();
        let run = run_with(vec![1.0; 400], vec![1.0; 400]);
        let err = fit_deltas(&[other], &run, InitialState::Steady).unwrap_err();
        assert!(err.to_string().contains("thrust_n"), "{err}");
        assert_eq!(fit_deltas(&[], &run, InitialState::Steady), Err(HealthError::NoOutputs));
    }
}
