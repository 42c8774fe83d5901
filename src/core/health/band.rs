//! An engine's normal band for a health delta: a robust centre and spread across that engine's
//! runs, and whether a run lies outside it.
//!
//! **Centre and spread.** The median and the median absolute deviation scaled to a normal σ
//! (×1.4826): a fault in a few runs moves neither (both break down only when half the runs are
//! off), where the mean and standard deviation would be dragged towards the faults they are meant
//! to expose.
//!
//! **Floor of the spread.** With a handful of runs the MAD can come out near zero by chance (three
//! of six runs agreeing to the last digit), and every run's own estimation noise would then be a
//! "deviation". A healthy engine's runs scatter at least as much as each run's own standard error,
//! so the spread is never taken below the median of the runs' standard errors.
//!
//! **Multiplier.** A run is outside when it is more than [`BAND_SIGMAS`] = 3.5 σ from the centre: a
//! normal population exceeds 3.5 σ with probability 4.7·10⁻⁴, so ≤ 0.05 % of healthy runs are
//! flagged per delta (about one false alarm in 500 runs with four deltas), while a fault that moves a
//! delta by several times its normal scatter is not missed. Beyond the band a deviation must also
//! exceed its own uncertainty: the run's 95 % interval must exclude the centre, so a short or
//! poorly excited run whose delta is merely unknown is not called faulty.
/// The band's half width in robust standard deviations (see the module documentation).
pub const BAND_SIGMAS: f64 = 3.5;
/// The MAD of a normal sample over its standard deviation is 1/1.4826.
pub const MAD_TO_SIGMA: f64 = 1.4826;

/// An engine's normal band for one delta.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Band {
    pub centre: f64,
    /// The robust standard deviation (with its floor).
    pub sigma: f64,
}

impl Band {
    /// The band of `values` (one per run; non-finite ones are left out), its spread not below the
    /// median of `std_errors` (the runs' own standard errors, where known). `None` without a value.
    pub fn of(values: &[f64], std_errors: &[f64]) -> Option<Band> {
        let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
        let centre = median(&finite)?;
        let deviations: Vec<f64> = finite.iter().map(|v| (v - centre).abs()).collect();
        let mad = median(&deviations).unwrap_or(0.0) * MAD_TO_SIGMA;
        let errors: Vec<f64> = std_errors.iter().copied().filter(|v| v.is_finite() && *v > 0.0).collect();
        let floor = median(&errors).unwrap_or(0.0);
        Some(Band { centre, sigma: mad.max(floor) })
    }

    pub fn low(&self) -> f64 {
        self.centre - BAND_SIGMAS * self.sigma
    }

    pub fn high(&self) -> f64 {
        self.centre + BAND_SIGMAS * self.sigma
    }

    /// Whether `value`, with its 95 % interval `ci95`, lies outside the band: beyond 3.5 σ of the
    /// centre and its interval excluding the centre (a delta without an interval counts as unknown,
    /// never outside).
    pub fn outside(&self, value: f64, ci95: Option<[f64; 2]>) -> bool {
        let Some([lo, hi]) = ci95 else { return false };
        let beyond = value < self.low() || value > self.high();
        beyond && !(lo..=hi).contains(&self.centre)
    }
}

/// The median of `values` (`None` when empty); the mean of the middle two for an even count.
pub fn median(values: &[f64]) -> Option<f64> {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(sorted[n / 2]),
        _ => Some(0.5 * (sorted[n / 2 - 1] + sorted[n / 2])),
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn a_fault_moves_neither_centre_nor_spread() {
        let healthy = [1.00, 1.01, 0.99, 1.005, 0.995, 1.0];
        let mut with_fault = healthy.to_vec();
        with_fault.push(1.3);
        let (a, b) = (Band::of(&healthy, &[]).unwrap(), Band::of(&with_fault, &[]).unwrap());
        assert!((a.centre - b.centre).abs() < 0.01 && b.sigma < 0.02, "{a:?} {b:?}");
        assert!(b.outside(1.3, Some([1.25, 1.35])));
        assert!(!b.outside(1.3, Some([0.9, 1.7])), "its own interval holds the centre");
        assert!(!b.outside(1.3, None));
        assert!(!b.outside(1.004, Some([1.003, 1.005])));
    }

    #[test]
    fn spread_is_never_below_the_runs_own_errors() {
        let band = Band::of(&[1.0, 1.0, 1.0, 1.0], &[0.02, 0.03, 0.02]).unwrap();
        assert!((band.sigma - 0.02).abs() < 1e-12);
        assert!(Band::of(&[f64::NAN], &[]).is_none());
    }
}
