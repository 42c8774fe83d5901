//! The static nonlinearity `y = f(v) = β0 + β1 v + … + βi vⁱ` of the Wiener model, fitted by linear
//! least squares on steady-state points (the paper fits the ratio y/v by gradient descent; linear
//! least squares on the same residual is exact).
//!
//! Internally the polynomial is kept in the scaled variable `x = (v − v_center) / v_scale` so that
//! high powers of v ≈ 10⁵ rpm stay well conditioned; [`StaticMap::beta`] gives the plain coefficients.
//! A fitted map's steady points span exactly `|x| ≤ 1`: its identified range.
//!
//! A fitted map is admissible by construction, so that every local gain a controller is scheduled
//! on has the engine's sign:
//! - it is monotone over the identified range, in the direction the steady points go (least squares
//!   under slope inequalities, which leave a map that is monotone already untouched);
//! - beyond that range it continues from its end with the end's value, slope and curvature, in a
//!   form that never turns back ([`Beyond::EndTrend`]). A polynomial continued past its last steady
//!   point bends over or runs away within a fraction of the range (the bundled thrust maps turn
//!   negative at 1.5 half-ranges), yet real runs pass beyond the steady holds in every transient
//!   that overshoots (the JetCat's identification runs spend 4 % of their samples up to 0.6
//!   half-ranges above its top hold). The data give the value, slope and curvature at the end and
//!   nothing further:
//!   - where the curvature slows the map outwards (a spool that saturates), the continuation is the
//!     exponential approach `f(e) + f'(e)·L·(1 − exp(−t/L))` with `L = |f'(e)/f''(e)|`: it matches
//!     all three and its slope keeps its sign for ever, decaying as the curvature says;
//!   - where the curvature speeds the map up outwards (thrust growing with the square of speed),
//!     the continuation is the parabola of the three, whose slope only grows outwards.
//!
//!   Either way the map and its first two derivatives are continuous at the end, and it never turns
//!   back. (The tangent alone, which drops the curvature, cost the JetCat's loop a fifth of its
//!   validation error: its runs spend much of their time just beyond the holds.)
//!
use serde::{Deserialize, Serialize};

use crate::core::numerics::constrained::{ConstrainedError, solve_lstsq_nonneg};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StaticMap {
    pub v_center: f64,
    pub v_scale: f64,
    /// Coefficients of powers 0, 1, … of the scaled variable.
    pub coeffs_scaled: Vec<f64>,
    /// How the map continues beyond its identified range `|x| > 1`. Model files written before
    /// maps had a range read as [`Beyond::Polynomial`], so they predict as they always did.
    #[serde(default)]
    pub beyond: Beyond,
}

/// The polynomial's value, slope d/dx and curvature d²/dx² at an end of the identified range, and
/// the length (in x) of the exponential approach when the curvature slows the map outwards (`None`:
/// the parabola of the three, whose slope grows outwards and so never turns back).
struct EndTrend {
    value: f64,
    slope: f64,
    curvature: f64,
    length: Option<f64>,
}

