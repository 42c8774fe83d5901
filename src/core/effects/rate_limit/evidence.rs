//! The rate limit's evidence: measured peak slopes that stop growing with the size of the change.
use super::super::Evidence;
use super::super::stats::{ResidualTrace, median};
use crate::core::numerics::stats::sigma_from_first_differences;

/// Half-width of the rate's difference quotient, samples: `(y[k+2] − y[k−2]) / 4dt` averages the
/// slope over four sample intervals, which divides white noise's rate by 4/√2 ≈ 2.8 against a
/// one-sample difference while a spool transient (seconds long) keeps its slope.
const RATE_HALF_SPAN: usize = 2;

/// A change counts when the model's rate exceeds this many standard deviations of the measured
/// rate's noise: the peak of a noisy rate over a change of a few tens of samples is inflated by
/// about 2–3 σ, so above 10 σ the inflation is below a third and cannot fake a saturation (the
/// slope below moves by at most ln 1.3 / ln 10 ≈ 0.1 over a decade of changes).
const MIN_PEAK_NOISE_SIGMAS: f64 = 10.0;

/// Two changes are compared only when the model's peak rates differ by at least this factor, so the
/// slope is read across sizes the noise cannot blur.
const MIN_PEAK_RATIO: f64 = 1.5;

/// Fewest changes a direction's slope is read from: one change spoiled by a dropout spoils n − 1 of
/// the n(n − 1)/2 pairs, a share 2/n, and the median of the pairwise slopes survives that from five
/// changes on (2/5 < 1/2). Since only pairs of clearly different size count, the rule is checked on
/// the pairs themselves as well: no change may take part in half of them or more.
const MIN_CHANGES: usize = 5;

/// The measurement follows a change when its rate over the change exceeds this many standard
/// deviations of the rate's noise: the largest of a hundred noise samples passes 5 σ with
/// probability 100 · 2.9·10⁻⁷ ≈ 3·10⁻⁵.
const MEASURED_MOVES_SIGMAS: f64 = 5.0;

/// Measured peak rates growing as the model's to a power below this saturate: a linear engine (or
/// one whose rise and fall time constants differ) scales every slope with the change, power 1; a
/// rate limit that binds caps the larger changes at one rate, power 0. One half is midway.
const SATURATION_POWER: f64 = 0.5;

/// `(x[k+h] − x[k−h]) / (2h·dt)`; zero within `h` samples of the ends.
pub(super) fn smoothed_rate(x: &[f64], dt_secs: f64) -> Vec<f64> {
    let h = RATE_HALF_SPAN;
    (0..x.len())
        .map(|k| match (k.checked_sub(h).and_then(|a| x.get(a)), x.get(k + h)) {
            (Some(a), Some(b)) => (b - a) / (2.0 * h as f64 * dt_secs),
            _ => 0.0,
        })
        .collect()
}

/// One change of the model's response: its peak rate and the measured one over the same stretch.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Change {
    model_peak: f64,
    measured_peak: f64,
}

/// A change of the model must keep at least this share of its travel for as long again as it took,
/// and must not give back more than this share of a change the other way just before it (as long
/// before as it takes): a schedule limits changes of level, and a model change that is undone (or
/// undoes another) that fast is a blip (an input dropout the engine does not follow, and the
/// recovery from it; a logger gap bridged by interpolation) or half an oscillation, whose peak rate
/// says nothing about a schedule. A step response keeps all of its travel, and even a pair damped to
/// 10 % overshoot keeps 90 %.
const MIN_KEPT_SHARE: f64 = 0.5;

