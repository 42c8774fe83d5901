//! Empirical frequency response of an input/output record by Welch's method, and −3 dB cut-offs.
//!
//! The chirp run is cut into Hann-windowed segments overlapping by half; each segment's discrete-time
//! Fourier transform is evaluated directly at the requested frequencies (no FFT grid), and the averaged
//! spectra give `H(ω) = S_uy / S_uu` and the magnitude-squared coherence `γ² = |S_uy|² / (S_uu·S_yy)`.
use std::f64::consts::PI;

use num_complex::Complex64;
use serde::{Deserialize, Serialize};

pub use crate::core::numerics::cutoff::{LowFrequencyLevel, bode_cutoff_rad_s, cutoff_rad_s};
use crate::core::numerics::spectral_error::check_grid;
pub use crate::core::numerics::spectral_error::{MIN_SEGMENT_LEN, SpectralError};
use crate::core::numerics::stats::{hann, mean};

/// What is subtracted from `u` and `y` before the spectra are taken.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Offset {
    /// Each segment's own mean (scipy's `detrend='constant'`); keeps a slow drift from leaking.
    SegmentMean,
    /// The whole record's mean.
    RecordMean,
    /// The first sample: deviations from the steady state the run starts in.
    FirstSample,
}

/// How long each Welch segment is.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum SegmentLength {
    /// Long enough for `min_periods` periods of the lowest grid frequency, but short enough that the
    /// record still gives `min_segments` segments (the record length wins when they conflict).
    Auto { min_periods: f64, min_segments: usize },
    /// A fixed number of samples.
    Samples(usize),
}

/// How the segments meet the ends of the record.
///
/// Without help, excitation near an end is seen only through the rising or falling edge of a single
/// window, which biases the phase there (several degrees at the lowest frequency of a chirp that starts
/// 10 s into the run). Holding the ends extends the record by its resting level so that every recorded
/// sample is covered like one in the middle. That is exact for a run that starts and ends at rest (the
/// chirp test's holds) and wrong for one that does not (it invents a step).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Ends {
    /// Segments lie inside the record.
    Cut,
    /// Extend both ends by the mean of their first (last) [`rest_len`] samples, held.
    Hold,
    /// Hold an end only where the input rests there: its first (last) [`rest_len`] samples have a
    /// standard deviation below a tenth of the whole input's.
    HoldIfAtRest,
}

/// The samples at each end that are checked for rest and averaged into the held level: 2 % of the
/// record, at least 8.
pub fn rest_len(n_samples: usize) -> usize {
    (n_samples / 50).max(8).min(n_samples)
}

/// Settings of [`welch_response`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct WelchOptions {
    pub segment: SegmentLength,
    /// Fraction of a segment shared with the next one, in [0, 1).
    ///
    /// On a swept sine the estimate's bias follows the slope of Σ w², the summed squared windows, at
    /// the time the sweep passes each frequency. For Hann windows that sum is flat at 2/3 or 3/4
    /// overlap but ripples at 1/2, which shows as a periodic phase error of a few degrees along the
    /// band; hence the default of 3/4. Half overlap is the classic choice for stationary noise.
    pub overlap_fraction: f64,
    pub offset: Offset,
    pub ends: Ends,
    /// Keep only the grid points whose input auto-spectrum reaches this fraction of the largest one
    /// on the grid (the excited band); `None` keeps every point.
    pub excited_only: Option<f64>,
}

impl Default for WelchOptions {
    /// Six periods of the lowest grid frequency per segment, at least four segments, 3/4 overlap,
    /// each segment's mean removed, ends held where the input rests.
    fn default() -> Self {
        Self {
            segment: SegmentLength::Auto { min_periods: 6.0, min_segments: 4 },
            overlap_fraction: 0.75,
            offset: Offset::SegmentMean,
            ends: Ends::HoldIfAtRest,
            excited_only: None,
        }
    }
}

/// The empirical frequency response, one value per kept grid frequency.
///
/// The first four fields match the figures' `EmpiricalBode` one for one.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EmpiricalResponse {
    pub omega_rad_s: Vec<f64>,
    pub mag_db: Vec<f64>,
    /// Unwrapped along the grid.
    pub phase_deg: Vec<f64>,
    /// Magnitude-squared coherence in [0, 1].
    pub coherence: Vec<f64>,
    /// Random error (one standard deviation) of `mag_db` and `phase_deg` implied by the coherence and
    /// the number of independent averages (Bendat & Piersol: ε = √(1 − γ²) / (|γ| √(2 n))). Leakage and
    /// windowing bias are not included.
    pub mag_std_db: Vec<f64>,
    pub phase_std_deg: Vec<f64>,
    /// Input auto-spectrum `S_uu` (averaged |windowed DTFT|², arbitrary but common scale).
    pub input_power: Vec<f64>,
    pub segment_len: usize,
    pub n_segments: usize,
    /// The number of independent averages the overlapping segments are worth (Welch 1967).
    pub effective_segments: f64,
    /// Frequency spacing of one segment's DFT, 2π/(L·T): points closer than ~2 of these to zero are
    /// smeared by the window.
    pub resolution_rad_s: f64,
}

