//! The automatic identification on engines it was never tuned on: for engines drawn from the
//! small-turbojet family (`jetid simulate --engine SEED`), the automatic model's held-out error
//! against the noiseless truth, beside a direct output-error Wiener fit with the same number of
//! poles on the same identification data.
//!
//! `cargo run --release --example family_study -- [FIRST_ENGINE] [ENGINES] [EFFECT_SPEC]`
use anyhow::{Context, Result};
use jetid::core::identification::cluster::RootKind;
use jetid::core::identification::direct_fit::direct_fit_of_order;
use jetid::core::identification::fits::segments_for;
use jetid::core::identification::pipeline::{identify_output, predict_wiener};
use jetid::core::identification::reduce::{IdentData, count_of};
use jetid::core::identification::segment::SegmentSettings;
use jetid::core::identification::settings::OutputSettings;
use jetid::core::numerics::metrics::metrics;
use jetid::sim::{EngineFamily, SimConfig, TestKind, simulate};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let first: u64 = args.get(1).map_or(Ok(1), |s| s.parse()).context("first engine")?;
    let count: u64 = args.get(2).map_or(Ok(8), |s| s.parse()).context("engine count")?;
    let effects: Vec<jetid::sim::Effect> = args.get(3).map(|s| s.parse()).transpose()?.into_iter().collect();
    let family = EngineFamily::small_turbojets();
    println!("| engine | output | poles/zeros | auto % | direct % | ratio | kept (m/J) |");
    println!("|---|---|---|---|---|---|---|");
    let mut ratios = Vec::new();
    for seed in first..first + count {
        let engine = family.draw(seed);
        eprintln!("{}", engine.describe());
        let run = |kind: TestKind, noise_seed: u64| -> Result<_> {
            Ok(simulate(
                &SimConfig::for_test(kind.name(), kind, noise_seed)?
                    .on_engine(&engine)
                    .with_effects(effects.clone()),
            )?)
        };
        let ident = run(TestKind::Ident, seed)?.measured;
        let validation = run(TestKind::Validation, seed + 1000)?;
        let segments = segments_for(&ident, None, &SegmentSettings::default())?;
        for output in ["shaft_speed_rpm", "thrust_n"] {
            let settings = OutputSettings::for_output(output);
            let start = std::time::Instant::now();
            let identified = match identify_output(&ident, output, &settings, &segments, None) {
                Ok(i) => i,
                Err(e) => {
                    println!("| {seed} | {output} | – | failed: {e} | | | |");
                    continue;
                }
            };
            let elapsed = start.elapsed().as_secs_f64();
            let truth = &validation.truth.output(output).context("truth")?.values;
            let score = |w: &jetid::core::identification::wiener::WienerModel| -> Result<f64> {
                let p = predict_wiener(w, &validation.measured, output)?;
                Ok(metrics(truth, &p.y_hat)?.rmspe_pct)
            };
            let auto = score(&identified.model.wiener)?;
            let groups = &identified.model.roots;
            let (np, nz) = (count_of(groups, RootKind::Pole), count_of(groups, RootKind::Zero));
            let delay = identified.proposal.as_ref().map_or(0, |p| p.dead_time.in_model());
            let data = IdentData::new(&identified.fits, &ident, &settings)?.with_delay(delay);
            let direct =
                direct_fit_of_order(&data, np, std::slice::from_ref(groups)).context("direct fit")?;
            let direct_model = jetid::core::identification::wiener::WienerModel {
                linear: direct.assembled.wiener.linear.clone(),
                map: direct.assembled.wiener.map.clone(),
            };
            let direct_pct = score(&direct_model)?;
            let kept: Vec<String> = identified
                .proposal
                .iter()
                .flat_map(|p| p.verdicts.iter().filter(|v| v.kept()))
                .map(|v| {
                    format!(
                        "{:.3}{:+.3}j {}/{}",
                        v.cluster.centre.re, v.cluster.centre.im, v.segments_found, v.segments_total
                    )
                })
                .collect();
            let ratio = auto / direct_pct;
            if output == "shaft_speed_rpm" {
                ratios.push(ratio);
            }
            println!(
                "| {seed} | {output} | {np}/{nz}{} | {auto:.3} | {direct_pct:.3} | {ratio:.2} | {} {} ({elapsed:.1} s) |",
                if delay > 0 { format!(" +{delay} dead") } else { String::new() },
                kept.join("; "),
                identified.model.direct_fit.as_ref().map_or("", |_| "DIRECT")
            );
            if let Some(p) = &identified.proposal {
                for s in p.sentences() {
                    eprintln!("    {output}: {s}");
                }
            }
        }
    }
    ratios.sort_by(f64::total_cmp);
    println!("speed ratio auto/direct: {ratios:.2?}");
    Ok(())
}
