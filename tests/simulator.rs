//! The turbojet simulator end to end: reproducibility, each effect acting in its physical direction,
//! bad configurations as errors, and the `jetid simulate` command.
#![allow(clippy::unwrap_used)]
use clap::Parser;
use jetid::core::effects::EffectId;
use jetid::sim::{
    DT_SECS, Effect, FuelProfile, SimConfig, SimError, SimOutput, TestKind, columns, designs, simulate,
};

fn sim(kind: TestKind, effects: &[&str], seed: u64) -> SimOutput {
    let effects = effects.iter().map(|e| e.parse::<Effect>().unwrap()).collect();
    simulate(&SimConfig::for_test("t", kind, seed).unwrap().with_effects(effects)).unwrap()
}

fn truth<'a>(out: &'a SimOutput, column: &str) -> &'a [f64] {
    &out.truth.channel(column).unwrap().values
}

fn measured<'a>(out: &'a SimOutput, column: &str) -> &'a [f64] {
    &out.measured.channel(column).unwrap().values
}

fn at(values: &[f64], t_secs: f64) -> f64 {
    values[(t_secs / DT_SECS).round() as usize]
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// First time after `from_secs` at which `values` crosses `level` (linear interpolation).
fn crossing_secs(values: &[f64], from_secs: f64, level: f64) -> f64 {
    let k0 = (from_secs / DT_SECS).round() as usize;
    for k in k0..values.len() - 1 {
        let (a, b) = (values[k] - level, values[k + 1] - level);
        if a == 0.0 || a.signum() != b.signum() {
            return (k as f64 + a / (a - b)) * DT_SECS;
        }
    }
    panic!("no crossing of {level} after {from_secs} s");
}

/// Time from a step at `step_secs` until the output has covered 63 % of its change.
fn rise_time_secs(values: &[f64], step_secs: f64, settle_secs: f64) -> f64 {
    let (y0, y1) = (at(values, step_secs - 0.5), at(values, settle_secs));
    crossing_secs(values, step_secs, y0 + 0.63 * (y1 - y0)) - step_secs
}

/// Periodogram power of `v` (mean removed) averaged over `[lo_hz, hi_hz]`.
fn band_power(v: &[f64], lo_hz: f64, hi_hz: f64) -> f64 {
    let m = mean(v);
    let n = v.len();
    let (mut total, mut count) = (0.0, 0);
    for bin in 1..n / 2 {
        let f_hz = bin as f64 / (n as f64 * DT_SECS);
        if f_hz < lo_hz || f_hz > hi_hz {
            continue;
        }
        let (mut re, mut im) = (0.0, 0.0);
        for (k, x) in v.iter().enumerate() {
            let angle = -2.0 * std::f64::consts::PI * (bin * k) as f64 / n as f64;
            re += (x - m) * angle.cos();
            im += (x - m) * angle.sin();
        }
        total += re * re + im * im;
        count += 1;
    }
    total / count as f64
}

#[test]
fn runs_carry_every_canonical_column() {
    let out = sim(TestKind::Chirp, &[], 1);
    let run = &out.measured;
    assert_eq!(run.input.name, columns::FUEL);
    let names: Vec<&str> = run.outputs.iter().chain(&run.aux).map(|c| c.name.as_str()).collect();
    assert_eq!(
        names,
        [
            columns::SPEED,
            columns::THRUST,
            columns::EGT,
            columns::AMBIENT_TEMP,
            columns::AMBIENT_PRESSURE,
            columns::HUMIDITY
        ]
    );
    assert!(run.outputs.iter().chain(&run.aux).all(|c| c.values.len() == run.len()));
    assert!((run.dt_secs - 1.0 / 8.85).abs() < 1e-12);
    assert!(run.t_secs.windows(2).all(|w| (w[1] - w[0] - run.dt_secs).abs() < 1e-9));
    // Without the ambient effect the day is standard, recorded with a little sensor noise.
    let temp = measured(&out, columns::AMBIENT_TEMP);
    assert!(temp.iter().all(|t| (t - 15.0).abs() < 0.5));
    assert!((mean(measured(&out, columns::AMBIENT_PRESSURE)) - 101.325).abs() < 0.01);
}

#[test]
fn a_seed_reproduces_its_run() {
    let (a, b, c) = (
        sim(TestKind::Validation, &[], 5),
        sim(TestKind::Validation, &[], 5),
        sim(TestKind::Validation, &[], 6),
    );
    assert_eq!(a, b);
    assert_ne!(a.measured, c.measured);
    assert_eq!(a.truth, c.truth, "the truth does not depend on the noise seed");
}

#[test]
fn steady_map_rises_across_the_range() {
    let mut last = (0.0, 0.0);
    for fuel in [2.0, 3.5, 5.43, 6.5, 7.6] {
        let mut cfg = SimConfig::for_test("s", TestKind::Steady, 3).unwrap();
        cfg.profile = FuelProfile::constant(fuel, 300, DT_SECS);
        let out = simulate(&cfg).unwrap();
        let point = (mean(measured(&out, columns::SPEED)), mean(measured(&out, columns::THRUST)));
        assert!(point.0 > last.0 && point.1 > last.1, "{fuel}: {point:?} after {last:?}");
        last = point;
    }
}

#[test]
fn transport_delay_shifts_the_response() {
    let (base, late) =
        (sim(TestKind::Ident, &[], 1), sim(TestKind::Ident, &["transport_delay:delay_s=0.45"], 1));
    let (s0, s1) = (truth(&base, columns::SPEED), truth(&late, columns::SPEED));
    let level = 0.5 * (at(s0, 59.0) + at(s0, 99.0));
    let shift = crossing_secs(s1, 60.0, level) - crossing_secs(s0, 60.0, level);
    assert!((shift - 0.45).abs() < 0.05, "shift {shift} s");
    // The recorded fuel is the metered command: not delayed.
    assert_eq!(base.truth.input, late.truth.input);
}

/// Fastest rise and fall of a signal over one sample, per second.
fn peak_rates(values: &[f64]) -> (f64, f64) {
    values.windows(2).fold((0.0f64, 0.0f64), |(up, down), w| {
        let r = (w[1] - w[0]) / DT_SECS;
        (up.max(r), down.max(-r))
    })
}

#[test]
fn rate_limit_caps_the_spool_slope_and_keeps_the_steady_states() {
    let spec = "rate_limit:rise_rpm_s=4000,fall_rpm_s=1500";
    let (base, limited) = (sim(TestKind::Ident, &[], 1), sim(TestKind::Ident, &[spec], 1));
    let (s0, s1) = (truth(&base, columns::SPEED), truth(&limited, columns::SPEED));
    let ((up0, down0), (up1, down1)) = (peak_rates(s0), peak_rates(s1));
    // The free engine is faster than the limits on its large steps; the limited one never is (the
    // RK4 step integrates a clamped rate, so a sample's slope is the limit at most).
    assert!(up0 > 1.2 * 4000.0 && down0 > 1.2 * 1500.0, "free engine: {up0} / {down0} rpm/s");
    assert!(up1 <= 4000.0 * 1.001 && down1 <= 1500.0 * 1.001, "limited: {up1} / {down1} rpm/s");
    assert!(up1 > 0.95 * 4000.0 && down1 > 0.95 * 1500.0, "the limits bind: {up1} / {down1} rpm/s");
    // Same steady states once each step has settled (step B ends at 150 s, the run at its end).
    for t in [59.0, 149.0, (s0.len() - 1) as f64 * DT_SECS] {
        assert!((at(s1, t) - at(s0, t)).abs() < 1.0, "at {t} s: {} vs {}", at(s1, t), at(s0, t));
    }
    // The recorded fuel is the command: the ECU's limit does not show in the input.
    assert_eq!(base.truth.input, limited.truth.input);
}

#[test]
fn thermal_soak_leaves_a_creeping_tail() {
    let (base, soak) = (sim(TestKind::Ident, &[], 1), sim(TestKind::Ident, &["thermal_soak"], 1));
    let (s0, s1) = (truth(&base, columns::SPEED), truth(&soak, columns::SPEED));
    // Step B at 100 s (3.0 → 4.3 gal/h), held to 150 s. Without soak the spool has settled after 20 s.
    assert!((at(s0, 149.0) - at(s0, 120.0)).abs() < 5.0);
    let creep = at(s1, 149.0) - at(s1, 120.0);
    assert!(creep > 200.0, "creep {creep} rpm");
    assert!(at(s1, 120.0) < at(s0, 120.0) - 400.0, "{} vs {}", at(s1, 120.0), at(s0, 120.0));
    // Same steady state in the end.
    assert!((at(s1, 59.0) - at(s0, 59.0)).abs() < 1.0);
}

#[test]
fn ambient_correction_acts_through_corrected_quantities() {
    let (base, hot) =
        (sim(TestKind::Validation, &[], 2), sim(TestKind::Validation, &["ambient_correction"], 2));
    let temp = truth(&hot, columns::AMBIENT_TEMP);
    assert!((temp[0] - 18.0).abs() < 1e-9 && (temp[temp.len() - 1] - 38.0).abs() < 1e-9);
    let rh = truth(&hot, columns::HUMIDITY);
    assert!(rh[rh.len() - 1] < rh[0]);
    // Last hold at 5.43 gal/h on a 38 °C day: same fuel, higher physical speed, less thrust.
    let end_secs = (hot.truth.len() - 1) as f64 * DT_SECS;
    let speed_gain = at(truth(&hot, columns::SPEED), end_secs) - at(truth(&base, columns::SPEED), end_secs);
    let thrust_loss =
        at(truth(&base, columns::THRUST), end_secs) - at(truth(&hot, columns::THRUST), end_secs);
    assert!(speed_gain > 800.0, "speed gain {speed_gain}");
    assert!(thrust_loss > 3.0, "thrust loss {thrust_loss}");
}

#[test]
fn asymmetric_dynamics_slows_deceleration_only() {
    let (base, asym) = (sim(TestKind::Ident, &[], 1), sim(TestKind::Ident, &["asymmetric_dynamics"], 1));
    let (s0, s1) = (truth(&base, columns::SPEED), truth(&asym, columns::SPEED));
    // Step B up at 100 s, step C down at 150 s.
    let (up0, up1) = (rise_time_secs(s0, 100.0, 149.0), rise_time_secs(s1, 100.0, 149.0));
    let (down0, down1) = (rise_time_secs(s0, 150.0, 189.0), rise_time_secs(s1, 150.0, 189.0));
    assert!((up1 / up0 - 1.0).abs() < 0.02, "up {up0} vs {up1}");
    assert!(down1 / down0 > 1.4, "down {down0} vs {down1}");
}

#[test]
fn sensor_dynamics_puts_a_peak_in_the_thrust_spectrum() {
    let (base, soft) = (sim(TestKind::Steady, &[], 4), sim(TestKind::Steady, &["sensor_dynamics"], 4));
    let ratio = |out: &SimOutput| {
        let thrust = measured(out, columns::THRUST);
        band_power(thrust, 1.2, 1.6) / band_power(thrust, 0.2, 0.8)
    };
    assert!(ratio(&base) < 2.5, "base ratio {}", ratio(&base));
    assert!(ratio(&soft) > 5.0, "soft ratio {}", ratio(&soft));
    // The sensor lag delays the thrust response to a step.
    let (base, soft) =
        (sim(TestKind::Ident, &[], 1), sim(TestKind::Ident, &["sensor_dynamics:buffet_n=0"], 1));
    let (f0, f1) = (truth(&base, columns::THRUST), truth(&soft, columns::THRUST));
    let level = 0.5 * (at(f0, 59.0) + at(f0, 99.0));
    let lag = crossing_secs(f1, 60.0, level) - crossing_secs(f0, 60.0, level);
    assert!(lag > 0.15, "lag {lag} s");
}

#[test]
fn bleed_valve_kinks_the_static_map() {
    let steady = |fuel: f64, effects: Vec<Effect>| {
        let mut cfg = SimConfig::for_test("s", TestKind::Steady, 1).unwrap().with_effects(effects);
        cfg.profile = FuelProfile::constant(fuel, 20, DT_SECS);
        let out = simulate(&cfg).unwrap();
        at(truth(&out, columns::SPEED), 0.0)
    };
    let bleed = || vec![Effect::with_defaults(EffectId::StaticMapOrder).unwrap()];
    assert!((steady(4.0, bleed()) - steady(4.0, vec![])).abs() < 1.0, "no change below the bleed speed");
    let drop_rpm = steady(designs::MAX_FUEL_GPH, vec![]) - steady(designs::MAX_FUEL_GPH, bleed());
    assert!(drop_rpm > 1_500.0, "drop {drop_rpm}");
}

#[test]
fn effects_combine() {
    let out = sim(
        TestKind::Validation,
        &[
            "transport_delay",
            "thermal_soak",
            "ambient_correction",
            "asymmetric_dynamics",
            "sensor_dynamics",
            "static_map_order",
        ],
        9,
    );
    assert!(out.measured.outputs.iter().all(|c| c.values.iter().all(|v| v.is_finite())));
}

#[test]
fn bad_configurations_are_errors() {
    assert!(
        matches!("warp_drive:factor=9".parse::<Effect>(), Err(SimError::UnknownEffect { id, .. }) if id == "warp_drive")
    );
    let twice = vec![
        Effect::with_defaults(EffectId::TransportDelay).unwrap(),
        Effect::with_defaults(EffectId::TransportDelay).unwrap(),
    ];
    let cfg = SimConfig::for_test("t", TestKind::Steady, 1).unwrap().with_effects(twice);
    assert!(matches!(simulate(&cfg), Err(SimError::DuplicateEffect { .. })));
    let mut cfg = SimConfig::for_test("t", TestKind::Steady, 1).unwrap();
    cfg.profile = FuelProfile::constant(25.0, 10, DT_SECS);
    assert!(matches!(simulate(&cfg), Err(SimError::FuelOutOfRange { .. })));
}

fn cli_run(args: &[&str]) -> anyhow::Result<()> {
    let cli = jetid::cli::Cli::try_parse_from(std::iter::once("jetid").chain(args.iter().copied()))?;
    jetid::cli::run(cli)
}

#[test]
fn cli_rejects_bad_effects_and_tests() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run.csv");
    let out = out.to_str().unwrap();
    let err = cli_run(&["simulate", "--test", "steady", "--effect", "warp_drive", "--out", out]).unwrap_err();
    assert!(format!("{err:#}").contains("unknown effect `warp_drive`"), "{err:#}");
    assert!(cli_run(&["simulate", "--test", "bogus", "--out", out]).is_err());
    assert!(!dir.path().join("run.csv").exists());
}

#[test]
fn cli_writes_the_run_and_its_truth() {
    let dir = tempfile::tempdir().unwrap();
    let (run, truth) = (dir.path().join("steady.csv"), dir.path().join("truth.csv"));
    let args = ["simulate", "--test", "steady", "--seed", "3", "--effect", "thermal_soak:gain=0.06,tau_s=40"];
    let paths = ["--out", run.to_str().unwrap(), "--truth-out", truth.to_str().unwrap()];
    cli_run(&[&args[..], &paths[..]].concat()).unwrap();
    for path in [&run, &truth] {
        let text = std::fs::read_to_string(path).unwrap();
        let header = text.lines().next().unwrap();
        for column in [columns::TIME, columns::FUEL, columns::SPEED, columns::THRUST, columns::AMBIENT_TEMP] {
            assert!(header.contains(column), "{header}");
        }
        assert_eq!(text.lines().count(), 301);
    }
}
