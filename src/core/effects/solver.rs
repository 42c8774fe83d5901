//! Levenberg–Marquardt for the effect fits, with the Jacobian factored once per iteration.
//!
//! `core::numerics::lm` solves every damped step as a fresh (n + p) × p SVD problem; the effect fits have
//! thousands of residuals and at most ten parameters and try several damping values per iteration,
//! so here the Jacobian is reduced to its p × p triangular factor by Householder QR once per
//! iteration, and each damped step `[R; √λ·D] δ = [−Qᵀr; 0]` is a small 2p × p Householder problem.
//! No normal equations are formed.
use crate::core::numerics::stats::sum_of_squares as cost_of;

/// Options of [`minimise`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LmSettings {
    pub max_iterations: usize,
    /// Stop when an accepted step lowers the cost by less than this fraction.
    pub cost_tol: f64,
    /// Relative forward-difference step of the Jacobian.
    pub diff_step: f64,
}

impl Default for LmSettings {
    fn default() -> Self {
        Self { max_iterations: 15, cost_tol: 1e-5, diff_step: 1e-6 }
    }
}

/// Householder QR of the columns `cols` (each of length m ≥ p), applied to `rhs` as well.
/// Returns the p × p upper factor (by columns) and the first p entries of `Qᵀ rhs`.
fn qr_reduce(mut cols: Vec<Vec<f64>>, mut rhs: Vec<f64>) -> (Vec<Vec<f64>>, Vec<f64>) {
    let p = cols.len();
    for k in 0..p {
        let Some(col) = cols.get(k) else { break };
        let m = col.len();
        if k >= m {
            break;
        }
        let norm = col[k..].iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm <= f64::MIN_POSITIVE {
            continue;
        }
        let alpha = if col[k] > 0.0 { -norm } else { norm };
        let mut v: Vec<f64> = col[k..].to_vec();
        v[0] -= alpha;
        let vnorm2: f64 = v.iter().map(|x| x * x).sum();
        if vnorm2 <= f64::MIN_POSITIVE {
            continue;
        }
        let reflect = |y: &mut [f64]| {
            let dot: f64 = v.iter().zip(y.iter()).map(|(a, b)| a * b).sum();
            let f = 2.0 * dot / vnorm2;
            for (yi, vi) in y.iter_mut().zip(&v) {
                *yi -= f * vi;
            }
        };
        for col in cols.iter_mut().skip(k) {
            if let Some(tail) = col.get_mut(k..) {
                reflect(tail);
            }
        }
        if let Some(tail) = rhs.get_mut(k..) {
            reflect(tail);
        }
    }
    let r = cols.iter().map(|c| c.iter().take(p).copied().collect()).collect();
    (r, rhs.into_iter().take(p).collect())
}

/// Solve the upper-triangular `R x = c`; components whose pivot is negligible are set to zero.
fn back_substitute(r: &[Vec<f64>], c: &[f64]) -> Vec<f64> {
    let p = r.len();
    let at = |i: usize, j: usize| r.get(j).and_then(|col| col.get(i)).copied().unwrap_or(0.0);
    let big = (0..p).map(|i| at(i, i).abs()).fold(0.0, f64::max);
    let tol = f64::EPSILON * p.max(1) as f64 * 100.0 * big;
    let mut x = vec![0.0; p];
    for i in (0..p).rev() {
        let pivot = at(i, i);
        if pivot.abs() <= tol {
            continue;
        }
        let s: f64 = (i + 1..p).map(|j| at(i, j) * x[j]).sum();
        x[i] = (c.get(i).copied().unwrap_or(0.0) - s) / pivot;
    }
    x
}