/// How a static map continues beyond the steady points it was fitted on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Beyond {
    /// The polynomial itself, everywhere.
    #[default]
    Polynomial,
    /// From the nearer end of `|x| ≤ 1`, value, slope and curvature continue without turning
    /// back: an exponential approach where the curvature slows the map outwards, else the parabola.
    EndTrend,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StaticMapError {
    #[error("a static map of order {order} needs at least {needed} steady-state points, got {points}")]
    TooFewPoints { order: usize, points: usize, needed: usize },
    #[error("static map order {order} is out of range 1..={MAX_ORDER}")]
    BadOrder { order: usize },
    #[error("v and y have different lengths ({v} vs {y})")]
    LengthMismatch { v: usize, y: usize },
    #[error("the monotone static map: {0}")]
    Constrained(#[from] ConstrainedError),
}

impl StaticMap {
    pub fn identity() -> Self {
        Self { v_center: 0.0, v_scale: 1.0, coeffs_scaled: vec![0.0, 1.0], beyond: Beyond::Polynomial }
    }

    pub fn order(&self) -> usize {
        self.coeffs_scaled.len().saturating_sub(1)
    }

    /// The range of v the map was fitted on, when it has one.
    pub fn identified_range(&self) -> Option<(f64, f64)> {
        (self.beyond == Beyond::EndTrend)
            .then_some((self.v_center - self.v_scale, self.v_center + self.v_scale))
    }

    #[inline]
    pub fn eval(&self, v: f64) -> f64 {
        let x = (v - self.v_center) / self.v_scale;
        match self.end_beyond(x) {
            Some(end) => {
                let trend = self.end_trend(end);
                let t = end * (x - end);
                trend.value
                    + match trend.length {
                        Some(l) => end * trend.slope * (l * (1.0 - (-t / l).exp())),
                        None => end * trend.slope * t + 0.5 * trend.curvature * t * t,
                    }
            }
            None => self.poly(x),
        }
    }

    /// Derivative df/dv.
    pub fn slope(&self, v: f64) -> f64 {
        let x = (v - self.v_center) / self.v_scale;
        let dx = match self.end_beyond(x) {
            Some(end) => {
                let trend = self.end_trend(end);
                let t = end * (x - end);
                match trend.length {
                    Some(l) => trend.slope * (-t / l).exp(),
                    None => trend.slope + end * trend.curvature * t,
                }
            }
            None => self.poly_slope(x),
        };
        dx / self.v_scale
    }

    /// The end of the identified range (±1) that `x` lies beyond, when the map continues past it.
    #[inline]
    fn end_beyond(&self, x: f64) -> Option<f64> {
        (self.beyond == Beyond::EndTrend && x.abs() > 1.0).then(|| x.signum())
    }

    /// The polynomial at the end `e` = ±1, and how it continues outwards.
    fn end_trend(&self, end: f64) -> EndTrend {
        let (value, slope, curvature) = (self.poly(end), self.poly_slope(end), self.poly_curvature(end));
        // Outwards the slope is `end · slope`; the curvature slows it when the two differ in sign.
        let slowing = end * slope * curvature < 0.0;
        EndTrend { value, slope, curvature, length: slowing.then(|| (slope / curvature).abs()) }
    }

    #[inline]
    fn poly(&self, x: f64) -> f64 {
        self.coeffs_scaled.iter().rev().fold(0.0, |acc, c| acc * x + c)
    }

    /// d(poly)/dx.
    fn poly_slope(&self, x: f64) -> f64 {
        self.coeffs_scaled.iter().enumerate().skip(1).rev().fold(0.0, |acc, (i, c)| acc * x + i as f64 * c)
    }

    /// d²(poly)/dx².
    fn poly_curvature(&self, x: f64) -> f64 {
        self.coeffs_scaled
            .iter()
            .enumerate()
            .skip(2)
            .rev()
            .fold(0.0, |acc, (i, c)| acc * x + (i * (i - 1)) as f64 * c)
    }

    /// Plain coefficients β0, β1, … of powers of v (the paper's form; inside the identified range).
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

/// Points of the identified range `|x| ≤ 1` where a map's slope is held to the sign of its trend.
/// The slope of a map of order ≤ [`MAX_ORDER`] is a polynomial of degree ≤ 5; between two grid
/// points 1/32 of a half-range apart where it is ≥ 0 it can dip below zero only by two roots closer
/// than that, a dip of order f‴·h²/8 ≈ 1e-4 of the map's curvature: no gain changes sign by it.
pub const MONOTONE_GRID: usize = 65;

/// The direction the steady points go: the sign of their least-squares line's slope (upwards
/// when they are flat).
pub fn trend_sign(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len().max(1) as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let cov: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    if cov < 0.0 { -1.0 } else { 1.0 }
}

/// One row per grid point of [`MONOTONE_GRID`]: `sign · d/dx` of the columns 1, x, …, x^order and,
/// when a kink's knot (in x) is given, of the hinge column `max(0, x − knot)`.
pub fn monotone_rows(order: usize, sign: f64, knot_x: Option<f64>) -> Vec<Vec<f64>> {
    (0..MONOTONE_GRID)
        .map(|j| {
            let x = -1.0 + 2.0 * j as f64 / (MONOTONE_GRID - 1) as f64;
            let mut row: Vec<f64> = (0..=order)
                .map(|i| if i == 0 { 0.0 } else { sign * i as f64 * x.powi(i as i32 - 1) })
                .collect();
            if let Some(knot) = knot_x {
                row.push(if x > knot { sign } else { 0.0 });
            }
            row
        })
        .collect()
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
    let x: Vec<f64> = v.iter().map(|vr| (vr - v_center) / v_scale).collect();
    let a = faer::Mat::from_fn(v.len(), needed, |r, c| x[r].powi(c as i32));
    let sol = solve_lstsq_nonneg(&a, y, &monotone_rows(order, trend_sign(&x, y), None))?;
    Ok(StaticMap { v_center, v_scale, coeffs_scaled: sol.x, beyond: Beyond::EndTrend })
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
    fn a_map_that_bends_over_is_held_monotone() {
        // Steady points of a saturating engine: the least-squares parabola through them peaks
        // inside the range, so its local gain would turn negative at the top.
        let v: Vec<f64> = (0..8).map(|i| 2.0 + i as f64).collect();
        let y: Vec<f64> = v.iter().map(|x| 10.0 * (1.0 - (-x / 3.0).exp()) - 0.02 * x * x).collect();
        let free = {
            let x: Vec<f64> = v.iter().map(|vr| (vr - 5.5) / 3.5).collect();
            let a = faer::Mat::from_fn(8, 3, |r, c| x[r].powi(c as i32));
            crate::core::numerics::lstsq::solve_lstsq(&a, &y).unwrap().x
        };
        assert!(free[1] - 2.0 * free[2] > 0.0 && free[1] + 2.0 * free[2] < 0.0, "free fit bends: {free:?}");
        let map = fit_static_map(&v, &y, 2).unwrap();
        assert_eq!(map.identified_range(), Some((2.0, 9.0)));
        let slopes: Vec<f64> = (0..=70).map(|i| map.slope(2.0 + 0.1 * i as f64)).collect();
        assert!(slopes.iter().all(|d| *d >= -1e-9), "{slopes:?}");
    }

    /// Value, slope and curvature at `v` by central differences of `eval`.
    fn local(map: &StaticMap, v: f64, h: f64) -> (f64, f64, f64) {
        let (a, b, c) = (map.eval(v - h), map.eval(v), map.eval(v + h));
        (b, (c - a) / (2.0 * h), (c - 2.0 * b + a) / (h * h))
    }

    #[test]
    fn beyond_its_range_a_map_continues_its_end_without_turning_back() {
        // A concave map rising to the top end: curvature slows it outwards there (the exponential
        // approach), speeds it up outwards at the bottom end (the parabola).
        let map = StaticMap {
            v_center: 0.0,
            v_scale: 1.0,
            coeffs_scaled: vec![0.0, 1.0, -0.3],
            beyond: Beyond::EndTrend,
        };
        for end in [-1.0, 1.0] {
            let (inside, outside) =
                (local(&map, end - 1e-3 * end, 1e-4), local(&map, end + 1e-3 * end, 1e-4));
            for (a, b) in [(inside.0, outside.0), (inside.1, outside.1), (inside.2, outside.2)] {
                assert!((a - b).abs() < 1e-2, "at {end}: {inside:?} against {outside:?}");
            }
        }
        // Top: slope 0.4, curvature −0.6, so L = 2/3 and the map approaches f(1) + 0.4·L.
        let (top, top_slope) = (map.eval(1.0), map.slope(1.0));
        let far = map.eval(50.0);
        assert!((far - (top + 0.4 * 2.0 / 3.0)).abs() < 1e-9, "{far}");
        assert!((1..200).all(|i| map.slope(1.0 + 0.1 * i as f64) > 0.0));
        assert!((map.slope(1.5) - top_slope * (-0.5_f64 / (2.0 / 3.0)).exp()).abs() < 1e-12);
        // Bottom: slope 1.6 steepening outwards: here the parabola is the polynomial itself.
        for v in [-1.5, -3.0, -10.0] {
            assert!((map.eval(v) - (v - 0.3 * v * v)).abs() < 1e-9 * (1.0 + v * v), "{v}");
            assert!((map.slope(v) - (1.0 - 0.6 * v)).abs() < 1e-9 * (1.0 + v.abs()), "{v}");
        }
    }

    #[test]
    fn a_cubic_continues_as_the_parabola_of_its_end_not_as_itself() {
        // y = x + x³ steepens outwards at both ends: value 2, slope 4, curvature ±6 at x = ±1.
        let map = StaticMap {
            v_center: 0.0,
            v_scale: 1.0,
            coeffs_scaled: vec![0.0, 1.0, 0.0, 1.0],
            beyond: Beyond::EndTrend,
        };
        assert!((map.eval(3.0) - (2.0 + 4.0 * 2.0 + 0.5 * 6.0 * 4.0)).abs() < 1e-12);
        assert!((map.eval(-3.0) + (2.0 + 4.0 * 2.0 + 0.5 * 6.0 * 4.0)).abs() < 1e-12);
        assert!((map.slope(3.0) - (4.0 + 6.0 * 2.0)).abs() < 1e-12);
    }

    #[test]
    fn a_falling_map_is_held_falling() {
        let v: Vec<f64> = (0..7).map(|i| i as f64).collect();
        let y: Vec<f64> = v.iter().map(|x| -x + 0.12 * x * x).collect();
        let map = fit_static_map(&v, &y, 2).unwrap();
        assert!((0..=60).all(|i| map.slope(0.1 * i as f64) <= 1e-9));
    }

    #[test]
    fn a_map_file_without_a_range_keeps_its_polynomial() {
        let json = r#"{"v_center": 0.0, "v_scale": 1.0, "coeffs_scaled": [0.0, 1.0, -1.0]}"#;
        let map: StaticMap = serde_json::from_str(json).unwrap();
        assert_eq!(map.beyond, Beyond::Polynomial);
        assert_eq!(map.identified_range(), None);
        assert!((map.eval(3.0) - (3.0 - 9.0)).abs() < 1e-12);
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
