//! The bundled turbojet simulator: an SR-30-class engine (fuel system, spool power balance, thrust on
//! a load cell, EGT), the test designs of METHOD.md and the effect catalog as switchable physics.
//!
//! [`simulate`] integrates the engine with RK4 at ≥ 10 steps per sample, samples it at 8.85 Hz and
//! returns the measured run (Gaussian sensor noise at the paper's fitted levels) together with the
//! noiseless truth on the same time base. Every run starts from the steady state of its first input.
//! Equations and parameter values are documented in [`engine`].
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

use crate::core::run::{Channel, Run};

pub mod ambient;
pub mod designs;
pub mod effects;
pub mod engine;
pub mod error;
pub mod family;
pub mod fleet;

pub use designs::{FuelProfile, TestKind};
pub use effects::{ActiveEffects, EFFECT_IDS, Effect};
pub use engine::{Engine, EngineParams};
pub use error::SimError;
pub use family::{DrawnEngine, EngineFamily};

use ambient::Day;
use engine::{Drive, State};

/// Sample rate of the paper's test bench, Hz.
pub const SAMPLE_RATE_HZ: f64 = 8.85;
/// Sample time, s.
pub const DT_SECS: f64 = 1.0 / SAMPLE_RATE_HZ;
/// Minimum RK4 steps per sample.
const MIN_SUBSTEPS: usize = 10;
/// How far inside an integration piece its drive is evaluated, s (keeps a jump on the right side).
const INSIDE_SECS: f64 = 1e-7;

/// Canonical column names of the simulated runs.
pub mod columns {
    pub const TIME: &str = "time_s";
    pub const FUEL: &str = "fuel_flow_gph";
    pub const SPEED: &str = "shaft_speed_rpm";
    pub const THRUST: &str = "thrust_n";
    pub const EGT: &str = "egt_c";
    pub const AMBIENT_TEMP: &str = "ambient_temp_c";
    pub const AMBIENT_PRESSURE: &str = "ambient_pressure_kpa";
    pub const HUMIDITY: &str = "relative_humidity_pct";
}

/// Standard deviations of the Gaussian sensor noise.
#[derive(Clone, Debug, PartialEq)]
pub struct SensorNoise {
    pub fuel_gph: f64,
    pub speed_rpm: f64,
    pub thrust_n: f64,
    pub egt_c: f64,
    pub temp_c: f64,
    pub pressure_kpa: f64,
    pub rh_pct: f64,
}

impl Default for SensorNoise {
    /// Fuel, speed and thrust at the paper's fitted levels (MLE on its 300-sample steady run).
    fn default() -> Self {
        Self {
            fuel_gph: 0.00327,
            speed_rpm: 50.7,
            thrust_n: 2.08,
            egt_c: 1.5,
            temp_c: 0.05,
            pressure_kpa: 0.01,
            rh_pct: 0.1,
        }
    }
}

impl SensorNoise {
    /// No noise at all (the measured run equals the truth).
    pub fn none() -> Self {
        Self {
            fuel_gph: 0.0,
            speed_rpm: 0.0,
            thrust_n: 0.0,
            egt_c: 0.0,
            temp_c: 0.0,
            pressure_kpa: 0.0,
            rh_pct: 0.0,
        }
    }
}

/// What to simulate.
#[derive(Clone, Debug, PartialEq)]
pub struct SimConfig {
    /// Name given to both runs.
    pub name: String,
    pub profile: FuelProfile,
    pub effects: Vec<Effect>,
    pub seed: u64,
    pub engine: EngineParams,
    pub noise: SensorNoise,
}

impl SimConfig {
    /// One of the test designs on the base engine, no effect, paper noise.
    pub fn for_test(name: &str, kind: TestKind, seed: u64) -> Result<Self, SimError> {
        Ok(Self {
            name: name.to_owned(),
            profile: FuelProfile::for_test(kind, DT_SECS)?,
            effects: Vec::new(),
            seed,
            engine: EngineParams::default(),
            noise: SensorNoise::default(),
        })
    }

