//! The SR-30-class turbojet: fuel system, spool power balance, thrust, load cell and EGT, as a
//! continuous-time state-space model integrated by fixed-step RK4.
//!
//! Equations (w fuel in gal/h, N speed in rpm, n = N_c / N_ref, all `_c` corrected when the
//! `ambient_correction` effect is on, θ = δ = 1 otherwise):
//! - fuel system (metering valve + line + injectors), second order, unit gain:
//!   ẅ_b = ω_f² (u(t − d) − w_b) − 2 ζ_f ω_f ẇ_b
//! - turbine power available at corrected burnt fuel w_c = w_b / (δ √θ), normalised to the reference
//!   point: p_t = (N_rl(w_c) / N_ref)^k with the running line N_rl(w) = r₀ + r₁ w + r₂ w²
//! - thermal soak (effect): ṡ = (p_t − s)/τ_s and net power p = p_t − g (p_t − s); otherwise p = p_t
//! - spool power balance J ω ω̇ = P_t − P_c with compressor power ∝ N^k, k = 2 + a (plus the bleed
//!   effect): Ṅ_c = K (p − n^k (1 + k_b max(0, n − n_b))) / n,  K = N_ref / (k τ_ref),
//!   so the linearised time constant is τ(N) = τ_ref · (N_ref / N)^a (the SR-30 calibration has
//!   a = 1: compressor power ∝ N³, τ ∝ 1/N); Ṅ_c is divided by the deceleration (acceleration)
//!   factor while negative (positive), then clamped to the ECU's limits (rate-limit effect);
//!   physical N = √θ · N_c
//! - engine thrust F = δ (F_0 + F_1 n^p_F)
//! - load cell: first-order lag τ_lc, then a second-order stand (f_s, ζ_s) driven by F (+ buffeting)
//! - EGT: gas temperature T_amb + θ ΔT_ref (w_c / w_ref) / n^β seen through a thermocouple lag τ_egt
use nalgebra::{Complex, DMatrix};

use super::ambient::Ambient;
use super::effects::ActiveEffects;
use super::error::SimError;

/// State layout.
pub const N_STATES: usize = 8;
/// Burnt fuel flow w_b, gal/h.
pub const FUEL: usize = 0;
/// Its rate, gal/h/s.
pub const FUEL_RATE: usize = 1;
/// Corrected spool speed N_c, rpm.
pub const SPEED: usize = 2;
/// Soak state s (normalised power).
pub const SOAK: usize = 3;
/// Load-cell lag output, N.
pub const CELL_LAG: usize = 4;
/// Stand (load-cell) output, N: the thrust the sensor reports.
pub const STAND: usize = 5;
/// Its rate, N/s.
pub const STAND_RATE: usize = 6;
/// Thermocouple reading, °C.
pub const EGT: usize = 7;

pub type State = [f64; N_STATES];

/// Below this a lag is treated as absent (a pass-through), s.
const MIN_LAG_SECS: f64 = 1e-3;
/// Lower bound on the normalised speed used in divisions.
const MIN_SPEED_RATIO: f64 = 0.05;

/// Physical parameters of the engine, test stand and sensors. `Default` is the SR-30 calibration.
#[derive(Clone, Debug, PartialEq)]
pub struct EngineParams {
    /// Reference speed N_ref, rpm (the paper's mean operating point).
    pub ref_speed_rpm: f64,
    /// Reference fuel flow w_ref, gal/h.
    pub ref_fuel_gph: f64,
    /// Spool time constant τ_ref at N_ref, s.
    pub spool_tau_ref_secs: f64,
    /// Exponent a of the time-constant law τ(N) = τ_ref (N_ref / N)^a; compressor power ∝ N^(2 + a).
    pub spool_tau_exponent: f64,
    /// Running line N_rl(w) = a + b w + c w² (rpm, rpm/(gal/h), rpm/(gal/h)²).
    pub running_line_rpm: [f64; 3],
    /// Fuel-system natural frequency ω_f, rad/s.
    pub fuel_omega_rad_s: f64,
    /// Fuel-system damping ratio ζ_f.
    pub fuel_zeta: f64,
    /// Thrust offset F_0, N.
    pub thrust_offset_n: f64,
    /// Thrust scale F_1, N.
    pub thrust_scale_n: f64,
    /// Thrust speed exponent p_F.
    pub thrust_exponent: f64,
    /// Load-cell lag τ_lc, s.
    pub cell_lag_secs: f64,
    /// Stand resonance f_s, Hz.
    pub stand_freq_hz: f64,
    /// Stand damping ratio ζ_s.
    pub stand_zeta: f64,
    /// Gas temperature rise at the reference point ΔT_ref, K.
    pub egt_rise_ref_k: f64,
    /// Speed exponent β of the gas temperature rise.
    pub egt_speed_exponent: f64,
    /// Thermocouple lag τ_egt, s.
    pub egt_lag_secs: f64,
    /// Admissible fuel command range, gal/h.
    pub fuel_range_gph: (f64, f64),
}

