//! Where the model fails: the residual `r = y − ŷ` of one output on one run, taken apart.
//!
//! [`analyse_residuals`] gives, in the output's unit unless a name says otherwise:
//! 1. the residual trace and the measurement-noise band (±`band_sigmas`·σ, default ±2σ) with the share
//!    of samples outside it;
//! 2. the error split by regime — steady / transient, accelerating / decelerating, low / mid / high
//!    operating point, and the whole run (callers combine runs) — rules in [`RegimeTable`];
//! 3. the residual autocorrelation (lags 0..L) and the residual–input cross-correlation (lags −L..L,
//!    input prewhitened) with the 99 % white-noise bounds ±2.576/√N;
//! 4. the residual spectrum (Welch, Hann window) with its largest peak;
//! 5. the residual against every recorded channel the model does not use, raw and smoothed, with
//!    significance from an effective sample size that accounts for autocorrelation;
//! 6. the worst stretches of the run, for jumping to them;
//! 7. short dips of the input the output does not follow (a sensor's dropouts, not fuel).
//!
//! [`summary()`] turns the numbers into a few plain sentences.
#![deny(clippy::indexing_slicing)]

use serde::{Deserialize, Serialize};

use crate::core::numerics::noise_fit::{Distribution, Family, fit};
use crate::core::run::{Channel, Run};

mod correlation;
mod dropouts;
mod regimes;
mod signal;
mod spectrum;
mod stretches;
mod summary;

pub use correlation::{
    ChannelCorrelation, ChannelScan, Correlogram, ExcludedChannel, ExclusionReason, InputCrossCorrelation,
    Z_99,
};
pub use dropouts::InputDropouts;
pub use regimes::{
    BandFit, Motion, NoiseBand, OperatingBand, OperatingBands, Regime, RegimeRow, RegimeTable, SampleRegimes,
    SigmaSource,
};
pub use spectrum::ResidualSpectrum;
pub use stretches::Stretch;
pub use summary::{summary, summary_sentences};

/// Fewest samples any analysis is run on.
const MIN_SAMPLES: usize = 64;

/// Settings of the residual analysis; check them with [`ResidualSettings::check`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ResidualSettings {
    /// Half-width of the noise band in noise standard deviations (2: ±2σ).
    pub band_sigmas: f64,
    /// Largest lag of the auto- and cross-correlations, s.
    pub max_lag_secs: f64,
    /// Order of the AR filter that prewhitens the input before the cross-correlation (0: none).
    pub prewhiten_order: usize,
    /// Window of the least-squares slope that tells steady from transient, s.
    pub slope_window_secs: f64,
    /// A sample is transient when |slope| exceeds this share of the run's output range per second
    /// (or 4 slope-noise σ, whichever is larger).
    pub transient_range_frac_per_s: f64,
    /// How the low / mid / high operating-point bands are drawn.
    pub operating_bands: OperatingBands,
    /// Welch segment length, samples (a power of two; shortened to the run).
    pub welch_segment_len: usize,
    /// Moving-average window of the slow channel correlations, s.
    pub slow_window_secs: f64,
    /// Family-wise significance level of the channel scan (split over its tests).
    pub channel_alpha: f64,
    /// Length of a worst stretch, s.
    pub stretch_secs: f64,
    /// How many worst stretches to return.
    pub stretch_count: usize,
    /// Recorded channels the model reads besides the input (left out of the channel scan).
    pub model_channels: Vec<String>,
}

impl Default for ResidualSettings {
    fn default() -> Self {
        Self {
            band_sigmas: 2.0,
            max_lag_secs: 3.0,
            prewhiten_order: 10,
            slope_window_secs: 1.5,
            transient_range_frac_per_s: 0.02,
            operating_bands: OperatingBands::RunRangeThirds,
            welch_segment_len: 256,
            slow_window_secs: 10.0,
            channel_alpha: 0.01,
            stretch_secs: 5.0,
            stretch_count: 5,
            model_channels: Vec::new(),
        }
    }
}

/// Settings converted to samples for one sample time.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckedSettings {
    /// The settings as given.
    pub settings: ResidualSettings,
    /// Largest correlation lag, samples.
    pub max_lag: usize,
    /// Half-width of the slope window, samples (the window is `2·slope_half + 1`).
    pub slope_half: usize,
    /// Moving-average window of the slow channel correlations, samples.
    pub slow_window: usize,
    /// Length of a worst stretch, samples.
    pub stretch_len: usize,
}

