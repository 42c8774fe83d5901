//! Residual autocorrelation, residual–input cross-correlation (after prewhitening the input), and the
//! residual against every recorded channel the model does not use.
use faer::Mat;
use serde::{Deserialize, Serialize};

use super::signal::{autocorrelation_pair, centred, moving_average, normal_two_sided_p};
use crate::core::numerics::lstsq::solve_lstsq;
use crate::core::numerics::stats::pearson;

/// Two-sided 99 % point of the standard normal distribution.
pub const Z_99: f64 = 2.576;
/// |r| between two channels above which they count as collinear.
const COLLINEAR_R: f64 = 0.9;

/// Correlation coefficients at a list of lags, with the 99 % bounds for white noise.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Correlogram {
    /// Lags in samples. For a cross-correlation a positive lag pairs the residual with the input
    /// that many samples *earlier* (the input leads).
    pub lags_samples: Vec<i64>,
    /// Correlation coefficient at each lag, −1..1.
    pub values: Vec<f64>,
    /// ±2.576/√N, the 99 % bounds when the residual is white (N: samples used).
    pub bound_99: f64,
    /// Lags whose |value| exceeds the bound (lag 0 of an autocorrelation, always 1, is left out).
    pub exceeding_lags_samples: Vec<i64>,
}

impl Correlogram {
    fn new(lags_samples: Vec<i64>, values: Vec<f64>, n_used: usize, skip_zero: bool) -> Self {
        let bound_99 = Z_99 / (n_used.max(1) as f64).sqrt();
        let exceeding_lags_samples = lags_samples
            .iter()
            .zip(&values)
            .filter(|(lag, v)| !(skip_zero && **lag == 0) && v.abs() > bound_99)
            .map(|(lag, _)| *lag)
            .collect();
        Self { lags_samples, values, bound_99, exceeding_lags_samples }
    }
}

/// The residual–input cross-correlation and its largest value.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InputCrossCorrelation {
    /// Name of the input channel.
    pub input: String,
    /// Lags −L..=L.
    pub correlogram: Correlogram,
    /// Order of the AR filter fitted to the input and applied to input and residual before
    /// correlating (0: not prewhitened). Prewhitening makes the white-noise bounds valid for a
    /// coloured input and sharpens the peak to where the residual responds to input changes.
    pub prewhitening_order: usize,
    /// Lag of the largest |value|, samples; positive when the input leads the residual. The
    /// prewhitened cross-correlation estimates the impulse response from the input to the residual,
    /// so a missing dead time `d` puts the peak at `d` plus the rise time of the engine's own impulse
    /// response (a few samples): an upper bound on the missing delay, not an estimate of it.
    pub peak_lag_samples: i64,
    /// The peak lag in seconds.
    pub peak_lag_secs: f64,
    /// The correlation at the peak lag (its sign is the sign of the residual's response).
    pub peak_value: f64,
    /// Whether the peak lies outside the 99 % bounds.
    pub peak_exceeds_bound: bool,
    /// Whether the peak lag is positive (the input leads).
    pub input_leads: bool,
}

/// Autocorrelation of the centred residual at lags 0..=max_lag.
pub(super) fn autocorrelation(residual: &[f64], max_lag: usize) -> Correlogram {
    let e = centred(residual);
    let c0: f64 = e.iter().map(|v| v * v).sum();
    let values = (0..=max_lag)
        .map(|lag| {
            let c: f64 = e.iter().zip(e.iter().skip(lag)).map(|(a, b)| a * b).sum();
            if c0 > f64::MIN_POSITIVE { c / c0 } else { 0.0 }
        })
        .collect();
    let lags = (0..=max_lag).map(|l| l as i64).collect();
    Correlogram::new(lags, values, residual.len(), true)
}

/// AR(order) coefficients `a` of `x(k) ≈ Σ a_i x(k−i)`, by least squares; `None` when the fit fails.
fn fit_ar(x: &[f64], order: usize) -> Option<Vec<f64>> {
    if order == 0 || x.len() <= 2 * order {
        return None;
    }
    let rows = x.len() - order;
    let a = Mat::from_fn(rows, order, |i, j| x.get(i + order - 1 - j).copied().unwrap_or(0.0));
    let b: Vec<f64> = x.iter().skip(order).copied().collect();
    solve_lstsq(&a, &b).ok().map(|s| s.x)
}

