//! The missing-physics loop on engines of the small-turbojet family, on both outputs: for each
//! hidden effect (and for effect-free engines), what the loop takes in `ROUNDS` rounds and the
//! held-out error against the noiseless truth of a third run, before and after the loop (and, on
//! thrust, the speed model's spool blocks shared, as the batch shares them), beside the same
//! engine's error without the effect.
//!
//! `cargo run --release --no-default-features --example attribution_study -- [effects|free] [ENGINES]`
//! (`effects`: every hidden effect on engines 3, 7, 11; `free`: effect-free engines 1..=ENGINES;
//! with `OFFERS=1` set, what each thrust model was offered of the speed's spool blocks; with
//! `READ_OFF_SPEED=1`, thrust read off the speed model too: see [`read_off_speed`]; with
//! `SPOOL_SCHEDULE=power_balance`, the scheduled time constant in the power balance's form; with
//! `SPOOL_SCHEDULE=speed`, on the shaft speed only).
use anyhow::{Context, Result};
use jetid::core::effects::ExtendedModel;
use jetid::core::identification::fits::segments_for;
use jetid::core::identification::pipeline::identify_output;
use jetid::core::identification::segment::SegmentSettings;
use jetid::core::identification::settings::{OutputSettings, SpoolSchedule};
use jetid::core::identification::static_map::fit_static_map;
use jetid::core::numerics::metrics::metrics;
use jetid::core::parallel::on_two_threads;
use jetid::core::run::Run;
use jetid::sim::{Effect, EngineFamily, SimConfig, SimOutput, TestKind, simulate};
use jetid::workflow::model::{EffectPlan, add_effects, share_spool};

const ROUNDS: usize = 3;
const OUTPUTS: [&str; 2] = ["shaft_speed_rpm", "thrust_n"];

/// A bench session: identification, validation and chirp runs for the loop, a third run to score.
struct Bench {
    ident: Run,
    validation: Run,
    chirp: Run,
    scored: SimOutput,
}

fn bench(seed: u64, first_day: &[Effect], second_day: &[Effect]) -> Result<Bench> {
    let engine = EngineFamily::small_turbojets().draw(seed);
    let run = |kind: TestKind, noise_seed: u64, effects: &[Effect]| -> Result<SimOutput> {
        Ok(simulate(
            &SimConfig::for_test(kind.name(), kind, noise_seed)?
                .on_engine(&engine)
                .with_effects(effects.to_vec()),
        )?)
    };
    Ok(Bench {
        ident: run(TestKind::Ident, seed, first_day)?.measured,
        validation: run(TestKind::Validation, seed + 1000, second_day)?.measured,
        chirp: run(TestKind::Chirp, seed + 2000, first_day)?.measured,
        scored: run(TestKind::Validation, seed + 3000, second_day)?,
    })
}

/// The loop on one output, then (for an output other than the speed) the speed model `spool`'s
/// spool blocks shared, as the batch does: what it took, the scored run's error before and after,
/// %, and the final model.
fn loop_on(
    b: &Bench,
    output: &str,
    spool: Option<&ExtendedModel>,
) -> Result<(Vec<String>, f64, f64, ExtendedModel)> {
    let mut settings = OutputSettings::for_output(output);
    let schedule = std::env::var("SPOOL_SCHEDULE").unwrap_or_default();
    if schedule == "power_balance" || (schedule == "speed" && output == OUTPUTS[0]) {
        settings.spool_schedule = SpoolSchedule::PowerBalance;
    }
    let segments = segments_for(&b.ident, None, &SegmentSettings::default())?;
    let identified = identify_output(&b.ident, output, &settings, &segments, None)?;
    let base = ExtendedModel::from_gray_box(&identified.model);
    let validation = [&b.validation, &b.chirp];
    let plan = EffectPlan { by_hand: Vec::new(), auto_rounds: ROUNDS };
    let mut effects = add_effects(
        &identified.model,
        &plan,
        &b.ident,
        &identified.fits,
        &settings,
        &validation,
        &mut |_| true,
    );
    if let Some(spool) = spool {
        share_spool(&mut effects, spool, &settings, &b.ident, &validation);
    }
    let truth = &b.scored.truth.output(output).context("truth")?.values;
    let score = |m: &ExtendedModel| -> Result<f64> {
        Ok(metrics(truth, &m.simulate_scored(&b.scored.measured, settings.initial_state)?)?.rmspe_pct)
    };
    let mut taken: Vec<String> =
        effects.rounds.iter().map(|r| format!("{}({})", r.added, short(&r.significance))).collect();
    taken.extend(effects.shared.iter().filter(|o| o.taken).map(|o| format!("shared:{}", o.id)));
    if std::env::var("OFFERS").is_ok() {
        for o in &effects.shared {
            eprintln!("{} {}", b.ident.name, o.words());
        }
    }
    let sequence = effects.sequence;
    if let (Ok(id), Some(report)) = (std::env::var("SHOW"), &sequence.final_diagnosis) {
        for d in report.entries.iter().filter(|d| d.effect.name() == id) {
            taken.push(format!(
                "[{} {:.2}→{:.2}σ p={:.1e} {} | {} | {}]",
                d.effect,
                d.beyond_noise_before,
                d.beyond_noise_after,
                d.test.p_value,
                d.significant,
                d.evidence,
                d.significance_words()
            ));
        }
    }
    Ok((taken, score(&base)?, score(&sequence.model)?, sequence.model))
}