impl Default for EngineParams {
    fn default() -> Self {
        Self {
            ref_speed_rpm: 73_850.0,
            ref_fuel_gph: 5.43,
            spool_tau_ref_secs: 1.7,
            spool_tau_exponent: 1.0,
            // Through (2.0 gal/h, 45,000 rpm), (5.43, 73,850), (7.6, 87,000).
            running_line_rpm: [23_618.25, 11_530.58, -419.852],
            fuel_omega_rad_s: 2.8,
            fuel_zeta: 0.6,
            // 25 N at 45,000 rpm, 87.8 N at 73,850 rpm, 178 N at 87,000 rpm.
            thrust_offset_n: 19.7,
            thrust_scale_n: 68.1,
            thrust_exponent: 5.15,
            cell_lag_secs: 0.04,
            stand_freq_hz: 3.5,
            stand_zeta: 0.35,
            egt_rise_ref_k: 580.0,
            egt_speed_exponent: 1.5,
            egt_lag_secs: 1.2,
            fuel_range_gph: (1.0, 10.0),
        }
    }
}

/// What drives the engine at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drive {
    /// Fuel command reaching the fuel system (already delayed), gal/h.
    pub fuel_cmd_gph: f64,
    pub ambient: Ambient,
    /// Whether the engine responds to `ambient` (corrected quantities).
    pub corrected: bool,
    /// Broadband force on the stand, N.
    pub buffet_n: f64,
}

impl Drive {
    fn theta_delta(&self) -> (f64, f64) {
        if self.corrected { (self.ambient.theta(), self.ambient.delta()) } else { (1.0, 1.0) }
    }
}

/// The engine with its effects switched in.
#[derive(Clone, Debug, PartialEq)]
pub struct Engine {
    pub params: EngineParams,
    pub effects: ActiveEffects,
}

/// Measurable quantities derived from a state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outputs {
    pub speed_rpm: f64,
    pub thrust_n: f64,
    pub egt_c: f64,
}

impl Engine {
    pub fn new(params: EngineParams, effects: ActiveEffects) -> Self {
        Self { params, effects }
    }

    /// Stand resonance (Hz, ζ) and sensor lag (s) in force.
    fn stand(&self) -> (f64, f64, f64) {
        match self.effects.stand {
            Some(s) => (s.freq_hz, s.zeta, s.lag_s),
            None => (self.params.stand_freq_hz, self.params.stand_zeta, self.params.cell_lag_secs),
        }
    }

    /// Shortest time scale of the model, s (sets the integration step).
    pub fn fastest_time_scale_secs(&self) -> f64 {
        let (freq_hz, _, lag_s) = self.stand();
        let stand_secs = 1.0 / (2.0 * std::f64::consts::PI * freq_hz);
        let lag_secs = if lag_s > MIN_LAG_SECS { lag_s } else { f64::INFINITY };
        stand_secs.min(lag_secs).min(1.0 / self.params.fuel_omega_rad_s)
    }

    /// Normalised turbine power available at corrected fuel flow w_c.
    fn turbine_power(&self, fuel_corr_gph: f64) -> f64 {
        let [a, b, c] = self.params.running_line_rpm;
        let w = fuel_corr_gph.max(0.0);
        let n_rl = ((a + b * w + c * w * w) / self.params.ref_speed_rpm).max(MIN_SPEED_RATIO);
        n_rl.powf(self.load_exponent())
    }

    /// Exponent k of the compressor power law P_c ∝ N^k.
    fn load_exponent(&self) -> f64 {
        2.0 + self.params.spool_tau_exponent
    }

    /// Normalised compressor (plus bleed) power at normalised corrected speed n.
    fn load_power(&self, n: f64) -> f64 {
        let bleed = self
            .effects
            .bleed
            .map_or(0.0, |(bleed_rpm, gain)| gain * (n - bleed_rpm / self.params.ref_speed_rpm).max(0.0));
        n.max(0.0).powf(self.load_exponent()) * (1.0 + bleed)
    }

