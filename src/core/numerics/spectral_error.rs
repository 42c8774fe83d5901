//! Why a record, grid, option or curve cannot be used by the spectral estimates (`spectral`) or
//! their cut-offs (`cutoff`), and the frequency-grid check both make.

/// The shortest segment Welch's method will use.
pub const MIN_SEGMENT_LEN: usize = 16;

/// Why a record, grid, option or curve cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SpectralError {
    #[error("the input has {u} samples but the output has {y}")]
    LengthMismatch { u: usize, y: usize },
    #[error("the record has {found} samples; Welch's method needs at least {needed}")]
    TooFewSamples { found: usize, needed: usize },
    #[error("the {signal} is not finite at sample {index}")]
    NonFinite { signal: &'static str, index: usize },
    #[error("sample time must be positive and finite, got {dt_secs}")]
    BadSampleTime { dt_secs: f64 },
    #[error("the frequency grid is empty")]
    EmptyGrid,
    #[error("grid frequency {index} ({omega_rad_s} rad/s) is not in (0, Nyquist = {nyquist_rad_s}]")]
    FrequencyOutOfRange { index: usize, omega_rad_s: f64, nyquist_rad_s: f64 },
    #[error("the frequency grid must increase; it does not at index {index}")]
    GridNotIncreasing { index: usize },
    #[error("segment length {segment_len} must be between {MIN_SEGMENT_LEN} and the record length {samples}")]
    BadSegmentLength { segment_len: usize, samples: usize },
    #[error("overlap fraction must be in [0, 1), got {overlap_fraction}")]
    BadOverlap { overlap_fraction: f64 },
    #[error("the minimum number of periods must be positive and finite, got {min_periods}")]
    BadMinPeriods { min_periods: f64 },
    #[error("the excited-band threshold must be in [0, 1], got {threshold}")]
    BadThreshold { threshold: f64 },
    #[error("the input has no power at {omega_rad_s} rad/s (is it constant?)")]
    NoInputPower { omega_rad_s: f64 },
    #[error("the magnitude has {mag} values for {omega} frequencies")]
    CurveLengthMismatch { omega: usize, mag: usize },
    #[error("the low-frequency level needs at least one point, got {count}")]
    BadLevelCount { count: usize },
}

/// The grid is non-empty, increasing and within (0, `nyquist_rad_s`].
pub fn check_grid(omegas_rad_s: &[f64], nyquist_rad_s: f64) -> Result<(), SpectralError> {
    if omegas_rad_s.is_empty() {
        return Err(SpectralError::EmptyGrid);
    }
    for (index, &omega_rad_s) in omegas_rad_s.iter().enumerate() {
        if !(omega_rad_s.is_finite() && omega_rad_s > 0.0 && omega_rad_s <= nyquist_rad_s) {
            return Err(SpectralError::FrequencyOutOfRange { index, omega_rad_s, nyquist_rad_s });
        }
    }
    match omegas_rad_s.windows(2).position(|p| p[1] <= p[0]) {
        Some(index) => Err(SpectralError::GridNotIncreasing { index: index + 1 }),
        None => Ok(()),
    }
}
