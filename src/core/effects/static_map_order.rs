//! `static_map_order`: the static map is too simple (bleed valve, limiter).
use super::Evidence;
use super::ParamSpec;
use super::stats::{ResidualTrace, mean, plateaus};
use crate::core::identification::static_map::{Beyond, StaticMap, monotone_rows, trend_sign};
use crate::core::numerics::constrained::solve_lstsq_nonneg;

/// A kink in the static map: a bleed valve that opens or a limiter that acts above an operating
/// point adds `slope_change · max(0, v − knot_v)` to the polynomial `f(v)`. The knot is fitted on
/// the simulation error of the identification data, the slope change with the polynomial by least
/// squares on the steady-state points.
#[derive(Clone, Debug, PartialEq)]
pub struct StaticMapOrder {
    /// Where the kink sits, in units of v.
    pub knot_v: f64,
    /// Change of df/dv above the knot.
    pub slope_change: f64,
}

/// Knots tried between consecutive steady points, as fractions of the gap.
const KNOT_FRACTIONS: [f64; 3] = [0.25, 0.5, 0.75];

impl StaticMapOrder {
    /// The kink's contribution at `v`.
    pub fn eval(&self, v: f64) -> f64 {
        self.slope_change * (v - self.knot_v).max(0.0)
    }

    pub(super) fn free_params(&self) -> Vec<f64> {
        vec![self.knot_v]
    }

    pub(super) fn with_free_params(&self, theta: &[f64]) -> Option<Self> {
        let knot_v = *theta.first()?;
        knot_v.is_finite().then_some(Self { knot_v, slope_change: self.slope_change })
    }

    /// Knots between the steady points, leaving at least two points on the polynomial's side.
    pub(super) fn guesses(steady_v: &[f64]) -> Vec<Self> {
        let mut v = steady_v.to_vec();
        v.sort_by(f64::total_cmp);
        v.windows(2)
            .skip(1)
            .flat_map(|w| {
                KNOT_FRACTIONS.map(|f| Self { knot_v: w[0] + f * (w[1] - w[0]), slope_change: 0.0 })
            })
            .collect()
    }
}

/// Least-squares polynomial of `order` through the points, plus a kink at `knot_v` when given,
/// held monotone over the points' range like every fitted map (see `identification::static_map`).
/// Returns the polynomial part and the kink's slope change.
pub fn fit_map_with_knot(
    v: &[f64],
    y: &[f64],
    order: usize,
    knot_v: Option<f64>,
) -> Option<(StaticMap, f64)> {
    let (lo, hi) = v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(*x), b.max(*x)));
    let v_center = 0.5 * (lo + hi);
    let v_scale = if hi > lo { 0.5 * (hi - lo) } else { 1.0 };
    let cols = order + 1 + usize::from(knot_v.is_some());
    if v.len() < cols || v.len() != y.len() {
        return None;
    }
    let a = faer::Mat::from_fn(v.len(), cols, |r, c| {
        let vr = v.get(r).copied().unwrap_or(0.0);
        match knot_v {
            Some(knot) if c == order + 1 => (vr - knot).max(0.0) / v_scale,
            _ => ((vr - v_center) / v_scale).powi(c as i32),
        }
    });
    let x: Vec<f64> = v.iter().map(|vr| (vr - v_center) / v_scale).collect();
    let knot_x = knot_v.map(|knot| (knot - v_center) / v_scale);
    let sol = solve_lstsq_nonneg(&a, y, &monotone_rows(order, trend_sign(&x, y), knot_x)).ok()?;
    let slope_change =
        if knot_v.is_some() { sol.x.get(order + 1).copied().unwrap_or(0.0) / v_scale } else { 0.0 };
    let coeffs_scaled = sol.x.iter().take(order + 1).copied().collect();
    Some((StaticMap { v_center, v_scale, coeffs_scaled, beyond: Beyond::EndTrend }, slope_change))
}

/// Steady-state residuals at the plateaus of every run against the operating point: their spread
/// and how far the largest lies outside what the noise of a plateau mean allows.
pub(super) fn evidence(traces: &[ResidualTrace]) -> Evidence {
    let mut points: Vec<(f64, f64, f64)> = Vec::new(); // (level, mean residual %, its standard error)
    for t in traces {
        let e = t.residual_pct();
        for (a, b) in plateaus(&t.u, t.dt_secs, 8.0, 3.0) {
            let (Some(seg), Some(ys)) = (e.get(a..b), t.y.get(a..b)) else { continue };
            let m = mean(seg);
            let sd =
                (seg.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (seg.len().max(2) - 1) as f64).sqrt();
            points.push((mean(ys), m, sd / (seg.len() as f64).sqrt()));
        }
    }
    if points.len() < 3 {
        return Evidence::none("too few steady plateaus to judge the static map");
    }
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (lo, hi) =
        points.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.1), b.max(p.1)));
    let worst = points.iter().map(|p| p.1.abs() / p.2.max(f64::MIN_POSITIVE)).fold(0.0, f64::max);
    let (low_end, high_end) = (points.first().map_or(0.0, |p| p.1), points.last().map_or(0.0, |p| p.1));
    let meaning = if worst > 10.0 && hi - lo > 0.5 {
        "steady states deviate from the map systematically across the operating range"
    } else if worst > 4.0 {
        "small systematic steady-state errors"
    } else {
        "steady states sit on the map within noise"
    };
    Evidence {
        sentence: format!(
            "steady-state residuals at {} plateaus range from {lo:+.2} % to {hi:+.2} % ({low_end:+.2} % at the \
             lowest, {high_end:+.2} % at the highest operating point; largest {worst:.0}× its noise): {meaning}",
            points.len()
        ),
        supports: worst > 4.0,
    }
}

block_impl!(
    StaticMapOrder { knot_v, slope_change },
    params: &[ParamSpec::real("knot_v", -1e12, 1e12), ParamSpec::real("slope_change", -1e6, 1e6)],
    physics: "the static map is too simple: a kink (bleed valve, limiter) is added to f(v)",
    evidence: evidence
);

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn a_kinked_map_is_recovered() {
        let v: Vec<f64> = (0..10).map(|i| 40.0 + 5.0 * i as f64).collect();
        let y: Vec<f64> = v.iter().map(|x| 1.0 + 0.9 * x - 0.6 * (x - 70.0).max(0.0)).collect();
        let (map, slope) = fit_map_with_knot(&v, &y, 1, Some(70.0)).unwrap();
        assert!((slope + 0.6).abs() < 1e-9, "{slope}");
        assert!((map.eval(50.0) - 46.0).abs() < 1e-9);
        assert_eq!(StaticMapOrder::guesses(&[1.0, 2.0, 3.0]).len(), 3);
    }
}