    fn engine_thrust_n(&self, n: f64, delta: f64) -> f64 {
        let p = &self.params;
        delta * (p.thrust_offset_n + p.thrust_scale_n * n.max(0.0).powf(p.thrust_exponent))
    }

    fn gas_temp_c(&self, fuel_corr_gph: f64, n: f64, drive: &Drive) -> f64 {
        let p = &self.params;
        let (theta, _) = drive.theta_delta();
        let rise_k = theta * p.egt_rise_ref_k * (fuel_corr_gph.max(0.0) / p.ref_fuel_gph)
            / n.max(MIN_SPEED_RATIO).powf(p.egt_speed_exponent);
        drive.ambient.temp_c + rise_k
    }

    /// ẋ = f(x, drive).
    pub fn derivative(&self, x: &State, drive: &Drive) -> State {
        let p = &self.params;
        let (theta, delta) = drive.theta_delta();
        let mut dx = [0.0; N_STATES];

        let omega_f = p.fuel_omega_rad_s;
        dx[FUEL] = x[FUEL_RATE];
        dx[FUEL_RATE] =
            omega_f * omega_f * (drive.fuel_cmd_gph - x[FUEL]) - 2.0 * p.fuel_zeta * omega_f * x[FUEL_RATE];

        let fuel_corr_gph = x[FUEL] / (delta * theta.sqrt());
        let power_turbine = self.turbine_power(fuel_corr_gph);
        let power_net = match self.effects.soak {
            Some((gain, tau_s)) => {
                dx[SOAK] = (power_turbine - x[SOAK]) / tau_s;
                power_turbine - gain * (power_turbine - x[SOAK])
            }
            None => power_turbine,
        };
        let n = (x[SPEED] / p.ref_speed_rpm).max(MIN_SPEED_RATIO);
        let gain_rpm_s = p.ref_speed_rpm / (self.load_exponent() * p.spool_tau_ref_secs);
        let speed_rate = gain_rpm_s * (power_net - self.load_power(n)) / n;
        dx[SPEED] = if speed_rate < 0.0 {
            speed_rate / self.effects.decel_factor
        } else {
            speed_rate / self.effects.accel_factor
        };
        if let Some((rise_rpm_s, fall_rpm_s)) = self.effects.rate_limit {
            dx[SPEED] = dx[SPEED].clamp(-fall_rpm_s, rise_rpm_s);
        }

        let thrust_n = self.engine_thrust_n(n, delta);
        let (freq_hz, zeta, lag_s) = self.stand();
        let stand_in_n = if lag_s > MIN_LAG_SECS {
            dx[CELL_LAG] = (thrust_n - x[CELL_LAG]) / lag_s;
            x[CELL_LAG]
        } else {
            thrust_n
        } + drive.buffet_n;
        let omega_s = 2.0 * std::f64::consts::PI * freq_hz;
        dx[STAND] = x[STAND_RATE];
        dx[STAND_RATE] = omega_s * omega_s * (stand_in_n - x[STAND]) - 2.0 * zeta * omega_s * x[STAND_RATE];

        dx[EGT] = (self.gas_temp_c(fuel_corr_gph, n, drive) - x[EGT]) / p.egt_lag_secs;
        dx
    }

    /// The noiseless sensor readings of a state.
    pub fn outputs(&self, x: &State, drive: &Drive) -> Outputs {
        let (theta, _) = drive.theta_delta();
        Outputs { speed_rpm: theta.sqrt() * x[SPEED], thrust_n: x[STAND], egt_c: x[EGT] }
    }

