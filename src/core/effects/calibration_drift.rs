//! `calibration_drift`: the input's calibration moves between test days.
use super::stats::{ResidualTrace, mean, plateaus};
use super::{Evidence, ParamSpec};

/// The logged input is not the same fuel flow on every run: a pump-voltage → fuel relation that
/// drifts with the pump, the fuel's temperature or the battery, or a flow meter re-zeroed between
/// test days. The engine is the same, so the model's dynamics and map stay; what moves is an
/// offset of the input, constant over a run. The block adds to each simulated run's input the
/// offset that puts the model's steady states on the run's own measured steady stretches (holds of
/// the output or the input, see [`CalibrationDrift::steady_stretches`]): a calibration taken from the
/// run itself, as a test engineer would take it from the idle hold at the start of a test day.
/// The identification data define the calibration (their offset is zero: the map is fitted on
/// them); a run without the output, or without a hold, is simulated uncalibrated.
///
/// Only an offset, not a gain: with the holds of a typical run (two to six, often near one end of
/// the range where the map is flat) a gain is poorly determined, and on the JetCat runs fitting one
/// made every run worse than the offset alone.
#[derive(Clone, Debug, PartialEq)]
pub struct CalibrationDrift {
    /// Shortest hold of the output that counts as a steady stretch, s.
    pub hold_s: f64,
}

/// Gauss–Newton iterations for a run's offset (one unknown; converges in a handful).
const MAX_ITERATIONS: usize = 30;

/// Largest offset, as a share of the run's input range: a calibration that moved by more than half
/// the operating range is not a drift but another engine or a wrong column.
const MAX_OFFSET_SHARE: f64 = 0.5;

impl CalibrationDrift {
    /// The block for a linear block whose slowest time constant is `tau_s`: a hold counts when it
    /// lasts five time constants (the response has settled to within e⁻⁵ < 1 % of the step), at
    /// least 2 s and at most 10 s.
    pub fn for_time_constant(tau_s: f64) -> Self {
        Self { hold_s: (5.0 * tau_s).clamp(2.0, 10.0) }
    }

    /// The steady stretches of a run, where the test held the engine steady: the second halves of
    /// the output's holds longer than `hold_s` (a speed held by the ECU's loop, whose input never
    /// holds), and the input's holds after `hold_s` of settling, for their last `hold_s / 2` (an
    /// open-loop test whose output, a noisy thrust, never holds within 1 % of its range); merged
    /// where both find the same hold.
    pub fn steady_stretches(&self, u: &[f64], y: &[f64], dt_secs: f64) -> Vec<(usize, usize)> {
        let tail = 0.5 * self.hold_s;
        let mut found = plateaus(y, dt_secs, self.hold_s, tail);
        found.extend(plateaus(u, dt_secs, self.hold_s + tail, tail));
        found.sort_unstable();
        let mut merged: Vec<(usize, usize)> = Vec::with_capacity(found.len());
        for (a, b) in found {
            match merged.last_mut() {
                Some(last) if a <= last.1 => last.1 = last.1.max(b),
                _ => merged.push((a, b)),
            }
        }
        merged
    }