impl CheckedSettings {
    /// Fewest samples these settings can analyse.
    pub fn min_samples(&self) -> usize {
        MIN_SAMPLES.max(4 * self.max_lag).max(4 * self.settings.prewhiten_order)
    }
}

fn bad(name: &'static str, value: f64, reason: &'static str) -> ResidualError {
    ResidualError::BadSetting { name, value, reason }
}

fn positive_secs(name: &'static str, secs: f64, dt_secs: f64) -> Result<usize, ResidualError> {
    if !(secs.is_finite() && secs > 0.0) {
        return Err(bad(name, secs, "must be positive and finite"));
    }
    Ok(((secs / dt_secs).round() as usize).max(1))
}

impl ResidualSettings {
    /// Check every setting and convert durations to samples at `dt_secs`.
    pub fn check(&self, dt_secs: f64) -> Result<CheckedSettings, ResidualError> {
        if !(dt_secs.is_finite() && dt_secs > 0.0) {
            return Err(ResidualError::BadSampleTime { dt_secs });
        }
        if !(self.band_sigmas.is_finite() && self.band_sigmas > 0.0 && self.band_sigmas <= 10.0) {
            return Err(bad("band_sigmas", self.band_sigmas, "must lie in (0, 10]"));
        }
        if self.prewhiten_order > 50 {
            return Err(bad("prewhiten_order", self.prewhiten_order as f64, "must be at most 50"));
        }
        if !(self.transient_range_frac_per_s.is_finite() && self.transient_range_frac_per_s > 0.0) {
            return Err(bad(
                "transient_range_frac_per_s",
                self.transient_range_frac_per_s,
                "must be positive",
            ));
        }
        if let OperatingBands::Fixed { low_below, high_from } = self.operating_bands
            && !(low_below.is_finite() && high_from.is_finite() && low_below <= high_from)
        {
            return Err(bad("operating_bands.low_below", low_below, "must be finite and ≤ high_from"));
        }
        if !self.welch_segment_len.is_power_of_two() || self.welch_segment_len < 16 {
            return Err(bad(
                "welch_segment_len",
                self.welch_segment_len as f64,
                "must be a power of two ≥ 16",
            ));
        }
        if !(self.channel_alpha > 0.0 && self.channel_alpha < 1.0) {
            return Err(bad("channel_alpha", self.channel_alpha, "must lie in (0, 1)"));
        }
        if self.stretch_count == 0 {
            return Err(bad("stretch_count", 0.0, "must be at least 1"));
        }
        Ok(CheckedSettings {
            max_lag: positive_secs("max_lag_secs", self.max_lag_secs, dt_secs)?,
            slope_half: positive_secs("slope_window_secs", 0.5 * self.slope_window_secs, dt_secs)?,
            slow_window: positive_secs("slow_window_secs", self.slow_window_secs, dt_secs)?,
            stretch_len: positive_secs("stretch_secs", self.stretch_secs, dt_secs)?,
            settings: self.clone(),
        })
    }
}

/// What can stop the residual analysis.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ResidualError {
    /// The run has no output of that name.
    #[error("run '{run}' has no output '{output}' (outputs: {available})")]
    UnknownOutput { run: String, output: String, available: String },
    /// The model's simulation is not as long as the run.
    #[error("the model gave {found} samples but the run has {expected}")]
    LengthMismatch { expected: usize, found: usize },
    /// The input or the analysed output is not as long as the run's time axis.
    #[error("channel '{channel}' has {found} samples but the run has {expected}")]
    ChannelLength { channel: String, expected: usize, found: usize },
    /// The run is shorter than the correlations and spectrum need.
    #[error("{samples} samples are too few for the residual analysis (need at least {needed})")]
    TooFewSamples { samples: usize, needed: usize },
    /// The input, the measured output or the model output (`signal`) holds a NaN or infinity.
    #[error("{signal} is not finite at sample {index}")]
    NonFinite { signal: String, index: usize },
    /// The supplied noise σ is zero, negative or not finite.
    #[error("the noise standard deviation {sigma} must be positive and finite")]
    BadNoiseSigma { sigma: f64 },
    /// The run's sample time is zero, negative or not finite.
    #[error("the sample time {dt_secs} s must be positive and finite")]
    BadSampleTime { dt_secs: f64 },
    /// A setting is out of its range.
    #[error("setting {name} = {value} is invalid: it {reason}")]
    BadSetting { name: &'static str, value: f64, reason: &'static str },
}

