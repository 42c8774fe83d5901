//! `transport_delay`: fuel line and valve dead time.
use super::Evidence;
use super::ParamSpec;
use super::stats::{ResidualTrace, mean, median};
use super::wording::after_or_before;

/// Fuel line and valve dead time: the fuel command reaches the engine `delay_samples` samples late,
/// so the input is delayed by z⁻ᵈ before the linear block. The delay may be fractional (linear
/// interpolation between samples), so it is fitted together with the roots: whole delays are
/// screened on the simulation error of the identification data (gain, offset and static map refitted
/// for each), then the best are refined continuously.
#[derive(Clone, Debug, PartialEq)]
pub struct TransportDelay {
    /// Dead time, samples (may be fractional).
    pub delay_samples: f64,
}

/// Longest delay screened, s.
const MAX_DELAY_SECS: f64 = 2.5;
/// Longest delay a model may hold, samples.
const MAX_DELAY_SAMPLES: f64 = 1000.0;

impl TransportDelay {
    /// The delay in seconds for a sample time.
    pub fn delay_secs(&self, dt_secs: f64) -> f64 {
        self.delay_samples * dt_secs
    }

    /// `u(k − d)`, linearly interpolated between samples, with the samples before the start equal to
    /// `u[0]` (the run starts steady).
    pub fn delay(&self, u: &[f64]) -> Vec<f64> {
        let u0 = u.first().copied().unwrap_or(0.0);
        let whole = self.delay_samples.floor();
        let frac = self.delay_samples - whole;
        let at = |k: isize| if k < 0 { u0 } else { u.get(k as usize).copied().unwrap_or(u0) };
        (0..u.len() as isize)
            .map(|k| {
                let j = k - whole as isize;
                (1.0 - frac) * at(j) + frac * at(j - 1)
            })
            .collect()
    }

    pub(super) fn free_params(&self) -> Vec<f64> {
        vec![self.delay_samples]
    }

    pub(super) fn with_free_params(&self, theta: &[f64]) -> Option<Self> {
        let delay_samples = *theta.first()?;
        (0.0..=MAX_DELAY_SAMPLES).contains(&delay_samples).then_some(Self { delay_samples })
    }

    /// Every whole delay from one sample up to [`MAX_DELAY_SECS`].
    pub(super) fn guesses(dt_secs: f64) -> Vec<Self> {
        let max = ((MAX_DELAY_SECS / dt_secs).round() as usize).max(1);
        (1..=max).map(|d| Self { delay_samples: d as f64 }).collect()
    }
}

/// Share of a step response at which its start is timed.
const ONSET_FRACTION: f64 = 0.1;
/// Share of a step response at which its middle is timed.
const MIDDLE_FRACTION: f64 = 0.5;
/// A step is an input change larger than this share of the run's input range within one sample.
const STEP_FRACTION: f64 = 0.1;

/// Time from `at` until `v` first covers `share` of the change from `before` to `after` (linear
/// interpolation), searched up to `end`.
fn crossing_secs(
    v: &[f64],
    at: usize,
    end: usize,
    before: f64,
    after: f64,
    share: f64,
    dt_secs: f64,
) -> Option<f64> {
    let level = before + share * (after - before);
    let sign = (after - before).signum();
    (at..end.min(v.len())).find_map(|k| {
        let (prev, cur) = (if k > 0 { *v.get(k - 1)? } else { before }, *v.get(k)?);
        ((cur - level) * sign >= 0.0).then(|| {
            let frac = if (cur - prev).abs() > 0.0 { (level - prev) / (cur - prev) } else { 1.0 };
            (k - at) as f64 * dt_secs - (1.0 - frac.clamp(0.0, 1.0)) * dt_secs
        })
    })
}

/// How late measured step responses are against the model's: the whole response (a dead time) or
/// only its later part (a lag).
#[derive(Clone, Debug, PartialEq)]
pub struct Lateness {
    /// Median over the clean steps of (measured − model) time to cover 10 % of the change, s.
    pub onset_secs: f64,
    /// The same at 50 % of the change, s.
    pub middle_secs: f64,
    /// Steps timed.
    pub steps: usize,
    pub dt_secs: f64,
}

impl Lateness {
    /// The whole response is shifted late, as a dead time shifts it: the onset is at least two
    /// samples late (one is the timing's own resolution) and the middle of the response is no
    /// later than the onset by more than half of it (a lag delays the middle more than the onset:
    /// a first-order lag τ moves the 10 % point by about 0.1 τ and the 50 % point by 0.7 τ).
    pub fn whole_response_late(&self) -> bool {
        self.steps > 0
            && self.onset_secs >= 2.0 * self.dt_secs
            && self.middle_secs - self.onset_secs <= 0.5 * self.onset_secs
    }

