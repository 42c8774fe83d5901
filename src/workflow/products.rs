//! What the batch's figures and the app's views both show, computed one way: the frequency grid of
//! the Bode curves, the chirp's measured frequency response, and the scores of a model on the
//! scored runs.
use crate::core::compare::{chirp_grid, chirp_welch_options};
use crate::core::numerics::spectral::welch_response;
use crate::core::numerics::tf::log_space;
use crate::core::run::Run;

/// Lowest frequency of the Bode curves, rad/s: a decade below the slowest spool pole of a small
/// engine (time constants of a few seconds), so every curve shows its low-frequency gain.
pub const LOWEST_OMEGA_RAD_S: f64 = 0.05;
/// Points of the Bode curves, log-spaced to the Nyquist frequency: about 50 a decade over the
/// three decades below it, finer than any resonance of the reduced models needs.
pub const BODE_POINTS: usize = 256;

/// The frequencies of every Bode curve at sample time `dt_secs`, rad/s.
pub fn bode_grid(dt_secs: f64) -> Vec<f64> {
    log_space(LOWEST_OMEGA_RAD_S, std::f64::consts::PI / dt_secs, BODE_POINTS)
}

/// A point of a measured frequency response: ω [rad/s], |G| [dB], ∠G [deg], coherence in 0..=1.
pub type EmpiricalPoint = (f64, f64, f64, f64);

/// The chirp run's measured response of `output` to its input in the excited band, by the Welch
/// estimate the batch's comparison uses (empty when the run lacks the output or the estimate
/// fails).
pub fn chirp_points(chirp: &Run, output: &str) -> Vec<EmpiricalPoint> {
    let Some(y) = chirp.output(output) else { return Vec::new() };
    let omegas = chirp_grid(chirp.dt_secs);
    let Ok(response) =
        welch_response(&chirp.input.values, &y.values, chirp.dt_secs, &omegas, &chirp_welch_options())
    else {
        return Vec::new();
    };
    let points = response.omega_rad_s.iter().zip(&response.mag_db).zip(&response.phase_deg);
    points
        .zip(&response.coherence)
        .map(|(((omega, mag), phase), coherence)| (*omega, *mag, *phase, *coherence))
        .filter(|(omega, mag, phase, coherence)| {
            [*omega, *mag, *phase, *coherence].iter().all(|v| v.is_finite())
        })
        .collect()
}
