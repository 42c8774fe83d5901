//! Engine families: small turbojets drawn at random from physically plausible ranges, so that the
//! identification can be checked on engines it was never tuned on.
//!
//! [`EngineFamily::small_turbojets`] spans the class of the SR-30 and its peers (50–300 N
//! single-spool engines on a bench sampled at 8.85 Hz). Every quantity that shapes what the
//! identification sees is drawn, each uniformly from a range argued below:
//! - **Fuel system** (metering valve, line, injectors): natural frequency ω_f in 2–5 rad/s and damping
//!   ζ_f in 0.45–0.85. The SR-30 calibration is 2.8 rad/s, 0.6; faster or better damped fuel systems
//!   make the fuel pole pair fainter beside the spool pole, which is exactly what a proposal must
//!   neither invent nor drop.
//! - **Spool**: time constant at the reference point τ_ref in 1.0–2.5 s, and the law of the time
//!   constant against speed τ(N) = τ_ref (N_ref/N)^a with a in 0.5–1.5 (a = 1 is a compressor power
//!   ∝ N³; real compressors move off it as their efficiency changes along the running line). The
//!   larger a, the further the engine is from a Wiener system.
//! - **Steady maps**: the running line through idle 40–50 krpm at 2.0 gal/h, the reference point
//!   68–78 krpm at 5.43 gal/h and the top 82–92 krpm at 7.6 gal/h (rejected unless it rises over
//!   the whole fuel range of the test designs); thrust F = F₀ + F₁ n^p with F₀ in 10–30 N, F(N_ref)
//!   in 60–120 N and p in 3.5–6 (the SR-30 fit is 5.15).
//! - **Stand and sensors**: load-cell lag 0.02–0.08 s; stand resonance 2.5–4.2 Hz (below the
//!   4.4 Hz Nyquist frequency) with ζ 0.2–0.5; thermocouple lag 0.8–1.6 s.
//! - **Sensor noise**: speed 25–80 rpm, thrust 1–3 N, fuel 0.002–0.005 gal/h (the paper's fitted
//!   levels, 50.7 rpm, 2.08 N and 0.00327 gal/h, lie inside).
//!
//! The draw is a pure function of the seed (ChaCha8, its own stream), so an engine is named by its
//! seed: `jetid simulate --engine SEED`.
use std::ops::Range;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::SensorNoise;
use super::designs::{IDLE_FUEL_GPH, MAX_FUEL_GPH, REF_FUEL_GPH};
use super::engine::EngineParams;

/// Stream of the random generator that draws engines (sensor noise uses stream 0, buffeting 1).
const FAMILY_STREAM: u64 = 7;
/// Draws tried before giving up on a seed whose running line does not rise (never seen in practice:
/// the speed ranges make a falling line rare).
const MAX_DRAWS: usize = 64;

/// Ranges an engine family draws its parameters from (uniformly).
#[derive(Clone, Debug, PartialEq)]
pub struct EngineFamily {
    pub fuel_omega_rad_s: Range<f64>,
    pub fuel_zeta: Range<f64>,
    pub spool_tau_ref_secs: Range<f64>,
    pub spool_tau_exponent: Range<f64>,
    pub idle_speed_rpm: Range<f64>,
    pub ref_speed_rpm: Range<f64>,
    pub max_speed_rpm: Range<f64>,
    pub thrust_offset_n: Range<f64>,
    pub ref_thrust_n: Range<f64>,
    pub thrust_exponent: Range<f64>,
    pub cell_lag_secs: Range<f64>,
    pub stand_freq_hz: Range<f64>,
    pub stand_zeta: Range<f64>,
    pub egt_lag_secs: Range<f64>,
    pub speed_noise_rpm: Range<f64>,
    pub thrust_noise_n: Range<f64>,
    pub fuel_noise_gph: Range<f64>,
}

/// One engine of a family: its physics and its sensors' noise.
#[derive(Clone, Debug, PartialEq)]
pub struct DrawnEngine {
    pub seed: u64,
    pub params: EngineParams,
    pub noise: SensorNoise,
}