    /// The equilibrium under a constant drive (buffeting ignored).
    pub fn steady_state(&self, drive: &Drive) -> Result<State, SimError> {
        let fuel_gph = drive.fuel_cmd_gph;
        let (lo_gph, hi_gph) = self.params.fuel_range_gph;
        if !(lo_gph..=hi_gph).contains(&fuel_gph) {
            return Err(SimError::FuelOutOfRange { t_secs: 0.0, fuel_gph, min_gph: lo_gph, max_gph: hi_gph });
        }
        let (theta, delta) = drive.theta_delta();
        let fuel_corr_gph = fuel_gph / (delta * theta.sqrt());
        let power = self.turbine_power(fuel_corr_gph);
        // load_power is increasing in n: bisect.
        let (mut lo, mut hi) = (MIN_SPEED_RATIO, 4.0);
        if self.load_power(lo) > power || self.load_power(hi) < power {
            return Err(SimError::NoSteadyState { fuel_gph, reason: "power balance has no root" });
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if self.load_power(mid) < power {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let n = 0.5 * (lo + hi);
        let thrust_n = self.engine_thrust_n(n, delta);
        let mut x = [0.0; N_STATES];
        x[FUEL] = fuel_gph;
        x[SPEED] = n * self.params.ref_speed_rpm;
        x[SOAK] = power;
        x[CELL_LAG] = thrust_n;
        x[STAND] = thrust_n;
        x[EGT] = self.gas_temp_c(fuel_corr_gph, n, drive);
        Ok(x)
    }

    /// One RK4 step of length `h_secs` from `t_secs`, with the drive evaluated at t, t + h/2, t + h.
    pub fn rk4_step(&self, x: &State, t_secs: f64, h_secs: f64, drive_at: &impl Fn(f64) -> Drive) -> State {
        let (d0, d1, d2) = (drive_at(t_secs), drive_at(t_secs + 0.5 * h_secs), drive_at(t_secs + h_secs));
        let k1 = self.derivative(x, &d0);
        let k2 = self.derivative(&axpy(x, 0.5 * h_secs, &k1), &d1);
        let k3 = self.derivative(&axpy(x, 0.5 * h_secs, &k2), &d1);
        let k4 = self.derivative(&axpy(x, h_secs, &k3), &d2);
        let mut next = *x;
        for (i, xi) in next.iter_mut().enumerate() {
            let slope = k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i];
            *xi += h_secs / 6.0 * slope;
        }
        next
    }

    /// Discrete poles z = exp(λ dt) of the fuel → speed path linearised at the steady state of a
    /// constant drive, sorted by decreasing modulus (then imaginary part).
    pub fn speed_poles_z(&self, drive: &Drive, dt_secs: f64) -> Result<Vec<Complex<f64>>, SimError> {
        let mut states = vec![FUEL, FUEL_RATE, SPEED];
        if self.effects.soak.is_some() {
            states.push(SOAK);
        }
        self.poles_z(drive, dt_secs, &states)
    }

    /// As [`Engine::speed_poles_z`] for the fuel → measured-thrust path (spool, load cell, stand).
    pub fn thrust_poles_z(&self, drive: &Drive, dt_secs: f64) -> Result<Vec<Complex<f64>>, SimError> {
        let mut states = vec![FUEL, FUEL_RATE, SPEED];
        if self.effects.soak.is_some() {
            states.push(SOAK);
        }
        if self.stand().2 > MIN_LAG_SECS {
            states.push(CELL_LAG);
        }
        states.extend([STAND, STAND_RATE]);
        self.poles_z(drive, dt_secs, &states)
    }

    /// Eigenvalues of the Jacobian restricted to `states` (the model is block-triangular along the
    /// signal path, so these are exactly that path's poles), mapped to the z-plane.
    fn poles_z(&self, drive: &Drive, dt_secs: f64, states: &[usize]) -> Result<Vec<Complex<f64>>, SimError> {
        let drive = Drive { buffet_n: 0.0, ..*drive };
        let x0 = self.steady_state(&drive)?;
        let m = states.len();
        let mut jac = DMatrix::<f64>::zeros(m, m);
        for (col, &j) in states.iter().enumerate() {
            let step = 1e-6 * x0[j].abs().max(1.0);
            let (mut xp, mut xm) = (x0, x0);
            xp[j] += step;
            xm[j] -= step;
            let (fp, fm) = (self.derivative(&xp, &drive), self.derivative(&xm, &drive));
            for (row, &i) in states.iter().enumerate() {
                jac[(row, col)] = (fp[i] - fm[i]) / (2.0 * step);
            }
        }
        let mut poles: Vec<Complex<f64>> =
            jac.complex_eigenvalues().iter().map(|lambda| (lambda * dt_secs).exp()).collect();
        poles.sort_by(|a, b| b.norm().total_cmp(&a.norm()).then(b.im.total_cmp(&a.im)));
        Ok(poles)
    }
}

fn axpy(x: &State, a: f64, y: &State) -> State {
    let mut out = *x;
    for (o, yi) in out.iter_mut().zip(y) {
        *o += a * yi;
    }
    out
}
