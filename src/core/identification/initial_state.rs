//! Scoring from an estimated initial state: a logged run often starts mid-transient (the engine is
//! still spooling up when the log begins), and a model simulated from the steady state of its first
//! input sample then starts in the wrong place. As MATLAB's `compare` does with an estimated initial
//! condition, the model's linear block is given the free response that best fits the first seconds
//! of the measured output, so a start-up transient is not counted as model error.
//!
//! **What is estimated.** A linear block with poles p₁…pₙ, started anywhere, differs from its
//! steady-state start by a free response v_free(k) = Σ cᵢ φᵢ(k): φ = pᵏ for a real pole, rᵏcos(kθ)
//! and rᵏsin(kθ) for a pair re^{±jθ}. The n coefficients are fitted by Gauss–Newton so that the
//! model's output, with the free response added to the linear block's output, matches the
//! measurement over a window at the start of the run; the rest of the run is then simulated with
//! that free response (it dies away with the poles).
//!
//! **The window** is three time constants of the slowest pole (its free response has then fallen to
//! e⁻³ ≈ 5 %, so later samples say nothing about the initial state but carry model error that would
//! bias it), at least four samples per coefficient, at most half the run.
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use crate::core::numerics::lstsq::solve_lstsq;

/// Gauss–Newton iterations; the problem is linear for a linear output stage and mildly nonlinear
/// through a monotone static map, so a few suffice (the loop stops once the step is negligible).
const ITERATIONS: usize = 8;
/// Relative step of the finite-difference Jacobian, on the scale of the output's change.
const DIFF_SCALE: f64 = 1e-6;

/// Where a scored simulation starts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InitialState {
    /// The steady state of the first input sample (the model's own start, and `predict`'s).
    Steady,
    /// The state that best fits the first seconds of the measured output (see the module doc).
    #[default]
    Estimated,
}

impl InitialState {
    /// How report.json and the app name the choice.
    pub fn describe(self) -> &'static str {
        match self {
            Self::Steady => "every model starts from the steady state of the run's first input sample",
            Self::Estimated => {
                "each model's linear block starts from the state that best fits the first seconds of \
                 the measured output (free response over three time constants of its slowest pole)"
            }
        }
    }
}

/// Poles this close to the origin have no mode of their own in the free response: it falls below
/// 1 % of its start within one sample, so it shapes the first sample alone, and fitting its
/// coefficient fits that one sample's noise. Two such poles (an admissible fit pins poles it pushes
/// off the negative axis at `1e-3`) give two all-but-equal columns whose coefficients the least
/// squares sends to plus and minus infinity, and the scored start zig-zags by tens of percent.
const FASTEST_MODE: f64 = 0.01;
/// Poles closer together than this (in the z-plane) give one mode: their columns differ by less
/// than the rounding of the fit can tell apart.
const SAME_POLE: f64 = 1e-6;

/// The free-response basis of a set of poles over `n` samples: one column per real pole, two per
/// conjugate pair (poles with a negative imaginary part are taken with their partner); none for a
/// pole faster than [`FASTEST_MODE`] or one that repeats another within [`SAME_POLE`].
pub fn free_modes(poles: &[Complex64], n: usize) -> Vec<Vec<f64>> {
    let mut modes = Vec::new();
    let mut taken: Vec<Complex64> = Vec::new();
    for p in poles.iter().filter(|p| p.im >= 0.0 && p.norm() < 1.0 && p.norm() >= FASTEST_MODE) {
        if taken.iter().any(|q| (q - p).norm() < SAME_POLE) {
            continue;
        }
        taken.push(*p);
        // pᵏ by repeated multiplication (this runs on every frame of a drag): for |p| < 1 the
        // rounding errors shrink with the powers, so the recurrence is as accurate as powi.
        let powers = std::iter::successors(Some(Complex64::new(1.0, 0.0)), |z| Some(z * p)).take(n);
        if p.im.abs() <= 1e-9 * (1.0 + p.norm()) {
            modes.push(std::iter::successors(Some(1.0), |x| Some(x * p.re)).take(n).collect());
        } else {
            let (re, im): (Vec<f64>, Vec<f64>) = powers.map(|z| (z.re, z.im)).unzip();
            modes.push(re);
            modes.push(im);
        }
    }
    modes
}

/// The fitting window in samples for these poles over a run of `n` samples (see the module
/// documentation).
pub fn window(poles: &[Complex64], n: usize) -> usize {
    let slowest = poles.iter().map(|p| p.norm()).filter(|m| *m < 1.0).fold(0.0, f64::max);
    let tau_samples = if slowest > 0.0 { -1.0 / slowest.ln() } else { 1.0 };
    let wanted = (3.0 * tau_samples).ceil() as usize;
    let n_modes = free_modes(poles, 1).len();
    wanted.max(4 * n_modes).min(n / 2)
}

