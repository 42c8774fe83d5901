//! A simulated fleet: engines drawn from a family ([`super::family`]), each with a commissioning run
//! (the identification design, to identify its reference from) and a series of test-bench runs,
//! each with a hidden health state:
//! - **fuel-meter calibration drift**: the meter's gain wanders slowly from run to run (a random walk
//!   of 0.3 % a run from an initial error of 1 %, the order of a turbine flow meter's drift between
//!   calibrations); the logged fuel is the burnt fuel times the meter's gain, so the engine seems to
//!   need 1/gain of the logged fuel.
//! - **thrust loss**: the thrust at the same speed falls linearly over the runs (wear of the turbine
//!   and nozzle; up to 0.25 N a run), a shift of the thrust map;
//! - **faults** (each run with probability `fault_rate`, one of three): the meter's calibration
//!   steps by 12 % (a meter replaced or miswired), the spool is 60 % slower (a bearing or rub), or the
//!   fuel supply fails during the top hold (the delivered fuel sinks from the top to 5.5 gal/h while
//!   the pump, read as the input, sits at its limit), or the spool's acceleration and deceleration
//!   are limited (a control unit's acceleration schedule set too low, or a fuel valve that sticks:
//!   the simulator's rate limit with its default rates, an effect of the catalog that no health
//!   delta stands for). At most a quarter of an engine's runs.
//!
//! Pure: the runs and their truth; the command line writes the files.
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use super::designs::{MAX_FUEL_GPH, Segment, Shape};
use super::effects::Effect;
use super::{DrawnEngine, EngineFamily, FuelProfile, SimConfig, SimError, TestKind, simulate};
use crate::core::effects::EffectId;
use crate::core::run::Run;

/// Stream of the generator that draws health states (the family uses 7, noise 0, buffeting 1).
const HEALTH_STREAM: u64 = 11;
/// The first hold (s) and each later hold (s): 25 s is over ten of the slowest spool time constants
/// of the family (2.5 s), so every hold settles.
const FIRST_HOLD_SECS: f64 = 20.0;
const HOLD_SECS: f64 = 25.0;
/// Range of the holds' fuel levels, gal/h (the family's running line is checked over idle to top).
const LOW_FUEL_GPH: f64 = 2.4;
const HIGH_FUEL_GPH: f64 = 7.2;
/// Where the delivered fuel sinks to when the supply fails, gal/h.
const STARVED_FUEL_GPH: f64 = 5.5;
/// The faults' sizes: a 12 % calibration step, a 60 % slower spool.
const CALIBRATION_STEP: f64 = 1.12;
const SLOW_SPOOL: f64 = 1.6;
/// At most one run in this many of an engine is faulty: an engine's normal band is what most of its
/// runs do (the fleet's median breaks down when half its runs are off), so a fleet whose engines
/// are mostly faulty would test the band's breakdown, not the flags.
const MAX_FAULT_SHARE: usize = 4;

/// What to simulate.
#[derive(Clone, Debug, PartialEq)]
pub struct FleetConfig {
    pub engines: usize,
    pub runs: usize,
    pub seed: u64,
    /// Length of each run, s (at least the first hold and three more).
    pub run_secs: f64,
    /// Probability that a run has a fault.
    pub fault_rate: f64,
}

/// A fault of one run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fault {
    CalibrationStep,
    SlowSpool,
    FuelStarvation,
    RateLimit,
}

impl Fault {
    pub fn name(self) -> &'static str {
        match self {
            Self::CalibrationStep => "calibration_step",
            Self::SlowSpool => "slow_spool",
            Self::FuelStarvation => "fuel_starvation",
            Self::RateLimit => "rate_limit",
        }
    }
}

/// The hidden health of one run.
#[derive(Clone, Debug, PartialEq)]
pub struct RunHealth {
    /// The fuel meter's gain (logged = burnt × gain), the fault's step included.
    pub meter_gain: f64,
    /// What the fleet should find as the input gain: 1 / meter gain.
    pub input_gain: f64,
    /// The spool's time constant over the engine's own.
    pub tau_scale: f64,
    /// The thrust's shift at the same speed, N (negative: lost).
    pub thrust_shift_n: f64,
    pub fault: Option<Fault>,
}

/// One simulated engine.
#[derive(Clone, Debug)]
pub struct SimulatedEngine {
    pub drawn: DrawnEngine,
    pub commissioning: Run,
    pub runs: Vec<(Run, RunHealth)>,
}

/// Check a fleet's sizes before simulating it.
pub fn check(cfg: &FleetConfig) -> Result<(), SimError> {
    let min_secs = FIRST_HOLD_SECS + 3.0 * HOLD_SECS;
    if cfg.engines == 0 || cfg.runs == 0 || !(cfg.run_secs.is_finite() && cfg.run_secs >= min_secs) {
        return Err(SimError::BadFleet {
            reason: format!("a fleet needs at least one engine, one run and runs of at least {min_secs} s"),
        });
    }
    if !(0.0..=1.0).contains(&cfg.fault_rate) {
        return Err(SimError::BadFleet {
            reason: format!("the fault rate {} is not a probability", cfg.fault_rate),
        });
    }
    Ok(())
}

