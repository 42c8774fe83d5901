//! The noise band and the split of the error by regime: steady / transient, accelerating /
//! decelerating, low / mid / high operating point.
//!
//! Rules (all on the *measured* output, so the split does not depend on the model):
//! - The slope is the least-squares slope over a centred window (`slope_window_secs`).
//! - A sample is **transient** when |slope| exceeds the larger of `transient_range_frac_per_s` × the
//!   run's output range per second and 4 × the slope's own noise (σ / (dt·√Σj²) for the window);
//!   otherwise it is **steady**. Transients with a positive slope are **accelerating**, with a negative
//!   slope **decelerating** (for thrust, "accelerating" means thrust rising).
//! - The operating point is **low / mid / high** by the bands of [`OperatingBands`]: by default the
//!   three equal thirds of the measured output's range on this run.
use serde::{Deserialize, Serialize};

use super::signal::{erfc, ls_slope_per_sec, slope_noise_per_sec};

/// How many slope-noise standard deviations a slope must exceed to count as transient.
const SLOPE_NOISE_FACTOR: f64 = 4.0;

/// Where the noise σ of the band came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum SigmaSource {
    /// Given by the caller (the noise fit of a steady run).
    Supplied,
    /// Estimated from the measured output itself: 1.4826·MAD(Δ²y)/√6.
    EstimatedFromSecondDifferences,
}

/// The measurement-noise band around zero residual.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NoiseBand {
    /// Measurement-noise standard deviation, in the output's unit.
    pub sigma: f64,
    /// Where `sigma` came from.
    pub sigma_source: SigmaSource,
    /// The band is ±`band_sigmas`·σ.
    pub band_sigmas: f64,
    /// `band_sigmas`·σ, in the output's unit.
    pub half_width: f64,
    /// Share of samples whose residual lies outside the band, 0–1.
    pub outside_fraction: f64,
    /// Share Gaussian white noise alone would leave outside, 0–1 (4.55 % for ±2σ).
    pub expected_outside_fraction: f64,
}

impl NoiseBand {
    pub(super) fn new(residual: &[f64], sigma: f64, sigma_source: SigmaSource, band_sigmas: f64) -> Self {
        let half_width = band_sigmas * sigma;
        let outside = residual.iter().filter(|r| r.abs() > half_width).count();
        Self {
            sigma,
            sigma_source,
            band_sigmas,
            half_width,
            outside_fraction: outside as f64 / residual.len().max(1) as f64,
            expected_outside_fraction: erfc(band_sigmas / std::f64::consts::SQRT_2),
        }
    }
}

/// The motion of the measured output at one sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Motion {
    /// |slope| at or below the transient threshold.
    Steady,
    /// Rising faster than the threshold.
    Accelerating,
    /// Falling faster than the threshold.
    Decelerating,
}

/// The operating-point band of one sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum OperatingBand {
    /// Below the lower limit.
    Low,
    /// Between the limits.
    Mid,
    /// At or above the upper limit.
    High,
}

/// How the low / mid / high operating-point bands are drawn.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum OperatingBands {
    /// Equal thirds of the measured output's range on this run.
    RunRangeThirds,
    /// Fixed limits in the output's unit (use the same on every run to combine runs):
    /// low below `low_below`, high at or above `high_from`.
    Fixed { low_below: f64, high_from: f64 },
}

/// A regime the error is split by.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Regime {
    /// Every sample of the run.
    Run,
    /// Samples whose measured output is steady.
    Steady,
    /// Samples whose measured output moves: accelerating or decelerating.
    Transient,
    /// Transient samples with a rising output.
    Accelerating,
    /// Transient samples with a falling output.
    Decelerating,
    /// The low operating point.
    Low,
    /// The mid operating point.
    Mid,
    /// The high operating point.
    High,
}

impl Regime {
    /// Every regime, in table order.
    pub const ALL: [Regime; 8] = [
        Self::Run,
        Self::Steady,
        Self::Transient,
        Self::Accelerating,
        Self::Decelerating,
        Self::Low,
        Self::Mid,
        Self::High,
    ];

    /// Lower-case words for tables and summaries.
    pub fn label(self) -> &'static str {
        match self {
            Self::Run => "whole run",
            Self::Steady => "steady",
            Self::Transient => "transient",
            Self::Accelerating => "accelerating",
            Self::Decelerating => "decelerating",
            Self::Low => "low operating point",
            Self::Mid => "mid operating point",
            Self::High => "high operating point",
        }
    }

    fn contains(self, motion: Motion, band: OperatingBand) -> bool {
        match self {
            Self::Run => true,
            Self::Steady => motion == Motion::Steady,
            Self::Transient => motion != Motion::Steady,
            Self::Accelerating => motion == Motion::Accelerating,
            Self::Decelerating => motion == Motion::Decelerating,
            Self::Low => band == OperatingBand::Low,
            Self::Mid => band == OperatingBand::Mid,
            Self::High => band == OperatingBand::High,
        }
    }
}