impl DrawnEngine {
    /// The parameters that shape identification, in one line (for test messages and notes).
    pub fn describe(&self) -> String {
        let p = &self.params;
        format!(
            "engine {}: fuel ω {:.2} rad/s ζ {:.2}; spool τ {:.2} s (N_ref/N)^{:.2}; N {:.0}/{:.0}/{:.0} rpm; \
             thrust {:.1}+{:.1}·n^{:.2} N; noise {:.0} rpm, {:.2} N",
            self.seed,
            p.fuel_omega_rad_s,
            p.fuel_zeta,
            p.spool_tau_ref_secs,
            p.spool_tau_exponent,
            running_line(p, IDLE_FUEL_GPH),
            p.ref_speed_rpm,
            running_line(p, MAX_FUEL_GPH),
            p.thrust_offset_n,
            p.thrust_scale_n,
            p.thrust_exponent,
            self.noise.speed_rpm,
            self.noise.thrust_n
        )
    }
}

fn running_line(p: &EngineParams, fuel_gph: f64) -> f64 {
    let [a, b, c] = p.running_line_rpm;
    a + b * fuel_gph + c * fuel_gph * fuel_gph
}

impl EngineFamily {
    /// Single-spool turbojets of the SR-30's class (see the module documentation for the ranges).
    pub fn small_turbojets() -> Self {
        Self {
            fuel_omega_rad_s: 2.0..5.0,
            fuel_zeta: 0.45..0.85,
            spool_tau_ref_secs: 1.0..2.5,
            spool_tau_exponent: 0.5..1.5,
            idle_speed_rpm: 40_000.0..50_000.0,
            ref_speed_rpm: 68_000.0..78_000.0,
            max_speed_rpm: 82_000.0..92_000.0,
            thrust_offset_n: 10.0..30.0,
            ref_thrust_n: 60.0..120.0,
            thrust_exponent: 3.5..6.0,
            cell_lag_secs: 0.02..0.08,
            stand_freq_hz: 2.5..4.2,
            stand_zeta: 0.2..0.5,
            egt_lag_secs: 0.8..1.6,
            speed_noise_rpm: 25.0..80.0,
            thrust_noise_n: 1.0..3.0,
            fuel_noise_gph: 0.002..0.005,
        }
    }

    /// The engine of this family named by `seed`.
    pub fn draw(&self, seed: u64) -> DrawnEngine {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(FAMILY_STREAM);
        let mut pick = |r: &Range<f64>| if r.start < r.end { rng.random_range(r.clone()) } else { r.start };
        let base = EngineParams::default();
        let mut line = quadratic_through(
            [IDLE_FUEL_GPH, REF_FUEL_GPH, MAX_FUEL_GPH],
            [pick(&self.idle_speed_rpm), pick(&self.ref_speed_rpm), pick(&self.max_speed_rpm)],
        );
        for _ in 0..MAX_DRAWS {
            if rises_over_design_range(line) {
                break;
            }
            line = quadratic_through(
                [IDLE_FUEL_GPH, REF_FUEL_GPH, MAX_FUEL_GPH],
                [pick(&self.idle_speed_rpm), pick(&self.ref_speed_rpm), pick(&self.max_speed_rpm)],
            );
        }
        if !rises_over_design_range(line) {
            line = base.running_line_rpm;
        }
        let ref_speed_rpm = line[0] + line[1] * REF_FUEL_GPH + line[2] * REF_FUEL_GPH * REF_FUEL_GPH;
        let thrust_offset_n = pick(&self.thrust_offset_n);
        let ref_thrust_n = pick(&self.ref_thrust_n).max(thrust_offset_n + 10.0);
        let params = EngineParams {
            ref_speed_rpm,
            ref_fuel_gph: REF_FUEL_GPH,
            spool_tau_ref_secs: pick(&self.spool_tau_ref_secs),
            spool_tau_exponent: pick(&self.spool_tau_exponent),
            running_line_rpm: line,
            fuel_omega_rad_s: pick(&self.fuel_omega_rad_s),
            fuel_zeta: pick(&self.fuel_zeta),
            thrust_offset_n,
            thrust_scale_n: ref_thrust_n - thrust_offset_n,
            thrust_exponent: pick(&self.thrust_exponent),
            cell_lag_secs: pick(&self.cell_lag_secs),
            stand_freq_hz: pick(&self.stand_freq_hz),
            stand_zeta: pick(&self.stand_zeta),
            egt_lag_secs: pick(&self.egt_lag_secs),
            ..base
        };
        let noise = SensorNoise {
            speed_rpm: pick(&self.speed_noise_rpm),
            thrust_n: pick(&self.thrust_noise_n),
            fuel_gph: pick(&self.fuel_noise_gph),
            ..SensorNoise::default()
        };
        DrawnEngine { seed, params, noise }
    }
}

