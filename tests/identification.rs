//! The gray-box pipeline on systems with known truth.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use jetid::core::identification::cluster::RootKind;
use jetid::core::identification::fits::segments_for;
use jetid::core::identification::pipeline::{identify_output, predict_wiener};
use jetid::core::identification::segment::SegmentSettings;
use jetid::core::identification::settings::OutputSettings;
use jetid::core::numerics::metrics::metrics;
use jetid::core::numerics::tf::DiscreteTf;
use jetid::core::run::{Channel, Run};
use num_complex::Complex64;

const DT: f64 = 1.0 / 8.85;

/// The paper's shaft-speed Wiener model: Gs(z) = 82.70 / ((z − 0.936)(z² − 1.608 z + 0.692)),
/// fs(v) = 2.878e4 + 4.021e-1 v + 1.532e-6 v².
fn paper_speed(u: &[f64]) -> Vec<f64> {
    let gs = DiscreteTf::new(vec![0.0, 0.0, 0.0, 82.70], vec![1.0, -2.544, 2.197088, -0.647712], DT).unwrap();
    gs.simulate_from_steady(u).iter().map(|v| 2.878e4 + 4.021e-1 * v + 1.532e-6 * v * v).collect()
}

fn staircase(levels: &[(f64, f64)]) -> Vec<f64> {
    levels.iter().flat_map(|&(level, secs)| std::iter::repeat_n(level, (secs / DT) as usize)).collect()
}

use crate::common::noisy;

fn run(name: &str, u: Vec<f64>, y: Vec<f64>) -> Run {
    Run {
        name: name.into(),
        dt_secs: DT,
        t_secs: (0..u.len()).map(|k| k as f64 * DT).collect(),
        input: Channel::new("fuel_flow_gph", u),
        outputs: vec![Channel::new("shaft_speed_rpm", y)],
        aux: vec![],
    }
}

/// The identification staircase of the paper-like tests: (fuel flow, seconds) per step.
const IDENT_STEPS: [(f64, f64); 9] = [
    (2.6, 60.0),
    (3.1, 40.0),
    (2.8, 40.0),
    (3.6, 40.0),
    (4.2, 40.0),
    (3.4, 40.0),
    (5.43, 40.0),
    (6.4, 40.0),
    (4.6, 40.0),
];

#[test]
fn paper_wiener_system_is_identified_to_under_0_2_pct() {
    let u_ident = staircase(&IDENT_STEPS);
    let y_ident = paper_speed(&u_ident);
    let ident = run("ident", noisy(&u_ident, 0.000327, 1), noisy(&y_ident, 5.07, 2));
    let settings = OutputSettings::for_output("shaft_speed_rpm");
    let segments = segments_for(&ident, None, &SegmentSettings::default()).unwrap();
    assert_eq!(segments.len(), 8);
    let result = identify_output(&ident, "shaft_speed_rpm", &settings, &segments, None).unwrap();

    let poles: Vec<Complex64> = result
        .evals
        .iter()
        .filter(|e| e.valid && e.cluster.kind == RootKind::Pole)
        .flat_map(|e| e.reduced_roots())
        .collect();
    assert!(poles.iter().any(|p| (p - Complex64::new(0.936, 0.0)).norm() < 0.02), "poles {poles:?}");

    // Validation: fast steps, a ramp and a sinusoid, scored against the noiseless output.
    let mut u_val = staircase(&[(3.0, 30.0), (5.0, 8.0), (3.5, 8.0), (6.0, 20.0)]);
    u_val.extend((0..300).map(|k| 6.0 - 3.0 * k as f64 / 300.0));
    u_val.extend((0..400).map(|k| 4.5 + 1.2 * (0.8 * k as f64 * DT).sin()));
    let y_true = paper_speed(&u_val);
    let val = run("val", noisy(&u_val, 0.000327, 3), noisy(&y_true, 5.07, 4));
    let pred = predict_wiener(&result.model.wiener, &val, "shaft_speed_rpm").unwrap();
    let m = metrics(&y_true, &pred.y_hat).unwrap();
    // The refined denominator is the paper's (z − 0.936)(z² − 1.608 z + 0.692).
    let den = &result.model.wiener.linear.tf.den_zinv;
    let truth = [1.0, -2.544, 2.197088, -0.647712];
    assert_eq!(den.len(), 4, "three poles expected, got {den:?}");
    for (a, b) in den.iter().zip(truth) {
        assert!((a - b).abs() < 0.01, "{den:?}");
    }
    assert!(m.rmspe_pct < 0.2, "validation RMSPE {:.4} %", m.rmspe_pct);
}

/// No dead ends: when no candidate cluster can be drawn (here the settings allow no circle wider
/// than 1e-4, so the noisy segment roots never gather), the linear block is fitted directly by
/// output error, the proposal says so in words, and the model still follows the engine.
#[test]
fn without_any_cluster_the_model_is_fitted_directly_and_says_so() {
    let u_ident = staircase(&IDENT_STEPS);
    let ident = run("ident", noisy(&u_ident, 0.000327, 1), noisy(&paper_speed(&u_ident), 5.07, 2));
    let mut settings = OutputSettings::for_output("shaft_speed_rpm");
    settings.cluster.max_radius = 1e-4;
    let segments = segments_for(&ident, None, &SegmentSettings::default()).unwrap();
    let result = identify_output(&ident, "shaft_speed_rpm", &settings, &segments, None).unwrap();
    let proposal = result.proposal.as_ref().unwrap();
    assert!(proposal.clusters.is_empty(), "{:?}", proposal.clusters);
    let note = proposal.direct.as_ref().map(|d| d.note.clone()).unwrap();
    assert!(note.contains("fitted directly"), "{note}");
    assert_eq!(result.model.direct_fit.as_deref(), Some(note.as_str()));
    assert!(result.model.roots.iter().all(|g| g.region.is_none() && g.kind == RootKind::Pole));

    let u_val = staircase(&[(3.0, 30.0), (5.0, 20.0), (3.5, 20.0), (6.0, 20.0)]);
    let y_true = paper_speed(&u_val);
    let val = run("val", noisy(&u_val, 0.000327, 3), noisy(&y_true, 5.07, 4));
    let pred = predict_wiener(&result.model.wiener, &val, "shaft_speed_rpm").unwrap();
    let m = metrics(&y_true, &pred.y_hat).unwrap();
    assert!(m.rmspe_pct < 0.5, "direct fit validation RMSPE {:.4} %", m.rmspe_pct);
}
