//! `transport_delay`: fuel line and valve dead time.
use super::ParamSpec;
use super::stats::{ResidualTrace, mean, median};

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
    /// Catalog id.
    pub const ID: &'static str = "transport_delay";
    pub(super) const PARAMS: &'static [ParamSpec] =
        &[ParamSpec::real("delay_samples", 0.0, MAX_DELAY_SAMPLES)];

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
/// A step is an input change larger than this share of the run's input range within one sample.
const STEP_FRACTION: f64 = 0.1;

/// Time from `at` until `v` first covers [`ONSET_FRACTION`] of the change from `before` to `after`
/// (linear interpolation), searched up to `end`.
fn onset_secs(v: &[f64], at: usize, end: usize, before: f64, after: f64, dt_secs: f64) -> Option<f64> {
    let level = before + ONSET_FRACTION * (after - before);
    let sign = (after - before).signum();
    (at..end.min(v.len())).find_map(|k| {
        let (prev, cur) = (if k > 0 { *v.get(k - 1)? } else { before }, *v.get(k)?);
        ((cur - level) * sign >= 0.0).then(|| {
            let frac = if (cur - prev).abs() > 0.0 { (level - prev) / (cur - prev) } else { 1.0 };
            (k - at) as f64 * dt_secs - (1.0 - frac.clamp(0.0, 1.0)) * dt_secs
        })
    })
}

/// When measured step responses start compared with the model's: the median, over the clean input
/// steps of all runs, of the difference between the times at which the measured and the modelled
/// output have covered 10 % of their change (measurement smoothed over three samples).
pub(super) fn evidence(traces: &[ResidualTrace]) -> String {
    let mut lags: Vec<f64> = Vec::new();
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
            if let (Some(tm), Some(th)) = (
                onset_secs(&smooth, at, end, m0, m1, t.dt_secs),
                onset_secs(&t.y_hat, at, end, h0, h1, t.dt_secs),
            ) {
                lags.push(tm - th);
            }
        }
    }
    if lags.is_empty() {
        return "no clean input step to time the response on".to_owned();
    }
    let lag_secs = median(&lags);
    let meaning = if lag_secs > 0.05 {
        "responses start late: fuel reaches the engine later than the model assumes"
    } else if lag_secs < -0.05 {
        "responses start earlier than the model's"
    } else {
        "responses start with the model's"
    };
    format!(
        "measured step responses start {lag_secs:+.2} s after the model's (median of {} steps): {meaning}",
        lags.len()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn delay_shifts_and_holds_the_start() {
        let d = TransportDelay { delay_samples: 2.0 };
        assert_eq!(d.delay(&[1.0, 2.0, 3.0, 4.0]), vec![1.0, 1.0, 1.0, 2.0]);
        let half = TransportDelay { delay_samples: 1.5 };
        assert_eq!(half.delay(&[1.0, 2.0, 3.0, 4.0]), vec![1.0, 1.0, 1.5, 2.5]);
        assert_eq!(TransportDelay::guesses(0.5).len(), 5);
    }
}