/// Welch estimate of the frequency response from `u` to `y` at the increasing grid `omegas_rad_s`.
pub fn welch_response(
    u: &[f64],
    y: &[f64],
    dt_secs: f64,
    omegas_rad_s: &[f64],
    opts: &WelchOptions,
) -> Result<EmpiricalResponse, SpectralError> {
    check_record(u, y, dt_secs)?;
    check_grid(omegas_rad_s, PI / dt_secs)?;
    if !(0.0..1.0).contains(&opts.overlap_fraction) {
        return Err(SpectralError::BadOverlap { overlap_fraction: opts.overlap_fraction });
    }
    if let Some(threshold) = opts.excited_only.filter(|t| !(0.0..=1.0).contains(t)) {
        return Err(SpectralError::BadThreshold { threshold });
    }
    let omega_lo = omegas_rad_s.first().copied().ok_or(SpectralError::EmptyGrid)?;
    let segment_len = match opts.segment {
        SegmentLength::Samples(len) => len,
        SegmentLength::Auto { min_periods, min_segments } => {
            auto_segment_len(u.len(), dt_secs, omega_lo, min_periods, min_segments, opts.overlap_fraction)?
        }
    };
    if !(MIN_SEGMENT_LEN..=u.len()).contains(&segment_len) {
        return Err(SpectralError::BadSegmentLength { segment_len, samples: u.len() });
    }
    let (u, y) = remove_record_offset(u, y, opts.offset);
    let step = segment_step(segment_len, opts.overlap_fraction);
    let (hold_front, hold_back) = match opts.ends {
        Ends::Cut => (false, false),
        Ends::Hold => (true, true),
        Ends::HoldIfAtRest => rests_at_ends(&u),
    };
    let u = hold_ends(&u, segment_len, step, hold_front, hold_back);
    let y = hold_ends(&y, segment_len, step, hold_front, hold_back);
    let spectra = averaged_spectra(&u, &y, dt_secs, omegas_rad_s, segment_len, opts)?;
    let effective_segments = effective_averages(&hann(segment_len), step, spectra.n_segments);
    let mut response = response_from_spectra(omegas_rad_s, &spectra, effective_segments);
    response.segment_len = segment_len;
    response.n_segments = spectra.n_segments;
    response.effective_segments = effective_segments;
    response.resolution_rad_s = 2.0 * PI / (segment_len as f64 * dt_secs);
    if let Some(threshold) = opts.excited_only {
        let max_power = response.input_power.iter().fold(0.0f64, |m, p| m.max(*p));
        let keep: Vec<bool> = response.input_power.iter().map(|p| *p >= threshold * max_power).collect();
        response = response.retain(&keep);
    }
    Ok(response)
}

/// Segment length for [`SegmentLength::Auto`]: `min_periods` periods of `omega_lo_rad_s`, capped so
/// that a record of `n_samples` still holds `min_segments` segments at the given overlap.
pub fn auto_segment_len(
    n_samples: usize,
    dt_secs: f64,
    omega_lo_rad_s: f64,
    min_periods: f64,
    min_segments: usize,
    overlap_fraction: f64,
) -> Result<usize, SpectralError> {
    if !(min_periods.is_finite() && min_periods > 0.0) {
        return Err(SpectralError::BadMinPeriods { min_periods });
    }
    let wanted = (min_periods * 2.0 * PI / (omega_lo_rad_s * dt_secs)).ceil();
    let span = 1.0 + min_segments.saturating_sub(1) as f64 * (1.0 - overlap_fraction);
    let cap = (n_samples as f64 / span).floor();
    if cap < MIN_SEGMENT_LEN as f64 {
        let needed = (MIN_SEGMENT_LEN as f64 * span).ceil() as usize;
        return Err(SpectralError::TooFewSamples { found: n_samples, needed });
    }
    Ok(wanted.clamp(MIN_SEGMENT_LEN as f64, cap) as usize)
}

impl EmpiricalResponse {
    /// The points with `lo_rad_s ≤ ω ≤ hi_rad_s`.
    pub fn within_band(&self, lo_rad_s: f64, hi_rad_s: f64) -> Self {
        let keep: Vec<bool> = self.omega_rad_s.iter().map(|w| (lo_rad_s..=hi_rad_s).contains(w)).collect();
        self.clone().retain(&keep)
    }

