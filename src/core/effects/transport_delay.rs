//! `transport_delay`: fuel line and valve dead time.
use super::ParamSpec;
use super::stats::{ResidualTrace, diff, lagged_correlation};

/// Fuel line and valve dead time: the fuel command reaches the engine `delay_samples` samples late,
/// so the input is delayed by z⁻ᵈ before the linear block. Fitted by searching d on the simulation
/// error of the identification data (gain, offset and static map refitted for every d).
#[derive(Clone, Debug, PartialEq)]
pub struct TransportDelay {
    pub delay_samples: usize,
}

/// Longest delay searched, s.
const MAX_DELAY_SECS: f64 = 2.5;

impl TransportDelay {
    pub const ID: &'static str = "transport_delay";
    pub(super) const PARAMS: &'static [ParamSpec] = &[ParamSpec::whole("delay_samples", 0.0, 1000.0)];

    /// `u[k − d]`, with the samples before the start equal to `u[0]` (the run starts steady).
    pub fn delay(&self, u: &[f64]) -> Vec<f64> {
        let u0 = u.first().copied().unwrap_or(0.0);
        (0..u.len()).map(|k| if k >= self.delay_samples { u[k - self.delay_samples] } else { u0 }).collect()
    }

    /// Every delay from one sample up to [`MAX_DELAY_SECS`].
    pub(super) fn guesses(dt_secs: f64) -> Vec<Self> {
        let max = ((MAX_DELAY_SECS / dt_secs).round() as usize).max(1);
        (1..=max).map(|delay_samples| Self { delay_samples }).collect()
    }
}

/// Cross-correlation of the residual with the input's changes: where it peaks and how strongly.
pub(super) fn evidence(traces: &[ResidualTrace]) -> String {
    let Some(dt_secs) = traces.first().map(|t| t.dt_secs) else { return String::new() };
    let max_lag = (MAX_DELAY_SECS / dt_secs).round() as isize;
    let n: usize = traces.iter().map(|t| t.y.len()).sum();
    // Pooled over runs, weighted by length.
    let r_at = |lag: isize| -> f64 {
        traces
            .iter()
            .map(|t| lagged_correlation(&t.residual(), &diff(&t.u), lag) * t.y.len() as f64)
            .sum::<f64>()
            / n.max(1) as f64
    };
    let (lag, r) = (-max_lag..=max_lag)
        .map(|lag| (lag, r_at(lag)))
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        .unwrap_or((0, 0.0));
    let bound = 2.576 / (n.max(1) as f64).sqrt();
    let meaning = if lag > 0 && r.abs() > bound {
        "the engine answers the fuel later than the model"
    } else if r.abs() > bound {
        "the mismatch starts at the input changes but does not point to a dead time"
    } else {
        "no clear dead-time signature"
    };
    format!(
        "residual–fuel-change cross-correlation peaks at lag {lag:+} samples ({:.2} s), r = {r:.2} \
         (99 % bound {bound:.2}): {meaning}",
        lag as f64 * dt_secs
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn delay_shifts_and_holds_the_start() {
        let d = TransportDelay { delay_samples: 2 };
        assert_eq!(d.delay(&[1.0, 2.0, 3.0, 4.0]), vec![1.0, 1.0, 1.0, 2.0]);
        assert_eq!(TransportDelay::guesses(0.5).len(), 5);
    }
}