/// Minimise `‖r(θ)‖²` from `theta0`; `residual` returns `None` where θ is not admissible. Returns
/// the best θ and its cost, or `None` when the start itself is not admissible.
pub fn minimise<F>(theta0: &[f64], mut residual: F, settings: &LmSettings) -> Option<(Vec<f64>, f64)>
where
    F: FnMut(&[f64]) -> Option<Vec<f64>>,
{
    let mut theta = theta0.to_vec();
    let mut r = residual(&theta)?;
    let mut cost = cost_of(&r);
    let p = theta.len();
    let mut lambda: f64 = 1e-3;
    for _ in 0..settings.max_iterations {
        if p == 0 {
            break;
        }
        let mut cols = Vec::with_capacity(p);
        for j in 0..p {
            let h = settings.diff_step * theta[j].abs().max(1e-3);
            let mut shifted = theta.clone();
            shifted[j] += h;
            let col = match residual(&shifted) {
                Some(rj) => rj.iter().zip(&r).map(|(a, b)| (a - b) / h).collect(),
                None => vec![0.0; r.len()],
            };
            cols.push(col);
        }
        let scales: Vec<f64> =
            cols.iter().map(|c| c.iter().map(|x| x * x).sum::<f64>().sqrt().max(1e-12)).collect();
        let neg_r: Vec<f64> = r.iter().map(|x| -x).collect();
        let (rfac, c) = qr_reduce(cols, neg_r);
        let mut accepted = false;
        for _ in 0..10 {
            let aug: Vec<Vec<f64>> = (0..p)
                .map(|j| {
                    let mut col: Vec<f64> = rfac.get(j).cloned().unwrap_or_default();
                    col.resize(2 * p, 0.0);
                    col[p + j] = lambda.sqrt() * scales[j];
                    col
                })
                .collect();
            let mut rhs = c.clone();
            rhs.resize(2 * p, 0.0);
            let (r2, c2) = qr_reduce(aug, rhs);
            let step = back_substitute(&r2, &c2);
            let candidate: Vec<f64> = theta.iter().zip(&step).map(|(t, d)| t + d).collect();
            match residual(&candidate) {
                Some(rc) if cost_of(&rc) < cost => {
                    let new_cost = cost_of(&rc);
                    let rel = (cost - new_cost) / cost.max(f64::MIN_POSITIVE);
                    theta = candidate;
                    r = rc;
                    cost = new_cost;
                    lambda = (lambda / 3.0).max(1e-12);
                    accepted = true;
                    if rel < settings.cost_tol {
                        return Some((theta, cost));
                    }
                    break;
                }
                _ => lambda *= 4.0,
            }
        }
        if !accepted {
            break;
        }
    }
    Some((theta, cost))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn fits_an_exponential_and_solves_least_squares() {
        let t: Vec<f64> = (0..50).map(|k| k as f64 * 0.1).collect();
        let y: Vec<f64> = t.iter().map(|t| 2.0 * (-0.7 * t).exp()).collect();
        let settings = LmSettings { max_iterations: 50, cost_tol: 1e-12, ..LmSettings::default() };
        let (theta, cost) = minimise(
            &[1.0, -0.2],
            |th| Some(t.iter().zip(&y).map(|(t, y)| th[0] * (th[1] * t).exp() - y).collect()),
            &settings,
        )
        .unwrap();
        assert!((theta[0] - 2.0).abs() < 1e-5 && (theta[1] + 0.7).abs() < 1e-5, "{theta:?}");
        assert!(cost < 1e-10);
        // Overdetermined linear system: the residual of the solution is orthogonal to the columns.
        let cols = vec![vec![1.0, 1.0, 1.0, 1.0], vec![0.0, 1.0, 2.0, 3.0]];
        let b = vec![1.0, 2.9, 5.1, 7.0];
        let (r, c) = qr_reduce(cols.clone(), b.clone());
        let x = back_substitute(&r, &c);
        let res: Vec<f64> = (0..4).map(|i| b[i] - x[0] * cols[0][i] - x[1] * cols[1][i]).collect();
        for col in &cols {
            assert!(col.iter().zip(&res).map(|(a, b)| a * b).sum::<f64>().abs() < 1e-12);
        }
    }
}
