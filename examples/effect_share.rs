//! How much of the error a hidden effect adds, and how much of that its block removes.
//!
//! The pipeline's model of an output carries a structural error of its own (see `wiener_floor`),
//! present with or without any hidden effect. For each effect and seed this prints the third-run
//! error (noiseless truth) of: the pipeline's model on runs with no hidden effect (the floor), the
//! pipeline's model on runs with the effect (before), and the best-ranked trial model (after), and
//! the share of the effect's own error removed, (before − after) / (before − floor).
//!
//! `cargo run --release --example effect_share [SPEC...]`
use jetid::core::diagnose::diagnose;
use jetid::core::effects::ExtendedModel;
use jetid::core::identification::fits::segments_for;
use jetid::core::identification::pipeline::identify_output;
use jetid::core::identification::segment::SegmentSettings;
use jetid::core::identification::settings::OutputSettings;
use jetid::core::numerics::metrics::metrics;
use jetid::core::run::Run;
use jetid::sim::{Effect, SimConfig, SimOutput, TestKind, simulate};

const SPEED: &str = "shaft_speed_rpm";

fn run(kind: TestKind, seed: u64, effects: &[Effect]) -> SimOutput {
    let config = SimConfig::for_test(kind.name(), kind, seed).map(|c| c.with_effects(effects.to_vec()));
    match config.and_then(|c| simulate(&c)) {
        Ok(out) => out,
        Err(e) => panic!("simulating {}: {e}", kind.name()),
    }
}

/// The pipeline's speed model on the runs of `seed` with `effects`.
fn model(ident: &Run) -> (ExtendedModel, jetid::core::identification::fits::SegmentFits, OutputSettings) {
    let settings = OutputSettings::for_output(SPEED);
    let segments = segments_for(ident, None, &SegmentSettings::default()).unwrap_or_else(|e| panic!("{e}"));
    let identified =
        identify_output(ident, SPEED, &settings, &segments, None).unwrap_or_else(|e| panic!("{e}"));
    (ExtendedModel::from_gray_box(&identified.model), identified.fits, settings)
}

fn third_error(model: &ExtendedModel, third: &SimOutput) -> f64 {
    let truth = third.truth.output(SPEED).map(|c| c.values.clone()).unwrap_or_default();
    let y = model.simulate(&third.measured).unwrap_or_else(|e| panic!("{e}"));
    metrics(&truth, &y).map(|m| m.rmspe_pct).unwrap_or(f64::NAN)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let specs = if args.is_empty() {
        vec!["static_map_order:gain=4".to_owned(), "static_map_order:gain=8".to_owned()]
    } else {
        args
    };
    println!("spec | seed | ranked first | floor % | before % | after % | after/before | share removed");
    for spec in &specs {
        let effect: Effect = spec.parse().unwrap_or_else(|e| panic!("{spec}: {e}"));
        for seed in [1u64, 2, 3] {
            let clean_ident = run(TestKind::Ident, seed, &[]).measured;
            let clean_third = run(TestKind::Validation, seed + 300, &[]);
            let (clean_model, ..) = model(&clean_ident);
            let floor = third_error(&clean_model, &clean_third);

            let effects = [effect.clone()];
            let ident = run(TestKind::Ident, seed, &effects).measured;
            let validation = run(TestKind::Validation, seed + 100, &effects).measured;
            let chirp = run(TestKind::Chirp, seed + 200, &effects).measured;
            let third = run(TestKind::Validation, seed + 300, &effects);
            let (current, fits, settings) = model(&ident);
            let report = diagnose(&current, &ident, &fits, &[&validation, &chirp], &settings)
                .unwrap_or_else(|e| panic!("{e}"));
            let Some(best) = report.best() else { continue };
            let before = third_error(&current, &third);
            let after = third_error(&best.model, &third);
            println!(
                "{spec} | {seed} | {} | {floor:.3} | {before:.3} | {after:.3} | {:.2} | {:.0} %",
                best.effect,
                after / before,
                100.0 * (before - after) / (before - floor)
            );
        }
    }
}
