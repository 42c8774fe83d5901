//! Why a model fails on a run (fit below 50 %, see [`crate::core::numerics::metrics::MIN_FIT_PCT`]):
//! the causes a simulation's error can be told apart by, read off the simulation, the measurement
//! and the input ranges alone, so they apply to every model alike.
use crate::core::numerics::stats::mean;

/// A simulation that goes further outside the measured range than this share of the measured span
/// has left the engine's operating range: an unstable recursion or a second equilibrium (a
/// well-identified model stays inside, give or take its error).
const RUNAWAY_SHARE: f64 = 0.5;
/// An error whose mean square is at least this share bias is mostly a constant offset.
const OFFSET_SHARE: f64 = 0.5;
/// A run whose input lies outside the identified range (by more than 2 % of that range) this
/// often makes the model extrapolate on a tenth of the run or more.
const OUTSIDE_SHARE: f64 = 0.1;
const RANGE_MARGIN: f64 = 0.02;

/// The reasons a failing simulation `y_hat` of measurement `y`, driven by `u`, fails, in words;
/// `ident_input` is the range of the identification input. Never empty.
pub fn failure_reasons(y: &[f64], y_hat: &[f64], u: &[f64], ident_input: (f64, f64)) -> Vec<String> {
    let n = y.len().min(y_hat.len());
    let (y, y_hat) = (&y[..n], &y_hat[..n]);
    let mut reasons = Vec::new();
    if n == 0 {
        return vec!["the run has no samples to compare".to_owned()];
    }
    let (lo, hi) = range(y);
    let span = (hi - lo).max(f64::MIN_POSITIVE);
    let (sim_lo, sim_hi) = range(y_hat);
    let beyond = (lo - sim_lo).max(sim_hi - hi);
    if !beyond.is_finite() || beyond > RUNAWAY_SHARE * span {
        let reached = if sim_hi - hi >= lo - sim_lo { sim_hi } else { sim_lo };
        reasons.push(format!(
            "its simulation leaves the measured range: it reaches {} where the measurement stays within \
             [{}, {}] (an unstable recursion, or the model resting at another equilibrium)",
            value(reached),
            value(lo),
            value(hi)
        ));
    }
    let e: Vec<f64> = y.iter().zip(y_hat).map(|(a, b)| a - b).collect();
    let bias = mean(&e);
    let mse = e.iter().map(|x| x * x).sum::<f64>() / n as f64;
    if mse > 0.0 && bias * bias >= OFFSET_SHARE * mse {
        reasons.push(format!(
            "{:.0} % of its squared error is a constant offset of {}: it settles where the engine does not",
            100.0 * bias * bias / mse,
            value(bias)
        ));
    } else if let Some((share, worst)) = steady_error(&e, u, mse) {
        reasons.push(format!(
            "{:.0} % of its squared error sits on the settled ends of the input's holds, up to {} off: \
             its steady states are wrong (a model resting at another equilibrium)",
            100.0 * share,
            value(worst)
        ));
    }
    let (u_lo, u_hi) = ident_input;
    let margin = RANGE_MARGIN * (u_hi - u_lo).abs();
    let outside = u.iter().filter(|x| **x < u_lo - margin || **x > u_hi + margin).count();
    if !u.is_empty() && outside as f64 >= OUTSIDE_SHARE * u.len() as f64 {
        reasons.push(format!(
            "{:.0} % of the run's input lies outside the identified range [{u_lo:.4}, {u_hi:.4}]: it extrapolates",
            100.0 * outside as f64 / u.len() as f64
        ));
    }
    if reasons.is_empty() {
        reasons.push(
            "its error is in the dynamics, not an offset or a runaway: it follows the level but not the changes"
                .to_owned(),
        );
    }
    reasons
}

/// `value` to four significant digits: plain between 10⁻³ and 10⁷ (an offset of 879.0 rpm), in
/// exponent form outside (a runaway's 1.000e24).
fn value(x: f64) -> String {
    let a = x.abs();
    if a == 0.0 {
        "0".to_owned()
    } else if (1e-3..1e7).contains(&a) {
        let decimals = (3 - a.log10().floor() as i32).clamp(0, 6) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.3e}")
    }
}