/// The changes of one trace in one direction (`sign` +1 rises, −1 falls): maximal stretches where
/// the model moves that way faster than the noise floor and then holds its new level (see
/// [`MIN_KEPT_SHARE`]). The measured peak is read over the stretch widened by half its length on
/// each side (a late or slowed response peaks later); a change the measurement does not follow
/// faster than the noise floor is left out too: a saturated slope is a rate the measurement shows,
/// and a measurement that does not move at all is a dropout or a model fault, not a schedule.
fn changes(t: &ResidualTrace, sign: f64, noise: f64) -> Vec<Change> {
    let floor = MIN_PEAK_NOISE_SIGMAS * noise;
    let model = smoothed_rate(&t.y_hat, t.dt_secs);
    let measured = smoothed_rate(&t.y, t.dt_secs);
    let mut out = Vec::new();
    let mut k = 0;
    while k < model.len() {
        if sign * model.get(k).copied().unwrap_or(0.0) <= floor {
            k += 1;
            continue;
        }
        let start = k;
        while k < model.len() && sign * model.get(k).copied().unwrap_or(0.0) > floor {
            k += 1;
        }
        let widen = (k - start).div_ceil(2);
        let peak = |r: &[f64], a: usize, b: usize| {
            r.get(a..b.min(r.len())).map_or(0.0, |s| s.iter().map(|x| sign * x).fold(0.0, f64::max))
        };
        let change = Change {
            model_peak: peak(&model, start, k),
            measured_peak: peak(&measured, start.saturating_sub(widen), k + widen),
        };
        let level = |i: usize| t.y_hat.get(i.min(t.y_hat.len().saturating_sub(1))).copied().unwrap_or(0.0);
        let travel = sign * (level(k.saturating_sub(1)) - level(start));
        let kept = sign * (level(k - 1 + (k - start)) - level(start));
        let undone = sign * (level(start.saturating_sub(k - start)) - level(start));
        let level_change = kept >= MIN_KEPT_SHARE * travel && undone < MIN_KEPT_SHARE * travel;
        if level_change && change.measured_peak > MEASURED_MOVES_SIGMAS * noise {
            out.push(change);
        }
    }
    out
}

/// How the measured peak rates of one direction grow with the model's: the Theil–Sen slope of
/// ln(measured peak) on ln(model peak) over pairs of changes of clearly different size (a median
/// of pairwise slopes: a dropout that spikes one change's measured rate moves it little), and
/// the fastest change's measured and model peaks.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Growth {
    power: f64,
    changes: usize,
    fastest_measured: f64,
    fastest_model: f64,
}

fn growth(changes: &[Change], noise: f64) -> Option<Growth> {
    let ln = |x: f64| x.max(noise).max(f64::MIN_POSITIVE).ln();
    let mut slopes = Vec::new();
    let mut part = vec![0usize; changes.len()];
    for (i, a) in changes.iter().enumerate() {
        for (j, b) in changes.iter().enumerate().skip(i + 1) {
            let dx = ln(b.model_peak) - ln(a.model_peak);
            if dx.abs() >= MIN_PEAK_RATIO.ln() {
                slopes.push((ln(b.measured_peak) - ln(a.measured_peak)) / dx);
                for k in [i, j] {
                    if let Some(p) = part.get_mut(k) {
                        *p += 1;
                    }
                }
            }
        }
    }
    let in_pairs = part.iter().filter(|p| **p > 0).count();
    let most = part.iter().copied().max().unwrap_or(0);
    let fastest = changes.iter().max_by(|a, b| a.model_peak.total_cmp(&b.model_peak))?;
    (in_pairs >= MIN_CHANGES && 2 * most < slopes.len()).then(|| Growth {
        power: median(&slopes),
        changes: changes.len(),
        fastest_measured: fastest.measured_peak,
        fastest_model: fastest.model_peak,
    })
}

/// A direction saturates when its measured peaks grow with less than [`SATURATION_POWER`] of the
/// model's and its fastest change is measured slower than the model makes it (the limit binds there).
fn saturates(g: &Growth) -> bool {
    g.power < SATURATION_POWER && g.fastest_measured < g.fastest_model
}

/// A rate as the sentence shows it: whole units from 100 up, three decimals below.
fn shown(x: f64) -> String {
    if x.abs() >= 100.0 { format!("{x:.0}") } else { format!("{x:.3}") }
}