/// `x(k) − Σ a_i x(k−i)` for k ≥ order.
fn ar_filter(x: &[f64], a: &[f64]) -> Vec<f64> {
    let order = a.len();
    x.windows(order + 1)
        .map(|w| {
            let mut rev = w.iter().rev();
            let now = rev.next().copied().unwrap_or(0.0);
            now - rev.zip(a).map(|(xi, ai)| xi * ai).sum::<f64>()
        })
        .collect()
}

/// Normalised cross-correlation Σ e(k)·u(k−lag) / (N·σe·σu) of two centred, equally long series.
fn cross_correlation_at(e: &[f64], u: &[f64], lag: i64, norm: f64) -> f64 {
    let shift = lag.unsigned_abs() as usize;
    let sum: f64 = if lag >= 0 {
        e.iter().skip(shift).zip(u).map(|(a, b)| a * b).sum()
    } else {
        e.iter().zip(u.iter().skip(shift)).map(|(a, b)| a * b).sum()
    };
    sum / norm
}

/// Residual–input cross-correlation at lags −max_lag..=max_lag; `None` when the input is constant.
pub(super) fn input_cross_correlation(
    input_name: &str,
    u: &[f64],
    residual: &[f64],
    max_lag: usize,
    prewhiten_order: usize,
    dt_secs: f64,
) -> Option<InputCrossCorrelation> {
    let (uc, ec) = (centred(u), centred(residual));
    let (uw, ew, order) = match fit_ar(&uc, prewhiten_order) {
        Some(a) => (centred(&ar_filter(&uc, &a)), centred(&ar_filter(&ec, &a)), a.len()),
        None => (uc, ec, 0),
    };
    let norm = (uw.iter().map(|v| v * v).sum::<f64>() * ew.iter().map(|v| v * v).sum::<f64>()).sqrt();
    if norm <= f64::MIN_POSITIVE || !norm.is_finite() {
        return None;
    }
    let l = max_lag as i64;
    let lags: Vec<i64> = (-l..=l).collect();
    let values: Vec<f64> = lags.iter().map(|&lag| cross_correlation_at(&ew, &uw, lag, norm)).collect();
    let correlogram = Correlogram::new(lags, values, uw.len(), false);
    let (peak_lag_samples, peak_value) = correlogram
        .lags_samples
        .iter()
        .zip(&correlogram.values)
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        .map_or((0, 0.0), |(lag, v)| (*lag, *v));
    Some(InputCrossCorrelation {
        input: input_name.to_owned(),
        peak_exceeds_bound: peak_value.abs() > correlogram.bound_99,
        correlogram,
        prewhitening_order: order,
        peak_lag_samples,
        peak_lag_secs: peak_lag_samples as f64 * dt_secs,
        peak_value,
        input_leads: peak_lag_samples > 0,
    })
}

/// The residual against one recorded channel the model does not use.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ChannelCorrelation {
    /// Channel name.
    pub channel: String,
    /// Channel unit.
    pub unit: String,
    /// Pearson r of residual and channel, sample by sample.
    pub r: f64,
    /// Effective sample size of `r` (Bartlett: N / (1 + 2 Σ (1 − k/N) ρ_e(k) ρ_x(k)), k ≤ N/4).
    pub n_eff: f64,
    /// Two-sided p-value of `r` (Fisher z with `n_eff`).
    pub p_value: f64,
    /// Pearson r after both are smoothed by the centred moving average (reveals slow dependence).
    pub r_slow: f64,
    /// Effective sample size of `r_slow`.
    pub n_eff_slow: f64,
    /// Two-sided p-value of `r_slow`.
    pub p_value_slow: f64,
    /// Whether either p-value is below the scan's per-test level.
    pub significant: bool,
    /// Other scanned channels that move with this one (|r| ≥ 0.9 between them, e.g. inlet
    /// temperature and humidity on a warming day): the residual cannot tell them apart.
    pub collinear_with: Vec<String>,
}

impl ChannelCorrelation {
    /// The stronger of `r` and `r_slow`, and whether it is the slow one.
    pub fn strongest(&self) -> (f64, bool) {
        if self.r_slow.abs() > self.r.abs() { (self.r_slow, true) } else { (self.r, false) }
    }
}

/// Why a recorded channel was left out of the scan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ExclusionReason {
    /// The model reads it (the input, the output itself, or a named model channel).
    UsedByModel,
    /// It does not vary on this run.
    Constant,
    /// It holds a NaN or infinity (first at `index`).
    NonFinite { index: usize },
    /// It is not as long as the run.
    LengthMismatch { found: usize, expected: usize },
}