    /// The −3 dB cut-off of the empirical magnitude; see [`cutoff_rad_s`].
    pub fn cutoff_rad_s(&self, level: LowFrequencyLevel) -> Result<Option<f64>, SpectralError> {
        cutoff_rad_s(&self.omega_rad_s, &self.mag_db, level)
    }

    fn retain(self, keep: &[bool]) -> Self {
        let pick = |v: Vec<f64>| -> Vec<f64> {
            v.into_iter().zip(keep).filter(|(_, k)| **k).map(|(x, _)| x).collect()
        };
        Self {
            omega_rad_s: pick(self.omega_rad_s),
            mag_db: pick(self.mag_db),
            phase_deg: pick(self.phase_deg),
            coherence: pick(self.coherence),
            mag_std_db: pick(self.mag_std_db),
            phase_std_deg: pick(self.phase_std_deg),
            input_power: pick(self.input_power),
            ..self
        }
    }
}

fn check_record(u: &[f64], y: &[f64], dt_secs: f64) -> Result<(), SpectralError> {
    if u.len() != y.len() {
        return Err(SpectralError::LengthMismatch { u: u.len(), y: y.len() });
    }
    if u.len() < MIN_SEGMENT_LEN {
        return Err(SpectralError::TooFewSamples { found: u.len(), needed: MIN_SEGMENT_LEN });
    }
    if !(dt_secs.is_finite() && dt_secs > 0.0) {
        return Err(SpectralError::BadSampleTime { dt_secs });
    }
    for (signal, x) in [("input", u), ("output", y)] {
        if let Some(index) = x.iter().position(|v| !v.is_finite()) {
            return Err(SpectralError::NonFinite { signal, index });
        }
    }
    Ok(())
}

fn remove_record_offset(u: &[f64], y: &[f64], offset: Offset) -> (Vec<f64>, Vec<f64>) {
    let (u0, y0) = match offset {
        Offset::SegmentMean => (0.0, 0.0),
        Offset::RecordMean => (mean(u), mean(y)),
        Offset::FirstSample => (u.first().copied().unwrap_or(0.0), y.first().copied().unwrap_or(0.0)),
    };
    (u.iter().map(|v| v - u0).collect(), y.iter().map(|v| v - y0).collect())
}

struct Spectra {
    s_uu: Vec<f64>,
    s_yy: Vec<f64>,
    s_uy: Vec<Complex64>,
    n_segments: usize,
}

fn segment_step(segment_len: usize, overlap_fraction: f64) -> usize {
    ((segment_len as f64 * (1.0 - overlap_fraction)).round() as usize).clamp(1, segment_len)
}

/// Whether the input rests at its start and at its end (see [`Ends::HoldIfAtRest`]).
fn rests_at_ends(u: &[f64]) -> (bool, bool) {
    let m = rest_len(u.len());
    let std = |x: &[f64]| {
        let mu = mean(x);
        (x.iter().map(|v| (v - mu).powi(2)).sum::<f64>() / x.len().max(1) as f64).sqrt()
    };
    let whole = std(u);
    (std(&u[..m]) < 0.1 * whole, std(&u[u.len() - m..]) < 0.1 * whole)
}

/// `x` extended, where asked, by the mean of its first (last) [`rest_len`] samples: `segment_len − step`
/// samples in front, and at the back enough for the last segment to end exactly at the end.
fn hold_ends(x: &[f64], segment_len: usize, step: usize, front: bool, back: bool) -> Vec<f64> {
    let m = rest_len(x.len());
    let pad = segment_len - step;
    let front_len = if front { pad } else { 0 };
    let back_len = if back {
        let unaligned = (front_len + x.len() + pad - segment_len) % step;
        pad + (step - unaligned) % step
    } else {
        0
    };
    let mut out = vec![mean(&x[..m]); front_len];
    out.extend_from_slice(x);
    out.extend(std::iter::repeat_n(mean(&x[x.len() - m..]), back_len));
    out
}

