//! Levenberg–Marquardt for `min ‖r(θ)‖²` with a forward-difference Jacobian, like
//! [`crate::core::numerics::lm`], but reporting after every iteration so a long fit can show progress and be
//! cancelled. Each step solves the damped problem `[J; √λ·D] δ = [−r; 0]` by least squares (SVD).
use faer::Mat;

use super::BaselineError;
use crate::core::numerics::lstsq::solve_lstsq;
use crate::core::numerics::stats::sum_of_squares as cost_of;

pub(super) struct LmSettings {
    pub max_iterations: usize,
    /// Stop when an accepted step lowers the cost by less than this fraction.
    pub cost_tol: f64,
    /// Relative step of the finite-difference Jacobian.
    pub diff_step: f64,
}

pub(super) struct LmOutcome {
    pub theta: Vec<f64>,
    pub cost: f64,
    pub iterations: usize,
}

/// Forward-difference Jacobian (backward where the forward point is inadmissible; a zero column
/// where neither is admissible), in rows `0..n` of an `(n + p) × p` matrix whose last `p` rows are
/// left for the damping.
fn jacobian(
    theta: &[f64],
    r: &[f64],
    residual: &mut dyn FnMut(&[f64]) -> Option<Vec<f64>>,
    diff_step: f64,
) -> Mat<f64> {
    let (n, p) = (r.len(), theta.len());
    let mut jac = Mat::<f64>::zeros(n + p, p);
    for (j, &t) in theta.iter().enumerate() {
        let h = diff_step * t.abs().max(1.0);
        let shifted = |delta: f64| -> Vec<f64> {
            theta.iter().enumerate().map(|(i, ti)| if i == j { ti + delta } else { *ti }).collect()
        };
        let (rj, signed_h) = match residual(&shifted(h)) {
            Some(rj) => (rj, h),
            None => {
                let Some(rj) = residual(&shifted(-h)) else { continue };
                (rj, -h)
            }
        };
        for (i, (a, b)) in rj.iter().zip(r).enumerate() {
            jac[(i, j)] = (a - b) / signed_h;
        }
    }
    jac
}

/// Minimise `‖r(θ)‖²` from `theta0`. `residual` returns `None` where θ is not admissible (an
/// unstable pole): such steps are rejected and the damping raised. `on_iteration(k)` is called after
/// iteration `k` and may abort the fit with its error.
pub(super) fn minimise(
    theta0: &[f64],
    residual: &mut dyn FnMut(&[f64]) -> Option<Vec<f64>>,
    settings: &LmSettings,
    stage: &'static str,
    on_iteration: &mut dyn FnMut(usize) -> Result<(), BaselineError>,
) -> Result<LmOutcome, BaselineError> {
    let mut theta = theta0.to_vec();
    let Some(mut r) = residual(&theta) else {
        return Err(BaselineError::Diverged { stage, rms_normalised: f64::INFINITY });
    };
    let mut cost = cost_of(&r);
    let mut lambda: f64 = 1e-3;
    let p = theta.len();
    let mut iterations = 0;
    while iterations < settings.max_iterations && p > 0 {
        iterations += 1;
        let n = r.len();
        let mut jac = jacobian(&theta, &r, residual, settings.diff_step);
        let col_norms: Vec<f64> =
            (0..p).map(|j| (0..n).map(|i| jac[(i, j)].powi(2)).sum::<f64>().sqrt().max(1e-12)).collect();
        let mut improved = false;
        let mut converged = false;
        for _ in 0..16 {
            for (j, norm) in col_norms.iter().enumerate() {
                jac[(n + j, j)] = lambda.sqrt() * norm;
            }
            let mut rhs: Vec<f64> = r.iter().map(|x| -x).collect();
            rhs.extend(std::iter::repeat_n(0.0, p));
            let step = solve_lstsq(&jac, &rhs)?;
            let candidate: Vec<f64> = theta.iter().zip(&step.x).map(|(t, d)| t + d).collect();
            match residual(&candidate) {
                Some(rc) if cost_of(&rc) < cost => {
                    let new_cost = cost_of(&rc);
                    converged = (cost - new_cost) < settings.cost_tol * cost;
                    (theta, r, cost) = (candidate, rc, new_cost);
                    lambda = (lambda / 3.0).max(1e-12);
                    improved = true;
                    break;
                }
                _ => lambda *= 4.0,
            }
        }
        on_iteration(iterations)?;
        if !improved || converged {
            break;
        }
    }
    Ok(LmOutcome { theta, cost, iterations })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn fits_an_exponential_and_can_be_stopped() {
        let t: Vec<f64> = (0..50).map(|k| k as f64 * 0.1).collect();
        let y: Vec<f64> = t.iter().map(|t| 2.0 * (-0.7 * t).exp()).collect();
        let mut residual =
            |th: &[f64]| Some(t.iter().zip(&y).map(|(t, y)| th[0] * (th[1] * t).exp() - y).collect());
        let settings = LmSettings { max_iterations: 100, cost_tol: 1e-12, diff_step: 1e-7 };
        let out = minimise(&[1.0, -0.2], &mut residual, &settings, "test", &mut |_| Ok(())).unwrap();
        assert!((out.theta[0] - 2.0).abs() < 1e-5 && (out.theta[1] + 0.7).abs() < 1e-5, "{:?}", out.theta);
        let stopped =
            minimise(&[1.0, -0.2], &mut residual, &settings, "test", &mut |_| Err(BaselineError::Cancelled));
        assert!(matches!(stopped, Err(BaselineError::Cancelled)));
    }
}