/// A channel left out of the scan, and why.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ExcludedChannel {
    /// Channel name.
    pub channel: String,
    /// Why it was left out.
    pub reason: ExclusionReason,
}

/// The residual against every recorded channel the model does not use, strongest first.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ChannelScan {
    /// Sorted by the larger of |r| and |r_slow|, descending.
    pub channels: Vec<ChannelCorrelation>,
    /// Recorded channels left out, with the reason.
    pub excluded: Vec<ExcludedChannel>,
    /// Moving-average window of the slow versions, s.
    pub slow_window_secs: f64,
    /// Per-test significance level: the scan's level over the number of tests (Bonferroni).
    pub alpha_per_test: f64,
}

/// A channel that passed the checks, borrowed for the scan.
pub(super) struct Candidate<'a> {
    pub name: &'a str,
    pub unit: &'a str,
    pub values: &'a [f64],
}

/// Bartlett's effective sample size of a correlation between two series with these
/// autocorrelations (lags 0..), clamped to 2..=n.
fn effective_samples(n: usize, rho_a: &[f64], rho_b: &[f64]) -> f64 {
    let nf = n as f64;
    let sum: f64 =
        rho_a.iter().zip(rho_b).enumerate().skip(1).map(|(k, (a, b))| (1.0 - k as f64 / nf) * a * b).sum();
    (nf / (1.0 + 2.0 * sum).max(f64::MIN_POSITIVE)).clamp(2.0, nf)
}

/// Fisher-z two-sided p-value of a correlation `r` from `n_eff` effective samples.
fn p_value(r: f64, n_eff: f64) -> f64 {
    if n_eff <= 3.0 {
        return 1.0;
    }
    let z = r.clamp(-0.999_999, 0.999_999).atanh() * (n_eff - 3.0).sqrt();
    normal_two_sided_p(z)
}

/// The other candidates whose values correlate with `c` at |r| ≥ [`COLLINEAR_R`].
fn collinear_with(c: &Candidate<'_>, candidates: &[Candidate<'_>]) -> Vec<String> {
    candidates
        .iter()
        .filter(|o| o.name != c.name && pearson(c.values, o.values).is_some_and(|r| r.abs() >= COLLINEAR_R))
        .map(|o| o.name.to_owned())
        .collect()
}

/// Correlate the residual with each candidate, raw and slow.
pub(super) fn scan_channels(
    residual: &[f64],
    candidates: &[Candidate<'_>],
    slow_window: usize,
    slow_window_secs: f64,
    alpha: f64,
    excluded: Vec<ExcludedChannel>,
) -> ChannelScan {
    let n = residual.len();
    let max_lag = n / 4;
    let residual_slow = moving_average(residual, slow_window);
    let (rho_e, rho_e_slow) = autocorrelation_pair(residual, &residual_slow, max_lag);
    let alpha_per_test = alpha / (2 * candidates.len()).max(1) as f64;
    let mut channels: Vec<ChannelCorrelation> = candidates
        .iter()
        .map(|c| {
            let slow = moving_average(c.values, slow_window);
            let (rho_x, rho_x_slow) = autocorrelation_pair(c.values, &slow, max_lag);
            // A residual without spread (a perfect model) correlates with nothing.
            let r = pearson(residual, c.values).unwrap_or(0.0);
            let r_slow = pearson(&residual_slow, &slow).unwrap_or(0.0);
            let n_eff = effective_samples(n, &rho_e, &rho_x);
            let n_eff_slow = effective_samples(n, &rho_e_slow, &rho_x_slow);
            let (p, p_slow) = (p_value(r, n_eff), p_value(r_slow, n_eff_slow));
            ChannelCorrelation {
                channel: c.name.to_owned(),
                unit: c.unit.to_owned(),
                r,
                n_eff,
                p_value: p,
                r_slow,
                n_eff_slow,
                p_value_slow: p_slow,
                significant: p.min(p_slow) < alpha_per_test,
                collinear_with: collinear_with(c, candidates),
            }
        })
        .collect();
    channels.sort_by(|a, b| b.strongest().0.abs().total_cmp(&a.strongest().0.abs()));
    ChannelScan { channels, excluded, slow_window_secs, alpha_per_test }
}
