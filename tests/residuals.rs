//! Residual analysis on residuals of known make: sensor noise alone, a missing dead time, a
//! resonance, a drifting inlet temperature, errors only in decelerations; and every error a caller
//! can cause.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::sync::OnceLock;

use jetid::core::identification::fits::segments_for;
use jetid::core::identification::pipeline::{identify_output, predict_wiener};
use jetid::core::identification::segment::SegmentSettings;
use jetid::core::identification::settings::OutputSettings;
use jetid::core::identification::wiener::WienerModel;
use jetid::core::residuals::{
    BandFit, ExclusionReason, OperatingBands, Regime, ResidualAnalysis, ResidualError, ResidualSettings,
    SigmaSource, analyse_residuals, summary,
};
use jetid::core::run::{Channel, Run};
use jetid::io::csv_run::{LoadOptions, load_run};
use jetid::sim::{DT_SECS, Effect, SimConfig, SimOutput, TestKind, simulate};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

const SPEED: &str = "shaft_speed_rpm";
const THRUST: &str = "thrust_n";
/// The simulator's sensor noise (the paper's fitted levels).
const SPEED_SIGMA_RPM: f64 = 50.7;
const THRUST_SIGMA_N: f64 = 2.08;

fn validation_run(seed: u64, effects: &[&str]) -> SimOutput {
    let effects = effects.iter().map(|e| e.parse::<Effect>().unwrap()).collect();
    simulate(&SimConfig::for_test("validation", TestKind::Validation, seed).unwrap().with_effects(effects))
        .unwrap()
}

fn sample(path: &str) -> Run {
    load_run(&crate::common::sample(path), &LoadOptions::default()).unwrap()
}

fn identify(ident: &Run, output: &str) -> WienerModel {
    let segments = segments_for(ident, None, &SegmentSettings::default()).unwrap();
    identify_output(ident, output, &OutputSettings::for_output(output), &segments, None).unwrap().model.wiener
}

/// Shaft-speed model identified on a standard-day simulator run without any effect.
fn standard_day_speed_model() -> &'static WienerModel {
    static MODEL: OnceLock<WienerModel> = OnceLock::new();
    MODEL.get_or_init(|| {
        let ident = simulate(&SimConfig::for_test("ident", TestKind::Ident, 31).unwrap()).unwrap().measured;
        identify(&ident, SPEED)
    })
}

fn analyse_model(model: &WienerModel, run: &Run, output: &str, sigma: f64) -> ResidualAnalysis {
    let y_hat = predict_wiener(model, run, output).unwrap().y_hat;
    analyse_residuals(run, output, &y_hat, Some(sigma), &ResidualSettings::default()).unwrap()
}

fn gaussian(n: usize, sigma: f64, seed: u64) -> Vec<f64> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let normal = Normal::new(0.0, sigma).unwrap();
    (0..n).map(|_| normal.sample(&mut rng)).collect()
}

#[test]
fn sensor_noise_alone_looks_white_and_unrelated() {
    let sim = validation_run(41, &[]);
    for (output, sigma) in [(SPEED, SPEED_SIGMA_RPM), (THRUST, THRUST_SIGMA_N)] {
        // Against the noiseless truth the residual is exactly the simulated sensor noise.
        let truth = &sim.truth.output(output).unwrap().values;
        let a = analyse_residuals(&sim.measured, output, truth, Some(sigma), &ResidualSettings::default())
            .unwrap();
        let acf = &a.autocorrelation;
        assert!(
            acf.exceeding_lags_samples.len() <= 1,
            "{output}: acf exceeds at {:?}",
            acf.exceeding_lags_samples
        );
        let xcorr = a.input_xcorr.as_ref().unwrap();
        assert!(xcorr.correlogram.exceeding_lags_samples.len() <= 2, "{output}: {xcorr:?}");
        assert!(a.channels.channels.iter().all(|c| !c.significant), "{output}: {:?}", a.channels);
        assert!(a.spectrum.peak_prominence < 4.0, "{output}: prominence {}", a.spectrum.peak_prominence);
        assert!((0.03..0.065).contains(&a.band.outside_fraction), "{output}: {:?}", a.band);
        assert!((a.band.expected_outside_fraction - 0.0455).abs() < 1e-3);
        assert!(summary(&a).contains("close to white"), "{}", summary(&a));
    }
}

