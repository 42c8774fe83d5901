//! How weak can a missing effect be and still be found? For each effect of the catalog, the
//! simulator hides it with a parameter that weakens step by step, the pipeline identifies the output
//! where the effect shows, and the diagnosis ranks the effects (never told which one is hidden).
//! Detection means: ranked first and significant. Each step also prints the effect's size on the
//! validation run as the RMS of (truth with effect − truth without) over the sensor's noise σ.
//!
//! `cargo run --release --example detection_sweep`
use jetid::core::diagnose::diagnose;
use jetid::core::effects::{ExtendedModel, FitData, refit};
use jetid::core::identification::arx::ArxOrders;
use jetid::core::identification::fits::{SegmentFits, fit_segments_for, segments_for};
use jetid::core::identification::pipeline::identify_output;
use jetid::core::identification::segment::SegmentSettings;
use jetid::core::identification::settings::OutputSettings;
use jetid::core::run::Run;
use jetid::sim::{Effect, SensorNoise, SimConfig, SimOutput, TestKind, simulate};

const SPEED: &str = "shaft_speed_rpm";
const THRUST: &str = "thrust_n";
const SEEDS: [u64; 2] = [2, 3];

/// One sweep: the effect, the output where it shows, and the parameter values, strongest first.
struct Sweep {
    output: &'static str,
    label: &'static str,
    specs: Vec<(f64, String)>,
    /// ARX orders of the pipeline's segment models (None: the output's defaults).
    orders: Option<ArxOrders>,
}

fn sweeps() -> Vec<Sweep> {
    let steps =
        |values: &[f64], spec: &dyn Fn(f64) -> String| values.iter().map(|v| (*v, spec(*v))).collect();
    vec![
        Sweep {
            output: SPEED,
            label: "transport_delay  delay_s",
            specs: steps(&[1.2, 1.0, 0.8, 0.6, 0.45, 0.3, 0.15], &|v| format!("transport_delay:delay_s={v}")),
            orders: Some(ArxOrders::new(19, 12)),
        },
        Sweep {
            output: SPEED,
            label: "thermal_soak  gain (tau_s 40)",
            specs: steps(&[0.15, 0.10, 0.06, 0.04, 0.02, 0.01, 0.005], &|v| format!("thermal_soak:gain={v}")),
            orders: None,
        },
        Sweep {
            output: SPEED,
            label: "ambient_correction  temperature drift over the run, °C",
            specs: steps(&[30.0, 20.0, 10.0, 5.0, 2.0, 1.0, 0.5], &|v| {
                format!(
                    "ambient_correction:t_start_c=18,t_end_c={},p_end_kpa={}",
                    18.0 + v,
                    101.325 - 0.02625 * v
                )
            }),
            orders: None,
        },
        Sweep {
            output: SPEED,
            label: "asymmetric_dynamics  decel_factor",
            specs: steps(&[1.8, 1.5, 1.3, 1.2, 1.1, 1.05], &|v| {
                format!("asymmetric_dynamics:decel_factor={v}")
            }),
            orders: None,
        },
        Sweep {
            output: SPEED,
            label: "static_map_order  gain (bleed_rpm 80000)",
            specs: steps(&[8.0, 4.0, 2.0, 1.0, 0.5], &|v| format!("static_map_order:gain={v}")),
            orders: None,
        },
        Sweep {
            output: THRUST,
            label: "sensor_dynamics  lag_s (1.4 Hz, zeta 0.06, buffet 1.5 N)",
            specs: steps(&[1.0, 0.6, 0.3, 0.1], &|v| format!("sensor_dynamics:lag_s={v}")),
            orders: None,
        },
    ]
}

fn sim(effects: &[Effect], kind: TestKind, seed: u64) -> Result<SimOutput, Box<dyn std::error::Error>> {
    Ok(simulate(&SimConfig::for_test(kind.name(), kind, seed)?.with_effects(effects.to_vec()))?)
}

