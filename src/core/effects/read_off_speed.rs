//! `read_off_speed`: an output read off the shaft speed's model (one spool, a static map per
//! output).
//!
//! Thrust follows the spool that the shaft speed measures. Its own Wiener model reads the spool
//! through its own linear block, whose blocks (a rate limit, a soak, the spool's schedule) are fitted
//! on thrust's noisy data through a strongly curved map. This block instead makes the output a
//! function of the speed model's simulated speed: the speed's linear block, effects and map, then
//! a polynomial `F = P(N)` fitted on the identification run's measured speed and output. A rate limit
//! on the spool's acceleration, a soak or a kink that the speed model holds then reaches thrust as
//! the speed has shown it. It is offered by the spool sharing (`core::diagnose::shared_spool`), and
//! kept only where the output's own validation runs do not lean against it.
use super::ParamSpec;
use super::ambient_correction::{AmbientCorrection, Conditions};
use super::stats::ResidualTrace;
use super::{EffectError, EffectId, Evidence};
use crate::core::identification::static_map::{Beyond, StaticMap, fit_static_map};

/// `output = P(N)`: a polynomial of order [`READ_OFF_ORDER`] in the scaled shaft speed
/// `(N − speed_center) / speed_scale`, continued beyond the identified speeds by its end trend,
/// like every fitted map.
///
/// When the speed's model is corrected for the inlet conditions, the polynomial relates the
/// corrected quantities, as the engine's similarity laws do: `y/(θ^a δ^b) = P(N/√θ)`, the output's
/// own exponents a, b (`theta_exp`, `delta_exp`; `F/δ` for thrust) and the speed's correction
/// undone first. Without the correction both exponents are 0 and unused.
#[derive(Clone, Debug, PartialEq)]
pub struct ReadOffSpeed {
    pub speed_center: f64,
    pub speed_scale: f64,
    pub c0: f64,
    pub c1: f64,
    pub c2: f64,
    pub c3: f64,
    pub c4: f64,
    pub theta_exp: f64,
    pub delta_exp: f64,
}

/// The polynomial's order. Across the family thrust grows as `F₀ + F₁·Nᵖ` with p = 3.5–6 (the
/// simulator's thrust law; the JetCat's thrust–speed curve is of the same kind); a quartic follows
/// that over a run's speed range to well below the load cell's noise, and the monotone fit keeps it
/// from turning back between the steady points. More would follow the noise of the transients.
pub const READ_OFF_ORDER: usize = 4;

impl ReadOffSpeed {
    /// The polynomial as a static map (its end trend beyond the identified speeds).
    pub fn map(&self) -> StaticMap {
        StaticMap {
            v_center: self.speed_center,
            v_scale: self.speed_scale,
            coeffs_scaled: vec![self.c0, self.c1, self.c2, self.c3, self.c4],
            beyond: Beyond::EndTrend,
        }
    }

    /// The output at shaft speed `n`.
    pub fn eval(&self, n: f64) -> f64 {
        self.map().eval(n)
    }

    /// d(output)/dN at shaft speed `n`.
    pub fn slope(&self, n: f64) -> f64 {
        self.map().slope(n)
    }

    /// The polynomial fitted by least squares (held monotone) to the measured `output` against the
    /// measured `speed` of the same run, sample by sample. The speed's noise (a few tenths of a
    /// percent) is small beside the output's, so the regression on the measured speed is nearly
    /// free of the errors-in-variables bias.
    /// `correction`, when the speed's model is corrected for the inlet conditions: the output's own
    /// correction, by which `output` has been divided (and `speed` by the speed's).
    pub fn fit(
        speed: &[f64],
        output: &[f64],
        correction: Option<&AmbientCorrection>,
    ) -> Result<Self, EffectError> {
        let usable: (Vec<f64>, Vec<f64>) = speed
            .iter()
            .zip(output)
            .filter(|(n, y)| n.is_finite() && y.is_finite())
            .map(|(n, y)| (*n, *y))
            .unzip();
        let map =
            fit_static_map(&usable.0, &usable.1, READ_OFF_ORDER).map_err(|e| EffectError::NotApplicable {
                effect: EffectId::ReadOffSpeed.name().to_owned(),
                reason: e.to_string(),
            })?;
        let c = |i: usize| map.coeffs_scaled.get(i).copied().unwrap_or(0.0);
        Ok(Self {
            speed_center: map.v_center,
            speed_scale: map.v_scale,
            c0: c(0),
            c1: c(1),
            c2: c(2),
            c3: c(3),
            c4: c(4),
            theta_exp: correction.map_or(0.0, |a| a.output_theta_exp),
            delta_exp: correction.map_or(0.0, |a| a.output_delta_exp),
        })
    }

    /// The output from the speed model's simulated speed `y` (replaced), given the inlet
    /// `conditions` and the speed's correction `speed_correction` when the model is corrected.
    pub fn apply(&self, y: &mut [f64], corrected: Option<(&AmbientCorrection, &Conditions)>) {
        let map = self.map();
        match corrected {
            Some((speed_correction, c)) => {
                let own =
                    AmbientCorrection { output_theta_exp: self.theta_exp, output_delta_exp: self.delta_exp };
                let (speed_factor, own_factor) = (speed_correction.output_factor(c), own.output_factor(c));
                for ((n, s), o) in y.iter_mut().zip(speed_factor).zip(own_factor) {
                    *n = map.eval(*n / s) * o;
                }
            }
            None => y.iter_mut().for_each(|n| *n = map.eval(*n)),
        }
    }
}

/// The block is a choice of the model's form, made by the spool sharing, not a residual's signature.
fn evidence(_: &[ResidualTrace]) -> Evidence {
    Evidence::none("offered with the shaft speed's model, not read from residuals")
}

block_impl!(
    ReadOffSpeed { speed_center, speed_scale, c0, c1, c2, c3, c4, theta_exp, delta_exp },
    params: &[
        ParamSpec::real("speed_center", -1e12, 1e12),
        ParamSpec::real("speed_scale", 1e-12, 1e12),
        ParamSpec::real("c0", -1e15, 1e15),
        ParamSpec::real("c1", -1e15, 1e15),
        ParamSpec::real("c2", -1e15, 1e15),
        ParamSpec::real("c3", -1e15, 1e15),
        ParamSpec::real("c4", -1e15, 1e15),
        ParamSpec::real("theta_exp", -10.0, 10.0),
        ParamSpec::real("delta_exp", -10.0, 10.0),
    ],
    physics: "the output follows the spool the shaft speed measures: it is read off the speed model's \
         simulated speed through a polynomial fitted on the identification run",
    evidence: evidence
);

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn a_power_law_is_read_back_within_the_range_and_bad_data_is_an_error() {
        let n: Vec<f64> = (0..400).map(|k| 40_000.0 + 200.0 * k as f64).collect();
        let f: Vec<f64> = n.iter().map(|n| 5.0 + 300.0 * (n / 120_000.0_f64).powf(4.5)).collect();
        let block = ReadOffSpeed::fit(&n, &f, None).unwrap();
        // Within 0.2 % of full scale, a bench load cell's accuracy class: the quartic's own error
        // stays below what the load cell can tell.
        let full_scale = f.iter().copied().fold(0.0, f64::max);
        for (n, f) in n.iter().zip(&f).step_by(37) {
            assert!((block.eval(*n) - f).abs() < 0.002 * full_scale, "{n}: {} vs {f}", block.eval(*n));
        }
        assert!(block.slope(100_000.0) > 0.0);
        assert!(matches!(ReadOffSpeed::fit(&n[..3], &f[..3], None), Err(EffectError::NotApplicable { .. })));
    }
}