/// Everything [`analyse_residuals`] finds for one output on one run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ResidualAnalysis {
    /// Name of the run analysed.
    pub run: String,
    /// Name of the output analysed.
    pub output: String,
    /// Unit of the output, the residual and every error figure not named otherwise.
    pub unit: String,
    /// Sample time of the run, s.
    pub dt_secs: f64,
    /// The residual y − ŷ, one value per sample (positive: the model under-predicts).
    pub residual: Vec<f64>,
    /// The measurement-noise band and the share of samples outside it.
    pub band: NoiseBand,
    /// The error split by regime.
    pub regimes: RegimeTable,
    /// The regime of every sample, for shading the trace.
    pub sample_regimes: SampleRegimes,
    /// Autocorrelation of the residual, lags 0..=L.
    pub autocorrelation: Correlogram,
    /// `None` when the input does not vary on this run.
    pub input_xcorr: Option<InputCrossCorrelation>,
    /// Welch spectrum of the residual.
    pub spectrum: ResidualSpectrum,
    /// The residual against every recorded channel the model does not use.
    pub channels: ChannelScan,
    /// Non-overlapping windows with the largest residual RMS, worst first.
    pub worst_stretches: Vec<Stretch>,
    /// Short dips of the input and whether the output follows them; `None` without dips the model
    /// would answer visibly.
    #[serde(default)]
    pub input_dropouts: Option<InputDropouts>,
}

fn check_length(channel: &Channel, expected: usize) -> Result<(), ResidualError> {
    if channel.values.len() == expected {
        return Ok(());
    }
    Err(ResidualError::ChannelLength { channel: channel.name.clone(), expected, found: channel.values.len() })
}

fn check_finite(signal: &str, values: &[f64]) -> Result<(), ResidualError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(ResidualError::NonFinite { signal: signal.to_owned(), index }),
        None => Ok(()),
    }
}

/// The measured output after every input check.
fn checked_output<'a>(
    run: &'a Run,
    output: &str,
    y_hat: &[f64],
    checked: &CheckedSettings,
) -> Result<&'a Channel, ResidualError> {
    let Some(channel) = run.output(output) else {
        return Err(ResidualError::UnknownOutput {
            run: run.name.clone(),
            output: output.to_owned(),
            available: run.outputs.iter().map(|c| c.name.as_str()).collect::<Vec<_>>().join(", "),
        });
    };
    let n = run.len();
    check_length(&run.input, n)?;
    check_length(channel, n)?;
    if y_hat.len() != n {
        return Err(ResidualError::LengthMismatch { expected: n, found: y_hat.len() });
    }
    let needed = checked.min_samples();
    if n < needed {
        return Err(ResidualError::TooFewSamples { samples: n, needed });
    }
    check_finite(&channel.name, &channel.values)?;
    check_finite("model output", y_hat)?;
    check_finite(&run.input.name, &run.input.values)?;
    Ok(channel)
}

/// Split the recorded channels into scan candidates and exclusions.
fn scan_candidates<'a>(
    run: &'a Run,
    output: &str,
    settings: &ResidualSettings,
) -> (Vec<correlation::Candidate<'a>>, Vec<ExcludedChannel>) {
    let n = run.len();
    let mut candidates = Vec::new();
    let mut excluded = Vec::new();
    for c in run.outputs.iter().filter(|c| c.name != output).chain(&run.aux) {
        let reason = if settings.model_channels.contains(&c.name) {
            Some(ExclusionReason::UsedByModel)
        } else if c.values.len() != n {
            Some(ExclusionReason::LengthMismatch { found: c.values.len(), expected: n })
        } else if let Some(index) = c.values.iter().position(|v| !v.is_finite()) {
            Some(ExclusionReason::NonFinite { index })
        } else {
            let (lo, hi) =
                c.values.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
            (hi - lo <= 1e-12 * lo.abs().max(hi.abs())).then_some(ExclusionReason::Constant)
        };
        match reason {
            Some(reason) => excluded.push(ExcludedChannel { channel: c.name.clone(), reason }),
            None => {
                candidates.push(correlation::Candidate { name: &c.name, unit: &c.unit, values: &c.values })
            }
        }
    }
    (candidates, excluded)
}