#[test]
fn noise_sigma_is_estimated_when_not_supplied() {
    let sim = validation_run(41, &[]);
    let truth = &sim.truth.output(SPEED).unwrap().values;
    let a = analyse_residuals(&sim.measured, SPEED, truth, None, &ResidualSettings::default()).unwrap();
    assert_eq!(a.band.sigma_source, SigmaSource::EstimatedFromSecondDifferences);
    assert!((a.band.sigma / SPEED_SIGMA_RPM - 1.0).abs() < 0.15, "{:?}", a.band);
}

#[test]
fn an_estimated_noise_band_applies_to_white_sensor_noise_and_not_to_telemetry() {
    let sim = validation_run(41, &[]);
    let truth = &sim.truth.output(SPEED).unwrap().values;
    // White sensor noise, and a model far off (a 5 % gain error): nearly every sample lies outside
    // the band, and the band is right, σ̂ being the noise.
    let off: Vec<f64> = truth.iter().map(|y| 0.95 * y).collect();
    let a = analyse_residuals(&sim.measured, SPEED, &off, None, &ResidualSettings::default()).unwrap();
    assert!(a.band.outside_fraction > 0.5, "{:?}", a.band);
    assert!(a.band.applies(), "{:?}", a.band.fit);
    assert!(
        matches!(a.band.fit, BandFit::Consistent { excess_db } if excess_db.abs() < 3.0),
        "{:?}",
        a.band.fit
    );
    assert!(summary(&a).contains("outside the ±2σ noise band"), "{}", summary(&a));
    // Telemetry like the JetCat ECU's: the speed in counts of 10 rpm, mostly a count of jitter and
    // now and then a jump. The robust σ̂ of the second differences sees the counts, a few rpm, while
    // the residual's fastest part carries the jumps: σ̂ is not its noise.
    let mut telemetry = sim.measured.clone();
    let channel = telemetry.outputs.iter_mut().find(|c| c.name == SPEED).unwrap();
    let (jitter, jumps) = (gaussian(truth.len(), 3.0, 7), gaussian(truth.len(), 150.0, 8));
    channel.values = truth
        .iter()
        .enumerate()
        .map(|(k, y)| {
            let noise = if k % 10 == 3 { jumps[k] } else { jitter[k] };
            ((y + noise) / 10.0).round() * 10.0
        })
        .collect();
    let a = analyse_residuals(&telemetry, SPEED, truth, None, &ResidualSettings::default()).unwrap();
    assert!(!a.band.applies(), "{:?} σ = {}", a.band.fit, a.band.sigma);
    let words = summary(&a);
    assert!(words.contains("does not apply") && !words.contains("lie outside"), "{words}");
    // A σ measured on a steady run is the sensor's: its band always applies.
    let a = analyse_residuals(&telemetry, SPEED, truth, Some(SPEED_SIGMA_RPM), &ResidualSettings::default())
        .unwrap();
    assert_eq!(a.band.fit, BandFit::Measured);
}

#[test]
fn missing_dead_time_shows_as_input_leading_cross_correlation() {
    let model = standard_day_speed_model();
    let delay_samples = (0.45 / DT_SECS).round() as i64;
    let delayed = analyse_model(
        model,
        &validation_run(42, &["transport_delay:delay_s=0.45"]).measured,
        SPEED,
        SPEED_SIGMA_RPM,
    );
    let plain = analyse_model(model, &validation_run(42, &[]).measured, SPEED, SPEED_SIGMA_RPM);
    let x = delayed.input_xcorr.as_ref().unwrap();
    assert!(x.input_leads && x.peak_lag_samples > 0, "{x:?}");
    // The peak is the missing dead time plus the rise of the engine's own impulse response.
    assert!(
        (delay_samples..=delay_samples + 3).contains(&x.peak_lag_samples),
        "peak at {}",
        x.peak_lag_samples
    );
    assert!((x.peak_lag_secs - x.peak_lag_samples as f64 * DT_SECS).abs() < 1e-12);
    assert!(x.peak_value.abs() > 3.0 * x.correlogram.bound_99, "{x:?}");
    // Larger than the same model's on the same design without the dead time by more than the 99 %
    // bound of a correlation estimate: beyond what the noise gives.
    let baseline = plain.input_xcorr.as_ref().unwrap();
    assert!(
        x.peak_value.abs() > baseline.peak_value.abs() + x.correlogram.bound_99,
        "{} vs {} (bound {})",
        x.peak_value,
        baseline.peak_value,
        x.correlogram.bound_99
    );
    assert!(summary(&delayed).contains("input leading"), "{}", summary(&delayed));
}

