//! The parsimony rule: a candidate (a root, a dead time, a free pole of the direct fit) enters the
//! model only when it beats the simpler model by enough, beyond noise.
//!
//! A candidate enters when (1) it lowers the held-out error by more than
//! [`MIN_STANDARD_ERRORS`] standard error of the per-segment improvements — the one-standard-error
//! rule of cross-validated model choice (Breiman et al.; Hastie, Tibshirani & Friedman §7.10): the
//! segments are J separate experiments, and a root that only fits noise in some of them does not
//! predict the others — and (2) it removes at least [`MIN_RELATIVE_REDUCTION`] (10 %) of the
//! held-out model error: the RMS error above the measurement noise (σ read from the data, see
//! [`IdentData::noise_sigma`]), which no structure can remove — on a thrust channel whose noise is
//! most of the error a faint but real pole pair would otherwise never count. Ten percent is the
//! share the diagnosis asks of a physical effect, so that a root and an effect are judged alike;
//! smaller gains come from roots that only shave an error dominated by what a Wiener model cannot
//! do (a speed-dependent time constant), which a controller designer would not want to carry. The
//! held-out error is used rather than the fit to all the data because every extra root lowers the
//! latter.
use std::fmt;

use serde::{Deserialize, Serialize};

use crate::core::identification::reduce::IdentData;
use crate::core::identification::words::fmt_error;

/// Smallest share of the held-out RMS error a root must remove to enter the model.
pub const MIN_RELATIVE_REDUCTION: f64 = 0.10;
/// Standard errors by which the held-out improvement must exceed zero (the one-standard-error rule).
pub const MIN_STANDARD_ERRORS: f64 = 1.0;
/// A trial is cross-validated only when its fit on all the data removes at least this share of
/// [`MIN_RELATIVE_REDUCTION`]: held-out improvements run below in-sample ones.
const SCREEN_SHARE: f64 = 0.5;

/// True when a trial's fit on all the data removes too little of the model error (`in_sample`, see
/// [`model_error_reduction`]) for its held-out error to be worth computing.
pub(super) fn too_little_to_cross_validate(in_sample: f64) -> bool {
    in_sample < SCREEN_SHARE * MIN_RELATIVE_REDUCTION
}

/// Mean of per-segment held-out mean squared errors.
pub(super) fn pooled(mse: &[f64]) -> f64 {
    mse.iter().sum::<f64>() / mse.len().max(1) as f64
}

/// A trial structure against the current one, over the held-out segments of a cross-validation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Gain {
    /// Share of the held-out model error (above the noise) the trial removes.
    pub reduction: f64,
    /// Held-out errors without and with the trial (output units, pooled over the segments).
    pub without: f64,
    pub with: f64,
    /// Segments whose held-out error the trial lowers, and how many segments there are.
    pub wins: usize,
    pub folds: usize,
    /// Mean per-segment relative improvement over its standard error.
    pub standard_errors: f64,
}

impl Gain {
    /// From the per-segment held-out mean squared errors of the two structures; `noise` is the
    /// measurement noise, which no structure can remove.
    pub fn of(without: &[f64], with: &[f64], noise: Noise) -> Self {
        let d: Vec<f64> = without.iter().zip(with).map(|(a, b)| (a - b) / a.max(f64::MIN_POSITIVE)).collect();
        let n = d.len().max(1) as f64;
        let mean = d.iter().sum::<f64>() / n;
        let sd = (d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt();
        let (without, with) = (pooled(without), pooled(with));
        Self {
            reduction: model_error_reduction(without, with, noise),
            without: without.sqrt(),
            with: with.sqrt(),
            wins: d.iter().filter(|x| **x > 0.0).count(),
            folds: d.len(),
            standard_errors: mean / (sd / n.sqrt()).max(f64::MIN_POSITIVE),
        }
    }

    /// The parsimony rule: enough of the model error removed, by enough standard errors.
    pub fn passes(&self) -> bool {
        self.reduction >= MIN_RELATIVE_REDUCTION && self.standard_errors >= MIN_STANDARD_ERRORS
    }
}

/// "held-out error from … to … (model error above noise −23 %), lower on 5 of 6 segments (2.1
/// standard errors); a root must remove …".
impl fmt::Display for Gain {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "held-out error from {} to {} (model error above noise {:+.0} %), lower on {} of {} segments \
             ({:.1} standard errors); a root must remove {:.0} % of the model error and more than {} \
             standard error",
            fmt_error(self.without),
            fmt_error(self.with),
            -100.0 * self.reduction,
            self.wins,
            self.folds,
            self.standard_errors,
            100.0 * MIN_RELATIVE_REDUCTION,
            MIN_STANDARD_ERRORS
        )
    }
}

/// The measurement noise's variance σ² as read from the data, and how uncertain that reading is.
#[derive(Clone, Copy, Debug)]
pub struct Noise {
    pub var: f64,
    /// Two standard errors of `var`: σ is read by a median (of absolute first differences), whose
    /// asymptotic efficiency for Gaussian noise is about 37 %, so SE(σ̂) ≈ 1.16 σ/√N and
    /// SE(σ̂²) ≈ 2.33 σ²/√N over N samples.
    pub uncertainty: f64,
}

impl Noise {
    /// σ² from [`IdentData::noise_sigma`], over the identification range's length.
    pub fn of(data: &IdentData) -> Self {
        let var = data.noise_sigma().powi(2);
        Self { var, uncertainty: 2.0 * 2.33 * var / (data.y.len().max(1) as f64).sqrt() }
    }
}

/// Share of the model error — the held-out mean squared error above the measurement noise's
/// variance — that a trial removes, as a share of RMS: 1 − √((with − σ²)/(without − σ²)). Zero when
/// the model error is within the noise reading's own uncertainty: the model is at the noise level
/// and nothing is left that a root could remove.
pub fn model_error_reduction(without_mse: f64, with_mse: f64, noise: Noise) -> f64 {
    let excess = without_mse - noise.var;
    if excess <= noise.uncertainty {
        return 0.0;
    }
    let left = (with_mse - noise.var).max(0.0);
    1.0 - (left / excess).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_trial_passes_only_when_it_removes_enough_error_above_noise_across_segments() {
        let noise = Noise { var: 1.0, uncertainty: 0.1 };
        let without = [5.0, 6.0, 5.5, 4.5];
        // Every segment's error above the noise shrinks to a third.
        let better: Vec<f64> = without.iter().map(|w| 1.0 + (w - 1.0) / 3.0).collect();
        let gain = Gain::of(&without, &better, noise);
        assert!(gain.passes() && gain.wins == 4 && gain.folds == 4 && gain.reduction > 0.4, "{gain:?}");
        // Two percent off every segment: consistent, but too little.
        let slight: Vec<f64> = without.iter().map(|w| 0.98 * w).collect();
        let gain = Gain::of(&without, &slight, noise);
        assert!(gain.standard_errors > MIN_STANDARD_ERRORS && gain.reduction < MIN_RELATIVE_REDUCTION);
        assert!(!gain.passes());
        // Enough on average, but from one segment while the others get worse: not beyond noise.
        let one = [1.0, 6.1, 5.6, 4.6];
        let gain = Gain::of(&without, &one, noise);
        assert!(gain.reduction >= MIN_RELATIVE_REDUCTION && gain.standard_errors < MIN_STANDARD_ERRORS);
        assert!(!gain.passes() && gain.wins == 1, "{gain:?}");
        // At the noise level nothing is left that a root could remove.
        assert!(model_error_reduction(1.05, 0.5, noise).abs() < 1e-15);
    }
}
