//! Operating points checked against the model's own simulation: the local gain against a finite
//! difference of steady-state predictions, the local linear model against the response of the full
//! nonlinear model to a small step, both with every effect that changes the dynamics applied.
#![allow(clippy::unwrap_used)]
use jetid::core::control::{PointSource, operating_points};
use jetid::core::effects::{
    EffectBlock, ExtendedModel, ScheduledTimeConstant, SensorDynamics, StaticMapOrder, ThermalSoak,
    TransportDelay,
};
use jetid::core::identification::static_map::{Beyond, StaticMap};
use jetid::core::identification::wiener::{LinearBlock, WienerModel, unit_gain_tf};
use jetid::core::run::{Channel, Run};
use num_complex::Complex64;

const DT: f64 = 0.1;
const RANGE: (f64, f64) = (2.0, 10.0);

/// A two-pole spool model (gain 4 from the input to v) with a concave map, a kink, and the effects
/// that shape the dynamics.
fn model(effects: &[EffectBlock]) -> ExtendedModel {
    let poles = [Complex64::new(0.96, 0.0), Complex64::new(0.6, 0.0)];
    let unit = unit_gain_tf(&poles, &[Complex64::new(0.2, 0.0)], DT).unwrap();
    let tf = jetid::core::numerics::tf::DiscreteTf::new(
        unit.num_zinv.iter().map(|b| 4.0 * b).collect(),
        unit.den_zinv.clone(),
        DT,
    )
    .unwrap();
    // Inputs below 2.25 read the map beyond its range (v < 10), where it continues its end.
    let map = StaticMap {
        v_center: 25.0,
        v_scale: 15.0,
        coeffs_scaled: vec![60.0, 30.0, -4.0],
        beyond: Beyond::EndTrend,
    };
    let mut m = ExtendedModel::new("speed_rpm", WienerModel { linear: LinearBlock { tf, offset: 1.0 }, map });
    for e in effects {
        m = m.with_effect(e.clone()).unwrap();
    }
    m
}

fn effects() -> Vec<EffectBlock> {
    let span: Vec<f64> = vec![RANGE.0, RANGE.1];
    let mut scheduled = ScheduledTimeConstant::for_input(&span, 1.2);
    scheduled.state_log_ratio = 0.4;
    vec![
        EffectBlock::TransportDelay(TransportDelay { delay_samples: 2.4 }),
        EffectBlock::ThermalSoak(ThermalSoak { gain: 0.15, tau_s: 8.0, power_exponent: 1.5 }),
        EffectBlock::ScheduledTimeConstant(scheduled),
        EffectBlock::SensorDynamics(SensorDynamics { freq_hz: 1.5, zeta: 0.35, lag_s: 0.05 }),
        EffectBlock::StaticMapOrder(StaticMapOrder { knot_v: 26.5, slope_change: -0.8 }),
    ]
}

fn run(u: Vec<f64>) -> Run {
    Run {
        name: "schedule".into(),
        dt_secs: DT,
        t_secs: (0..u.len()).map(|k| k as f64 * DT).collect(),
        input: Channel::new("fuel_flow_gph", u),
        outputs: vec![],
        aux: vec![],
    }
}

/// The model's steady output at `u`, reached by simulation from another level (far from `u`) over
/// a hundred times the slowest time constant.
fn settled(m: &ExtendedModel, u: f64) -> f64 {
    let mut input = vec![RANGE.0 + RANGE.1 - u; 10];
    input.extend(vec![u; 6000]);
    *m.simulate(&run(input)).unwrap().last().unwrap()
}

#[test]
fn local_gains_are_the_slope_of_the_simulated_steady_states() {
    for (label, m) in [("plain", model(&[])), ("all effects", model(&effects()))] {
        let points = operating_points(&m, RANGE, &[("steady_run".into(), 6.3)]).unwrap();
        assert_eq!(points.len(), 10, "{label}: nine grid points and the plateau");
        assert_eq!(points[9].source, PointSource::SteadyRun("steady_run".into()));
        for p in &points {
            let h = 1e-3;
            let fd = (settled(&m, p.u + h) - settled(&m, p.u - h)) / (2.0 * h);
            assert!(
                (p.gain - fd).abs() <= 1e-5 * fd.abs().max(1.0),
                "{label}, u = {}: gain {} vs {fd}",
                p.u,
                p.gain
            );
            assert!((p.y - settled(&m, p.u)).abs() <= 1e-8 * p.y.abs(), "{label}, u = {}: y* {}", p.u, p.y);
        }
        // The concave map and the kink make the gain fall along the range.
        assert!(points[0].gain > points[8].gain, "{label}: {} vs {}", points[0].gain, points[8].gain);
    }
}

#[test]
fn the_local_model_is_the_response_of_the_full_model_to_a_small_step() {
    let m = model(&effects());
    let points = operating_points(&m, RANGE, &[]).unwrap();
    for p in [&points[1], &points[4], &points[7]] {
        let h = 1e-4 * (RANGE.1 - RANGE.0);
        let n = 600;
        let mut input = vec![p.u; 5];
        input.extend(vec![p.u + h; n]);
        let y = m.simulate(&run(input.clone())).unwrap();
        let step: Vec<f64> = input.iter().map(|x| x - p.u).collect();
        let linear = p.local.simulate_with_history(&step, 0.0, 0.0);
        let scale = p.gain.abs() * h;
        let worst = y.iter().zip(&linear).map(|(a, b)| ((a - p.y) - b).abs()).fold(0.0, f64::max);
        assert!(worst <= 2e-3 * scale, "u = {}: worst deviation {worst} against a step of {scale}", p.u);
    }
    // The schedule makes the low end slower.
    let rise = |i: usize| points[i].step.rise_s.unwrap();
    assert!(rise(0) > 1.5 * rise(8), "{} vs {}", rise(0), rise(8));
}

#[test]
fn every_point_has_a_continuous_equivalent_with_its_gain() {
    let m = model(&effects());
    for p in operating_points(&m, RANGE, &[]).unwrap() {
        let c = p.continuous.as_ref().unwrap_or_else(|| panic!("u = {}: {:?}", p.u, p.continuous_note));
        let dc = c.num_s.last().unwrap() / c.den_s.last().unwrap();
        assert!((dc - p.gain).abs() <= 1e-6 * p.gain.abs(), "u = {}: {dc} vs {}", p.u, p.gain);
        assert!(p.bandwidth_rad_s.is_some_and(|w| w > 0.0));
        assert!(p.step.rise_s.is_some_and(|r| r > 0.0) && p.step.settling_s.is_some());
    }
}

#[test]
fn a_bad_range_is_an_error_with_the_range() {
    let m = model(&[]);
    let err = operating_points(&m, (5.0, 5.0), &[]).unwrap_err();
    assert!(err.to_string().contains("5..5"), "{err}");
}
