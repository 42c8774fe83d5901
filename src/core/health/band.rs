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
//! **A band that follows slow change.** A fuel meter's calibration drifts and an engine wears from
//! run to run: the engine's normal value moves slowly, and a run that merely sits at the end of such a
//! drift is not faulty. So the centre is the engine's robust linear trend over its runs in date order
//! ([`local_bands`]): Theil–Sen, the median of the slopes between every pair of runs, through the
//! median of the runs' offsets from it, and the spread is the scaled MAD of the runs' deviations from
//! that line. Its breakdown point is 29 %: up to two faulty runs in eight (adjacent or not) move
//! neither the line nor the spread, so a step in one run stands out while a drift the runs share does
//! not. (A median of each run's neighbours would follow a curved drift more closely, but two faults
//! among four neighbours break it.)
//!
//! **Multiplier.** A run is outside when it is more than [`BAND_SIGMAS`] = 3.5 σ from the centre: a
//! normal population exceeds 3.5 σ with probability 4.7·10⁻⁴, so ≤ 0.05 % of healthy runs are
//! flagged per delta (about one false alarm in 500 runs with four deltas), while a fault that moves a
//! delta by several times its normal scatter is not missed. Beyond the band a deviation must also
//! exceed its own uncertainty: the run's 95 % interval must exclude the centre, so a short or
//! poorly excited run whose delta is merely unknown is not called faulty.
//!
//! **A run noisier than the engine's usual.** The spread holds the scatter of typical runs, their
//! estimation noise included (its floor is their median standard error). A run whose own standard
//! error σᵣ is larger than that typical σₜ scatters more for that reason alone, so its distance from
//! the centre is measured against `√(σ² + max(0, σᵣ² − σₜ²))`: the band's spread with the run's
//! extra estimation noise added in quadrature, as for the difference of two independent errors.
//! Without it, one poorly fitted run on the reference day was flagged or not according to the last
//! digits of its neighbours' fits: the T07's 2023-02-10 run 02, speed-map shift +3.11 krpm with a
//! standard error of 1.45, 4.06 from a centre whose band has σ = 1.12 and whose typical run a
//! standard error of 0.65 (3.6 σ, against 2.4 with its own extra noise counted).
use super::deltas::Z95;

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
    /// A typical run's own standard error (the median of the runs'; 0 where none is known).
    pub typical_error: f64,
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
        Some(Band { centre, sigma: mad.max(floor), typical_error: floor })
    }

    pub fn low(&self) -> f64 {
        self.centre - BAND_SIGMAS * self.sigma
    }

    pub fn high(&self) -> f64 {
        self.centre + BAND_SIGMAS * self.sigma
    }

    /// Whether `value`, with its 95 % interval `ci95`, lies outside the band: beyond 3.5 times the
    /// spread from the centre (the band's σ with the run's own standard error beyond a typical run's
    /// added, see the module documentation), by more than `smallest` (the smallest change that
    /// matters physically, see the fleet's flags), and its interval excluding the centre (a delta
    /// without an interval counts as unknown, never outside).
    pub fn outside(&self, value: f64, ci95: Option<[f64; 2]>, smallest: f64) -> bool {
        let Some([lo, hi]) = ci95 else { return false };
        let beyond = (value - self.centre).abs() > BAND_SIGMAS * self.spread_for(ci95);
        beyond && (value - self.centre).abs() > smallest && !(lo..=hi).contains(&self.centre)
    }

    /// The spread a run with the 95 % interval `ci95` is judged against: the band's σ with the
    /// run's own standard error beyond a typical run's added in quadrature (see the module
    /// documentation); σ itself for a run no noisier than the typical one, or without an interval.
    pub fn spread_for(&self, ci95: Option<[f64; 2]>) -> f64 {
        let own = ci95.map_or(0.0, |[lo, hi]| (hi - lo).abs() / (2.0 * Z95));
        let extra = (own * own - self.typical_error * self.typical_error).max(0.0);
        (self.sigma * self.sigma + extra).sqrt()
    }

    /// The band a run with the 95 % interval `ci95` is judged against, `[low, high]`: the centre ±
    /// [`BAND_SIGMAS`] times [`Band::spread_for`] (wider than [`Band::low`]..[`Band::high`] for a
    /// run noisier than the typical one). What the trend figure and the app draw for each run.
    pub fn limits_for(&self, ci95: Option<[f64; 2]>) -> [f64; 2] {
        let half = BAND_SIGMAS * self.spread_for(ci95);
        [self.centre - half, self.centre + half]
    }
}