/// The linear block's output `v` with the free response of `poles` that makes `output(v)` best fit
/// `y` over the first samples (see the module documentation). `output` maps a linear-block output
/// (any length) to the model's output (same length) and must be causal. Returns `v` unchanged when
/// there is nothing to fit.
pub fn fit_free_response<F>(poles: &[Complex64], v: &[f64], y: &[f64], output: F) -> Vec<f64>
where
    F: Fn(&[f64]) -> Vec<f64>,
{
    let n = v.len().min(y.len());
    let w = window(poles, n);
    let modes = free_modes(poles, v.len());
    if modes.is_empty() || w < 2 * modes.len() {
        return v.to_vec();
    }
    let with = |c: &[f64], len: usize| -> Vec<f64> {
        (0..len).map(|k| v[k] + modes.iter().zip(c).map(|(m, ci)| ci * m[k]).sum::<f64>()).collect()
    };
    let scale = y[..w].iter().map(|x| x.abs()).fold(0.0, f64::max).max(1.0);
    let h = DIFF_SCALE * scale;
    let mut c = vec![0.0; modes.len()];
    for _ in 0..ITERATIONS {
        let base = output(&with(&c, w));
        let r: Vec<f64> = (0..w).map(|k| y[k] - base[k]).collect();
        let columns: Vec<Vec<f64>> = (0..c.len())
            .map(|i| {
                let mut shifted = c.clone();
                shifted[i] += h;
                let out = output(&with(&shifted, w));
                (0..w).map(|k| (out[k] - base[k]) / h).collect()
            })
            .collect();
        let a = faer::Mat::from_fn(w, c.len(), |k, i| columns[i][k]);
        let Ok(step) = solve_lstsq(&a, &r) else { break };
        for (ci, di) in c.iter_mut().zip(&step.x) {
            *ci += di;
        }
        if step.x.iter().map(|d| d.abs()).fold(0.0, f64::max) <= 1e-9 * scale {
            break;
        }
    }
    with(&c, v.len())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::core::identification::wiener::unit_gain_tf;

    /// A block started away from its steady state is matched: the estimated start recovers the
    /// measured transient, which a steady start misses.
    #[test]
    fn a_start_mid_transient_is_recovered() {
        let poles = [Complex64::new(0.9, 0.0), Complex64::new(0.6, 0.3), Complex64::new(0.6, -0.3)];
        let tf = unit_gain_tf(&poles, &[], 0.1).unwrap();
        let u = vec![1.0; 200];
        // Truth: the same block started at rest (0) instead of at its steady state (1), through a
        // monotone quadratic map.
        let map = |v: &[f64]| v.iter().map(|x| 50.0 + 10.0 * x + 3.0 * x * x).collect::<Vec<f64>>();
        let truth = map(&tf.simulate_with_history(&u, 0.0, 0.0));
        let v_steady = tf.simulate_from_steady(&u);
        let fitted = fit_free_response(&poles, &v_steady, &truth, map);
        let err = |v: &[f64]| map(v).iter().zip(&truth).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
        assert!(err(&v_steady) > 1.0, "the steady start misses the transient");
        assert!(err(&fitted) < 1e-6, "estimated start error {}", err(&fitted));
        assert_eq!(free_modes(&poles, 3).len(), 3);
        assert_eq!(window(&poles, 200), 29, "three time constants of the 0.9 pole");
    }

    /// Two poles pinned next to the origin (as an admissible fit leaves them) have no mode of their
    /// own, nor has a pole that repeats another: only the 0.9 pole's free response is estimated,
    /// and the estimated start of a noisy measurement lies within the noise of the truth.
    #[test]
    fn poles_at_the_origin_and_repeated_poles_have_no_mode_of_their_own() {
        let poles = [
            Complex64::new(0.9, 0.0),
            Complex64::new(0.9 + 1e-9, 0.0),
            Complex64::new(0.001 - 5e-9, 0.0),
            Complex64::new(0.001 + 5e-9, 0.0),
        ];
        assert_eq!(free_modes(&poles, 5).len(), 1, "only the 0.9 pole has a mode");
        let tf = unit_gain_tf(&poles, &[], 0.1).unwrap();
        let u = vec![1.0; 200];
        let map = |v: &[f64]| v.iter().map(|x| 100.0 * x).collect::<Vec<f64>>();
        // The truth starts 0.4 below its steady state on the 0.9 pole's mode; the measurement has
        // a noise of ±0.5 alternating sample by sample.
        let steady = tf.simulate_from_steady(&u);
        let truth =
            map(&steady.iter().enumerate().map(|(k, v)| v - 0.4 * 0.9f64.powi(k as i32)).collect::<Vec<_>>());
        let measured: Vec<f64> =
            truth.iter().enumerate().map(|(k, y)| y + if k % 2 == 0 { 0.5 } else { -0.5 }).collect();
        let fitted = map(&fit_free_response(&poles, &steady, &measured, map));
        let worst = fitted.iter().zip(&truth).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(worst < 0.5, "the estimated start is {worst} off the truth");
    }
}
