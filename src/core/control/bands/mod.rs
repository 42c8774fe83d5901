//! A model's parameter covariance carried to what people read off it: 95 % intervals of each
//! operating point's figures, and a 95 % band of the noiseless output on a run.
//!
//! **Operating points: Monte Carlo over the covariance.** Rise and settling times jump where a
//! step response's overshoot crosses the 2 % band, and the bandwidth where a resonance crosses
//! −3 dB, so a first-order (delta-method) propagation can be arbitrarily wrong for them. The
//! intervals are the 2.5 and 97.5 percentiles of each figure over [`DRAWS`] models drawn from the
//! covariance (as MATLAB's `simsd` does for outputs).
//!
//! **The output band: delta method.** The simulated output is a smooth function of the parameters
//! at every sample, and the first-order propagation needs two simulations per parameter where
//! percentiles would need hundreds: `var ŷₖ = gₖᵀ Σ gₖ`, `gₖ` the output's gradient at sample k.
//!
//! The parts:
//! - `points`: the operating points' intervals and the local step responses' bands;
//! - `output`: the band of the noiseless output;
//! - `shape`: the Bode band of the linear block and the roots' regions in z;
//! - `parameters`: the model's numbers (map, effects, continuous-time block) with intervals.
mod output;
mod parameters;
mod points;
mod shape;

pub use output::output_half_widths;
pub use parameters::{ParameterInterval, parameter_intervals};
pub use points::{step_band, with_intervals};
pub use shape::{BodeBand, RootRegion, bode_band, root_regions};

/// Models drawn for the operating points' intervals. Each 2.5 % tail then holds 5 draws; the
/// binomial spread of the share of a distribution below the 2.5 % percentile of 200 draws is
/// √(0.025·0.975/200) ≈ 1.1 points, so a calibrated interval covers 95 ± 1.6 % of the time, well
/// inside the 85–99 % a user can rely on; 1,000 draws would cost five times the time for half that.
pub const DRAWS: usize = 200;
/// A figure gets an interval only when at least this share of the draws have it (a bandwidth
/// that some draws lose above Nyquist has no honest percentile).
pub(super) const MIN_SHARE: f64 = 0.9;
/// The two-sided 95 % quantile of the normal distribution.
pub(super) const Z95: f64 = 1.959_963_985;

/// The 2.5 and 97.5 percentiles of `values` when they hold at least [`MIN_SHARE`] of `draws`.
pub(super) fn percentile_interval(mut values: Vec<f64>, draws: usize) -> Option<[f64; 2]> {
    values.retain(|v| v.is_finite());
    if values.is_empty() || (values.len() as f64) < MIN_SHARE * draws as f64 {
        return None;
    }
    values.sort_by(f64::total_cmp);
    let at = |q: f64| {
        let pos = q * (values.len() - 1) as f64;
        let (i, f) = (pos.floor() as usize, pos - pos.floor());
        values[i] + f * (values[(i + 1).min(values.len() - 1)] - values[i])
    };
    Some([at(0.025), at(0.975)])
}

#[cfg(test)]
mod tests;
