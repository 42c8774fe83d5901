//! `asymmetric_dynamics`: acceleration and deceleration differ.
use num_complex::Complex64;

use super::Evidence;
use super::spool;
use super::spool::SplitShape;
use super::stats::{ResidualTrace, diff};
use super::wording::lags_or_leads;
use super::{EffectError, ParamSpec};
use crate::core::numerics::lstsq::solve_lstsq;

/// Acceleration and deceleration differ (acceleration schedule, combustor): the slowest real pole
/// of G(z), the spool, has its time constant multiplied by `decel_factor` while the response falls.
/// G is split as `G = G_rest · (1 − p) z⁻¹ / (1 − p z⁻¹)`; the first-order part runs with
/// `p` while rising and `p^(1/decel_factor)` while falling, so steady states are unchanged.
#[derive(Clone, Debug, PartialEq)]
pub struct AsymmetricDynamics {
    /// Falling time constant over rising time constant of the spool pole.
    pub decel_factor: f64,
}

impl AsymmetricDynamics {
    /// Split off the spool: the slowest real pole in (0, 1), or when there is none the slowest
    /// complex pair, and the unit-gain rest (see `SplitShape::of`).
    pub fn split(poles: &[Complex64], zeros: &[Complex64], dt_secs: f64) -> Result<SplitShape, EffectError> {
        SplitShape::of(poles, zeros, dt_secs, <Self as super::Block>::ID)
    }

    /// Unit-gain response of the split block to `u`, from the steady state of `u[0]`.
    pub fn respond(&self, shape: &SplitShape, u: &[f64]) -> Vec<f64> {
        spool::respond(shape, u, self.decel_factor, |_, _| 1.0)
    }

    pub(super) fn free_params(&self) -> Vec<f64> {
        vec![self.decel_factor.ln()]
    }

    pub(super) fn with_free_params(&self, theta: &[f64]) -> Option<Self> {
        let decel_factor = theta.first()?.exp();
        (0.1..=10.0).contains(&decel_factor).then_some(Self { decel_factor })
    }

    pub(super) fn guesses() -> Vec<Self> {
        [0.5, 0.7, 1.4, 2.0, 3.0].iter().map(|&decel_factor| Self { decel_factor }).collect()
    }
}

/// The lags (s) of the measurement behind the model on two classes of samples: the residual
/// regressed on the model's rate of change (`e ≈ −lag·dŷ/dt`), with one lag for the samples `first`
/// picks and one for the rest. `None` when the response never moves.
///
/// With `level_term`, the regression also has a lag that grows linearly with the operating level
/// (the model's output, centred on the middle of its range): a spool whose time constant follows
/// the operating point lags more at the low end, and since falls end low and rises end high its
/// falls look slower although each direction is as fast as the other at any one level. The two
/// lags returned are then the direction's own, at the middle of the range.
fn split_lags(
    traces: &[ResidualTrace],
    first: impl Fn(f64, f64) -> bool,
    level_term: bool,
) -> Option<(f64, f64)> {
    let (lo, hi) = traces
        .iter()
        .flat_map(|t| t.y_hat.iter())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| (a.min(*y), b.max(*y)));
    let (middle, half) = (0.5 * (lo + hi), (0.5 * (hi - lo)).max(f64::MIN_POSITIVE));
    let (mut rows, mut e) = (Vec::new(), Vec::new());
    for t in traces {
        let rate: Vec<f64> = diff(&t.y_hat).iter().map(|d| d / t.dt_secs).collect();
        for ((r, ek), level) in rate.iter().zip(t.residual()).zip(&t.y_hat) {
            let ours = first(*r, *level);
            let by_level = if level_term { *r * (level - middle) / half } else { 0.0 };
            rows.push([if ours { *r } else { 0.0 }, if ours { 0.0 } else { *r }, by_level, 1.0]);
            e.push(ek);
        }
    }
    let columns = if level_term { 4 } else { 3 };
    let a = faer::Mat::from_fn(rows.len(), columns, |i, j| {
        let j = if !level_term && j == 2 { 3 } else { j };
        rows.get(i).map_or(0.0, |r| r[j])
    });
    let sol = solve_lstsq(&a, &e).ok()?;
    Some((-sol.x.first().copied().unwrap_or(0.0), sol.x.get(1).map_or(0.0, |c| -c)))
}

/// Lags that differ by more than this, s, differ (about one sample at 8.85 Hz).
const LAG_DIFFERENCE_SECS: f64 = 0.1;

/// "lags the model by 0.12 s", or "leads it by 0.07 s" for a negative lag.
fn lag_clause(lag_secs: f64, model: &str) -> String {
    let (verb, amount) = lags_or_leads(lag_secs);
    format!("{verb} {model} by {amount}")
}

