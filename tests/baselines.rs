//! The black-box baselines: recovery of known systems, determinism, every user error, and the bundled
//! SR-30 runs.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;

use jetid::core::baselines::{
    BaselineError, HwModel, HwOptions, HwOrders, NnarxModel, NnarxOptions, fit_hammerstein_wiener, fit_nnarx,
};
use jetid::core::numerics::metrics::metrics;
use jetid::core::numerics::tf::DiscreteTf;
use jetid::core::run::Run;
use jetid::io::csv_run::{LoadOptions, load_run};
use num_complex::Complex64;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const DT: f64 = 1.0 / 8.85;

/// Random levels in `lo..hi`, each held for 30–100 samples: the identification test's step design.
fn random_levels(n: usize, lo: f64, hi: f64, hold: (usize, usize), seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut u = Vec::with_capacity(n);
    while u.len() < n {
        let level = rng.random_range(lo..hi);
        let len = rng.random_range(hold.0..=hold.1);
        u.extend(std::iter::repeat_n(level, len));
    }
    u.truncate(n);
    u
}

use crate::common::noisy;

fn rmspe(y: &[f64], yhat: &[f64]) -> f64 {
    metrics(y, yhat).unwrap().rmspe_pct
}

/// A model read back from JSON simulates like the original (serde_json's default float parsing may
/// differ in the last bit, so not bit-identical).
fn assert_survives_json<M>(model: &M, simulate: impl Fn(&M) -> Vec<f64>)
where
    M: serde::Serialize + serde::de::DeserializeOwned,
{
    let back: M = serde_json::from_str(&serde_json::to_string(model).unwrap()).unwrap();
    for (a, b) in simulate(model).iter().zip(simulate(&back)) {
        assert!((a - b).abs() <= 1e-9 * a.abs().max(1.0), "{a} vs {b}");
    }
}

fn no_progress() -> impl FnMut(f64) -> bool {
    |_| true
}

// ---------------------------------------------------------------- Hammerstein–Wiener

/// A speed-like Hammerstein–Wiener system: `w = 1 + 0.5u + 0.05u²`, a unit-gain third-order `G`
/// with poles 0.936 and 0.8 ± 0.21j (the paper's speed poles, roughly), `y = 3·10⁴ + 5000v + 200v²`.
fn hw_truth_poles() -> [Complex64; 3] {
    [Complex64::new(0.936, 0.0), Complex64::new(0.8, 0.21), Complex64::new(0.8, -0.21)]
}

fn hw_truth(u: &[f64]) -> Vec<f64> {
    let shape = DiscreteTf::from_zpk(&[], &hw_truth_poles(), 1.0, DT).unwrap();
    let g = DiscreteTf::from_zpk(&[], &hw_truth_poles(), 1.0 / shape.dc_gain().unwrap(), DT).unwrap();
    let w: Vec<f64> = u.iter().map(|u| 1.0 + 0.5 * u + 0.05 * u * u).collect();
    g.simulate_from_steady(&w).iter().map(|v| 3.0e4 + 5000.0 * v + 200.0 * v * v).collect()
}

fn fit_hw_truth() -> HwModel {
    let u = random_levels(2000, 2.0, 7.6, (30, 100), 1);
    let y = noisy(&hw_truth(&u), 50.0, 2);
    fit_hammerstein_wiener(&u, &y, DT, HwOrders::paper_speed(), &HwOptions::default(), &mut no_progress())
        .unwrap()
}

#[test]
fn hw_recovers_a_known_system_on_fresh_input() {
    let model = fit_hw_truth();
    let u_val = random_levels(1500, 2.0, 7.6, (10, 80), 3);
    let err = rmspe(&hw_truth(&u_val), &model.simulate(&u_val));
    eprintln!("HW known system: validation RMSPE {err:.4} %, {:?}", model.diagnostics);
    assert!(err < 0.5, "RMSPE {err} %");
    // The scale conventions hold and the dynamics are the true ones.
    assert!((model.linear.dc_gain().unwrap() - 1.0).abs() < 1e-9);
    assert!(model.input_poly.coeffs[0].abs() < 1e-300 && (model.input_poly.coeffs[1] - 1.0).abs() < 1e-12);
    let poles = model.linear.poles().unwrap();
    for truth in hw_truth_poles() {
        assert!(poles.iter().any(|p| (p - truth).norm() < 0.02), "{poles:?}");
    }
    let d = &model.diagnostics;
    assert!(d.final_rms <= d.initial_rms && d.final_rms < 60.0, "{d:?}");
}