    /// The input offset that best puts the model's response on the measured holds of `y` (least
    /// squares over the holds' means); zero without holds, or when no admissible offset is found.
    /// `response(b)` is the model's output over the whole run with the offset `b` added to its input.
    pub fn run_offset(&self, u: &[f64], y: &[f64], dt_secs: f64, response: impl Fn(f64) -> Vec<f64>) -> f64 {
        let holds: Vec<(usize, usize, f64)> = self
            .steady_stretches(u, y, dt_secs)
            .into_iter()
            .filter_map(|(a, b)| Some((a, b, mean(y.get(a..b)?))))
            .collect();
        let (lo, hi) = u.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(*x), b.max(*x)));
        let span = (hi - lo).max(f64::MIN_POSITIVE);
        if holds.is_empty() || !span.is_finite() {
            return 0.0;
        }
        let at_holds = |b: f64| -> Vec<f64> {
            let r = response(b);
            holds.iter().map(|&(a, e, _)| r.get(a..e).map_or(f64::NAN, mean)).collect()
        };
        let cost = |m: &[f64]| holds.iter().zip(m).map(|(h, m)| (h.2 - m).powi(2)).sum::<f64>();
        let h = 1e-4 * span;
        let mut offset = 0.0;
        let mut here = at_holds(offset);
        for _ in 0..MAX_ITERATIONS {
            let (up, down) = (at_holds(offset + h), at_holds(offset - h));
            let (mut jtj, mut jtr) = (0.0, 0.0);
            for (k, hold) in holds.iter().enumerate() {
                let j = (up[k] - down[k]) / (2.0 * h);
                jtj += j * j;
                jtr += j * (hold.2 - here[k]);
            }
            if jtj.is_nan() || jtj <= f64::MIN_POSITIVE {
                break;
            }
            let mut step = (jtr / jtj).clamp(-0.1 * span, 0.1 * span);
            let mut next = at_holds(offset + step);
            // Halve a step that does not lower the cost (the map may bend back at its ends).
            let worse = |next: &[f64]| cost(next).is_nan() || cost(next) > cost(&here);
            while step.abs() > 1e-12 * span && worse(&next) {
                step *= 0.5;
                next = at_holds(offset + step);
            }
            offset += step;
            here = next;
            if step.abs() <= 1e-9 * span {
                break;
            }
        }
        if offset.is_finite() && offset.abs() <= MAX_OFFSET_SHARE * span { offset } else { 0.0 }
    }
}