/// Each run's band (values in date order; `None` for a run without a finite value): its centre the
/// engine's Theil–Sen trend at that run (the engine's median when fewer than three runs have a value),
/// its spread the scaled MAD of the runs' deviations from the trend, never below the median of
/// `std_errors`.
pub fn local_bands(values: &[f64], std_errors: &[f64]) -> Vec<Option<Band>> {
    let with_value: Vec<usize> = (0..values.len()).filter(|&i| values[i].is_finite()).collect();
    let Some(global) = Band::of(values, std_errors) else { return vec![None; values.len()] };
    if with_value.len() < 3 {
        return values.iter().map(|v| v.is_finite().then_some(global)).collect();
    }
    let mut slopes = Vec::new();
    for (a, &i) in with_value.iter().enumerate() {
        for &j in &with_value[a + 1..] {
            slopes.push((values[j] - values[i]) / (j - i) as f64);
        }
    }
    let slope = median(&slopes).unwrap_or(0.0);
    let offsets: Vec<f64> = with_value.iter().map(|&i| values[i] - slope * i as f64).collect();
    let intercept = median(&offsets).unwrap_or(global.centre);
    let centre = |i: usize| intercept + slope * i as f64;
    let deviations: Vec<f64> = with_value.iter().map(|&i| (values[i] - centre(i)).abs()).collect();
    let typical_error = global.typical_error;
    let sigma = (median(&deviations).unwrap_or(0.0) * MAD_TO_SIGMA).max(typical_error);
    (0..values.len())
        .map(|i| values[i].is_finite().then_some(Band { centre: centre(i), sigma, typical_error }))
        .collect()
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
        assert!(b.outside(1.3, Some([1.25, 1.35]), 0.0));
        assert!(!b.outside(1.3, Some([0.9, 1.7]), 0.0), "its own interval holds the centre");
        assert!(!b.outside(1.3, None, 0.0));
        assert!(!b.outside(1.004, Some([1.003, 1.005]), 0.0));
    }

    #[test]
    fn a_run_noisier_than_the_usual_needs_a_larger_deviation() {
        // Five runs with standard errors 0.5–0.65, one at 1.45: the same value is outside the band
        // with a typical interval and inside it with its own wide one.
        let band = Band { centre: 0.0, sigma: 1.0, typical_error: 0.6 };
        let typical = 0.6 * Z95;
        assert!(band.outside(4.0, Some([4.0 - typical, 4.0 + typical]), 0.0));
        let wide = 1.45 * Z95;
        assert!(!band.outside(4.0, Some([4.0 - wide, 4.0 + wide]), 0.0), "3.5 σ of √(1 + 1.45² − 0.6²)");
        assert!(band.outside(6.5, Some([6.5 - wide, 6.5 + wide]), 0.0), "beyond 3.5 × 1.66");
    }

    #[test]
    fn a_drift_stays_inside_its_band_and_a_step_does_not() {
        // A meter drifting 0.4 % a run, with a little scatter, and 10 % steps in runs 3 and 6.
        let mut values: Vec<f64> =
            (0..12).map(|i| 1.0 + 0.004 * i as f64 + 0.001 * ((i * 7 % 5) as f64 - 2.0)).collect();
        values[3] -= 0.1;
        values[6] += 0.1;
        let bands = local_bands(&values, &[]);
        for (i, (v, band)) in values.iter().zip(&bands).enumerate() {
            let band = band.unwrap();
            assert_eq!(
                band.outside(*v, Some([v - 1e-4, v + 1e-4]), 0.01),
                i == 3 || i == 6,
                "run {i}: {v} against {band:?}"
            );
        }
    }

    #[test]
    fn the_drawn_limits_are_what_a_run_is_judged_against() {
        let band = Band { centre: 10.0, sigma: 1.0, typical_error: 0.5 };
        let typical = Some([9.0, 9.0 + 2.0 * Z95 * 0.5]);
        let noisy = Some([8.0, 8.0 + 2.0 * Z95 * 2.0]);
        let near = |[a, b]: [f64; 2], [c, d]: [f64; 2]| (a - c).abs() < 1e-12 && (b - d).abs() < 1e-12;
        assert!(near(band.limits_for(typical), [band.low(), band.high()]));
        assert!(near(band.limits_for(None), [band.low(), band.high()]));
        let [lo, hi] = band.limits_for(noisy);
        assert!(lo < band.low() && hi > band.high(), "a noisier run's band is wider: {lo}..{hi}");
        // A run as noisy, its interval clear of the centre: flagged exactly beyond the drawn limit.
        let clear = Some([10.5, 10.5 + 2.0 * Z95 * 2.0]);
        assert!(near(band.limits_for(clear), [lo, hi]));
        assert!(!band.outside(hi - 1e-6, clear, 0.0));
        assert!(band.outside(hi + 1e-6, clear, 0.0));
    }

    #[test]
    fn spread_is_never_below_the_runs_own_errors() {
        let band = Band::of(&[1.0, 1.0, 1.0, 1.0], &[0.02, 0.03, 0.02]).unwrap();
        assert!((band.sigma - 0.02).abs() < 1e-12);
        assert!(Band::of(&[f64::NAN], &[]).is_none());
    }
}
