//! How well can *any* Wiener model with the gray-box structure (three poles, no zeros, order-2 static
//! map) reproduce the simulator's noiseless validation run? The linear block's poles are fitted by
//! Levenberg–Marquardt directly on the validation truth (gain, offset and static map re-solved by least
//! squares at each step), starting from the pipeline's model. The result is a floor for the
//! validation RMSPE of the gray-box speed model on this simulator, which the pipeline, fitted on
//! the identification run only, cannot beat.
//!
//! `cargo run --release --example wiener_floor`
use anyhow::{Context, Result};
use jetid::core::identification::fits::segments_for;
use jetid::core::identification::pipeline::{identify_output, predict_wiener};
use jetid::core::identification::segment::SegmentSettings;
use jetid::core::identification::settings::OutputSettings;
use jetid::core::identification::static_map::fit_static_map;
use jetid::core::identification::wiener::fit_linear_block;
use jetid::core::numerics::lm::{
    Damping, Jacobian, LeastSquares, LmError, LmSettings, StepSolver, minimise, no_progress,
};
use jetid::io::csv_run::{LoadOptions, load_run};
use jetid::sim::designs::TestKind;
use jetid::sim::{SimConfig, simulate};
use num_complex::Complex64;

fn main() -> Result<()> {
    let output = "shaft_speed_rpm";
    let ident = load_run("sample_runs/sr30/ident.csv".as_ref(), &LoadOptions::default())?;
    let val = load_run("sample_runs/sr30/validation.csv".as_ref(), &LoadOptions::default())?;
    // sample_runs/README.md: the validation run is `simulate --test validation --seed 12`.
    let truth = simulate(&SimConfig::for_test("validation", TestKind::Validation, 12)?)?.truth;
    let y = &truth.output(output).context("truth has speed")?.values;
    let settings = OutputSettings::for_output(output);
    let segments = segments_for(&ident, None, &SegmentSettings::default())?;
    let model = identify_output(&ident, output, &settings, &segments, None)?.model;
    let pipeline = predict_wiener(&model.wiener, &val, output)?;
    let pipeline_rmspe = jetid::core::numerics::metrics::metrics(y, &pipeline.y_hat)?.rmspe_pct;
    let poles = model.wiener.linear.tf.poles()?;
    let real = poles.iter().find(|p| p.im.abs() < 1e-9).context("a real pole")?;
    let pair = poles.iter().find(|p| p.im > 1e-9).context("a complex pair")?;
    let u = &val.input.values;
    let residual = |th: &[f64]| -> Option<Vec<f64>> {
        let (&[a, re, im], dt) = (th, val.dt_secs) else { return None };
        let poles = [Complex64::new(a, 0.0), Complex64::new(re, im), Complex64::new(re, -im)];
        let block = fit_linear_block(&poles, &[], u, y, dt).ok()?;
        let v = block.simulate(u);
        let map = fit_static_map(&v, y, 2).ok()?;
        Some(v.iter().zip(y).map(|(vk, yk)| (map.eval(*vk) - yk) / yk).collect())
    };
    let settings = LmSettings { max_iterations: 200, cost_tol: 1e-9, damping: Damping::marquardt(12) };
    let mut problem: LeastSquares<_, LmError> =
        LeastSquares::new(residual, Jacobian::default(), StepSolver::Svd);
    let fit = minimise(&mut problem, &[real.re, pair.re, pair.im], &settings, &mut no_progress)?;
    let n = y.len() as f64;
    println!("pipeline (fitted on ident):      validation RMSPE vs truth {pipeline_rmspe:.4} %");
    println!(
        "best Wiener fitted on validation: validation RMSPE vs truth {:.4} % (poles {:.4}, {:.4} ± {:.4}j)",
        100.0 * (fit.cost / n).sqrt(),
        fit.theta.first().unwrap_or(&f64::NAN),
        fit.theta.get(1).unwrap_or(&f64::NAN),
        fit.theta.get(2).unwrap_or(&f64::NAN)
    );
    Ok(())
}