#[test]
fn a_resonance_in_the_residual_is_found_in_the_spectrum() {
    let sim = validation_run(43, &[]);
    let freq_hz = 1.4;
    let truth = &sim.truth.output(THRUST).unwrap().values;
    let y_hat: Vec<f64> = truth
        .iter()
        .zip(&sim.measured.t_secs)
        .map(|(y, t)| y - 3.0 * (2.0 * std::f64::consts::PI * freq_hz * t).sin())
        .collect();
    let a =
        analyse_residuals(&sim.measured, THRUST, &y_hat, Some(THRUST_SIGMA_N), &ResidualSettings::default())
            .unwrap();
    let s = &a.spectrum;
    let bin_hz = 1.0 / (DT_SECS * s.segment_len as f64);
    assert!((s.peak_freq_hz - freq_hz).abs() <= bin_hz, "peak at {} Hz", s.peak_freq_hz);
    assert!((s.peak_omega_rad_s - 2.0 * std::f64::consts::PI * s.peak_freq_hz).abs() < 1e-9);
    assert!(s.peak_prominence > 20.0, "prominence {}", s.peak_prominence);
    assert!(summary(&a).contains("rad/s"), "{}", summary(&a));
}

#[test]
fn a_ramped_inlet_temperature_ranks_first() {
    // Only the temperature drifts: pressure held at standard, no water vapour to make humidity drift.
    let effect = "ambient_correction:t_start_c=18,t_end_c=38,p_end_kpa=101.325,rh_start_pct=0";
    let run = validation_run(44, &[effect]).measured;
    let a = analyse_model(standard_day_speed_model(), &run, SPEED, SPEED_SIGMA_RPM);
    let top = a.channels.channels.first().unwrap();
    assert_eq!(top.channel, "ambient_temp_c", "{:?}", a.channels.channels);
    assert!(top.r.abs() > 0.6 && top.strongest().0.abs() > 0.7, "{top:?}");
    assert!(a.channels.channels.iter().skip(1).all(|c| c.r.abs() < 0.2), "{:?}", a.channels.channels);
    assert!(top.n_eff < run.len() as f64 / 10.0, "a drifting pair has few effective samples: {top:?}");
}

#[test]
fn collinear_inlet_channels_on_the_hot_day_are_flagged() {
    let model = identify(&sample("hot_day/ident.csv"), SPEED);
    let a = analyse_model(&model, &sample("hot_day/validation.csv"), SPEED, SPEED_SIGMA_RPM);
    let top = a.channels.channels.first().unwrap();
    let inlet = ["ambient_temp_c", "ambient_pressure_kpa", "relative_humidity_pct"];
    assert!(inlet.contains(&top.channel.as_str()), "{:?}", a.channels.channels);
    assert!(top.strongest().0.abs() > 0.7, "{top:?}");
    assert_eq!(top.collinear_with.len(), 2, "{top:?}");
    assert!(summary(&a).contains("cannot be told apart"), "{}", summary(&a));
}

/// A staircase of alternating rises and falls through a first-order engine (τ = 1 s); the model is
/// exact except in falls, where it lags by 0.5 s (it over-predicts while the engine decelerates).
struct DecelCase {
    run: Run,
    y_hat: Vec<f64>,
    down_steps: Vec<usize>,
}

