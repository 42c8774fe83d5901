//! The static nonlinearity `y = f(v) = β0 + β1 v + … + βi vⁱ` of the Wiener model, fitted by linear
//! least squares on steady-state points (the paper fits the ratio y/v by gradient descent; linear
//! least squares on the same residual is exact).
//!
//! Internally the polynomial is kept in the scaled variable `x = (v − v_center) / v_scale` so that
//! high powers of v ≈ 10⁵ rpm stay well conditioned; [`StaticMap::beta`] gives the plain coefficients.
use serde::{Deserialize, Serialize};

use crate::core::numerics::lstsq::{LstsqError, solve_lstsq};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StaticMap {
    pub v_center: f64,
    pub v_scale: f64,
    /// Coefficients of powers 0, 1, … of the scaled variable.
    pub coeffs_scaled: Vec<f64>,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StaticMapError {
    #[error("a static map of order {order} needs at least {needed} steady-state points, got {points}")]
    TooFewPoints { order: usize, points: usize, needed: usize },
    #[error("static map order {order} is out of range 1..={MAX_ORDER}")]
    BadOrder { order: usize },
    #[error("v and y have different lengths ({v} vs {y})")]
    LengthMismatch { v: usize, y: usize },
    #[error(transparent)]
    Lstsq(#[from] LstsqError),
}

impl StaticMap {
    pub fn identity() -> Self {
        Self { v_center: 0.0, v_scale: 1.0, coeffs_scaled: vec![0.0, 1.0] }
    }

    pub fn order(&self) -> usize {
        self.coeffs_scaled.len().saturating_sub(1)
    }

    pub fn eval(&self, v: f64) -> f64 {
        let x = (v - self.v_center) / self.v_scale;
        self.coeffs_scaled.iter().rev().fold(0.0, |acc, c| acc * x + c)
    }

    /// Derivative df/dv.
    pub fn slope(&self, v: f64) -> f64 {
        let x = (v - self.v_center) / self.v_scale;
        let d = self
            .coeffs_scaled
            .iter()
            .enumerate()
            .skip(1)
            .rev()
            .fold(0.0, |acc, (i, c)| acc * x + i as f64 * c);
        d / self.v_scale
    }

    /// Plain coefficients β0, β1, … of powers of v (the paper's form).
    pub fn beta(&self) -> Vec<f64> {
        let n = self.coeffs_scaled.len();
        let mut beta = vec![0.0; n];
        // Σ γ_i ((v − c)/s)^i = Σ γ_i s^-i Σ_k C(i,k) v^k (−c)^(i−k)
        for (i, gamma) in self.coeffs_scaled.iter().enumerate() {
            let g = gamma / self.v_scale.powi(i as i32);
            let mut binom = 1.0;
            for (k, b) in beta.iter_mut().enumerate().take(i + 1) {
                if k > 0 {
                    binom = binom * (i + 1 - k) as f64 / k as f64;
                }
                *b += g * binom * (-self.v_center).powi((i - k) as i32);
            }
        }
        beta
    }
}

/// Highest order of a static map: an identification run holds a handful to a few dozen steady
/// points, and a polynomial of higher order through them follows their noise between them (and the
/// scaled Vandermonde system loses digits beyond it). Order 0 would be a constant: no map.
pub const MAX_ORDER: usize = 6;

/// Least-squares polynomial of `order` through the points (v, y).
pub fn fit_static_map(v: &[f64], y: &[f64], order: usize) -> Result<StaticMap, StaticMapError> {
    if !(1..=MAX_ORDER).contains(&order) {
        return Err(StaticMapError::BadOrder { order });
    }
    if v.len() != y.len() {
        return Err(StaticMapError::LengthMismatch { v: v.len(), y: y.len() });
    }
    let needed = order + 1;
    if v.len() < needed {
        return Err(StaticMapError::TooFewPoints { order, points: v.len(), needed });
    }
    let (lo, hi) = v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(*x), b.max(*x)));
    let v_center = 0.5 * (lo + hi);
    let v_scale = if hi > lo { 0.5 * (hi - lo) } else { 1.0 };
    let a = faer::Mat::from_fn(v.len(), needed, |r, c| ((v[r] - v_center) / v_scale).powi(c as i32));
    let sol = solve_lstsq(&a, y)?;
    Ok(StaticMap { v_center, v_scale, coeffs_scaled: sol.x })
}

/// The order the data support: leave-one-out RMSE for each order, and the smallest order within 10 %
/// of the best (simpler maps are preferred, as in the paper).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OrderSuggestion {
    pub order: usize,
    /// (order, leave-one-out RMSE) for every order tried.
    pub loo_rmse: Vec<(usize, f64)>,
}

pub fn suggest_order(v: &[f64], y: &[f64], max_order: usize) -> Result<OrderSuggestion, StaticMapError> {
    let mut loo_rmse = Vec::new();
    for order in 1..=max_order.min(MAX_ORDER) {
        // Leave-one-out needs order + 2 points so each fit is determined.
        if v.len() < order + 2 {
            break;
        }
        let mut sq = 0.0;
        for leave in 0..v.len() {
            let vs: Vec<f64> = v.iter().enumerate().filter(|(i, _)| *i != leave).map(|(_, x)| *x).collect();
            let ys: Vec<f64> = y.iter().enumerate().filter(|(i, _)| *i != leave).map(|(_, x)| *x).collect();
            let map = fit_static_map(&vs, &ys, order)?;
            sq += (map.eval(v[leave]) - y[leave]).powi(2);
        }
        loo_rmse.push((order, (sq / v.len() as f64).sqrt()));
    }
    let Some(best) = loo_rmse.iter().map(|(_, e)| *e).min_by(f64::total_cmp) else {
        return Err(StaticMapError::TooFewPoints { order: 1, points: v.len(), needed: 3 });
    };
    let order = loo_rmse.iter().find(|(_, e)| *e <= 1.1 * best + 1e-12).map_or(1, |(o, _)| *o);
    Ok(OrderSuggestion { order, loo_rmse })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn recovers_the_papers_speed_map() {
        // fs(v) = 2.878e4 + 4.021e-1 v + 1.532e-6 v²
        let beta = [2.878e4, 4.021e-1, 1.532e-6];
        let v: Vec<f64> = (0..9).map(|i| 40_000.0 + 6_000.0 * i as f64).collect();
        let y: Vec<f64> = v.iter().map(|x| beta[0] + beta[1] * x + beta[2] * x * x).collect();
        let map = fit_static_map(&v, &y, 2).unwrap();
        let b = map.beta();
        for (got, want) in b.iter().zip(beta) {
            assert!((got - want).abs() < 1e-6 * want.abs(), "{b:?}");
        }
        assert!((map.slope(80_000.0) - (beta[1] + 2.0 * beta[2] * 80_000.0)).abs() < 1e-9);
        assert_eq!(suggest_order(&v, &y, 4).unwrap().order, 2);
    }

    #[test]
    fn errors() {
        assert!(matches!(
            fit_static_map(&[1.0, 2.0], &[1.0, 2.0], 2),
            Err(StaticMapError::TooFewPoints { .. })
        ));
        assert!(matches!(fit_static_map(&[1.0], &[1.0, 2.0], 1), Err(StaticMapError::LengthMismatch { .. })));
        assert!(matches!(fit_static_map(&[1.0], &[1.0], 0), Err(StaticMapError::BadOrder { .. })));
    }
}
