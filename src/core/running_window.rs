//! The running window of a test-cell log: from the end of the start-up run-up to the fuel cut.
//!
//! A log that holds a whole engine run starts with the fuel off, lights off, runs up to idle under
//! the starter and the start sequence, runs, and ends with the fuel cut and the spool-down. Only the
//! running part shows the engine a model is meant for: the run-up is driven by the starter and a
//! start schedule, and after the cut the engine coasts (and flow meters may freeze). The window is
//! found from the input and the outputs alone, so it works on any log, not only on one that
//! records the controller's stage.
//!
//! 1. **Fuel on.** The fuel is off where the input is within [`OFF_SHARE`] of its 95th percentile
//!    of zero. The longest stretch of fuel on (gaps shorter than [`MERGE_GAP_S`] bridged) is the
//!    run; with no such sample the fuel is on throughout.
//! 2. **Fuel cut.** The run ends where the final fall begins: walking back from the last fuel-on
//!    sample while the input one second earlier stood more than [`CUT_DROP_SHARE`] of its range
//!    higher, and likewise on each output (which falls with the fuel actually burnt, while a flow
//!    meter's reading may trail it); the earliest of these.
//! 3. **Run-up over.** When the run starts on light-off fuel (below [`RUNUP_SHARE`] of its running
//!    median), every output that starts well below its running range (its lower quartile, by more
//!    than [`RUNUP_SHARE`] of the range up to the 95th percentile: a run-up, not an engine already
//!    at idle) must first have left its start-up level (climbed [`RUNUP_SHARE`] of the way from its value at light-off to its
//!    median over the run) and then held within [`SETTLE_SHARE`] of its running range for
//!    [`SETTLE_S`]: the start is the latest such moment over the outputs.
use serde::{Deserialize, Serialize};

use crate::core::numerics::stats::quantile;

/// Fuel counts as off within this share of the input's 95th percentile of zero: small engines idle
/// on 15–30 % of their full fuel, a cut input reads zero (plus a flow meter's offset of ~1 %).
pub const OFF_SHARE: f64 = 0.05;
/// Fuel-off gaps shorter than this are sensor dropouts, not shutdowns (a restart takes longer than
/// a starter cycle of tens of seconds; flow-meter dropouts last 1–3 s).
pub const MERGE_GAP_S: f64 = 5.0;
/// The fuel cut: a signal falls by more than this share of its range within one second (valves
/// close in well under a second and the gas generator follows within about one; a controller's
/// deceleration ramp at the end of a run, tens of seconds over the range, stays below this rate).
pub const CUT_DROP_SHARE: f64 = 0.05;
/// The run-up has left the start-up level once an output has come this share of the way from its
/// light-off value to its median over the run (idle lies well above it on every output of a
/// turbine: speed, pressure ratio and power all rise several-fold from light-off to idle).
pub const RUNUP_SHARE: f64 = 0.25;
/// An output has settled when it holds within this share of its running range (5th to 95th
/// percentile) …
pub const SETTLE_SHARE: f64 = 0.03;
/// … for this long: a few time constants of a small spool at idle (0.5–2 s).
pub const SETTLE_S: f64 = 5.0;

/// Where a run's running part lies, in samples `[start, end)`, and how it was found.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunningWindow {
    pub start: usize,
    pub end: usize,
    /// Fuel on at this sample (light-off), when the log starts with the fuel off.
    pub fuel_on: Option<usize>,
    /// How the ends were found, in words.
    pub reason: String,
}