    pub fn with_effects(mut self, effects: Vec<Effect>) -> Self {
        self.effects = effects;
        self
    }

    /// The same test on another engine, with that engine's sensor noise.
    pub fn on_engine(mut self, engine: &DrawnEngine) -> Self {
        self.engine = engine.params.clone();
        self.noise = engine.noise.clone();
        self
    }
}

/// A simulated run and its noiseless truth (same time base and column names).
#[derive(Clone, Debug, PartialEq)]
pub struct SimOutput {
    pub measured: Run,
    pub truth: Run,
}

/// Noiseless signals at the sample instants.
struct Traces {
    fuel_gph: Vec<f64>,
    speed_rpm: Vec<f64>,
    thrust_n: Vec<f64>,
    egt_c: Vec<f64>,
    temp_c: Vec<f64>,
    pressure_kpa: Vec<f64>,
    rh_pct: Vec<f64>,
}

/// Simulate a run: the measured signals and the noiseless truth.
pub fn simulate(cfg: &SimConfig) -> Result<SimOutput, SimError> {
    let effects = ActiveEffects::from_effects(&cfg.effects)?;
    let engine = Engine::new(cfg.engine.clone(), effects);
    let truth = integrate(&engine, &cfg.profile, cfg.seed)?;
    let t_secs: Vec<f64> = (0..cfg.profile.n_samples).map(|k| k as f64 * DT_SECS).collect();
    let mut measured = add_noise(&truth, &cfg.noise, cfg.seed);
    for fuel in &mut measured.fuel_gph {
        *fuel += engine.effects.meter_offset_gph;
    }
    Ok(SimOutput { measured: to_run(&cfg.name, &t_secs, measured), truth: to_run(&cfg.name, &t_secs, truth) })
}

/// Integrate the engine over the profile from the steady state of its first input.
fn integrate(engine: &Engine, profile: &FuelProfile, seed: u64) -> Result<Traces, SimError> {
    let n = profile.n_samples;
    let effects = &engine.effects;
    let day = Day::new(effects.ambient, n.saturating_sub(1) as f64 * DT_SECS);
    let delay_s = effects.delay_s;
    let corrected = day.engine_corrected();
    let buffet = buffet_sequence(n, effects.stand.map_or(0.0, |s| s.buffet_n), seed);
    let (lo_gph, hi_gph) = engine.params.fuel_range_gph;

    let drive_at = |t_secs: f64, buffet_n: f64| Drive {
        fuel_cmd_gph: profile.fuel_at(t_secs - delay_s),
        ambient: day.at(t_secs),
        corrected,
        buffet_n,
    };
    let mut x: State = engine.steady_state(&drive_at(0.0, 0.0))?;
    let breaks_secs: Vec<f64> = profile.boundaries_secs().iter().map(|b| b + delay_s).collect();
    let substeps = MIN_SUBSTEPS.max((DT_SECS / (0.2 * engine.fastest_time_scale_secs())).ceil() as usize);
    let h_secs = DT_SECS / substeps as f64;

    let mut tr = Traces {
        fuel_gph: Vec::with_capacity(n),
        speed_rpm: Vec::with_capacity(n),
        thrust_n: Vec::with_capacity(n),
        egt_c: Vec::with_capacity(n),
        temp_c: Vec::with_capacity(n),
        pressure_kpa: Vec::with_capacity(n),
        rh_pct: Vec::with_capacity(n),
    };
    for k in 0..n {
        let t_secs = k as f64 * DT_SECS;
        let fuel_gph = profile.fuel_at(t_secs);
        if !(lo_gph..=hi_gph).contains(&fuel_gph) {
            return Err(SimError::FuelOutOfRange { t_secs, fuel_gph, min_gph: lo_gph, max_gph: hi_gph });
        }
        let buffet_n = buffet.get(k).copied().unwrap_or(0.0);
        let drive = drive_at(t_secs, buffet_n);
        let out = engine.outputs(&x, &drive);
        for (channel, value) in [("shaft speed", out.speed_rpm), ("thrust", out.thrust_n), ("EGT", out.egt_c)]
        {
            if !value.is_finite() {
                return Err(SimError::NonFinite { channel, t_secs });
            }
        }
        tr.fuel_gph.push(fuel_gph);
        tr.speed_rpm.push(out.speed_rpm);
        tr.thrust_n.push(out.thrust_n);
        tr.egt_c.push(out.egt_c);
        tr.temp_c.push(drive.ambient.temp_c);
        tr.pressure_kpa.push(drive.ambient.pressure_kpa);
        tr.rh_pct.push(drive.ambient.rh_pct);
        // Buffeting is held over the sample interval that starts at t_k.
        for s in 0..substeps {
            let a_secs = t_secs + s as f64 * h_secs;
            x = step_across(engine, &x, a_secs, a_secs + h_secs, &breaks_secs, &|t| drive_at(t, buffet_n));
        }
    }
    Ok(tr)
}