fn decel_case() -> DecelCase {
    let levels = [3.0, 5.0, 3.5, 6.0, 4.0, 6.5, 3.0, 5.5, 2.5, 6.0, 4.5, 7.0, 3.0, 5.0, 2.8];
    let hold = (12.0 / DT_SECS) as usize;
    let u: Vec<f64> = levels.iter().flat_map(|&l| std::iter::repeat_n(l, hold)).collect();
    let down_steps: Vec<usize> =
        levels.windows(2).enumerate().filter(|(_, w)| w[1] < w[0]).map(|(i, _)| (i + 1) * hold).collect();
    let tau_secs = 1.0;
    let a = (-DT_SECS / tau_secs).exp();
    let target = |u: f64| 35_000.0 + 7_000.0 * u;
    let mut y_true = Vec::with_capacity(u.len());
    let mut y_hat = Vec::with_capacity(u.len());
    let mut y = target(u[0]);
    for &uk in &u {
        let rate_per_s = (target(uk) - y) / tau_secs;
        y_true.push(y);
        y_hat.push(if rate_per_s < 0.0 { y - 0.5 * rate_per_s } else { y });
        y = a * y + (1.0 - a) * target(uk);
    }
    let noise = gaussian(u.len(), SPEED_SIGMA_RPM, 7);
    let measured: Vec<f64> = y_true.iter().zip(&noise).map(|(y, e)| y + e).collect();
    let n = u.len();
    let run = Run {
        name: "decel".into(),
        dt_secs: DT_SECS,
        t_secs: (0..n).map(|k| k as f64 * DT_SECS).collect(),
        input: Channel::new("fuel_flow_gph", u),
        outputs: vec![Channel::new(SPEED, measured)],
        aux: vec![Channel::new("ambient_temp_c", gaussian(n, 0.05, 8).iter().map(|e| 15.0 + e).collect())],
    };
    DecelCase { run, y_hat, down_steps }
}

#[test]
fn errors_only_in_decelerations_are_reported_so() {
    let case = decel_case();
    let a =
        analyse_residuals(&case.run, SPEED, &case.y_hat, Some(SPEED_SIGMA_RPM), &ResidualSettings::default())
            .unwrap();
    let row = |r: Regime| a.regimes.row(r).unwrap();
    let (decel, accel) = (row(Regime::Decelerating), row(Regime::Accelerating));
    assert!(decel.share_of_squared_error_pct > 80.0, "{:?}", a.regimes);
    assert!(decel.rmse.unwrap() > 3.0 * accel.rmse.unwrap(), "{:?}", a.regimes);
    assert!(accel.rmse.unwrap() < 1.3 * SPEED_SIGMA_RPM, "{accel:?}");
    assert!(decel.mean_error.unwrap() < 0.0, "the lagging model over-predicts: {decel:?}");
    let text = summary(&a);
    assert!(text.contains("decelerations are") && text.contains("worse than accelerations"), "{text}");
    assert_eq!(a.worst_stretches.len(), 5);
    for s in &a.worst_stretches {
        assert!(case.down_steps.iter().any(|&k| (s.start_sample..s.end_sample).contains(&k)), "{s:?}");
        assert!((s.start_secs - case.run.t_secs[s.start_sample]).abs() < 1e-12);
    }
    assert!(a.worst_stretches.windows(2).all(|w| w[0].rms >= w[1].rms
        && w[0].end_sample.min(w[1].end_sample) <= w[0].start_sample.max(w[1].start_sample)));
}