/// How far the measurement lags the model while the model's response rises and while it falls, at
/// the same operating level (see `split_lags`): asymmetry is a difference between directions that
/// a time constant following the operating point does not explain.
pub(super) fn evidence(traces: &[ResidualTrace]) -> Evidence {
    let Some((lag_up, lag_down)) = split_lags(traces, |rate, _| rate > 0.0, true) else {
        return Evidence::none("the response never moves");
    };
    let differ = (lag_down - lag_up).abs() > LAG_DIFFERENCE_SECS;
    let meaning = match (differ, lag_down > lag_up) {
        (true, true) => "decelerations are slower than the model",
        (true, false) => "accelerations are slower than the model",
        (false, _) => "rise and fall look alike",
    };
    Evidence {
        sentence: format!(
            "measured response {} while it rises and {} while it falls (at the same operating level): {meaning}",
            lag_clause(lag_up, "the model"),
            lag_clause(lag_down, "it")
        ),
        supports: differ,
    }
}

/// How far the measurement lags the model below and above the median output level.
pub(super) fn level_evidence(traces: &[ResidualTrace]) -> Evidence {
    let mut levels: Vec<f64> = traces.iter().flat_map(|t| t.y_hat.iter().copied()).collect();
    levels.sort_by(f64::total_cmp);
    let Some(&middle) = levels.get(levels.len() / 2) else { return Evidence::none("no response to look at") };
    let Some((lag_low, lag_high)) = split_lags(traces, |_, level| level < middle, false) else {
        return Evidence::none("the response never moves");
    };
    let differ = (lag_low - lag_high).abs() > LAG_DIFFERENCE_SECS;
    let meaning = match (differ, lag_low > lag_high) {
        (true, true) => "the engine responds more slowly at the low end than the model",
        (true, false) => "the engine responds more slowly at the high end than the model",
        (false, _) => "the response is as fast at both ends",
    };
    Evidence {
        sentence: format!(
            "measured response {} below the middle of the operating range and {} above it: {meaning}",
            lag_clause(lag_low, "the model"),
            lag_clause(lag_high, "it")
        ),
        supports: differ,
    }
}

block_impl!(
    AsymmetricDynamics { decel_factor },
    params: &[ParamSpec::real("decel_factor", 0.1, 10.0)],
    physics: "acceleration and deceleration differ: the spool time constant is scaled while slowing down",
    evidence: evidence
);

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::core::identification::wiener::unit_gain_tf;

    #[test]
    fn a_negative_lag_reads_as_a_lead() {
        assert_eq!(lag_clause(0.12, "the model"), "lags the model by 0.12 s");
        assert_eq!(lag_clause(-0.07, "it"), "leads it by 0.07 s");
    }

    #[test]
    fn symmetric_factor_reproduces_the_linear_block() {
        let poles = [Complex64::new(0.9, 0.0), Complex64::new(0.5, 0.2), Complex64::new(0.5, -0.2)];
        let tf = unit_gain_tf(&poles, &[], 0.1).unwrap();
        let u: Vec<f64> = (0..200).map(|k| if (k / 40) % 2 == 0 { 1.0 } else { 3.0 }).collect();
        let split = AsymmetricDynamics::split(&poles, &[], 0.1).unwrap();
        assert!((split.spool.re - 0.9).abs() < 1e-12 && !split.is_pair());
        let same = AsymmetricDynamics { decel_factor: 1.0 }.respond(&split, &u);
        for (a, b) in same.iter().zip(tf.simulate_from_steady(&u)) {
            assert!((a - b).abs() < 1e-9, "{a} vs {b}");
        }
        let slow = AsymmetricDynamics { decel_factor: 3.0 }.respond(&split, &u);
        assert!(slow[90] > same[90] + 0.1 && (slow[50] - same[50]).abs() < 1e-9);
        // A block of one complex pair schedules the pair; one whose only pole is negative has no spool.
        let pair = [Complex64::new(0.8, 0.15), Complex64::new(0.8, -0.15)];
        let split = AsymmetricDynamics::split(&pair, &[], 0.1).unwrap();
        assert!(split.is_pair() && split.rest.is_none());
        let pair_tf = unit_gain_tf(&pair, &[], 0.1).unwrap();
        let same = AsymmetricDynamics { decel_factor: 1.0 }.respond(&split, &u);
        for (a, b) in same.iter().zip(pair_tf.simulate_from_steady(&u)) {
            assert!((a - b).abs() < 1e-9, "pair: {a} vs {b}");
        }
        assert!(matches!(
            AsymmetricDynamics::split(&[Complex64::new(-0.5, 0.0)], &[], 0.1),
            Err(EffectError::NotApplicable { .. })
        ));
    }
}