/// A run's steady-state residual, %: mean over its holds, and the standard error of that mean from
/// the scatter between holds. `None` without holds.
fn steady_residual(t: &ResidualTrace, hold_s: f64) -> Option<(f64, f64, usize)> {
    let e = t.residual_pct();
    let per_hold: Vec<f64> = plateaus(&t.y, t.dt_secs, hold_s, 0.5 * hold_s)
        .into_iter()
        .filter_map(|(a, b)| e.get(a..b).map(mean))
        .collect();
    let n = per_hold.len();
    if n == 0 {
        return None;
    }
    let m = mean(&per_hold);
    let sd = if n > 1 {
        (per_hold.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
    } else {
        0.0
    };
    Some((m, sd / (n as f64).sqrt(), n))
}

/// Hold that counts as steady for the evidence, s (the block's own default for a 1 s spool).
const EVIDENCE_HOLD_S: f64 = 5.0;

/// Runs disagree on the steady state when their mean steady residuals differ by more than this
/// many standard errors of the difference (about p < 10⁻⁴ for normal errors: a drift, not the
/// scatter of the holds) …
const DISAGREE_SE: f64 = 4.0;
/// … and by more than this, %: smaller offsets are within what a bench's calibration holds.
const DISAGREE_MIN_PCT: f64 = 0.5;

/// Inlet temperatures further apart than this, °C, change a small turbojet's corrected speed by more
/// than the 0.5 % a calibration is trusted to (√(T₁/T₂) − 1 ≈ 0.5 % at 288 K needs ~3 K).
const INLET_GAP_C: f64 = 3.0;

/// Mean inlet temperature of run `a` minus that of run `b`, when both record one.
fn inlet_temperature_gap(traces: &[ResidualTrace], a: &str, b: &str) -> Option<f64> {
    let temp = |name: &str| {
        let t = traces.iter().find(|t| t.run == name)?;
        let c = t.aux.iter().find(|c| c.name == super::AmbientCorrection::CHANNELS[0])?;
        (!c.values.is_empty()).then(|| mean(&c.values))
    };
    Some(temp(a)? - temp(b)?)
}

/// Whether the runs' steady-state residuals disagree: the run-to-run part of the steady error.
pub fn evidence(traces: &[ResidualTrace]) -> Evidence {
    let runs: Vec<(&str, f64, f64)> = traces
        .iter()
        .filter_map(|t| steady_residual(t, EVIDENCE_HOLD_S).map(|(m, se, _)| (t.run.as_str(), m, se)))
        .collect();
    if runs.len() < 2 {
        return Evidence::none("fewer than two runs hold a steady state long enough to compare runs");
    }
    let listed: Vec<String> = runs.iter().map(|(name, m, _)| format!("{m:+.2} % on '{name}'")).collect();
    let (Some(low), Some(high)) =
        (runs.iter().min_by(|a, b| a.1.total_cmp(&b.1)), runs.iter().max_by(|a, b| a.1.total_cmp(&b.1)))
    else {
        return Evidence::none("no steady states to compare");
    };
    let gap = high.1 - low.1;
    let se = (high.2.powi(2) + low.2.powi(2)).sqrt();
    let differ = gap > DISAGREE_MIN_PCT && gap > DISAGREE_SE * se;
    let meaning = if differ {
        let inlet = inlet_temperature_gap(traces, high.0, low.0)
            .filter(|dt| dt.abs() > INLET_GAP_C)
            .map(|dt| {
                format!(
                    "; their inlet temperatures differ by {:.1} °C, so other inlet conditions may explain it",
                    dt.abs()
                )
            })
            .unwrap_or_default();
        format!(
            "runs disagree on the steady state by {gap:.1} % ('{}' against '{}'): a calibration drift or a \
             different engine build{inlet}",
            high.0, low.0
        )
    } else {
        format!(
            "the runs' steady states are {gap:.1} % apart, within {DISAGREE_SE} standard errors of the scatter \
             between their holds (SE {se:.1} %): no consistent offset between runs"
        )
    };
    Evidence { sentence: format!("steady-state residual {}: {meaning}", listed.join(", ")), supports: differ }
}

block_impl!(
    CalibrationDrift { hold_s },
    params: &[ParamSpec::real("hold_s", 0.5, 120.0)],
    physics: "the input's calibration drifts between runs (pump voltage to fuel, flow-meter zero): each run's \
         input gets the offset its own steady holds call for",
    evidence: evidence
);

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::core::effects::stats::low_pass;

    #[test]
    fn the_offset_puts_the_steady_states_on_the_holds() {
        // Holds at 1, 2 and 3 input units, the engine's steady output y = 10 + 5u + u², logged with
        // the input reading 0.2 low.
        let steady = |u: f64| 10.0 + 5.0 * u + u * u;
        let u: Vec<f64> = (0..600).map(|k| 1.0 + (k / 200) as f64).collect();
        let y: Vec<f64> = u.iter().map(|u| steady(u + 0.2)).collect();
        let block = CalibrationDrift { hold_s: 5.0 };
        let response = |b: f64| u.iter().map(|u| steady(u + b)).collect::<Vec<_>>();
        let offset = block.run_offset(&u, &y, 0.1, response);
        assert!((offset - 0.2).abs() < 1e-6, "{offset}");
        // No hold (a ramp): no calibration.
        let ramp: Vec<f64> = (0..600).map(|k| k as f64 * 0.01).collect();
        let y_ramp: Vec<f64> = ramp.iter().map(|u| steady(*u)).collect();
        let response = |b: f64| ramp.iter().map(|u| steady(u + b)).collect::<Vec<_>>();
        assert!(block.run_offset(&ramp, &y_ramp, 0.1, response).abs() < 1e-12);
    }

    #[test]
    fn holds_that_have_not_settled_are_read_through_the_models_own_response() {
        // A slow spool (τ = 3 s) held 10 s at each level: the input's holds count after 7.5 s, when
        // the response is still e^(−7.5/3) ≈ 8 % of the step short of its steady state. More rises
        // than falls, so the shortfalls do not cancel in the mean.
        let (dt, tau) = (0.1, 3.0);
        let u: Vec<f64> = [1.0, 3.0, 2.0, 2.5, 3.0].iter().flat_map(|&level| [level; 100]).collect();
        let lag = |b: f64| low_pass(&u.iter().map(|x| x + b).collect::<Vec<_>>(), dt, tau);
        let y = lag(0.2);
        let block = CalibrationDrift { hold_s: 5.0 };
        assert!(!block.steady_stretches(&u, &y, dt).is_empty(), "the run has holds");
        let offset = block.run_offset(&u, &y, dt, lag);
        assert!((offset - 0.2).abs() < 1e-6, "{offset}");
        // Read against the steady state instead, the same holds give another offset: the holds
        // really are unsettled, so the test would catch a steady-state calibration.
        let steady = |b: f64| u.iter().map(|x| x + b).collect::<Vec<_>>();
        let biased = block.run_offset(&u, &y, dt, steady);
        assert!((biased - 0.2).abs() > 0.01, "{biased}");
    }
}