#[test]
fn regime_rows_partition_the_run() {
    let case = decel_case();
    let lo = 35_000.0 + 7_000.0 * 4.0;
    let hi = 35_000.0 + 7_000.0 * 5.5;
    for bands in [OperatingBands::RunRangeThirds, OperatingBands::Fixed { low_below: lo, high_from: hi }] {
        let settings = ResidualSettings { operating_bands: bands, ..ResidualSettings::default() };
        let a = analyse_residuals(&case.run, SPEED, &case.y_hat, Some(SPEED_SIGMA_RPM), &settings).unwrap();
        let n = |r: Regime| a.regimes.row(r).unwrap().samples;
        let share = |r: Regime| a.regimes.row(r).unwrap().share_of_squared_error_pct;
        assert_eq!(n(Regime::Run), case.run.len());
        assert_eq!(n(Regime::Steady) + n(Regime::Transient), n(Regime::Run));
        assert_eq!(n(Regime::Accelerating) + n(Regime::Decelerating), n(Regime::Transient));
        assert_eq!(n(Regime::Low) + n(Regime::Mid) + n(Regime::High), n(Regime::Run));
        assert!((share(Regime::Low) + share(Regime::Mid) + share(Regime::High) - 100.0).abs() < 1e-9);
        assert!((share(Regime::Steady) + share(Regime::Transient) - 100.0).abs() < 1e-9);
        let (lo_used, hi_used) = a.regimes.band_limits;
        let y = &case.run.output(SPEED).unwrap().values;
        assert_eq!(n(Regime::Low), y.iter().filter(|v| **v < lo_used).count());
        assert_eq!(n(Regime::High), y.iter().filter(|v| **v >= hi_used).count());
    }
}

#[test]
fn analysis_survives_a_json_round_trip() {
    let case = decel_case();
    let a = analyse_residuals(&case.run, SPEED, &case.y_hat, None, &ResidualSettings::default()).unwrap();
    let back: ResidualAnalysis = serde_json::from_str(&serde_json::to_string(&a).unwrap()).unwrap();
    // serde_json's default float parser may round the last bit; everything else is exact.
    let close =
        |x: &[f64], y: &[f64]| x.iter().zip(y).all(|(p, q)| (p - q).abs() <= 1e-14 * p.abs().max(1.0));
    assert!(back.residual.len() == a.residual.len() && close(&back.residual, &a.residual));
    assert!(close(&back.spectrum.psd_per_hz, &a.spectrum.psd_per_hz));
    assert_eq!(back.sample_regimes, a.sample_regimes);
    assert_eq!(back.autocorrelation.exceeding_lags_samples, a.autocorrelation.exceeding_lags_samples);
    let starts = |x: &ResidualAnalysis| x.worst_stretches.iter().map(|s| s.start_sample).collect::<Vec<_>>();
    assert_eq!(starts(&back), starts(&a));
    let counts =
        |x: &ResidualAnalysis| x.regimes.rows.iter().map(|r| (r.regime, r.samples)).collect::<Vec<_>>();
    assert_eq!(counts(&back), counts(&a));
    let sentences = jetid::core::residuals::summary_sentences(&a);
    assert!((2..=4).contains(&sentences.len()), "{sentences:?}");
}

#[test]
fn channels_the_scan_cannot_use_are_listed_with_the_reason() {
    let DecelCase { mut run, y_hat, .. } = decel_case();
    let n = run.len();
    let mut dropout: Vec<f64> = gaussian(n, 1.0, 9);
    dropout[100] = f64::NAN;
    run.aux.push(Channel::new("egt_c", dropout));
    run.aux.push(Channel::new("relative_humidity_pct", vec![50.0; n]));
    run.aux.push(Channel::new("inlet_corrected_gph", gaussian(n, 1.0, 10)));
    run.aux.push(Channel::new("short_c", vec![1.0; 10]));
    let settings =
        ResidualSettings { model_channels: vec!["inlet_corrected_gph".into()], ..Default::default() };
    let a = analyse_residuals(&run, SPEED, &y_hat, Some(SPEED_SIGMA_RPM), &settings).unwrap();
    let reason =
        |name: &str| a.channels.excluded.iter().find(|e| e.channel == name).map(|e| e.reason.clone());
    assert_eq!(reason("egt_c"), Some(ExclusionReason::NonFinite { index: 100 }));
    assert_eq!(reason("relative_humidity_pct"), Some(ExclusionReason::Constant));
    assert_eq!(reason("inlet_corrected_gph"), Some(ExclusionReason::UsedByModel));
    assert_eq!(reason("short_c"), Some(ExclusionReason::LengthMismatch { found: 10, expected: n }));
    let scanned: Vec<&str> = a.channels.channels.iter().map(|c| c.channel.as_str()).collect();
    assert_eq!(scanned, ["ambient_temp_c"]);
}