/// The p-value the decision read: the combined one when the held-out responses witness.
fn short(words: &str) -> String {
    let p =
        |s: &str| s.split("p = ").nth(1).map(|t| t.split([';', ')', ' ']).next().unwrap_or("").to_owned());
    words.split("together ").nth(1).and_then(p).or_else(|| p(words)).unwrap_or_default()
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let mode = args.get(1).map_or("effects", String::as_str);
    let engines: u64 = args.get(2).map_or(Ok(20), |s| s.parse()).context("engines")?;
    let specs: Vec<&str> = match mode {
        "free" => vec![""],
        "one" => vec![args.get(3).map_or("", String::as_str)],
        _ => vec![
            "thermal_soak",
            "asymmetric_dynamics",
            "ambient_correction",
            "rate_limit",
            "static_map_order:bleed_rpm=78000,gain=8",
            "transport_delay:delay_s=0.9",
            "calibration_drift:offset_gph=0.2",
        ],
    };
    let seeds: Vec<u64> = if mode == "free" { (1..=engines).collect() } else { vec![3, 7, 11] };
    let cases: Vec<(&str, u64)> = specs.iter().flat_map(|s| seeds.iter().map(move |e| (*s, *e))).collect();
    let rows = on_two_threads(&cases, |&(spec, seed)| -> Result<String> {
        let effect: Vec<Effect> = if spec.is_empty() { vec![] } else { vec![spec.parse()?] };
        let drift = spec.starts_with("calibration_drift");
        let b = if drift { bench(seed, &[], &effect)? } else { bench(seed, &effect, &effect)? };
        let clean = bench(seed, &[], &[])?;
        let mut line = String::new();
        let (mut spool, mut clean_spool) = (None, None);
        for output in OUTPUTS {
            let (taken, before, after, model) = loop_on(&b, output, spool.as_ref())?;
            let clean_after = if spec.is_empty() {
                after
            } else {
                let (_, _, clean_after, clean_model) = loop_on(&clean, output, clean_spool.as_ref())?;
                clean_spool.get_or_insert(clean_model);
                clean_after
            };
            spool.get_or_insert(model);
            let read_off = match (output, std::env::var("READ_OFF_SPEED").is_ok(), &spool, &clean_spool) {
                ("thrust_n", true, Some(spool), clean_spool) => {
                    let read = read_off_speed(&b, spool)?;
                    let clean_read = match clean_spool {
                        Some(c) if !spec.is_empty() => read_off_speed(&clean, c)?,
                        _ => read,
                    };
                    format!(" [read off the speed: {read:.3} %, effect-free {clean_read:.3} %]")
                }
                _ => String::new(),
            };
            line += &format!(
                "| {} | {seed} | {output} | {} | {before:.3} | {after:.3} | {clean_after:.3} | {:.2} |\n",
                if spec.is_empty() { "none" } else { spec.split(':').next().unwrap_or(spec) },
                taken.join(" ") + &read_off,
                after / clean_after
            );
        }
        Ok(line)
    });
    println!(
        "| effect | engine | output | taken | scored before % | after % | effect-free after % | ratio |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for row in rows {
        match row {
            Ok(r) => print!("{r}"),
            Err(e) => println!("| failed: {e} |"),
        }
    }
    Ok(())
}

/// Thrust read off the speed model (the joint form: one spool, a static map per output): a
/// polynomial of the measured speed fitted to the measured thrust on the identification run,
/// evaluated at the speed model `spool`'s simulation of the scored run; its error there, %.
fn read_off_speed(b: &Bench, spool: &ExtendedModel) -> Result<f64> {
    let speed = &b.ident.output(OUTPUTS[0]).context("no speed")?.values;
    let thrust = &b.ident.output(OUTPUTS[1]).context("no thrust")?.values;
    let map = fit_static_map(speed, thrust, READ_OFF_ORDER)?;
    let simulated =
        spool.simulate_scored(&b.scored.measured, OutputSettings::for_output(OUTPUTS[0]).initial_state)?;
    let read: Vec<f64> = simulated.iter().map(|n| map.eval(*n)).collect();
    let truth = &b.scored.truth.output(OUTPUTS[1]).context("truth")?.values;
    Ok(metrics(truth, &read)?.rmspe_pct)
}

/// The polynomial's order: thrust grows as F₀ + F₁ nᵖ with p = 3.5–6 across the family, which a
/// quartic follows over the speed range of the runs.
const READ_OFF_ORDER: usize = 4;
