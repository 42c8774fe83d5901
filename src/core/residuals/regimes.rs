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

/// Share of the spectrum, by frequency up to Nyquist, whose level is compared with white noise of
/// the estimated σ (the top quarter).
const TOP_BAND_SHARE: f64 = 0.25;
/// How far, in dB, the residual's spectrum near Nyquist may lie above white noise of the estimated
/// σ before that σ is judged not to be the residual's noise.
const NOISE_EXCESS_LIMIT_DB: f64 = 10.0;
/// How many times the estimated σ the residual's RMS may be before the band is judged meaningless.
const RESIDUAL_OVER_SIGMA_LIMIT: f64 = 100.0;

/// Whether the band may be read as the measurement noise of this residual.
///
/// A σ measured on a steady run is the sensor's noise: its band applies. A σ estimated from the
/// run itself is a robust scale of the output's sample-to-sample jitter, 1.4826·MAD(Δ²y)/√6: the
/// measurement noise when that noise is white and Gaussian and the output is smooth at the sample
/// scale. Test-bench telemetry often is neither, and a band from a failed estimate leaves every
/// sample outside for any model, good or bad (the JetCat: 99 %). Two tests, either of which
/// rejects the estimate:
///
/// 1. **The spectrum near Nyquist.** White noise of σ has the flat one-sided PSD 2σ²·dt. In the
///    top quarter of the frequencies up to Nyquist, far above a spool's bandwidth of a few rad/s,
///    the residual of a model the band describes is that noise. If the residual's median PSD there
///    lies more than [`NOISE_EXCESS_LIMIT_DB`] above 2σ̂²·dt (10 dB: ten times the power), the
///    residual's fastest part is not the noise σ̂ describes. The JetCat's speed is logged in counts
///    of 10 rpm: half its second differences are 0 or ±10 rpm, so σ̂ = 6 rpm, while the largest 1 %
///    reach 700 rpm (the ECU's jumps and the engine's fastest transients at 9.4 Hz); its residuals
///    lie 16–17 dB above, those of the T07 test-cell runs 10–18 dB. The median over the top-quarter
///    bins of a Welch estimate of white noise lies within about 2 dB of 2σ²·dt, so 10 dB leaves
///    room for some model error there too; the simulated runs with white sensor noise sit within
///    a decibel.
/// 2. **The residual's own scale.** Samples interpolated between sparser logs (a resampled run)
///    or smoothed by the logger have second differences near zero and a spectrum near Nyquist near
///    zero too: test 1 passes while σ̂ is far below the sensor's noise. When the residual's RMS is
///    more than [`RESIDUAL_OVER_SIGMA_LIMIT`] times σ̂, the ±2σ̂ band is ±2 % of the residual's
///    scale: a line at zero on its plot that leaves nearly every sample outside whatever σ̂ is, so
///    the share says nothing the RMS does not, and an estimate that far below the error is more
///    likely to have failed than the sensor to be a hundred times better than the model (the
///    pressure ratio of two resampled T07 runs: 1 900 and 2 400 times). A model far off on a run
///    with white sensor noise stays well inside the limit: the hot-day speed model before its
///    effects is off by 24 σ and leaves 98 % outside, and there the band is right — the share
///    outside alone could not tell.
///
/// A σ̂ of zero (samples that mostly repeat) never applies.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum BandFit {
    /// σ was measured on a steady run: the band is the sensor's noise.
    Measured,
    /// σ was estimated from the run, and the residual's spectrum near Nyquist lies `excess_db`
    /// above white noise of that σ (at most [`NOISE_EXCESS_LIMIT_DB`]) and its RMS within
    /// [`RESIDUAL_OVER_SIGMA_LIMIT`] times σ: the band applies.
    Consistent { excess_db: f64 },
    /// σ was estimated from the run, but the residual's spectrum near Nyquist lies `excess_db`
    /// above white noise of that σ (`None`: σ̂ is zero): σ̂ is not the residual's noise.
    NotTheNoise { excess_db: Option<f64> },
    /// σ was estimated from the run, but the residual's RMS is `rms_over_sigma` times σ̂, more than
    /// [`RESIDUAL_OVER_SIGMA_LIMIT`]: a band that narrow says nothing.
    FarBelowTheResidual { rms_over_sigma: f64 },
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
    /// Whether the band is the residual's noise (see [`BandFit`]).
    #[serde(default = "measured")]
    pub fit: BandFit,
}