#[test]
fn every_caller_error_is_a_typed_error() {
    let case = decel_case();
    let (run, y_hat) = (&case.run, &case.y_hat);
    let n = run.len();
    let ok = ResidualSettings::default();
    let go = |run: &Run, y_hat: &[f64], sigma: Option<f64>, s: &ResidualSettings| {
        analyse_residuals(run, SPEED, y_hat, sigma, s).unwrap_err()
    };

    assert!(matches!(analyse_residuals(run, "thrust_n", y_hat, None, &ok),
        Err(ResidualError::UnknownOutput { output, available, .. }) if output == "thrust_n" && available == SPEED));
    assert_eq!(
        go(run, &y_hat[..n - 3], None, &ok),
        ResidualError::LengthMismatch { expected: n, found: n - 3 }
    );

    let mut short_input = run.clone();
    short_input.input.values.truncate(n - 1);
    assert_eq!(
        go(&short_input, y_hat, None, &ok),
        ResidualError::ChannelLength { channel: "fuel_flow_gph".into(), expected: n, found: n - 1 }
    );

    let mut tiny = run.clone();
    tiny.t_secs.truncate(40);
    tiny.input.values.truncate(40);
    tiny.outputs[0].values.truncate(40);
    assert!(
        matches!(go(&tiny, &y_hat[..40], None, &ok), ResidualError::TooFewSamples { samples: 40, needed } if needed > 40)
    );

    let mut bad_hat = y_hat.clone();
    bad_hat[17] = f64::NAN;
    assert_eq!(
        go(run, &bad_hat, None, &ok),
        ResidualError::NonFinite { signal: "model output".into(), index: 17 }
    );
    let mut bad_y = run.clone();
    bad_y.outputs[0].values[5] = f64::INFINITY;
    assert_eq!(go(&bad_y, y_hat, None, &ok), ResidualError::NonFinite { signal: SPEED.into(), index: 5 });
    let mut bad_u = run.clone();
    bad_u.input.values[9] = f64::NAN;
    assert_eq!(
        go(&bad_u, y_hat, None, &ok),
        ResidualError::NonFinite { signal: "fuel_flow_gph".into(), index: 9 }
    );

    for sigma in [0.0, -1.0, f64::NAN] {
        assert!(
            matches!(go(run, y_hat, Some(sigma), &ok), ResidualError::BadNoiseSigma { .. }),
            "σ = {sigma}"
        );
    }
    let mut no_dt = run.clone();
    no_dt.dt_secs = 0.0;
    assert!(matches!(go(&no_dt, y_hat, None, &ok), ResidualError::BadSampleTime { .. }));

    let bad_settings = [
        ("band_sigmas", ResidualSettings { band_sigmas: 0.0, ..ok.clone() }),
        ("max_lag_secs", ResidualSettings { max_lag_secs: f64::NAN, ..ok.clone() }),
        ("prewhiten_order", ResidualSettings { prewhiten_order: 60, ..ok.clone() }),
        ("slope_window_secs", ResidualSettings { slope_window_secs: -1.0, ..ok.clone() }),
        ("transient_range_frac_per_s", ResidualSettings { transient_range_frac_per_s: 0.0, ..ok.clone() }),
        (
            "operating_bands.low_below",
            ResidualSettings {
                operating_bands: OperatingBands::Fixed { low_below: 2.0, high_from: 1.0 },
                ..ok.clone()
            },
        ),
        ("welch_segment_len", ResidualSettings { welch_segment_len: 100, ..ok.clone() }),
        ("slow_window_secs", ResidualSettings { slow_window_secs: 0.0, ..ok.clone() }),
        ("channel_alpha", ResidualSettings { channel_alpha: 1.5, ..ok.clone() }),
        ("stretch_secs", ResidualSettings { stretch_secs: f64::INFINITY, ..ok.clone() }),
        ("stretch_count", ResidualSettings { stretch_count: 0, ..ok.clone() }),
    ];
    for (name, settings) in bad_settings {
        assert!(
            matches!(go(run, y_hat, None, &settings), ResidualError::BadSetting { name: got, .. } if got == name),
            "{name}"
        );
    }
}
