//! The loss every candidate is judged by: residuals in units of the output's measurement noise.
//!
//! A percentage error divides by the measurement, so where the output is small its noise is large
//! in percent: at idle thrust the load cell's noise alone is 10–20 % of the value, and a percentage
//! loss is dominated by those samples, whatever the model does at full power where the physics
//! acts. Scaled by the noise σ of the run instead (`z = (y − ŷ)/σ`), every sample weighs by how far
//! the model misses beyond what the sensor can resolve, on speed and thrust alike, and the tests
//! compare models where they differ. RMSPE stays the metric reported to the user; the decision
//! (test, reduction, ranking) reads `z`.
//!
//! σ is each run's own, from the median absolute first difference
//! ([`sigma_from_first_differences`]): steps barely move a median, and runs of different days or
//! sensors each get their own. A quantised log whose median difference is zero (a speed logged in
//! steps of 10 rpm that mostly holds) falls back to the RMS first difference over √2, an upper
//! bound that includes the dynamics: the scale then errs towards calling changes noise.
use crate::core::numerics::stats::sigma_from_first_differences;

/// A model's errors over one run or one held-out response, in both units.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Errors {
    /// `100 (y − ŷ)/y`, % (the reported metric).
    pub(super) pct: Vec<f64>,
    /// `(y − ŷ)/σ`, in units of the run's measurement noise (the loss the decision reads).
    pub(super) noise: Vec<f64>,
}

impl Errors {
    /// The errors of `y_hat` on `y` over `range` (samples where the measurement is zero are left
    /// out, for every model alike), with the run's noise `sigma`.
    pub(super) fn of(y: &[f64], y_hat: &[f64], range: std::ops::Range<usize>, sigma: f64) -> Self {
        let end = range.end.min(y.len()).min(y_hat.len());
        let kept = (range.start.min(end)..end).filter(|&k| y[k].abs() > f64::MIN_POSITIVE);
        let (pct, noise) =
            kept.map(|k| (100.0 * (y[k] - y_hat[k]) / y[k], (y[k] - y_hat[k]) / sigma)).unzip();
        Self { pct, noise }
    }

    /// Whether every error is a number.
    pub(super) fn finite(&self) -> bool {
        self.noise.iter().chain(&self.pct).all(|e| e.is_finite())
    }
}

/// The measurement noise σ of a run's output (see the module documentation); positive.
pub(super) fn measurement_sigma(y: &[f64]) -> f64 {
    let median_based = sigma_from_first_differences(y);
    if median_based > 0.0 {
        return median_based;
    }
    let n = y.len().saturating_sub(1).max(1) as f64;
    let rms_diff = (y.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum::<f64>() / n).sqrt();
    if rms_diff > 0.0 { rms_diff / std::f64::consts::SQRT_2 } else { 1.0 }
}

/// Root mean square of a list; 0 when empty.
pub(super) fn rms(x: &[f64]) -> f64 {
    mean_square(x).sqrt()
}

/// The model's error beyond the measurement noise, in units of the noise, averaged over the runs
/// (every run counts the same, as the validation RMSPE averages them): the error a decision
/// compares.
///
/// The measured output is the truth plus noise of σ, independent of the model, so a run's mean
/// square `z` is the model's mean square error against the truth (over σ²) plus one: `√(ms − 1)`
/// estimates the RMS error against the noiseless truth, in units of σ. This is what a change must
/// reduce to matter: a model already at the noise floor has nothing left to gain, and a share of
/// the total (truth error and noise together) would make a real effect look small exactly where
/// the sensor is noisy, on thrust.
pub(super) fn mean_beyond_noise(runs: &[Errors]) -> f64 {
    runs.iter().map(|e| (mean_square(&e.noise) - 1.0).max(0.0).sqrt()).sum::<f64>() / runs.len().max(1) as f64
}

fn mean_square(x: &[f64]) -> f64 {
    x.iter().map(|e| e * e).sum::<f64>() / x.len().max(1) as f64
}

/// Each run's RMSPE averaged over the runs, % (the reported metric).
pub(super) fn mean_pct_rms(runs: &[Errors]) -> f64 {
    runs.iter().map(|e| rms(&e.pct)).sum::<f64>() / runs.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_scale_by_the_noise_and_skip_zero_measurements() {
        let y = [0.0, 10.0, 20.0, 40.0];
        let y_hat = [1.0, 9.0, 22.0, 40.0];
        let e = Errors::of(&y, &y_hat, 0..10, 2.0);
        assert_eq!(e.pct, vec![10.0, -10.0, 0.0]);
        assert_eq!(e.noise, vec![0.5, -1.0, 0.0]);
        assert!(e.finite());
        // Mean square 1.25/3 < 1: within the noise, nothing beyond it.
        assert!(mean_beyond_noise(&[e]).abs() < 1e-15);
        let far = Errors { pct: vec![], noise: vec![3.0, -3.0] };
        assert!((mean_beyond_noise(&[far]) - 8f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn a_quantised_log_still_has_a_positive_noise_scale() {
        // Mostly holding, with a few 10-rpm steps: the median difference is zero.
        let y: Vec<f64> = (0..100).map(|k| 50_000.0 + 10.0 * f64::from(u8::from(k % 10 == 0))).collect();
        let sigma = measurement_sigma(&y);
        assert!(sigma > 0.0 && sigma < 10.0, "{sigma}");
        assert!((measurement_sigma(&[3.0; 5]) - 1.0).abs() < 1e-12);
    }
}