/// The windowed segments' DTFTs at each grid frequency, averaged into auto- and cross-spectra.
fn averaged_spectra(
    u: &[f64],
    y: &[f64],
    dt_secs: f64,
    omegas_rad_s: &[f64],
    segment_len: usize,
    opts: &WelchOptions,
) -> Result<Spectra, SpectralError> {
    let window = hann(segment_len);
    let step = segment_step(segment_len, opts.overlap_fraction);
    let starts: Vec<usize> = (0..=u.len() - segment_len).step_by(step).collect();
    let segments: Vec<(Vec<f64>, Vec<f64>)> = starts
        .iter()
        .map(|&s| {
            let (us, ys) = (&u[s..s + segment_len], &y[s..s + segment_len]);
            let (mu, my) = match opts.offset {
                Offset::SegmentMean => (mean(us), mean(ys)),
                Offset::RecordMean | Offset::FirstSample => (0.0, 0.0),
            };
            let taper = |x: &[f64], m: f64| x.iter().zip(&window).map(|(v, w)| (v - m) * w).collect();
            (taper(us, mu), taper(ys, my))
        })
        .collect();
    let energy: f64 = segments.iter().map(|(us, _)| us.iter().map(|v| v * v).sum::<f64>()).sum();
    let mut out = Spectra { s_uu: vec![], s_yy: vec![], s_uy: vec![], n_segments: starts.len() };
    for &omega in omegas_rad_s {
        let kernel: Vec<Complex64> =
            (0..segment_len).map(|k| Complex64::from_polar(1.0, -omega * dt_secs * k as f64)).collect();
        let dtft = |x: &[f64]| x.iter().zip(&kernel).map(|(v, e)| e * v).sum::<Complex64>();
        let (mut s_uu, mut s_yy, mut s_uy) = (0.0, 0.0, Complex64::new(0.0, 0.0));
        for (us, ys) in &segments {
            let (cu, cy) = (dtft(us), dtft(ys));
            s_uu += cu.norm_sqr();
            s_yy += cy.norm_sqr();
            s_uy += cu.conj() * cy;
        }
        // Parseval: the mean of |U(ω)|² over frequency is the segment energy, so this is "none at all".
        if !(s_uu > 1e-20 * energy && s_uu > 0.0) {
            return Err(SpectralError::NoInputPower { omega_rad_s: omega });
        }
        let k = starts.len() as f64;
        out.s_uu.push(s_uu / k);
        out.s_yy.push(s_yy / k);
        out.s_uy.push(s_uy / k);
    }
    Ok(out)
}

/// Independent averages worth `n_segments` windows `step` apart: n / (1 + 2 Σⱼ (1 − j/n) c(j)) with
/// c(j) the squared normalised overlap of two windows j steps apart.
fn effective_averages(window: &[f64], step: usize, n_segments: usize) -> f64 {
    let energy: f64 = window.iter().map(|w| w * w).sum();
    let n = n_segments as f64;
    let correlated: f64 = (1..n_segments)
        .map(|j| {
            let shifted = window.iter().skip(j * step);
            let overlap: f64 = window.iter().zip(shifted).map(|(a, b)| a * b).sum();
            (1.0 - j as f64 / n) * (overlap / energy).powi(2)
        })
        .sum();
    n / (1.0 + 2.0 * correlated)
}

fn response_from_spectra(
    omegas_rad_s: &[f64],
    spectra: &Spectra,
    effective_segments: f64,
) -> EmpiricalResponse {
    let mut response = EmpiricalResponse {
        omega_rad_s: omegas_rad_s.to_vec(),
        mag_db: vec![],
        phase_deg: vec![],
        coherence: vec![],
        mag_std_db: vec![],
        phase_std_deg: vec![],
        input_power: spectra.s_uu.clone(),
        segment_len: 0,
        n_segments: 0,
        effective_segments: f64::NAN,
        resolution_rad_s: f64::NAN,
    };
    let mut prev_phase: Option<f64> = None;
    for ((s_uu, s_yy), s_uy) in spectra.s_uu.iter().zip(&spectra.s_yy).zip(&spectra.s_uy) {
        let h = s_uy / s_uu;
        let coherence = if *s_yy > 0.0 { (s_uy.norm_sqr() / (s_uu * s_yy)).clamp(0.0, 1.0) } else { 0.0 };
        let phase = unwrap_deg(h.arg().to_degrees(), prev_phase);
        prev_phase = Some(phase);
        response.mag_db.push(20.0 * h.norm().max(1e-300).log10());
        response.phase_deg.push(phase);
        response.coherence.push(coherence);
        let relative = ((1.0 - coherence) / (coherence * 2.0 * effective_segments)).sqrt();
        response.mag_std_db.push(20.0 * std::f64::consts::LOG10_E * relative);
        response.phase_std_deg.push(relative.to_degrees());
    }
    response
}

/// `phase_deg` shifted by whole turns to lie within 180° of `prev`.
fn unwrap_deg(phase_deg: f64, prev: Option<f64>) -> f64 {
    let Some(prev) = prev else { return phase_deg };
    phase_deg - 360.0 * ((phase_deg - prev) / 360.0).round()
}
