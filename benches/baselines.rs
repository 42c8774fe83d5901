//! Speed of the black-box baselines on the bundled sr30 identification run (the baselines were most
//! of the batch's time): the NNARX training (5 restarts of 100 Levenberg–Marquardt iterations, the
//! paper's network) and the Hammerstein–Wiener fit, per output.
//! Run: `cargo bench --bench baselines --no-default-features`.
use std::path::Path;

use jetid::core::baselines::{HwOptions, HwOrders, NnarxOptions, fit_hammerstein_wiener, fit_nnarx};
use jetid::core::run::Run;
use jetid::io::csv_run::{LoadOptions, load_run};

fn main() {
    divan::main();
}

fn ident() -> Run {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("sample_runs/sr30/ident.csv");
    match load_run(&path, &LoadOptions::default()) {
        Ok(run) => run,
        Err(err) => panic!("bench needs the bundled sample runs: {err}"),
    }
}

const OUTPUTS: [&str; 2] = ["shaft_speed_rpm", "thrust_n"];

fn signals(run: &Run, output: &str) -> (Vec<f64>, Vec<f64>) {
    let y = run.output(output).map(|c| c.values.clone()).unwrap_or_default();
    (run.input.values.clone(), y)
}

#[divan::bench(args = OUTPUTS, sample_count = 5)]
fn nnarx(bencher: divan::Bencher, output: &str) {
    let (u, y) = signals(&ident(), output);
    bencher.bench(|| fit_nnarx(&u, &y, &NnarxOptions::default(), &mut |_| true).map(|m| m.weights.len()));
}

#[divan::bench(args = OUTPUTS, sample_count = 5)]
fn hammerstein_wiener(bencher: divan::Bencher, output: &str) {
    let run = ident();
    let (u, y) = signals(&run, output);
    let orders = HwOrders { input_poly: 2, n_poles: 2, n_zeros: 1, output_poly: 2 };
    bencher.bench(|| {
        fit_hammerstein_wiener(&u, &y, run.dt_secs, orders, &HwOptions::default(), &mut |_| true).is_ok()
    });
}