/// "grow as the model's to the power 0.21 (12 changes; fastest 5400 against the model's 9100 per s)".
fn growth_clause(g: Option<&Growth>) -> String {
    match g {
        Some(g) => format!(
            "grow as the model's to the power {:.2} ({} changes; fastest {} against the model's {} per s)",
            g.power,
            g.changes,
            shown(g.fastest_measured),
            shown(g.fastest_model)
        ),
        None => "are too few or too alike in size to compare".to_owned(),
    }
}

/// Whether the measured slope saturates at a constant rate while the model's keeps growing with the
/// size of the change, on rises and on falls (identification range and validation runs together).
pub(super) fn evidence(traces: &[ResidualTrace]) -> Evidence {
    let mut found = [Vec::new(), Vec::new()];
    let mut noises = Vec::new();
    for t in traces {
        // Noise of the measured rate: white noise σ gives the rate σ·√2 / (2h·dt).
        let sigma = sigma_from_first_differences(&t.residual());
        let noise = sigma * std::f64::consts::SQRT_2 / (2.0 * RATE_HALF_SPAN as f64 * t.dt_secs);
        noises.push(noise);
        for (slot, sign) in found.iter_mut().zip([1.0, -1.0]) {
            slot.extend(changes(t, sign, noise));
        }
    }
    let noise = median(&noises);
    let [rises, falls] = found;
    let (up, down) = (growth(&rises, noise), growth(&falls, noise));
    let (up_sat, down_sat) = (up.as_ref().is_some_and(saturates), down.as_ref().is_some_and(saturates));
    let meaning = match (up_sat, down_sat) {
        (true, true) => "both accelerations and decelerations saturate at a constant rate",
        (true, false) => "accelerations saturate at a constant rate",
        (false, true) => "decelerations saturate at a constant rate",
        (false, false) if up.is_none() && down.is_none() => "no saturating slope to be seen",
        (false, false) => "the slopes scale with the size of the change, as a linear engine's do",
    };
    Evidence {
        sentence: format!(
            "measured peak slopes on rises {}, on falls {}: {meaning}",
            growth_clause(up.as_ref()),
            growth_clause(down.as_ref())
        ),
        supports: up_sat || down_sat,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A slew limiter on a signal: how a measurement saturates, for the evidence's tests.
    fn slew(v: &[f64], rise: f64, fall: f64, dt: f64) -> Vec<f64> {
        let mut held = v[0];
        v.iter()
            .map(|x| {
                held += (x - held).clamp(-fall * dt, rise * dt);
                held
            })
            .collect()
    }

    fn trace(y: Vec<f64>, y_hat: Vec<f64>) -> ResidualTrace {
        ResidualTrace { run: "r".into(), dt_secs: 0.1, u: vec![0.0; y.len()], y, y_hat, aux: vec![] }
    }

    /// Steps of several sizes through a first-order lag; the measurement rate-limited or not.
    fn steps(limit: Option<(f64, f64)>) -> ResidualTrace {
        let levels = [0.0, 1.0, 0.0, 2.0, 0.0, 3.0, 0.0, 4.0, 0.0, 6.0, 0.0, 8.0, 0.0, 10.0, 0.0];
        let u: Vec<f64> = levels.iter().flat_map(|l| vec![*l; 80]).collect();
        let lag = super::super::super::stats::low_pass(&u, 0.1, 0.8);
        let noise: Vec<f64> = (0..u.len()).map(|k| 0.002 * ((k * 7919 % 101) as f64 - 50.0) / 50.0).collect();
        let y: Vec<f64> = match limit {
            Some((rise, fall)) => slew(&lag, rise, fall, 0.1),
            None => lag.clone(),
        };
        trace(y.iter().zip(&noise).map(|(a, b)| a + b).collect(), lag)
    }

    #[test]
    fn saturating_slopes_are_evidence_and_proportional_ones_are_not() {
        let linear = evidence(&[steps(None)]);
        assert!(!linear.supports, "{}", linear.sentence);
        let limited = evidence(&[steps(Some((2.0, 100.0)))]);
        assert!(
            limited.supports && limited.sentence.contains("accelerations saturate"),
            "{}",
            limited.sentence
        );
    }
}
