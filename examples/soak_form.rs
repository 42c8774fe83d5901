//! Which form of the thermal soak the simulator's soak has: the soak-free engine's noiseless
//! response, soaked afterwards in one form or another (share 0.10, 40 s, the simulator's defaults),
//! against the noiseless response of the same engine with the soak, on a validation run (RMSPE %).
//!
//! - speed, on `v` (the same share of every step on the fuel-equivalent spool state, through the
//!   engine's own running line) or on N³ (the fan law's power);
//! - thrust, on F^k for a few k (the soak in thrust's units; N³ is about F^(3/5) where thrust grows
//!   as the fifth power of the speed), and on the engine's own N³ read through its thrust law.
//!
//! `cargo run --release --no-default-features --example soak_form`
use anyhow::{Context, Result};
use jetid::core::effects::stats::low_pass;
use jetid::sim::{Effect, EngineFamily, SimConfig, TestKind, simulate};

const GAIN: f64 = 0.10;
const TAU_S: f64 = 40.0;
const THRUST_EXPONENTS: [f64; 6] = [1.0, 0.8, 0.6, 0.5, 0.4, 0.3];

fn soak(x: &[f64], dt: f64) -> Vec<f64> {
    let slow = low_pass(x, dt, TAU_S);
    x.iter().zip(&slow).map(|(xk, sk)| xk + GAIN * (sk - xk)).collect()
}

/// `y` soaked on `y^k`.
fn soak_on_power(y: &[f64], k: f64, dt: f64) -> Vec<f64> {
    let power: Vec<f64> = y.iter().map(|x| x.powf(k)).collect();
    soak(&power, dt).iter().map(|p| p.powf(1.0 / k)).collect()
}

fn rmspe(model: &[f64], truth: &[f64]) -> f64 {
    let sum: f64 = model.iter().zip(truth).map(|(m, t)| ((m - t) / t).powi(2)).sum();
    100.0 * (sum / truth.len() as f64).sqrt()
}

fn main() -> Result<()> {
    for seed in [3u64, 7, 11] {
        let engine = EngineFamily::small_turbojets().draw(seed);
        let p = &engine.params;
        let truth = |effects: Vec<Effect>, output: &str| -> Result<(Vec<f64>, f64)> {
            let config = SimConfig::for_test("v", TestKind::Validation, seed + 3000)?;
            let o = simulate(&config.on_engine(&engine).with_effects(effects))?;
            Ok((o.truth.output(output).context("no such output")?.values.clone(), o.measured.dt_secs))
        };
        let (clean, dt) = truth(vec![], "shaft_speed_rpm")?;
        let (soaked, _) = truth(vec!["thermal_soak".parse()?], "shaft_speed_rpm")?;
        let [a, b, c] = p.running_line_rpm;
        let fuel_of = |n: f64| (-b + (b * b - 4.0 * c * (a - n)).sqrt()) / (2.0 * c);
        let on_v: Vec<f64> = soak(&clean.iter().map(|n| fuel_of(*n)).collect::<Vec<_>>(), dt)
            .iter()
            .map(|w| a + b * w + c * w * w)
            .collect();
        println!(
            "engine {seed} speed: no soak {:.3}, on v {:.3}, on N^3 {:.3}",
            rmspe(&clean, &soaked),
            rmspe(&on_v, &soaked),
            rmspe(&soak_on_power(&clean, 3.0, dt), &soaked)
        );
        let (clean, _) = truth(vec![], "thrust_n")?;
        let (soaked, _) = truth(vec!["thermal_soak".parse()?], "thrust_n")?;
        let speed_of =
            |f: f64| ((f - p.thrust_offset_n) / p.thrust_scale_n).max(0.0).powf(1.0 / p.thrust_exponent);
        let exact: Vec<f64> = soak_on_power(&clean.iter().map(|f| speed_of(*f)).collect::<Vec<_>>(), 3.0, dt)
            .iter()
            .map(|n| p.thrust_offset_n + p.thrust_scale_n * n.powf(p.thrust_exponent))
            .collect();
        let powers: Vec<String> = THRUST_EXPONENTS
            .iter()
            .map(|&k| format!("F^{k} {:.3}", rmspe(&soak_on_power(&clean, k, dt), &soaked)))
            .collect();
        println!(
            "engine {seed} thrust (p = {:.2}): no soak {:.3}, on N^3 {:.3}, {}",
            p.thrust_exponent,
            rmspe(&clean, &soaked),
            rmspe(&exact, &soaked),
            powers.join(", ")
        );
    }
    Ok(())
}