/// Coefficients [a, b, c] of a + b x + c x² through three points with distinct abscissae.
fn quadratic_through(x: [f64; 3], y: [f64; 3]) -> [f64; 3] {
    let [x0, x1, x2] = x;
    let [y0, y1, y2] = y;
    let d01 = (y1 - y0) / (x1 - x0);
    let d12 = (y2 - y1) / (x2 - x1);
    let c = (d12 - d01) / (x2 - x0);
    let b = d01 - c * (x0 + x1);
    let a = y0 - b * x0 - c * x0 * x0;
    [a, b, c]
}

/// The running line rises from the engine's lowest admissible fuel flow to the top of the designs.
fn rises_over_design_range(line: [f64; 3]) -> bool {
    let [a, b, c] = line;
    let slope = |x: f64| b + 2.0 * c * x;
    let lowest = EngineParams::default().fuel_range_gph.0;
    slope(lowest) > 0.0 && slope(MAX_FUEL_GPH) > 0.0 && a + b * lowest + c * lowest * lowest > 0.0
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::sim::engine::{Drive, Engine};
    use crate::sim::{ActiveEffects, DT_SECS, ambient::STANDARD_DAY};

    fn drive(fuel_gph: f64) -> Drive {
        Drive { fuel_cmd_gph: fuel_gph, ambient: STANDARD_DAY, corrected: false, buffet_n: 0.0 }
    }

    #[test]
    fn drawn_engines_lie_in_their_ranges_and_have_steady_states() {
        let family = EngineFamily::small_turbojets();
        for seed in 0..40 {
            let e = family.draw(seed);
            assert_eq!(e, family.draw(seed), "a seed names one engine");
            let p = &e.params;
            assert!(family.fuel_omega_rad_s.contains(&p.fuel_omega_rad_s));
            assert!(family.spool_tau_exponent.contains(&p.spool_tau_exponent));
            assert!(family.speed_noise_rpm.contains(&e.noise.speed_rpm));
            let engine = Engine::new(p.clone(), ActiveEffects::none());
            let mut last = 0.0;
            for fuel in [IDLE_FUEL_GPH, 3.5, REF_FUEL_GPH, MAX_FUEL_GPH] {
                let x = engine.steady_state(&drive(fuel)).unwrap();
                let speed = x[crate::sim::engine::SPEED];
                assert!(speed > last, "{}: speed must rise with fuel", e.describe());
                last = speed;
            }
        }
        assert_ne!(family.draw(1), family.draw(2));
    }

    /// The spool time constant follows τ_ref (N_ref/N)^a: the slowest pole of the speed path at two
    /// operating points gives the exponent back.
    #[test]
    fn the_time_constant_law_is_the_drawn_one() {
        let family = EngineFamily::small_turbojets();
        for seed in [3, 11] {
            let e = family.draw(seed);
            let engine = Engine::new(e.params.clone(), ActiveEffects::none());
            let tau_and_speed = |fuel: f64| {
                let pole = engine.speed_poles_z(&drive(fuel), DT_SECS).unwrap()[0];
                let speed = engine.steady_state(&drive(fuel)).unwrap()[crate::sim::engine::SPEED];
                (-DT_SECS / pole.re.ln(), speed)
            };
            let (tau_lo, n_lo) = tau_and_speed(IDLE_FUEL_GPH);
            let (tau_hi, n_hi) = tau_and_speed(MAX_FUEL_GPH);
            let a = (tau_lo / tau_hi).ln() / (n_hi / n_lo).ln();
            assert!((a - e.params.spool_tau_exponent).abs() < 0.02, "{}: a = {a}", e.describe());
        }
    }

    #[test]
    fn the_sr30_calibration_keeps_its_cube_law() {
        let quad = quadratic_through([1.0, 2.0, 3.0], [1.0, 4.0, 9.0]);
        assert!(quad.iter().zip([0.0, 0.0, 1.0]).all(|(a, b)| (a - b).abs() < 1e-12));
        assert!((EngineParams::default().spool_tau_exponent - 1.0).abs() < 1e-15);
    }
}