/// The running window of a run with input `u` and `outputs`, sampled every `dt_secs` from `t0_secs`
/// (the times in the reason are the log's own).
pub fn running_window(u: &[f64], outputs: &[&[f64]], dt_secs: f64, t0_secs: f64) -> RunningWindow {
    let n = u.len();
    if n < 4 || dt_secs.is_nan() || dt_secs <= 0.0 {
        return RunningWindow {
            start: 0,
            end: n,
            fuel_on: None,
            reason: "the run is too short to look for a start-up: kept whole".to_owned(),
        };
    }
    let p95 = quantile(u, 0.95);
    let off_level = OFF_SHARE * p95.abs();
    let on: Vec<bool> = u.iter().map(|v| v.abs() > off_level).collect();
    let fuel_on = if on.iter().all(|&b| b) {
        None
    } else {
        longest_on_stretch(&on, (MERGE_GAP_S / dt_secs).round() as usize)
    };
    let (a, b) = fuel_on.unwrap_or((0, n));
    let w = ((1.0 / dt_secs).round() as usize).max(1);
    let end_input = final_fall_start(u, a, b, w);
    // The outputs fall with the fuel actually burnt, which a flow meter's reading may trail by a
    // second: the run ends where the first of them starts its final fall.
    let end = outputs
        .iter()
        .map(|y| final_fall_start(y, a, end_input, w))
        .min()
        .unwrap_or(end_input)
        .min(end_input);
    let hold = (SETTLE_S / dt_secs).round() as usize + 1;
    // The log holds the light-off when the fuel was off before the run, or when the run starts on
    // light-off fuel: below a quarter of the running median (idle fuel of a small engine is already
    // 15–30 % of full fuel, so an engine logged from idle is above it).
    // Failing both, an output that starts a whole running spread below its lower quartile can only
    // be standing still before light-off (a flow meter may read a running flow from the first sample).
    let lit_in_log = a > 0
        || u.get(a..end).is_some_and(|run| u[a] < RUNUP_SHARE * quantile(run, 0.5))
        || outputs.iter().any(|y| starts_below_running_range(y, a, end, 1.0));
    let start = if lit_in_log {
        outputs.iter().filter_map(|y| settled_after_runup(y, a, end, hold)).max().unwrap_or(a)
    } else {
        a
    };
    if start + 2 >= end {
        return RunningWindow {
            start: 0,
            end: n,
            fuel_on: None,
            reason: "no output settles after the start-up before the fuel cut: kept whole".to_owned(),
        };
    }
    let t = |k: usize| t0_secs + k as f64 * dt_secs;
    let lit = match fuel_on {
        Some(_) => format!("fuel on at {:.1} s", t(a)),
        None => "the fuel is on from the first sample".to_owned(),
    };
    let settled = if start > a {
        format!("every output settled after the run-up at {:.1} s", t(start))
    } else {
        "no run-up in the log".to_owned()
    };
    let cut = if end < n { format!("fuel cut at {:.1} s", t(end)) } else { "no fuel cut".to_owned() };
    RunningWindow { start, end, fuel_on: fuel_on.map(|(a, _)| a), reason: format!("{lit}, {settled}, {cut}") }
}

/// When `y` runs up at the start of `[a, end)` (it starts more than [`RUNUP_SHARE`] of its running
/// spread below its lower quartile), the first sample after which it has left its
/// light-off level and holds still for `hold` samples; `None` when there is no run-up to wait for.
fn settled_after_runup(y: &[f64], a: usize, end: usize, hold: usize) -> Option<usize> {
    let run = y.get(a..end)?;
    if run.len() <= hold {
        return None;
    }
    if !starts_below_running_range(y, a, end, RUNUP_SHARE) {
        return None;
    }
    let spread = quantile(run, 0.95) - quantile(run, 0.05);
    let level = y[a] + RUNUP_SHARE * (quantile(run, 0.5) - y[a]);
    let still = SETTLE_SHARE * spread;
    (a..end - hold).find(|&s| {
        let (lo, hi) = y[s..s + hold]
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(*v), h.max(*v)));
        y[s] >= level && hi - lo <= still
    })
}

/// Where the final fall of `x` inside `[a, b)` begins (the end of the run before it): walking back
/// from `b` while `x` one second (`w` samples) earlier stood more than [`CUT_DROP_SHARE`] of its
/// range higher.
fn final_fall_start(x: &[f64], a: usize, b: usize, w: usize) -> usize {
    let Some(run) = x.get(a..b).filter(|r| !r.is_empty()) else { return b };
    let range = quantile(run, 0.95) - quantile(run, 0.0);
    let mut end = b;
    while end > a + w + 1 && x[end - 1 - w] - x[end - 1] > CUT_DROP_SHARE * range {
        end -= 1;
    }
    end
}

