//! Speed of identification on the bundled sr30 runs:
//! (a) all segment ARX fits of one output, (b) the live path after a cluster change — reduced model,
//! static map, simulation of every validation run, Bode at 512 frequencies, metrics.
//! Run: `cargo bench --bench live_path --no-default-features`.
use std::path::Path;

use jetid::core::identification::fits::{fit_segments_for, segments_for};
use jetid::core::identification::pipeline::{live_update, propose};
use jetid::core::identification::segment::SegmentSettings;
use jetid::core::identification::settings::OutputSettings;
use jetid::core::numerics::tf::log_space;
use jetid::core::run::Run;
use jetid::io::csv_run::{LoadOptions, load_run};

fn main() {
    divan::main();
}

fn sample(name: &str) -> Run {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("sample_runs/sr30").join(name);
    match load_run(&path, &LoadOptions::default()) {
        Ok(run) => run,
        Err(err) => panic!("bench needs the bundled sample runs: {err}"),
    }
}

const OUTPUTS: [&str; 2] = ["shaft_speed_rpm", "thrust_n"];

#[divan::bench(args = OUTPUTS)]
fn segment_fits(bencher: divan::Bencher, output: &str) {
    let ident = sample("ident.csv");
    let settings = OutputSettings::for_output(output);
    let segments = segments_for(&ident, None, &SegmentSettings::default()).unwrap_or_default();
    bencher.bench(|| fit_segments_for(&ident, output, &segments, &settings).map(|f| f.models.len()));
}

fn live(bencher: divan::Bencher, output: &str, refine: bool) {
    let ident = sample("ident.csv");
    let validation = [sample("validation.csv"), sample("chirp.csv")];
    let refs: Vec<&Run> = validation.iter().collect();
    let settings = OutputSettings { refine, ..OutputSettings::for_output(output) };
    let segments = segments_for(&ident, None, &SegmentSettings::default()).unwrap_or_default();
    let Ok(fits) = fit_segments_for(&ident, output, &segments, &settings) else { panic!("fits failed") };
    let Ok(mut clusters) = propose(&fits, &ident, &settings).map(|p| p.clusters) else {
        panic!("no clusters")
    };
    let omegas = log_space(0.05, std::f64::consts::PI / ident.dt_secs, 512);
    let mut k = 0u32;
    bencher.bench_local(|| {
        // A drag step: the first cluster's radius changes a little every call.
        k = k.wrapping_add(1);
        if let Some(c) = clusters.first_mut() {
            c.radius *= if k.is_multiple_of(2) { 1.001 } else { 1.0 / 1.001 };
        }
        live_update(&fits, &ident, &clusters, &settings, &refs, &omegas).map(|r| r.predictions.len())
    });
}

/// The live path as the app runs it while dragging (centroids, no polishing).
#[divan::bench(args = OUTPUTS)]
fn live_path_drag(bencher: divan::Bencher, output: &str) {
    live(bencher, output, false);
}

/// The live path with the simulation-error polish of the reduced roots (what batch does).
#[divan::bench(args = OUTPUTS)]
fn live_path_refined(bencher: divan::Bencher, output: &str) {
    live(bencher, output, true);
}
