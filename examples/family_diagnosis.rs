//! The missing-physics diagnosis on engines of the small-turbojet family, with or without a hidden
//! effect: what ranks first, what is significant, and the evidence, for both outputs.
//!
//! `cargo run --release --example family_diagnosis -- FIRST_ENGINE ENGINES [EFFECT_SPEC]`
//! e.g. `-- 1 6 transport_delay:delay_s=0.9`
use anyhow::{Context, Result};
use jetid::core::diagnose::{DiagnosisKind, diagnose};
use jetid::core::effects::ExtendedModel;
use jetid::core::identification::fits::segments_for;
use jetid::core::identification::pipeline::identify_output;
use jetid::core::identification::segment::SegmentSettings;
use jetid::core::identification::settings::OutputSettings;
use jetid::sim::{Effect, EngineFamily, SimConfig, TestKind, simulate};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let first: u64 = args.get(1).map_or(Ok(1), |s| s.parse()).context("first engine")?;
    let count: u64 = args.get(2).map_or(Ok(4), |s| s.parse()).context("engine count")?;
    let effects: Vec<Effect> = args.get(3).map(|s| s.parse()).transpose()?.into_iter().collect();
    let family = EngineFamily::small_turbojets();
    for seed in first..first + count {
        let engine = family.draw(seed);
        println!("{}", engine.describe());
        let run = |kind: TestKind, noise_seed: u64| -> Result<_> {
            let cfg = SimConfig::for_test(kind.name(), kind, noise_seed)?
                .on_engine(&engine)
                .with_effects(effects.clone());
            Ok(simulate(&cfg)?.measured)
        };
        let ident = run(TestKind::Ident, seed)?;
        let validation = run(TestKind::Validation, seed + 1000)?;
        let chirp = run(TestKind::Chirp, seed + 2000)?;
        let segments = segments_for(&ident, None, &SegmentSettings::default())?;
        for output in ["shaft_speed_rpm", "thrust_n"] {
            let settings = OutputSettings::for_output(output);
            let identified = match identify_output(&ident, output, &settings, &segments, None) {
                Ok(i) => i,
                Err(e) => {
                    println!("  {output}: identification failed: {e}");
                    continue;
                }
            };
            let mut model = ExtendedModel::from_gray_box(&identified.model);
            let start = std::time::Instant::now();
            // As a user would: apply a significant structural refinement and diagnose again.
            let mut round = 0;
            let report = loop {
                let report =
                    match diagnose(&model, &ident, &identified.fits, &[&validation, &chirp], &settings) {
                        Ok(r) => r,
                        Err(e) => {
                            println!("  {output}: diagnosis failed: {e}");
                            break None;
                        }
                    };
                round += 1;
                match report.best().filter(|b| b.significant && b.kind == DiagnosisKind::Structure) {
                    Some(b) if round < 3 => {
                        println!("  {output}: applied {} ({})", b.effect, b.evidence);
                        model = b.model.clone();
                    }
                    _ => break Some(report),
                }
            };
            let Some(report) = report else { continue };
            let poles = identified.model.roots.iter().map(|g| g.count()).sum::<usize>();
            println!(
                "  {output} ({poles} roots{}; {:.1} s): current {:.3} % refit {:.3} %",
                if identified.model.direct_fit.is_some() { ", direct fit" } else { "" },
                start.elapsed().as_secs_f64(),
                report.rmspe_current_pct,
                report.rmspe_refit_pct
            );
            for d in report.entries.iter().take(4) {
                println!(
                    "    {:<20} {:<9} {} {:.3} → {:.3} p={:.1e}  | {}",
                    d.effect,
                    d.kind.label(),
                    if d.significant { "SIG" } else { "   " },
                    d.rmspe_before_pct,
                    d.rmspe_after_pct,
                    d.test.p_value,
                    d.evidence
                );
            }
            if let Some(note) = &report.structure_note {
                println!("    NOTE {note}");
            }
            if let Some(note) = &report.attribution_note {
                println!("    TIE {note}");
            }
        }
    }
    Ok(())
}