/// Whether `y` starts `[a, end)` more than `share` of its running spread (lower quartile to 95th
/// percentile) below its lower quartile. A run-up is a small part of a test run (under a quarter
/// of it), so the quartile lies in the running part.
fn starts_below_running_range(y: &[f64], a: usize, end: usize, share: f64) -> bool {
    let Some(run) = y.get(a..end).filter(|r| !r.is_empty()) else { return false };
    let q1 = quantile(run, 0.25);
    y[a] < q1 - share * (quantile(run, 0.95) - q1)
}

/// The longest stretch of `on` with gaps of at most `gap` samples bridged, as `[start, end)`.
fn longest_on_stretch(on: &[bool], gap: usize) -> Option<(usize, usize)> {
    let mut best: Option<(usize, usize)> = None;
    let mut current: Option<(usize, usize)> = None;
    for (k, _) in on.iter().enumerate().filter(|(_, b)| **b) {
        current = match current {
            Some((s, e)) if k - e <= gap => Some((s, k + 1)),
            _ => Some((k, k + 1)),
        };
        if let Some((s, e)) = current
            && best.is_none_or(|(bs, be)| e - s > be - bs)
        {
            best = Some((s, e));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// A synthetic log: fuel off, light-off, run-up to idle, a ramp, a hold, fuel cut, coast-down.
    fn log(dt: f64) -> (Vec<f64>, Vec<f64>, usize, usize) {
        let n = (200.0 / dt) as usize;
        let (mut u, mut y) = (Vec::with_capacity(n), Vec::with_capacity(n));
        let (light_off, cut) = ((5.0 / dt) as usize, (180.0 / dt) as usize);
        let mut state: f64 = 0.0;
        for k in 0..n {
            let t = k as f64 * dt;
            let fuel = if k < light_off || k >= cut {
                0.0
            } else if t < 60.0 {
                0.3
            } else {
                (0.3 + 0.004 * (t - 60.0)).min(0.5)
            };
            // The output follows 3·fuel with a 2 s lag once lit; before light-off it idles at 0.
            let target = 3.0 * fuel;
            state += (target - state) * (dt / 2.0).min(1.0);
            u.push(fuel);
            y.push(state);
        }
        (u, y, light_off, cut)
    }

    #[test]
    fn the_window_runs_from_the_settled_run_up_to_the_fuel_cut() {
        let dt = 0.1;
        let (u, y, light_off, cut) = log(dt);
        let w = running_window(&u, &[&y], dt, 0.0);
        assert_eq!(w.fuel_on, Some(light_off));
        assert_eq!(w.end, cut, "{w:?}");
        // The 2 s lag has settled within 3 % of the range after about 3.5 time constants.
        assert!(
            w.start > light_off + (5.0 / dt) as usize && w.start < light_off + (12.0 / dt) as usize,
            "{w:?}"
        );
    }

    #[test]
    fn a_log_that_never_cuts_the_fuel_is_kept_whole() {
        let u: Vec<f64> = (0..500).map(|k| 2.0 + (k / 100) as f64).collect();
        let y: Vec<f64> = u.iter().map(|v| 1000.0 * v).collect();
        let w = running_window(&u, &[&y], 0.1, 0.0);
        assert_eq!((w.start, w.end, w.fuel_on), (0, 500, None), "{w:?}");
    }

    #[test]
    fn short_fuel_dropouts_do_not_end_the_run() {
        let dt = 0.1;
        let (mut u, y, _, cut) = log(dt);
        for v in &mut u[(100.0 / dt) as usize..(102.0 / dt) as usize] {
            *v = 0.0;
        }
        assert_eq!(running_window(&u, &[&y], dt, 0.0).end, cut);
    }
}