#[test]
fn hw_simulation_starts_settled_and_survives_serde() {
    let model = fit_hw_truth();
    let y = model.simulate(&[5.0; 40]);
    assert!(y.iter().all(|v| (v - y[0]).abs() < 1e-9 * y[0].abs()));
    assert!(model.simulate(&[]).is_empty());
    assert_survives_json(&model, |m: &HwModel| m.simulate(&[3.0, 3.0, 7.0, 7.0, 5.0]));
}

// ---------------------------------------------------------------- NNARX

/// `y(k) = 0.6y(k−1) − 0.1y(k−2) + 0.05y(k−1)² + 0.5·tanh(u(k))`.
fn narx_truth(u: &[f64]) -> Vec<f64> {
    let mut y: Vec<f64> = Vec::with_capacity(u.len());
    for (k, uk) in u.iter().enumerate() {
        let past = |lag: usize| k.checked_sub(lag).map_or(0.0, |i| y[i]);
        y.push(0.6 * past(1) - 0.1 * past(2) + 0.05 * past(1).powi(2) + 0.5 * uk.tanh());
    }
    y
}

fn narx_data(seed: u64) -> (Vec<f64>, Vec<f64>) {
    let u = random_levels(1500, -2.0, 2.0, (5, 30), seed);
    let y = noisy(&narx_truth(&u), 0.005, seed + 100);
    (u, y)
}

fn nrmse_pct(y: &[f64], yhat: &[f64]) -> f64 {
    100.0 * (1.0 - metrics(y, yhat).unwrap().fit_pct / 100.0)
}

#[test]
fn nnarx_recovers_a_known_nonlinear_arx_system() {
    let (u, y) = narx_data(1);
    let model = fit_nnarx(&u, &y, &NnarxOptions::default(), &mut no_progress()).unwrap();
    // Fresh input; the truth starts at rest, so compare after the start-up transient.
    let u_val = random_levels(1000, -1.9, 1.9, (3, 40), 7);
    let truth = narx_truth(&u_val);
    let one_step = model.predict_one_step(&u_val, &truth);
    let oe = model.simulate(&u_val);
    let (one_step_err, oe_err) =
        (nrmse_pct(&truth[20..], &one_step[20..]), nrmse_pct(&truth[20..], &oe[20..]));
    let d = &model.diagnostics;
    eprintln!("NNARX known system: one-step NRMSE {one_step_err:.3} %, OE NRMSE {oe_err:.3} %, {d:?}");
    assert!(one_step_err < 2.0 && oe_err < 3.0, "one-step {one_step_err} %, OE {oe_err} %");
    assert!(d.gamma > 1.0 && d.gamma < d.n_weights as f64 && d.alpha > 0.0 && d.beta > 0.0, "{d:?}");
    assert_eq!(d.restarts.len(), 5);
    assert!(d.restarts.iter().all(|r| r.oe_rms >= d.oe_rms || r.several_equilibria > 0));
    assert!(d.several_equilibria_at.is_empty(), "{d:?}");
}

#[test]
fn nnarx_same_seed_same_model_other_seed_also_converges() {
    let (u, y) = narx_data(2);
    let opts = NnarxOptions { restarts: 2, seed: 11, ..NnarxOptions::default() };
    let a = fit_nnarx(&u, &y, &opts, &mut no_progress()).unwrap();
    let b = fit_nnarx(&u, &y, &opts, &mut no_progress()).unwrap();
    assert_eq!(a, b);
    let c = fit_nnarx(&u, &y, &NnarxOptions { seed: 12, ..opts }, &mut no_progress()).unwrap();
    assert_ne!(a.weights, c.weights);
    let u_val = random_levels(800, -1.9, 1.9, (3, 40), 8);
    let truth = narx_truth(&u_val);
    for model in [&a, &c] {
        let err = nrmse_pct(&truth[20..], &model.simulate(&u_val)[20..]);
        assert!(err < 3.0, "OE NRMSE {err} %");
    }
    assert_survives_json(&a, |m: &NnarxModel| m.simulate(&[0.0, 0.0, 1.5, 1.5, -1.0]));
}

#[test]
fn nnarx_simulation_starts_at_its_equilibrium() {
    let (u, y) = narx_data(3);
    let model =
        fit_nnarx(&u, &y, &NnarxOptions { restarts: 1, ..NnarxOptions::default() }, &mut no_progress())
            .unwrap();
    let eq = model.equilibrium(1.0);
    let sim = model.simulate(&[1.0; 30]);
    assert!(sim.iter().all(|v| (v - eq.y).abs() < 1e-6), "{eq:?} vs {sim:?}");
    // The true equilibrium for u = 1: y = 0.5y + 0.05y² + 0.5·tanh(1).
    let truth = (0.5 - (0.25f64 - 0.2 * 0.5 * 1f64.tanh()).sqrt()) / 0.1;
    assert!((eq.y - truth).abs() < 0.02, "{} vs {truth}", eq.y);
    assert!(model.equilibria(1.0).iter().any(|r| (r - eq.y).abs() < 1e-6));
}