    /// The evidence sentence.
    pub fn sentence(&self) -> String {
        if self.steps == 0 {
            return "no clean input step to time the response on".to_owned();
        }
        let meaning = if self.whole_response_late() {
            "the whole response is shifted late, as a dead time shifts it: fuel reaches the engine later \
             than the model assumes"
        } else if self.onset_secs > 0.05 && self.middle_secs > self.onset_secs {
            "responses start late but their middle later still: a lag more than a dead time"
        } else if self.onset_secs < -0.05 {
            "responses start earlier than the model's"
        } else {
            "responses start with the model's"
        };
        format!(
            "measured step responses start {} the model's and reach half their change {} it (median of \
             {} steps): {meaning}",
            after_or_before(self.onset_secs),
            after_or_before(self.middle_secs),
            self.steps
        )
    }
}

/// When measured step responses start and reach half their change compared with the model's: the
/// medians, over the clean input steps of all runs, of the differences between the times at which
/// the measured and the modelled output have covered 10 % and 50 % of their change (measurement
/// smoothed over three samples).
pub fn lateness(traces: &[ResidualTrace]) -> Lateness {
    let (mut onsets, mut middles) = (Vec::new(), Vec::new());
    let dt_secs = traces.first().map_or(1.0, |t| t.dt_secs);
    for t in traces {
        let (lo, hi) =
            t.u.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(*x), b.max(*x)));
        let steps: Vec<usize> =
            (1..t.u.len()).filter(|&k| (t.u[k] - t.u[k - 1]).abs() > STEP_FRACTION * (hi - lo)).collect();
        let smooth: Vec<f64> = (0..t.y.len())
            .map(|k| {
                let (a, b) = (k.saturating_sub(1), (k + 2).min(t.y.len()));
                mean(&t.y[a..b])
            })
            .collect();
        let settle = (3.0 / t.dt_secs) as usize;
        let before = (0.5 / t.dt_secs).ceil() as usize;
        for (i, &at) in steps.iter().enumerate() {
            let end = steps.get(i + 1).copied().unwrap_or(t.y.len());
            if end < at + settle || at < before {
                continue;
            }
            let base = |v: &[f64]| mean(&v[at - before..at]);
            let last = |v: &[f64]| v.get(end - 1).copied().unwrap_or(0.0);
            let (m0, m1, h0, h1) = (base(&smooth), last(&smooth), base(&t.y_hat), last(&t.y_hat));
            let timed = |share: f64| -> Option<f64> {
                Some(
                    crossing_secs(&smooth, at, end, m0, m1, share, t.dt_secs)?
                        - crossing_secs(&t.y_hat, at, end, h0, h1, share, t.dt_secs)?,
                )
            };
            if let (Some(onset), Some(middle)) = (timed(ONSET_FRACTION), timed(MIDDLE_FRACTION)) {
                onsets.push(onset);
                middles.push(middle);
            }
        }
    }
    Lateness { onset_secs: median(&onsets), middle_secs: median(&middles), steps: onsets.len(), dt_secs }
}

/// The evidence of a dead time (see [`lateness`]): it supports one when the responses start at
/// least two samples late (one is the timing's own resolution).
pub(super) fn evidence(traces: &[ResidualTrace]) -> Evidence {
    let late = lateness(traces);
    Evidence { supports: late.steps > 0 && late.onset_secs >= 2.0 * late.dt_secs, sentence: late.sentence() }
}

block_impl!(
    TransportDelay { delay_samples },
    params: &[ParamSpec::real("delay_samples", 0.0, MAX_DELAY_SAMPLES)],
    physics: "fuel line and valve dead time: the input reaches the engine d samples late",
    evidence: evidence
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_early_start_reads_as_before_the_models() {
        let early = Lateness { onset_secs: -0.06, middle_secs: 0.07, steps: 5, dt_secs: 0.1 };
        let sentence = early.sentence();
        assert!(
            sentence.starts_with(
                "measured step responses start 0.06 s before the model's and reach half their change \
                 0.07 s after it (median of 5 steps)"
            ),
            "{sentence}"
        );
        assert!(!sentence.contains('-') && !sentence.contains('−'), "no negative times: {sentence}");
    }

    #[test]
    fn delay_shifts_and_holds_the_start() {
        let d = TransportDelay { delay_samples: 2.0 };
        assert_eq!(d.delay(&[1.0, 2.0, 3.0, 4.0]), vec![1.0, 1.0, 1.0, 2.0]);
        let half = TransportDelay { delay_samples: 1.5 };
        assert_eq!(half.delay(&[1.0, 2.0, 3.0, 4.0]), vec![1.0, 1.0, 1.5, 2.5]);
        assert_eq!(TransportDelay::guesses(0.5).len(), 5);
    }
}
