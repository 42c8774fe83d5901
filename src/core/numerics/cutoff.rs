//! The −3 dB cut-off of a magnitude curve: measured or model, from its low-frequency level.
use serde::{Deserialize, Serialize};

use crate::core::numerics::spectral_error::{SpectralError, check_grid};
use crate::core::numerics::tf::BodePoint;

/// The level a cut-off is measured from.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum LowFrequencyLevel {
    /// The magnitude at the lowest grid frequency.
    FirstPoint,
    /// The mean magnitude (dB) of the lowest `n` grid points (steadier on noisy estimates).
    MeanOfFirst(usize),
    /// A given level, e.g. a model's DC gain in dB.
    Db(f64),
}

/// The lowest ω where `mag_db` falls 3 dB below the low-frequency level, interpolated linearly in
/// log ω between the grid points around the crossing.
///
/// `Ok(None)` when the magnitude does not cross that level inside the grid (never falls that far, or,
/// with [`LowFrequencyLevel::Db`], is already below it at the first point).
pub fn cutoff_rad_s(
    omega_rad_s: &[f64],
    mag_db: &[f64],
    level: LowFrequencyLevel,
) -> Result<Option<f64>, SpectralError> {
    if omega_rad_s.len() != mag_db.len() {
        return Err(SpectralError::CurveLengthMismatch { omega: omega_rad_s.len(), mag: mag_db.len() });
    }
    check_grid(omega_rad_s, f64::INFINITY)?;
    if let Some(index) = mag_db.iter().position(|m| m.is_nan()) {
        return Err(SpectralError::NonFinite { signal: "magnitude", index });
    }
    let reference_db = match level {
        LowFrequencyLevel::FirstPoint => mag_db.first().copied().unwrap_or(0.0),
        LowFrequencyLevel::MeanOfFirst(count) => {
            if count == 0 {
                return Err(SpectralError::BadLevelCount { count });
            }
            let head = &mag_db[..count.min(mag_db.len())];
            head.iter().sum::<f64>() / head.len() as f64
        }
        LowFrequencyLevel::Db(db) => db,
    };
    let target = reference_db - 3.0;
    if mag_db.first().is_some_and(|m| *m <= target) {
        return Ok(None);
    }
    let points: Vec<(f64, f64)> = omega_rad_s.iter().copied().zip(mag_db.iter().copied()).collect();
    Ok(points.windows(2).find_map(|pair| {
        let [(w0, m0), (w1, m1)] = pair else { return None };
        if *m1 > target {
            return None;
        }
        let frac = if m0 - m1 > 0.0 { (m0 - target) / (m0 - m1) } else { 1.0 };
        Some((w0.ln() + frac * (w1.ln() - w0.ln())).exp())
    }))
}

/// [`cutoff_rad_s`] of a model's Bode points.
pub fn bode_cutoff_rad_s(
    points: &[BodePoint],
    level: LowFrequencyLevel,
) -> Result<Option<f64>, SpectralError> {
    let omega: Vec<f64> = points.iter().map(|p| p.omega_rad_s).collect();
    let mag: Vec<f64> = points.iter().map(|p| p.mag_db).collect();
    cutoff_rad_s(&omega, &mag, level)
}