/// The current model of the output: the pipeline's for speed; for thrust the speed model's linear
/// block refitted on thrust (thrust is a static function of spool speed).
fn current_model(
    ident: &Run,
    output: &str,
    orders: Option<ArxOrders>,
) -> Result<(ExtendedModel, SegmentFits, OutputSettings), Box<dyn std::error::Error>> {
    let segments = segments_for(ident, None, &SegmentSettings::default())?;
    let mut speed_settings = OutputSettings::for_output(SPEED);
    if let Some(orders) = orders {
        speed_settings.orders = orders;
    }
    let speed = identify_output(ident, SPEED, &speed_settings, &segments, None)?;
    if output == SPEED {
        return Ok((ExtendedModel::from_gray_box(&speed.model), speed.fits, speed_settings));
    }
    let settings = OutputSettings::for_output(output);
    let fits = fit_segments_for(ident, output, &speed.fits.segments, &settings)?;
    let data = FitData::new(ident, &fits, &settings)?;
    let model = refit(&ExtendedModel::new(output, speed.model.wiener.clone()), &data)?;
    Ok((model, fits, settings))
}

/// RMS of the effect on the noiseless validation run, in units of the output's sensor noise.
fn size_over_noise(effect: &Effect, output: &str) -> Result<f64, Box<dyn std::error::Error>> {
    let with = sim(std::slice::from_ref(effect), TestKind::Validation, 1)?;
    let without = sim(&[], TestKind::Validation, 1)?;
    let (a, b) = (
        &with.truth.output(output).ok_or("no output")?.values,
        &without.truth.output(output).ok_or("no output")?.values,
    );
    let rms = (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len().max(1) as f64).sqrt();
    let noise = SensorNoise::default();
    Ok(rms / if output == SPEED { noise.speed_rpm } else { noise.thrust_n })
}

/// Diagnose one seed; returns whether the hidden effect ranked first and significant, and a note.
fn detect(
    effect: &Effect,
    output: &str,
    orders: Option<ArxOrders>,
    seed: u64,
) -> Result<(bool, String), Box<dyn std::error::Error>> {
    let effects = [effect.clone()];
    let ident = sim(&effects, TestKind::Ident, seed)?.measured;
    let validation = sim(&effects, TestKind::Validation, seed + 100)?.measured;
    let chirp = sim(&effects, TestKind::Chirp, seed + 200)?.measured;
    let (model, fits, settings) = match current_model(&ident, output, orders) {
        Ok(m) => m,
        Err(e) => return Ok((false, format!("no base model ({e})"))),
    };
    let report = diagnose(&model, &ident, &fits, &[&validation, &chirp], &settings)?;
    let Some(best) = report.best() else { return Ok((false, "nothing tried".into())) };
    let found = best.effect.name() == effect.id().name() && best.significant;
    let mine = report.entries.iter().position(|d| d.effect.name() == effect.id().name());
    let note = match mine.and_then(|i| report.entries.get(i).map(|d| (i, d))) {
        Some((i, d)) => format!(
            "rank {} {:+.0}% p={:.0e}{}",
            i + 1,
            -100.0 * d.test.reduction,
            d.test.p_value,
            if i == 0 { String::new() } else { format!(" (first: {})", best.effect) }
        ),
        None => "not tried".into(),
    };
    Ok((found, note))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    println!(
        "detection = ranked first and significant (p < 0.01, ≥ 10 % less validation error); seeds {SEEDS:?}\n"
    );
    for sweep in sweeps() {
        println!("{} on {}", sweep.label, sweep.output);
        let mut threshold: Option<f64> = None;
        let mut stopped = false;
        for (value, spec) in &sweep.specs {
            let effect: Effect = spec.parse()?;
            let size = size_over_noise(&effect, sweep.output)?;
            let mut notes = Vec::new();
            let mut all = true;
            for seed in SEEDS {
                let (found, note) = detect(&effect, sweep.output, sweep.orders, seed)?;
                all &= found;
                notes.push(format!("{}{}", if found { "✓ " } else { "✗ " }, note));
            }
            println!("  {value:>7} | effect/noise {size:>6.1} | {}", notes.join(" | "));
            if all && !stopped {
                threshold = Some(*value);
            } else {
                stopped = true;
            }
        }
        match threshold {
            Some(v) => println!("  → detected on every seed down to {v}\n"),
            None => println!("  → not detected at any strength tried\n"),
        }
    }
    Ok(())
}