/// Engine `index` of the fleet: drawn, commissioned and run.
pub fn simulate_engine(cfg: &FleetConfig, index: usize) -> Result<SimulatedEngine, SimError> {
    let engine_seed = cfg.seed.wrapping_mul(1_000_003).wrapping_add(index as u64);
    let drawn = EngineFamily::small_turbojets().draw(engine_seed);
    let commissioning =
        simulate(&SimConfig::for_test("commissioning", TestKind::Ident, engine_seed)?.on_engine(&drawn))?
            .measured;
    let mut rng = ChaCha8Rng::seed_from_u64(engine_seed);
    rng.set_stream(HEALTH_STREAM);
    let normal = |sd: f64| Normal::new(0.0, sd).map_err(|e| SimError::BadFleet { reason: e.to_string() });
    let (start, walk) = (normal(0.01)?, normal(0.003)?);
    let mut meter = 1.0 + start.sample(&mut rng);
    let loss_per_run = rng.random_range(0.0..0.25);
    let mut runs = Vec::with_capacity(cfg.runs);
    let mut faults = 0;
    for r in 0..cfg.runs {
        meter += walk.sample(&mut rng);
        let drawn_fault = rng.random_bool(cfg.fault_rate);
        let fault =
            (drawn_fault && faults < cfg.runs / MAX_FAULT_SHARE).then(|| match rng.random_range(0..4) {
                0 => Fault::CalibrationStep,
                1 => Fault::SlowSpool,
                2 => Fault::FuelStarvation,
                _ => Fault::RateLimit,
            });
        faults += usize::from(fault.is_some());
        let meter_gain = if fault == Some(Fault::CalibrationStep) { meter * CALIBRATION_STEP } else { meter };
        let health = RunHealth {
            meter_gain,
            input_gain: 1.0 / meter_gain,
            tau_scale: if fault == Some(Fault::SlowSpool) { SLOW_SPOOL } else { 1.0 },
            thrust_shift_n: -loss_per_run * r as f64,
            fault,
        };
        let levels = hold_levels(cfg.run_secs, &mut rng);
        let run = simulate_run(
            &drawn,
            &format!("run{:02}", r + 1),
            engine_seed ^ ((r as u64 + 1) << 20),
            &levels,
            &health,
        )?;
        runs.push((run, health));
    }
    Ok(SimulatedEngine { drawn, commissioning, runs })
}

/// The holds of a run: a mid start, then levels at least 0.6 gal/h apart, the last at the top.
fn hold_levels(run_secs: f64, rng: &mut ChaCha8Rng) -> Vec<f64> {
    let holds = ((run_secs - FIRST_HOLD_SECS) / HOLD_SECS).floor().max(3.0) as usize;
    let mut levels = vec![4.5];
    for _ in 1..holds {
        let last = levels.last().copied().unwrap_or(4.5);
        let mut next = rng.random_range(LOW_FUEL_GPH..HIGH_FUEL_GPH);
        while (next - last).abs() < 0.6 {
            next = rng.random_range(LOW_FUEL_GPH..HIGH_FUEL_GPH);
        }
        levels.push(next);
    }
    levels.push(MAX_FUEL_GPH);
    levels
}

fn simulate_run(
    drawn: &DrawnEngine,
    name: &str,
    seed: u64,
    levels: &[f64],
    health: &RunHealth,
) -> Result<Run, SimError> {
    let starved = health.fault == Some(Fault::FuelStarvation);
    let last = levels.len() - 1;
    let segments: Vec<Segment> = levels
        .iter()
        .enumerate()
        .map(|(i, &fuel_gph)| {
            let duration_secs = if i == 0 { FIRST_HOLD_SECS } else { HOLD_SECS };
            let shape = if starved && i == last {
                Shape::Ramp { from_gph: fuel_gph, to_gph: STARVED_FUEL_GPH }
            } else {
                Shape::Hold { fuel_gph }
            };
            Segment { duration_secs, shape }
        })
        .collect();
    let mut cfg = SimConfig::for_test(name, TestKind::Validation, seed)?.on_engine(drawn);
    cfg.profile = FuelProfile::new(segments, super::DT_SECS)?;
    cfg.engine.spool_tau_ref_secs *= health.tau_scale;
    if health.fault == Some(Fault::RateLimit) {
        cfg.effects = vec![Effect::with_defaults(EffectId::RateLimit)?];
    }
    let mut run = simulate(&cfg)?.measured;
    let top_from = ((cfg.profile.duration_secs() - HOLD_SECS) / super::DT_SECS).ceil() as usize;
    for (k, u) in run.input.values.iter_mut().enumerate() {
        // The pump at its limit reads its limit exactly (an actuator's end stop, not a measurement).
        *u = if starved && k >= top_from { MAX_FUEL_GPH * health.meter_gain } else { *u * health.meter_gain };
    }
    if let Some(thrust) = run.outputs.iter_mut().find(|c| c.name == super::columns::THRUST) {
        thrust.values.iter_mut().for_each(|f| *f += health.thrust_shift_n);
    }
    Ok(run)
}