// ---------------------------------------------------------------- user errors

fn steps(n: usize) -> Vec<f64> {
    random_levels(n, 2.0, 7.6, (20, 40), 5)
}

#[test]
fn hw_user_errors_are_typed() {
    let (u, opts, orders) = (steps(300), HwOptions::default(), HwOrders::paper_speed());
    let y = hw_truth(&u);
    let fit = |u: &[f64], y: &[f64], orders: HwOrders| {
        fit_hammerstein_wiener(u, y, DT, orders, &opts, &mut no_progress())
    };
    let needed = orders.samples_needed();
    assert_eq!(
        fit(&u[..20], &y[..20], orders).unwrap_err(),
        BaselineError::TooFewSamples { samples: 20, needed }
    );
    assert_eq!(fit(&u, &y[1..], orders).unwrap_err(), BaselineError::LengthMismatch { u: 300, y: 299 });
    let mut bad = u.clone();
    bad[17] = f64::NAN;
    assert_eq!(fit(&bad, &y, orders).unwrap_err(), BaselineError::NonFinite { what: "input", index: 17 });
    let mut bad = y.clone();
    bad[40] = f64::INFINITY;
    assert_eq!(fit(&u, &bad, orders).unwrap_err(), BaselineError::NonFinite { what: "output", index: 40 });
    assert_eq!(fit(&u, &[7.0e4; 300], orders).unwrap_err(), BaselineError::ConstantSignal { what: "output" });
    let improper = HwOrders { n_zeros: 4, ..orders };
    assert!(matches!(
        fit(&u, &y, improper),
        Err(BaselineError::InvalidOption { option: "n_zeros", value: 4, .. })
    ));
    let static_only = HwOrders { n_poles: 0, ..orders };
    assert!(matches!(fit(&u, &y, static_only), Err(BaselineError::InvalidOption { option: "n_poles", .. })));
    let no_poly = HwOrders { input_poly: 0, ..orders };
    assert!(matches!(fit(&u, &y, no_poly), Err(BaselineError::InvalidOption { option: "input_poly", .. })));
    let bad_dt = fit_hammerstein_wiener(&u, &y, 0.0, orders, &opts, &mut no_progress());
    assert!(matches!(bad_dt, Err(BaselineError::Tf(_))), "{bad_dt:?}");
}

#[test]
fn nnarx_user_errors_are_typed() {
    let u = steps(300);
    let y = hw_truth(&u);
    let opts = NnarxOptions::default();
    let fit = |u: &[f64], y: &[f64], opts: &NnarxOptions| fit_nnarx(u, y, opts, &mut no_progress());
    let needed = opts.samples_needed();
    assert_eq!(
        fit(&u[..50], &y[..50], &opts).unwrap_err(),
        BaselineError::TooFewSamples { samples: 50, needed }
    );
    assert_eq!(fit(&u[1..], &y, &opts).unwrap_err(), BaselineError::LengthMismatch { u: 299, y: 300 });
    let mut bad = y.clone();
    bad[3] = f64::NAN;
    assert_eq!(fit(&u, &bad, &opts).unwrap_err(), BaselineError::NonFinite { what: "output", index: 3 });
    assert_eq!(fit(&[5.0; 300], &y, &opts).unwrap_err(), BaselineError::ConstantSignal { what: "input" });
    for (option, changed) in [
        ("restarts", NnarxOptions { restarts: 0, ..opts.clone() }),
        ("hidden", NnarxOptions { hidden: 0, ..opts.clone() }),
        ("nu", NnarxOptions { nu: 0, ..opts.clone() }),
        ("max_iterations", NnarxOptions { max_iterations: 0, ..opts.clone() }),
    ] {
        assert!(
            matches!(fit(&u, &y, &changed), Err(BaselineError::InvalidOption { option: o, value: 0, .. }) if o == option),
            "{option}"
        );
    }
}