/// A hold of the input lasts at least this share of the run (a step and its settling on a bench
/// run) with the input within [`HOLD_TOLERANCE`] of its span; its second half counts as settled.
const MIN_HOLD_SHARE: f64 = 0.02;
const HOLD_TOLERANCE: f64 = 0.01;
/// Settled samples holding at least this share of the squared error make it a steady-state error.
const STEADY_SHARE: f64 = 0.5;

/// The share of the squared error `e` on the settled halves of the input's holds, and the largest
/// mean error of one hold, when that share is at least [`STEADY_SHARE`].
fn steady_error(e: &[f64], u: &[f64], mse: f64) -> Option<(f64, f64)> {
    let n = e.len().min(u.len());
    let (lo, hi) = range(&u[..n]);
    let tol = HOLD_TOLERANCE * (hi - lo);
    let need = ((MIN_HOLD_SHARE * n as f64).ceil() as usize).max(4);
    let (mut settled_sq, mut worst, mut start) = (0.0, 0.0f64, 0);
    for k in 1..=n {
        if k < n && (u[k] - u[start]).abs() <= tol {
            continue;
        }
        if k - start >= need {
            let tail = &e[start + (k - start) / 2..k];
            settled_sq += tail.iter().map(|x| x * x).sum::<f64>();
            worst = worst.max(mean(tail).abs());
        }
        start = k;
    }
    let share = settled_sq / (mse * n as f64);
    (mse > 0.0 && share >= STEADY_SHARE).then_some((share, worst))
}

fn range(x: &[f64]) -> (f64, f64) {
    x.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_read_plainly_in_the_engine_range_and_as_exponents_beyond() {
        assert_eq!(value(879.0), "879.0");
        assert_eq!(value(-0.01234567), "-0.01235");
        assert_eq!(value(52_721.6), "52722");
        assert_eq!(value(0.0), "0");
        assert_eq!(value(-1e24), "-1.000e24");
        assert_eq!(value(2e-5), "2.000e-5");
    }

    fn steps() -> (Vec<f64>, Vec<f64>) {
        let u: Vec<f64> = (0..400).map(|k| if (k / 100) % 2 == 0 { 2.0 } else { 4.0 }).collect();
        let y: Vec<f64> = u.iter().map(|u| 10.0 * u).collect();
        (u, y)
    }

    #[test]
    fn each_cause_is_named() {
        let (u, y) = steps();
        let runaway: Vec<f64> = (0..400).map(|k| 20.0 + k as f64).collect();
        assert!(failure_reasons(&y, &runaway, &u, (2.0, 4.0))[0].contains("leaves the measured range"));
        let offset: Vec<f64> = y.iter().map(|v| v + 6.0).collect();
        let r = failure_reasons(&y, &offset, &u, (2.0, 4.0));
        assert!(r.len() == 1 && r[0].contains("constant offset of -6.0"), "{r:?}");
        let r = failure_reasons(&y, &offset, &u, (2.0, 3.0));
        assert!(r.iter().any(|s| s.contains("50 % of the run's input lies outside")), "{r:?}");
        // Late by 20 samples of each 100-sample hold: the error is in the transients.
        let late: Vec<f64> = (0..400usize).map(|k| y[k.saturating_sub(20)]).collect();
        let r = failure_reasons(&y, &late, &u, (2.0, 4.0));
        assert!(r[0].contains("in the dynamics"), "{r:?}");
        // Right on the first holds, then resting at levels of its own, above and below.
        let latched: Vec<f64> = (0..400)
            .map(|k| {
                if k < 200 {
                    y[k]
                } else if k < 300 {
                    33.0
                } else {
                    25.0
                }
            })
            .collect();
        let r = failure_reasons(&y, &latched, &u, (2.0, 4.0));
        assert!(r[0].contains("sits on the settled ends of the input's holds"), "{r:?}");
    }
}