/// Integrate from `a_secs` to `b_secs`, splitting the step where the (delayed) command jumps and
/// evaluating the drive strictly inside each piece, so a jump acts exactly at its time.
fn step_across(
    engine: &Engine,
    x: &State,
    a_secs: f64,
    b_secs: f64,
    breaks_secs: &[f64],
    drive_at: &impl Fn(f64) -> Drive,
) -> State {
    let mut x = *x;
    let mut lo = a_secs;
    // The breaks are sorted: bisect to those inside the step.
    let from = breaks_secs.partition_point(|&t| t <= a_secs + INSIDE_SECS);
    let inner =
        breaks_secs.get(from..).unwrap_or_default().iter().copied().take_while(|&t| t < b_secs - INSIDE_SECS);
    for hi in inner.chain(std::iter::once(b_secs)) {
        let inside = |t: f64| drive_at(t.clamp(lo + INSIDE_SECS, hi - INSIDE_SECS));
        x = engine.rk4_step(&x, lo, hi - lo, &inside);
        lo = hi;
    }
    x
}

/// Broadband stand excitation, one value per sample interval, from its own random stream so the
/// sensor noise is the same with or without it.
fn buffet_sequence(n: usize, std_n: f64, seed: u64) -> Vec<f64> {
    if std_n <= 0.0 {
        return vec![0.0; n];
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(1);
    (0..n).map(|_| std_n * rng.sample::<f64, _>(StandardNormal)).collect()
}

fn add_noise(truth: &Traces, noise: &SensorNoise, seed: u64) -> Traces {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut noisy = |values: &[f64], std: f64| -> Vec<f64> {
        values.iter().map(|v| v + std * rng.sample::<f64, _>(StandardNormal)).collect()
    };
    Traces {
        fuel_gph: noisy(&truth.fuel_gph, noise.fuel_gph),
        speed_rpm: noisy(&truth.speed_rpm, noise.speed_rpm),
        thrust_n: noisy(&truth.thrust_n, noise.thrust_n),
        egt_c: noisy(&truth.egt_c, noise.egt_c),
        temp_c: noisy(&truth.temp_c, noise.temp_c),
        pressure_kpa: noisy(&truth.pressure_kpa, noise.pressure_kpa),
        rh_pct: noisy(&truth.rh_pct, noise.rh_pct),
    }
}

fn to_run(name: &str, t_secs: &[f64], tr: Traces) -> Run {
    Run {
        name: name.to_owned(),
        dt_secs: DT_SECS,
        t_secs: t_secs.to_vec(),
        input: Channel::new(columns::FUEL, tr.fuel_gph),
        outputs: vec![Channel::new(columns::SPEED, tr.speed_rpm), Channel::new(columns::THRUST, tr.thrust_n)],
        aux: vec![
            Channel::new(columns::EGT, tr.egt_c),
            Channel::new(columns::AMBIENT_TEMP, tr.temp_c),
            Channel::new(columns::AMBIENT_PRESSURE, tr.pressure_kpa),
            Channel::new(columns::HUMIDITY, tr.rh_pct),
        ],
    }
}

#[cfg(test)]
mod tests;