/// Error statistics of one regime; errors are `y − ŷ` in the output's unit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RegimeRow {
    /// The regime of this row.
    pub regime: Regime,
    /// Samples in the regime.
    pub samples: usize,
    /// Share of the run's samples in this regime, %.
    pub share_of_samples_pct: f64,
    /// Root mean square error; `None` when the regime is empty.
    pub rmse: Option<f64>,
    /// 100·sqrt(mean(((y − ŷ)/y)²)); `None` when empty or when y is zero at a sample.
    pub rmspe_pct: Option<f64>,
    /// Mean error (bias), positive when the model under-predicts; `None` when empty.
    pub mean_error: Option<f64>,
    /// Share of the run's sum of squared errors that falls in this regime, %.
    pub share_of_squared_error_pct: f64,
}

/// The error split by regime, one row per [`Regime`] in [`Regime::ALL`] order, with the rule used.
///
/// Rules (on the *measured* output, so the split does not depend on the model): a sample is
/// transient when the least-squares slope over `slope_window_secs` exceeds, in magnitude, the larger
/// of `transient_range_frac_per_s` × the run's output range per second and 4 × the slope's own noise;
/// accelerating / decelerating by the sign of that slope; low / mid / high by [`OperatingBands`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RegimeTable {
    /// One row per regime, in [`Regime::ALL`] order.
    pub rows: Vec<RegimeRow>,
    /// |slope| above which a sample is transient, output unit per second.
    pub transient_slope_per_s: f64,
    /// Operating-point limits actually used, output unit: low below the first, high from the second.
    pub band_limits: (f64, f64),
}

impl RegimeTable {
    /// The row of one regime.
    pub fn row(&self, regime: Regime) -> Option<&RegimeRow> {
        self.rows.iter().find(|r| r.regime == regime)
    }
}

/// Per-sample regime labels, for shading a trace.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SampleRegimes {
    /// Steady, accelerating or decelerating, per sample.
    pub motion: Vec<Motion>,
    /// Low, mid or high operating point, per sample.
    pub band: Vec<OperatingBand>,
}

/// Classify every sample and tabulate the error by regime.
pub(super) fn split_by_regime(
    y: &[f64],
    residual: &[f64],
    dt_secs: f64,
    slope_half: usize,
    range_frac_per_s: f64,
    sigma: f64,
    bands: OperatingBands,
) -> (RegimeTable, SampleRegimes) {
    let (lo, hi) = y.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
    let range = (hi - lo).max(0.0);
    let threshold =
        (range_frac_per_s * range).max(SLOPE_NOISE_FACTOR * sigma * slope_noise_per_sec(slope_half, dt_secs));
    let motion: Vec<Motion> = ls_slope_per_sec(y, slope_half, dt_secs)
        .into_iter()
        .map(|s| match s {
            s if s > threshold => Motion::Accelerating,
            s if s < -threshold => Motion::Decelerating,
            _ => Motion::Steady,
        })
        .collect();
    let band_limits = match bands {
        OperatingBands::RunRangeThirds => (lo + range / 3.0, lo + 2.0 * range / 3.0),
        OperatingBands::Fixed { low_below, high_from } => (low_below, high_from),
    };
    let band: Vec<OperatingBand> = y
        .iter()
        .map(|v| match *v {
            v if v < band_limits.0 => OperatingBand::Low,
            v if v >= band_limits.1 => OperatingBand::High,
            _ => OperatingBand::Mid,
        })
        .collect();
    let labels = SampleRegimes { motion, band };
    let total_sq: f64 = residual.iter().map(|r| r * r).sum();
    let rows = Regime::ALL.iter().map(|&regime| regime_row(regime, y, residual, &labels, total_sq)).collect();
    (RegimeTable { rows, transient_slope_per_s: threshold, band_limits }, labels)
}

fn regime_row(
    regime: Regime,
    y: &[f64],
    residual: &[f64],
    labels: &SampleRegimes,
    total_sq: f64,
) -> RegimeRow {
    let (mut n, mut sum, mut sum_sq, mut sum_pct_sq, mut pct_defined) = (0usize, 0.0, 0.0, 0.0, true);
    let samples = y.iter().zip(residual).zip(labels.motion.iter().zip(&labels.band));
    for ((yk, rk), (motion, band)) in samples {
        if !regime.contains(*motion, *band) {
            continue;
        }
        n += 1;
        sum += rk;
        sum_sq += rk * rk;
        if yk.abs() > f64::MIN_POSITIVE {
            sum_pct_sq += (rk / yk).powi(2);
        } else {
            pct_defined = false;
        }
    }
    let count = n as f64;
    let nonempty = n > 0;
    RegimeRow {
        regime,
        samples: n,
        share_of_samples_pct: 100.0 * count / y.len().max(1) as f64,
        rmse: nonempty.then(|| (sum_sq / count).sqrt()),
        rmspe_pct: (nonempty && pct_defined).then(|| 100.0 * (sum_pct_sq / count).sqrt()),
        mean_error: nonempty.then(|| sum / count),
        share_of_squared_error_pct: if total_sq > 0.0 { 100.0 * sum_sq / total_sq } else { 0.0 },
    }
}
