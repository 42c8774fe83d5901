//! The chirp run's measured frequency response, drawn on the Bode view: a Welch estimate at a few
//! dozen log-spaced frequencies of the excited band. Recomputed only when the chirp run (or the
//! identification run it is checked against) changes, never while clusters are dragged.
use std::sync::Arc;

use crate::core::numerics::spectral::{WelchOptions, welch_response};
use crate::core::numerics::tf::log_space;
use crate::core::run::Run;
use crate::ui::derived::model_cache::{DT_TOLERANCE, EmpiricalPoint, OutputCache};
use crate::ui::state::session::{Role, Session};

/// Grid points from the lowest frequency to 0.9 × Nyquist; those the chirp does not excite are dropped.
const GRID_POINTS: usize = 64;
const LOWEST_OMEGA_RAD_S: f64 = 0.3;
/// A grid point is in the chirp's band when its input power reaches this fraction of the largest.
const EXCITED_FRACTION: f64 = 0.01;

/// The runs the points were computed from (compared by pointer).
pub struct EmpiricalSource {
    chirp: Arc<Run>,
    ident: Arc<Run>,
}

/// Bring `cache.empirical_bode` up to date with the session's first chirp run that has the output
/// and the identification run's sampling; empty when there is none or the estimate fails.
pub fn refresh_empirical_bode(cache: &mut OutputCache, session: &Session, ident: &Arc<Run>) {
    let chirp = session.runs.iter().filter(|r| r.role == Role::Chirp).map(|r| &r.run).find(|run| {
        run.output(&cache.name).is_some() && (run.dt_secs / ident.dt_secs - 1.0).abs() <= DT_TOLERANCE
    });
    let Some(chirp) = chirp else {
        cache.empirical_bode.clear();
        cache.empirical_source = None;
        return;
    };
    let unchanged = cache
        .empirical_source
        .as_ref()
        .is_some_and(|s| Arc::ptr_eq(&s.chirp, chirp) && Arc::ptr_eq(&s.ident, ident));
    if unchanged {
        return;
    }
    cache.empirical_bode = chirp_points(chirp, &cache.name);
    cache.empirical_source = Some(EmpiricalSource { chirp: Arc::clone(chirp), ident: Arc::clone(ident) });
}

/// Welch estimate of `output` over the input of `chirp` in the excited band (empty on failure).
pub fn chirp_points(chirp: &Run, output: &str) -> Vec<EmpiricalPoint> {
    let Some(y) = chirp.output(output) else { return Vec::new() };
    let nyquist = std::f64::consts::PI / chirp.dt_secs;
    let omegas = log_space(LOWEST_OMEGA_RAD_S, 0.9 * nyquist, GRID_POINTS);
    let options = WelchOptions { excited_only: Some(EXCITED_FRACTION), ..WelchOptions::default() };
    let Ok(response) = welch_response(&chirp.input.values, &y.values, chirp.dt_secs, &omegas, &options)
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