/// Fewest samples of a steady run that give a noise σ: the relative standard error of σ̂ is about
/// 1/√(2n), so below 10 samples it exceeds 22 % and the band would say more than the data does.
const MIN_STEADY_SAMPLES: usize = 10;

/// The measurement-noise σ of `output` from a steady run: the maximum-likelihood normal fit of the
/// recorded output (its standard deviation about the mean), `None` when the run lacks the output,
/// is shorter than [`MIN_STEADY_SAMPLES`] or does not vary. The batch and the app both use it.
pub fn steady_noise_sigma(steady: &Run, output: &str) -> Option<f64> {
    let values = &steady.output(output)?.values;
    if values.len() < MIN_STEADY_SAMPLES {
        return None;
    }
    match fit(Family::Normal, values).ok()? {
        Distribution::Normal { std, .. } if std.is_finite() && std > 0.0 => Some(std),
        _ => None,
    }
}

impl ResidualSettings {
    /// The default settings for a model that reads `model_channels` besides the input (they are
    /// left out of the channel scan).
    pub fn for_model_channels(model_channels: &[&str]) -> Self {
        Self { model_channels: model_channels.iter().map(|c| (*c).to_owned()).collect(), ..Self::default() }
    }
}

/// Analyse the residual of `output` on `run` given the model's simulation `y_hat`.
///
/// `noise_sigma` is the output's measurement-noise σ (from the noise fit of a steady run); when
/// `None` it is estimated from the measured output's second differences, and the band says so.
pub fn analyse_residuals(
    run: &Run,
    output: &str,
    y_hat: &[f64],
    noise_sigma: Option<f64>,
    settings: &ResidualSettings,
) -> Result<ResidualAnalysis, ResidualError> {
    let checked = settings.check(run.dt_secs)?;
    let channel = checked_output(run, output, y_hat, &checked)?;
    let y = &channel.values;
    let (sigma, sigma_source) = match noise_sigma {
        Some(sigma) if sigma.is_finite() && sigma > 0.0 => (sigma, SigmaSource::Supplied),
        Some(sigma) => return Err(ResidualError::BadNoiseSigma { sigma }),
        None => (signal::sigma_from_second_differences(y), SigmaSource::EstimatedFromSecondDifferences),
    };
    let dt_secs = run.dt_secs;
    let residual: Vec<f64> = y.iter().zip(y_hat).map(|(a, b)| a - b).collect();
    let band = NoiseBand::new(&residual, sigma, sigma_source, settings.band_sigmas);
    let (regimes, sample_regimes) = regimes::split_by_regime(
        y,
        &residual,
        dt_secs,
        checked.slope_half,
        settings.transient_range_frac_per_s,
        sigma,
        settings.operating_bands,
    );
    let autocorrelation = correlation::autocorrelation(&residual, checked.max_lag);
    let input_xcorr = correlation::input_cross_correlation(
        &run.input.name,
        &run.input.values,
        &residual,
        checked.max_lag,
        settings.prewhiten_order,
        dt_secs,
    );
    let spectrum = spectrum::welch(&residual, settings.welch_segment_len, dt_secs);
    let band = band.judged(&residual, &spectrum.freq_hz, &spectrum.psd_per_hz, dt_secs);
    let (candidates, excluded) = scan_candidates(run, output, settings);
    let channels = correlation::scan_channels(
        &residual,
        &candidates,
        checked.slow_window,
        checked.slow_window as f64 * dt_secs,
        settings.channel_alpha,
        excluded,
    );
    let worst_stretches = stretches::worst_stretches(
        &residual,
        &run.t_secs,
        &sample_regimes.motion,
        checked.stretch_len,
        settings.stretch_count,
    );
    let input_dropouts =
        dropouts::input_dropouts(&run.input.name, &run.input.values, y, y_hat, &residual, dt_secs, sigma);
    Ok(ResidualAnalysis {
        run: run.name.clone(),
        output: output.to_owned(),
        unit: channel.unit.clone(),
        dt_secs,
        residual,
        band,
        regimes,
        sample_regimes,
        autocorrelation,
        input_xcorr,
        spectrum,
        channels,
        worst_stretches,
        input_dropouts,
    })
}
