//! Unit tests of the simulator as a whole: calibration, linearised poles, noise, effects.
#![allow(clippy::unwrap_used)]

use super::ambient::STANDARD_DAY;
use super::engine::Drive;
use super::*;
use crate::core::effects::EffectId;

fn drive(fuel_cmd_gph: f64) -> Drive {
    Drive { fuel_cmd_gph, ambient: STANDARD_DAY, corrected: false, buffet_n: 0.0 }
}

fn base_engine() -> Engine {
    Engine::new(EngineParams::default(), ActiveEffects::none())
}

fn steady(engine: &Engine, fuel_gph: f64) -> (f64, f64) {
    let d = drive(fuel_gph);
    let x = engine.steady_state(&d).unwrap();
    let out = engine.outputs(&x, &d);
    (out.speed_rpm, out.thrust_n)
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

fn std(v: &[f64]) -> f64 {
    let m = mean(v);
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() as f64 - 1.0)).sqrt()
}

#[test]
fn steady_map_hits_the_calibration_points() {
    let engine = base_engine();
    let (speed, thrust) = steady(&engine, designs::REF_FUEL_GPH);
    assert!((speed - 73_850.0).abs() < 100.0, "{speed}");
    assert!((80.0..=95.0).contains(&thrust), "{thrust}");
    let (speed, thrust) = steady(&engine, designs::IDLE_FUEL_GPH);
    assert!((speed - 45_000.0).abs() < 500.0, "{speed}");
    assert!((20.0..=35.0).contains(&thrust), "{thrust}");
    let (speed, thrust) = steady(&engine, designs::MAX_FUEL_GPH);
    assert!((speed - 87_000.0).abs() < 500.0, "{speed}");
    assert!((thrust - 178.0).abs() < 5.0, "{thrust}");
}

#[test]
fn steady_state_is_an_equilibrium() {
    let engine = Engine::new(
        EngineParams::default(),
        ActiveEffects::from_effects(&[
            Effect::with_defaults(EffectId::ThermalSoak).unwrap(),
            Effect::with_defaults(EffectId::StaticMapOrder).unwrap(),
            Effect::with_defaults(EffectId::SensorDynamics).unwrap(),
        ])
        .unwrap(),
    );
    for fuel in [2.0, 4.0, 5.43, 7.6] {
        let x = engine.steady_state(&drive(fuel)).unwrap();
        let dx = engine.derivative(&x, &drive(fuel));
        assert!(dx.iter().all(|d| d.abs() < 1e-6), "{fuel}: {dx:?}");
    }
}

#[test]
fn linearised_speed_poles_match_the_paper() {
    let poles = base_engine().speed_poles_z(&drive(5.43), DT_SECS).unwrap();
    assert_eq!(poles.len(), 3);
    let real: Vec<_> = poles.iter().filter(|p| p.im.abs() < 1e-9).collect();
    let complex: Vec<_> = poles.iter().filter(|p| p.im > 1e-9).collect();
    assert_eq!((real.len(), complex.len()), (1, 1), "{poles:?}");
    assert!((real[0].re - 0.936).abs() < 0.005, "{poles:?}");
    assert!((complex[0].re - 0.80).abs() < 0.02 && (complex[0].im - 0.21).abs() < 0.02, "{poles:?}");
}

#[test]
fn spool_slows_down_at_low_speed() {
    let engine = base_engine();
    let real_pole = |fuel: f64| {
        let poles = engine.speed_poles_z(&drive(fuel), DT_SECS).unwrap();
        poles.iter().filter(|p| p.im.abs() < 1e-9).map(|p| p.re).fold(0.0, f64::max)
    };
    assert!(real_pole(2.0) > real_pole(5.43) && real_pole(5.43) > real_pole(7.6));
}

#[test]
fn thrust_path_is_dominated_by_the_spool_pole() {
    let poles = base_engine().thrust_poles_z(&drive(5.43), DT_SECS).unwrap();
    let slowest = poles.first().unwrap();
    assert!(slowest.im.abs() < 1e-9 && (slowest.re - 0.936).abs() < 0.005, "{poles:?}");
    // The stand is fast and mildly damped: its poles sit well inside the unit circle.
    assert!(poles.iter().filter(|p| p.im.abs() > 0.5).all(|p| p.norm() < 0.6), "{poles:?}");
}

#[test]
fn steady_run_noise_matches_the_paper() {
    let out = simulate(&SimConfig::for_test("steady", TestKind::Steady, 7).unwrap()).unwrap();
    let run = &out.measured;
    assert_eq!(run.len(), 300);
    let speed = &run.output(columns::SPEED).unwrap().values;
    let thrust = &run.output(columns::THRUST).unwrap().values;
    let fuel = &run.input.values;
    assert!((mean(speed) - 73_850.0).abs() < 100.0);
    assert!((80.0..=95.0).contains(&mean(thrust)));
    for (values, paper) in [(speed, 50.7), (thrust, 2.08), (fuel, 0.00327)] {
        let ratio = std(values) / paper;
        assert!((0.8..=1.2).contains(&ratio), "std ratio {ratio}");
    }
    // The truth is flat: the run starts settled.
    let truth = &out.truth.output(columns::SPEED).unwrap().values;
    assert!(std(truth) < 1e-6);
}
