//! Black-box baselines the gray-box model is compared with (the paper's section 5.3):
//! a Hammerstein–Wiener model fitted by output-error Levenberg–Marquardt
//! ([`hammerstein_wiener`]) and an NNARX network trained with Bayesian regularisation ([`nnarx`]).
//!
//! Both fitting functions are long-running, so they take a progress callback
//! `progress: &mut dyn FnMut(f64) -> bool`: the argument is the fraction done in `0..=1`, returning
//! `false` cancels the fit with [`BaselineError::Cancelled`]. Callers that do not care pass
//! `&mut |_| true`.
use serde::{Deserialize, Serialize};

use crate::core::numerics::lm::LmError;
use crate::core::numerics::lstsq::LstsqError;
use crate::core::numerics::poly::PolyError;
use crate::core::numerics::tf::TfError;

pub mod hammerstein_wiener;
mod mlp;
pub mod nnarx;
mod nnarx_train;
pub mod references;
mod spd;

pub use hammerstein_wiener::{
    AscendingPoly, HwDiagnostics, HwModel, HwOptions, HwOrders, fit_hammerstein_wiener,
};
pub use nnarx::{
    EQUILIBRIUM_CHECKS, Equilibrium, EquilibriumMethod, NnarxDiagnostics, NnarxModel, NnarxOptions,
    RestartSummary, fit_nnarx,
};

/// Everything that can go wrong while fitting a baseline.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BaselineError {
    #[error("input has {u} samples but output has {y}")]
    LengthMismatch { u: usize, y: usize },
    #[error("{samples} samples are too few for this model (need at least {needed})")]
    TooFewSamples { samples: usize, needed: usize },
    #[error("the {what} is not finite at sample {index}")]
    NonFinite { what: &'static str, index: usize },
    #[error("the {what} is constant, so nothing can be identified from it")]
    ConstantSignal { what: &'static str },
    #[error("option {option} = {value} is invalid: {requirement}")]
    InvalidOption { option: &'static str, value: usize, requirement: &'static str },
    #[error("the {stage} fit diverged: its simulation error RMS is {rms_normalised} (in normalised units)")]
    Diverged { stage: &'static str, rms_normalised: f64 },
    #[error("the {stage} starting model has an unstable pole at |z| = {modulus:.4}")]
    Unstable { stage: &'static str, modulus: f64 },
    #[error("the fit was cancelled")]
    Cancelled,
    #[error(transparent)]
    Lstsq(#[from] LstsqError),
    #[error(transparent)]
    Lm(LmError),
    #[error(transparent)]
    Tf(#[from] TfError),
    #[error(transparent)]
    Poly(#[from] PolyError),
    #[error("the {what} is not numerically positive definite")]
    Factorisation { what: &'static str },
}

impl From<LmError> for BaselineError {
    /// A least-squares failure inside Levenberg–Marquardt is the solver's error as the baselines
    /// report it everywhere else.
    fn from(e: LmError) -> Self {
        match e {
            LmError::Lstsq(e) => Self::Lstsq(e),
            other => Self::Lm(other),
        }
    }
}

/// An affine change of units: `normalised = (physical − offset) / scale`, with `scale > 0`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Scaling {
    pub offset: f64,
    pub scale: f64,
}

impl Scaling {
    /// Maps the range of `x` onto `[−1, 1]`. `None` when `x` is empty or constant.
    pub fn unit_range(x: &[f64]) -> Option<Self> {
        let lo = x.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = x.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let half = 0.5 * (hi - lo);
        (half.is_finite() && half > f64::EPSILON * lo.abs().max(hi.abs()))
            .then_some(Self { offset: 0.5 * (hi + lo), scale: half })
    }

    /// Zero mean, unit standard deviation. `None` when `x` has fewer than two samples or is constant.
    pub fn standardise(x: &[f64]) -> Option<Self> {
        if x.len() < 2 {
            return None;
        }
        let n = x.len() as f64;
        let mean = x.iter().sum::<f64>() / n;
        let std = (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        (std.is_finite() && std > f64::EPSILON * mean.abs()).then_some(Self { offset: mean, scale: std })
    }

    pub fn normalised_from_physical(&self, x: f64) -> f64 {
        (x - self.offset) / self.scale
    }

    pub fn physical_from_normalised(&self, x: f64) -> f64 {
        self.offset + self.scale * x
    }

    pub fn normalise_all(&self, x: &[f64]) -> Vec<f64> {
        x.iter().map(|v| self.normalised_from_physical(*v)).collect()
    }
}

/// The boundary checks shared by both baselines: equal lengths, enough samples, finite values and
/// a non-constant input and output.
fn check_signals(u: &[f64], y: &[f64], needed: usize) -> Result<(), BaselineError> {
    if u.len() != y.len() {
        return Err(BaselineError::LengthMismatch { u: u.len(), y: y.len() });
    }
    if u.len() < needed {
        return Err(BaselineError::TooFewSamples { samples: u.len(), needed });
    }
    for (what, x) in [("input", u), ("output", y)] {
        if let Some(index) = x.iter().position(|v| !v.is_finite()) {
            return Err(BaselineError::NonFinite { what, index });
        }
    }
    Ok(())
}

/// Forwards progress to the caller's callback, turning a `false` answer into `Cancelled`.
fn report(progress: &mut dyn FnMut(f64) -> bool, fraction: f64) -> Result<(), BaselineError> {
    if progress(fraction.clamp(0.0, 1.0)) { Ok(()) } else { Err(BaselineError::Cancelled) }
}

/// Root mean square of `a − b`.
fn rms_error(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len()).max(1) as f64;
    (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / n).sqrt()
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn scalings_round_trip_and_reject_constants() {
        let x = [2.0, 7.6, 3.0];
        let s = Scaling::unit_range(&x).unwrap();
        assert!((s.normalised_from_physical(2.0) + 1.0).abs() < 1e-12);
        assert!((s.normalised_from_physical(7.6) - 1.0).abs() < 1e-12);
        assert!((s.physical_from_normalised(s.normalised_from_physical(3.0)) - 3.0).abs() < 1e-12);
        let z = Scaling::standardise(&x).unwrap();
        let n = z.normalise_all(&x);
        assert!(n.iter().sum::<f64>().abs() < 1e-12);
        assert!(Scaling::unit_range(&[70_000.0; 4]).is_none());
        assert!(Scaling::standardise(&[5.0; 4]).is_none());
        assert!(Scaling::standardise(&[5.0]).is_none());
    }
}
