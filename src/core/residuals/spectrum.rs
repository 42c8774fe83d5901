//! The residual's power spectral density by Welch's method: Hann-windowed segments, half overlapping,
//! each with its mean removed, one-sided and scaled to the output's unit² per Hz.
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::signal::{fft_in_place, median};
use crate::core::numerics::stats::hann;

/// The residual spectrum and its largest peak.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ResidualSpectrum {
    /// Bin frequencies, Hz (0 to Nyquist).
    pub freq_hz: Vec<f64>,
    /// The same frequencies, rad/s.
    pub omega_rad_s: Vec<f64>,
    /// One-sided power spectral density, (output unit)²/Hz.
    pub psd_per_hz: Vec<f64>,
    /// Welch segment length, samples.
    pub segment_len: usize,
    /// Number of segments averaged.
    pub segments: usize,
    /// Frequency of the largest bin above 0 Hz.
    pub peak_freq_hz: f64,
    /// The peak frequency in rad/s.
    pub peak_omega_rad_s: f64,
    /// Peak PSD over the median PSD of the bins above 0 Hz (≈ 1–3 for white noise).
    pub peak_prominence: f64,
}

/// Welch PSD of `x` with segments of `segment_len` samples, shortened to the largest power of two
/// that fits in `x`.
pub(super) fn welch(x: &[f64], segment_len: usize, dt_secs: f64) -> ResidualSpectrum {
    let fits = segment_len.min(x.len()).max(2);
    let len = 1usize << (usize::BITS - 1 - fits.leading_zeros());
    let window = hann(len);
    let window_power: f64 = window.iter().map(|w| w * w).sum();
    let hop = (len / 2).max(1);
    let bins = len / 2 + 1;
    let mut acc = vec![0.0; bins];
    let mut segments = 0usize;
    let mut buffer: Vec<Complex64> = Vec::with_capacity(len);
    for start in (0..=x.len().saturating_sub(len)).step_by(hop) {
        let Some(seg) = x.get(start..start + len) else { continue };
        let seg_mean = seg.iter().sum::<f64>() / len as f64;
        buffer.clear();
        buffer.extend(seg.iter().zip(&window).map(|(v, w)| Complex64::new((v - seg_mean) * w, 0.0)));
        fft_in_place(&mut buffer, false);
        for (a, c) in acc.iter_mut().zip(&buffer) {
            *a += c.norm_sqr();
        }
        segments += 1;
    }
    let fs_hz = 1.0 / dt_secs;
    let scale = 1.0 / (fs_hz * window_power * segments.max(1) as f64);
    let psd_per_hz: Vec<f64> = acc
        .iter()
        .enumerate()
        .map(|(k, a)| if k == 0 || 2 * k == len { a * scale } else { 2.0 * a * scale })
        .collect();
    let freq_hz: Vec<f64> = (0..bins).map(|k| k as f64 * fs_hz / len as f64).collect();
    let omega_rad_s = freq_hz.iter().map(|f| 2.0 * std::f64::consts::PI * f).collect();
    let above_dc = psd_per_hz.get(1..).unwrap_or_default();
    let (peak_bin, peak_psd) =
        above_dc.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).map_or((0, 0.0), |(i, p)| (i + 1, *p));
    let level = median(above_dc);
    let peak_freq_hz = freq_hz.get(peak_bin).copied().unwrap_or(0.0);
    ResidualSpectrum {
        peak_freq_hz,
        peak_omega_rad_s: 2.0 * std::f64::consts::PI * peak_freq_hz,
        peak_prominence: if level > f64::MIN_POSITIVE { peak_psd / level } else { 0.0 },
        freq_hz,
        omega_rad_s,
        psd_per_hz,
        segment_len: len,
        segments,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Parseval: the PSD integrates to the variance of a stationary signal.
    #[test]
    fn psd_integrates_to_the_variance() {
        let dt = 0.1;
        let x: Vec<f64> =
            (0..4096).map(|k| 3.0 * (1.3 * k as f64 * dt).sin() + ((k * 7919) % 11) as f64 - 5.0).collect();
        let s = welch(&x, 256, dt);
        let df = 1.0 / (dt * 256.0);
        let power: f64 = s.psd_per_hz.iter().sum::<f64>() * df;
        let m = x.iter().sum::<f64>() / x.len() as f64;
        let var = x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / x.len() as f64;
        assert!((power / var - 1.0).abs() < 0.05, "power {power} var {var}");
    }
}