fn measured() -> BandFit {
    BandFit::Measured
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
            fit: BandFit::Measured,
        }
    }

    /// Judge an estimated σ against the `residual` and its spectrum `psd_per_hz` at `freq_hz`
    /// (one-sided, unit²/Hz) for a run sampled every `dt_secs` (see [`BandFit`]). A supplied σ stays
    /// measured; a spectrum without bins near Nyquist leaves that test passed.
    pub(super) fn judged(
        mut self,
        residual: &[f64],
        freq_hz: &[f64],
        psd_per_hz: &[f64],
        dt_secs: f64,
    ) -> Self {
        if self.sigma_source == SigmaSource::Supplied {
            return self;
        }
        let white = 2.0 * self.sigma * self.sigma * dt_secs;
        if !(white > 0.0 && white.is_finite()) {
            self.fit = BandFit::NotTheNoise { excess_db: None };
            return self;
        }
        let nyquist_hz = 0.5 / dt_secs;
        let top: Vec<f64> = freq_hz
            .iter()
            .zip(psd_per_hz)
            .filter(|(f, p)| **f >= (1.0 - TOP_BAND_SHARE) * nyquist_hz && p.is_finite())
            .map(|(_, p)| *p)
            .collect();
        let excess_db =
            if top.is_empty() { 0.0 } else { 10.0 * (super::signal::median(&top) / white).log10() };
        let finite: Vec<f64> = residual.iter().copied().filter(|r| r.is_finite()).collect();
        let rms = (finite.iter().map(|r| r * r).sum::<f64>() / finite.len().max(1) as f64).sqrt();
        let rms_over_sigma = rms / self.sigma;
        self.fit = if excess_db > NOISE_EXCESS_LIMIT_DB {
            BandFit::NotTheNoise { excess_db: Some(excess_db) }
        } else if rms_over_sigma > RESIDUAL_OVER_SIGMA_LIMIT {
            BandFit::FarBelowTheResidual { rms_over_sigma }
        } else {
            BandFit::Consistent { excess_db }
        };
        self
    }

    /// Whether the band may be read as this residual's noise.
    pub fn applies(&self) -> bool {
        matches!(self.fit, BandFit::Measured | BandFit::Consistent { .. })
    }

    /// Why the band does not apply, in words; `None` when it does.
    pub fn why_not(&self, unit: &str) -> Option<String> {
        let unit = if unit.is_empty() { String::new() } else { format!(" {unit}") };
        let sigma =
            format!("σ = {}{unit}, estimated from the run's second differences,", significant3(self.sigma));
        let why = match self.fit {
            BandFit::Measured | BandFit::Consistent { .. } => return None,
            BandFit::NotTheNoise { excess_db: Some(db) } => format!(
                "{sigma} is not this residual's noise (the residual's spectrum near Nyquist lies {db:.0} dB \
                 above white noise of that σ: quantised or non-Gaussian jitter, or motion faster than the \
                 sampling)"
            ),
            BandFit::NotTheNoise { excess_db: None } => {
                "the run's second differences give σ = 0 (samples that mostly repeat)".to_owned()
            }
            BandFit::FarBelowTheResidual { rms_over_sigma } => format!(
                "{sigma} is {rms_over_sigma:.0} times below the residual's RMS (samples interpolated or \
                 smoothed between sparser logs keep their second differences near zero)"
            ),
        };
        Some(format!(
            "the noise band does not apply: {why}, so the share of samples outside it says nothing about \
             the model"
        ))
    }
}

/// Three significant figures, no exponent for everyday magnitudes.
fn significant3(x: f64) -> String {
    match x.abs() {
        a if a >= 100.0 => format!("{x:.0}"),
        a if a >= 10.0 => format!("{x:.1}"),
        a if a >= 1.0 => format!("{x:.2}"),
        a if a >= 0.001 => format!("{x:.3}"),
        _ => format!("{x:.2e}"),
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
