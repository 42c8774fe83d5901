//! Levenberg–Marquardt for small nonlinear least-squares problems `min ‖r(θ)‖²`, with a forward-
//! difference Jacobian. Each step solves the damped problem `[J; √λ·D] δ = [−r; 0]` by least squares
//! (SVD), not the normal equations.
use faer::Mat;

use crate::core::numerics::lstsq::{LstsqError, solve_lstsq};
use crate::core::numerics::stats::sum_of_squares as cost_of;

#[derive(Clone, Debug, PartialEq)]
pub struct LmOptions {
    pub max_iterations: usize,
    /// Stop when the relative decrease of the cost falls below this.
    pub cost_tol: f64,
    pub initial_lambda: f64,
    /// Relative step for the finite-difference Jacobian.
    pub diff_step: f64,
}

impl Default for LmOptions {
    fn default() -> Self {
        Self { max_iterations: 40, cost_tol: 1e-9, initial_lambda: 1e-3, diff_step: 1e-6 }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct LmResult {
    pub theta: Vec<f64>,
    pub cost: f64,
    pub initial_cost: f64,
    pub iterations: usize,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LmError {
    #[error("the residual cannot be evaluated at the starting point")]
    BadStart,
    #[error(transparent)]
    Lstsq(#[from] LstsqError),
}

/// Minimise `‖r(θ)‖²` from `theta0`. `residual` returns `None` where θ is not admissible (e.g. an
/// unstable pole): such steps are rejected and the damping raised.
pub fn levenberg_marquardt<F>(theta0: &[f64], mut residual: F, opts: &LmOptions) -> Result<LmResult, LmError>
where
    F: FnMut(&[f64]) -> Option<Vec<f64>>,
{
    let mut theta = theta0.to_vec();
    let Some(mut r) = residual(&theta) else { return Err(LmError::BadStart) };
    let initial_cost = cost_of(&r);
    let mut cost = initial_cost;
    let mut lambda = opts.initial_lambda;
    let p = theta.len();
    let mut iterations = 0;
    while iterations < opts.max_iterations && p > 0 {
        iterations += 1;
        let n = r.len();
        let mut jac = Mat::<f64>::zeros(n + p, p);
        for j in 0..p {
            let h = opts.diff_step * theta[j].abs().max(1e-3);
            let mut shifted = theta.clone();
            shifted[j] += h;
            let Some(rj) = residual(&shifted) else { continue };
            for i in 0..n {
                jac[(i, j)] = (rj[i] - r[i]) / h;
            }
        }
        let col_norms: Vec<f64> =
            (0..p).map(|j| (0..n).map(|i| jac[(i, j)].powi(2)).sum::<f64>().sqrt().max(1e-12)).collect();
        let mut improved = false;
        for _ in 0..12 {
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
                    let rel = (cost - new_cost) / cost.max(f64::MIN_POSITIVE);
                    theta = candidate;
                    r = rc;
                    cost = new_cost;
                    lambda = (lambda / 3.0).max(1e-12);
                    improved = true;
                    if rel < opts.cost_tol {
                        return Ok(LmResult { theta, cost, initial_cost, iterations });
                    }
                    break;
                }
                _ => lambda *= 4.0,
            }
        }
        if !improved {
            break;
        }
    }
    Ok(LmResult { theta, cost, initial_cost, iterations })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn fits_an_exponential() {
        let t: Vec<f64> = (0..50).map(|k| k as f64 * 0.1).collect();
        let y: Vec<f64> = t.iter().map(|t| 2.0 * (-0.7 * t).exp()).collect();
        let res = levenberg_marquardt(
            &[1.0, -0.2],
            |th| Some(t.iter().zip(&y).map(|(t, y)| th[0] * (th[1] * t).exp() - y).collect()),
            &LmOptions::default(),
        )
        .unwrap();
        assert!((res.theta[0] - 2.0).abs() < 1e-6 && (res.theta[1] + 0.7).abs() < 1e-6, "{:?}", res.theta);
        assert!(res.cost < 1e-12 && res.cost < res.initial_cost);
    }

    #[test]
    fn inadmissible_start_is_an_error() {
        assert_eq!(levenberg_marquardt(&[1.0], |_| None, &LmOptions::default()), Err(LmError::BadStart));
    }
}