#[test]
fn fits_report_progress_and_can_be_cancelled() {
    let u = steps(400);
    let y = noisy(&hw_truth(&u), 50.0, 9);
    let (orders, hw_opts) = (HwOrders::paper_speed(), HwOptions::default());
    let nn_opts = NnarxOptions { restarts: 2, max_iterations: 10, ..NnarxOptions::default() };
    // Progress starts at 0, never goes back and ends at 1.
    for which in ["hw", "nnarx"] {
        let mut seen = Vec::new();
        let mut record = |f: f64| {
            seen.push(f);
            true
        };
        if which == "hw" {
            fit_hammerstein_wiener(&u, &y, DT, orders, &hw_opts, &mut record).unwrap();
        } else {
            fit_nnarx(&u, &y, &nn_opts, &mut record).unwrap();
        }
        assert!(
            seen.len() > 2 && seen[0].abs() < 1e-15 && (seen[seen.len() - 1] - 1.0).abs() < 1e-15,
            "{seen:?}"
        );
        assert!(seen.windows(2).all(|w| w[0] <= w[1]), "{which}: {seen:?}");
    }
    // Cancel at once, and part-way through.
    for stop_after in [0, 3] {
        let mut calls = 0;
        let mut cancel = |_: f64| {
            calls += 1;
            calls <= stop_after
        };
        let hw = fit_hammerstein_wiener(&u, &y, DT, orders, &hw_opts, &mut cancel);
        assert_eq!(hw.unwrap_err(), BaselineError::Cancelled);
        let mut calls = 0;
        let mut cancel = |_: f64| {
            calls += 1;
            calls <= stop_after
        };
        assert_eq!(fit_nnarx(&u, &y, &nn_opts, &mut cancel).unwrap_err(), BaselineError::Cancelled);
    }
}

// ---------------------------------------------------------------- sr30 sample runs

fn sr30(name: &str) -> Run {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("sample_runs/sr30").join(name);
    load_run(&path, &LoadOptions::default()).unwrap()
}

fn output<'r>(run: &'r Run, name: &str) -> &'r [f64] {
    &run.output(name).unwrap().values
}

/// Fits both baselines to speed and thrust of `ident.csv` and scores them on `validation.csv`.
///
/// Known limitation, asserted as such: the thrust NNARX is trained on noisy thrust (σ ≈ 2 N), so
/// its one-step predictor leans on the past outputs, and on the validation run's 2 → 7.6 gal/h step
/// (a state never seen in `ident.csv`) it is captured by a spurious equilibrium. Its validation
/// RMSPE is only required to be finite, its chirp RMSPE (inside the identified range) below 10 %.
#[test]
fn sr30_baselines_fit_and_validate() {
    let (ident, validation, chirp) = (sr30("ident.csv"), sr30("validation.csv"), sr30("chirp.csv"));
    for (name, orders) in
        [("shaft_speed_rpm", HwOrders::paper_speed()), ("thrust_n", HwOrders::paper_thrust())]
    {
        let (u, y) = (&ident.input.values, output(&ident, name));
        let start = std::time::Instant::now();
        let hw =
            fit_hammerstein_wiener(u, y, ident.dt_secs, orders, &HwOptions::default(), &mut no_progress())
                .unwrap();
        let hw_secs = start.elapsed().as_secs_f64();
        let start = std::time::Instant::now();
        let nn = fit_nnarx(u, y, &NnarxOptions::default(), &mut no_progress()).unwrap();
        let nn_secs = start.elapsed().as_secs_f64();
        let score = |run: &Run, simulate: &dyn Fn(&[f64]) -> Vec<f64>| {
            rmspe(output(run, name), &simulate(&run.input.values))
        };
        let hw_pct = score(&validation, &|u| hw.simulate(u));
        let nn_pct = score(&validation, &|u| nn.simulate(u));
        let hw_chirp = score(&chirp, &|u| hw.simulate(u));
        let nn_chirp = score(&chirp, &|u| nn.simulate(u));
        eprintln!(
            "{name}: HW RMSPE validation {hw_pct:.3} %, chirp {hw_chirp:.3} % ({hw_secs:.2} s, {:?})",
            hw.diagnostics
        );
        eprintln!(
            "{name}: NNARX RMSPE validation {nn_pct:.3} %, chirp {nn_chirp:.3} % ({nn_secs:.2} s, {:?})",
            nn.diagnostics
        );
        assert!(hw_pct < 10.0 && hw_chirp < 10.0, "{name}: HW RMSPE {hw_pct}, chirp {hw_chirp}");
        assert!(nn_pct.is_finite() && nn_chirp < 10.0, "{name}: NNARX RMSPE {nn_pct}, chirp {nn_chirp}");
        if name == "shaft_speed_rpm" {
            assert!(nn_pct < 10.0, "{name}: NNARX RMSPE {nn_pct}");
        }
    }
}
