//! Frequency validation, noise fits and Monte Carlo error propagation, checked on systems and
//! distributions with known answers, and on the bundled SR-30 runs.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::f64::consts::PI;
use std::path::Path;

use jetid::core::monte_carlo::{InputNoise, MonteCarloConfig, MonteCarloError, RunKind, monte_carlo};
use jetid::core::numerics::noise_fit::{Distribution, Family, NoiseFitError, fit, fit_all};
use jetid::core::numerics::spectral::{
    LowFrequencyLevel, SegmentLength, SpectralError, WelchOptions, bode_cutoff_rad_s, cutoff_rad_s,
    welch_response,
};
use jetid::core::numerics::tf::{DiscreteTf, log_space};
use jetid::io::csv_run::{LoadOptions, load_run};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

const DT: f64 = 1.0 / 8.85;
const BAND: (f64, f64) = (0.574, 13.78);

/// The paper's frequency test: 10 s hold, 160 s logarithmic chirp over `BAND`, 10 s hold.
fn paper_chirp() -> Vec<f64> {
    let (w0, w1) = BAND;
    let (hold, sweep) = (10.0, 160.0);
    (0..(180.0 / DT) as usize)
        .map(|k| {
            let t = k as f64 * DT - hold;
            if !(0.0..sweep).contains(&t) {
                return 5.0;
            }
            let ratio = w1 / w0;
            5.0 + 0.8 * (w0 * sweep / ratio.ln() * (ratio.powf(t / sweep) - 1.0)).sin()
        })
        .collect()
}

/// Gs(z) = 82.70 / ((z − 0.936)(z² − 1.608 z + 0.692)), the paper's shaft-speed model.
fn paper_gs() -> DiscreteTf {
    let den = [1.0, -1.608 - 0.936, 0.692 + 1.608 * 0.936, -0.692 * 0.936];
    DiscreteTf::new(vec![0.0, 0.0, 0.0, 82.70], den.to_vec(), DT).unwrap()
}

/// K (1 − p) z⁻¹ / (1 − p z⁻¹): DC gain K, pole p.
fn first_order(k: f64, p: f64) -> DiscreteTf {
    DiscreteTf::new(vec![0.0, k * (1.0 - p)], vec![1.0, -p], DT).unwrap()
}

fn normal_draws(n: usize, mean: f64, std: f64, seed: u64) -> Vec<f64> {
    draws(&Distribution::Normal { mean, std }, n, seed)
}

fn draws(d: &Distribution, n: usize, seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n).map(|_| d.sample(&mut rng)).collect()
}

fn wrap_deg(d: f64) -> f64 {
    d - 360.0 * (d / 360.0).round()
}

#[test]
fn welch_matches_a_known_tf_where_coherent() {
    let tf = paper_gs();
    let u = paper_chirp();
    let grid = log_space(BAND.0, BAND.1, 40);
    let exact = tf.bode_response(&grid);
    let y = tf.simulate_from_steady(&u);
    // Noise-free: only the method's bias is left, everywhere in the band.
    let clean = welch_response(&u, &y, DT, &grid, &WelchOptions::default()).unwrap();
    for (i, p) in exact.iter().enumerate() {
        assert!(
            (clean.mag_db[i] - p.mag_db).abs() < 0.3,
            "ω {}: {} vs {} dB",
            p.omega_rad_s,
            clean.mag_db[i],
            p.mag_db
        );
        let dphi = wrap_deg(clean.phase_deg[i] - p.phase_deg);
        assert!(dphi.abs() < 2.0, "ω {}: phase off by {dphi}°", p.omega_rad_s);
    }
    // Sensor-like noise: the output sinks into it near the top of the band, where coherence drops.
    let noise = normal_draws(u.len(), 0.0, 20.0, 7);
    let y: Vec<f64> = y.iter().zip(&noise).map(|(y, e)| y + e).collect();
    let est = welch_response(&u, &y, DT, &grid, &WelchOptions::default()).unwrap();
    let mut coherent = 0;
    for (i, p) in exact.iter().enumerate().filter(|(i, _)| est.coherence[*i] > 0.9) {
        coherent += 1;
        // The bias above plus three of the estimate's own standard errors (≈0.75 dB, 5° at γ² = 0.9).
        let (dmag, dphi) = (est.mag_db[i] - p.mag_db, wrap_deg(est.phase_deg[i] - p.phase_deg));
        let (mag_tol, phase_tol) = (0.5 + 3.0 * est.mag_std_db[i], 2.0 + 3.0 * est.phase_std_deg[i]);
        assert!(dmag.abs() < mag_tol.min(2.0), "ω {}: {dmag} dB off, tolerance {mag_tol}", p.omega_rad_s);
        assert!(dphi.abs() < phase_tol, "ω {}: {dphi}° off, tolerance {phase_tol}", p.omega_rad_s);
        if est.coherence[i] > 0.95 {
            assert!(dmag.abs() < 1.0, "ω {}: {dmag} dB off at γ² {}", p.omega_rad_s, est.coherence[i]);
        }
    }
    assert!(coherent >= 30, "only {coherent} of 40 points coherent: {:?}", est.coherence);
    assert!(est.n_segments >= 4 && est.effective_segments < est.n_segments as f64);
}

#[test]
fn coherence_is_low_when_the_output_is_pure_noise() {
    let u = paper_chirp();
    let y = normal_draws(u.len(), 0.0, 1.0, 3);
    let est = welch_response(&u, &y, DT, &log_space(BAND.0, BAND.1, 40), &WelchOptions::default()).unwrap();
    let mean = est.coherence.iter().sum::<f64>() / est.coherence.len() as f64;
    assert!(mean < 0.3, "mean coherence {mean} for an unrelated output");
}

#[test]
fn cutoff_of_a_first_order_system_is_the_analytic_one() {
    let p: f64 = 0.9;
    let analytic = ((-1.0 + 4.0 * p - p * p) / (2.0 * p)).acos() / DT;
    let tf = first_order(2.0, p);
    let grid = log_space(0.01, 0.99 * PI / DT, 300);
    let model = bode_cutoff_rad_s(&tf.bode_response(&grid), LowFrequencyLevel::FirstPoint).unwrap().unwrap();
    assert!((model / analytic - 1.0).abs() < 0.005, "{model} vs {analytic}");
    // The same finder on a Welch estimate from white-noise excitation.
    let u = normal_draws(6000, 0.0, 1.0, 11);
    let y = tf.simulate_with_history(&u, 0.0, 0.0);
    let grid = log_space(0.1, 20.0, 60);
    let est = welch_response(&u, &y, DT, &grid, &WelchOptions::default()).unwrap();
    let level = LowFrequencyLevel::Db(20.0 * 2f64.log10());
    let measured = est.cutoff_rad_s(level).unwrap().unwrap();
    assert!((measured / analytic - 1.0).abs() < 0.05, "{measured} vs {analytic}");
    // A flat response never falls.
    assert_eq!(cutoff_rad_s(&[1.0, 2.0, 3.0], &[0.0, -1.0, -2.9], LowFrequencyLevel::FirstPoint), Ok(None));
}

#[test]
fn excited_band_options_drop_unexcited_points() {
    let u = paper_chirp();
    let y = paper_gs().simulate_from_steady(&u);
    let grid = log_space(0.2, 25.0, 50);
    let all = welch_response(&u, &y, DT, &grid, &WelchOptions::default()).unwrap();
    let opts = WelchOptions { excited_only: Some(0.1), ..WelchOptions::default() };
    let excited = welch_response(&u, &y, DT, &grid, &opts).unwrap();
    assert!(excited.omega_rad_s.len() < all.omega_rad_s.len());
    assert!(excited.omega_rad_s.iter().all(|w| (0.3..20.0).contains(w)), "{:?}", excited.omega_rad_s);
    let band = all.within_band(BAND.0, BAND.1);
    assert!(band.omega_rad_s.iter().all(|w| (BAND.0..=BAND.1).contains(w)));
    assert_eq!(band.omega_rad_s.len(), band.coherence.len());
}

#[test]
fn spectral_errors_name_the_cause() {
    let u = paper_chirp();
    let grid = [1.0, 2.0];
    let opts = WelchOptions::default();
    let e = |u: &[f64], y: &[f64], dt: f64, g: &[f64], o: &WelchOptions| {
        welch_response(u, y, dt, g, o).unwrap_err()
    };
    assert_eq!(
        e(&u, &u[1..], DT, &grid, &opts),
        SpectralError::LengthMismatch { u: u.len(), y: u.len() - 1 }
    );
    assert!(matches!(
        e(&u[..10], &u[..10], DT, &grid, &opts),
        SpectralError::TooFewSamples { found: 10, .. }
    ));
    let mut bad = u.clone();
    bad[5] = f64::NAN;
    assert_eq!(e(&u, &bad, DT, &grid, &opts), SpectralError::NonFinite { signal: "output", index: 5 });
    assert_eq!(e(&u, &u, 0.0, &grid, &opts), SpectralError::BadSampleTime { dt_secs: 0.0 });
    assert_eq!(e(&u, &u, DT, &[], &opts), SpectralError::EmptyGrid);
    assert!(matches!(
        e(&u, &u, DT, &[1.0, 40.0], &opts),
        SpectralError::FrequencyOutOfRange { index: 1, .. }
    ));
    assert_eq!(e(&u, &u, DT, &[2.0, 1.0], &opts), SpectralError::GridNotIncreasing { index: 1 });
    let long = WelchOptions { segment: SegmentLength::Samples(u.len() + 1), ..opts };
    assert!(matches!(e(&u, &u, DT, &grid, &long), SpectralError::BadSegmentLength { .. }));
    let overlap = WelchOptions { overlap_fraction: 1.0, ..opts };
    assert_eq!(e(&u, &u, DT, &grid, &overlap), SpectralError::BadOverlap { overlap_fraction: 1.0 });
    let periods = WelchOptions { segment: SegmentLength::Auto { min_periods: 0.0, min_segments: 4 }, ..opts };
    assert_eq!(e(&u, &u, DT, &grid, &periods), SpectralError::BadMinPeriods { min_periods: 0.0 });
    let threshold = WelchOptions { excited_only: Some(2.0), ..opts };
    assert_eq!(e(&u, &u, DT, &grid, &threshold), SpectralError::BadThreshold { threshold: 2.0 });
    let flat = vec![5.0; u.len()];
    assert_eq!(e(&flat, &u, DT, &grid, &opts), SpectralError::NoInputPower { omega_rad_s: 1.0 });
    let level = LowFrequencyLevel::FirstPoint;
    assert_eq!(
        cutoff_rad_s(&[1.0], &[], level),
        Err(SpectralError::CurveLengthMismatch { omega: 1, mag: 0 })
    );
    let zero = LowFrequencyLevel::MeanOfFirst(0);
    assert_eq!(cutoff_rad_s(&[1.0], &[0.0], zero), Err(SpectralError::BadLevelCount { count: 0 }));
}

fn bundled(name: &str) -> jetid::core::run::Run {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("sample_runs/sr30").join(name);
    load_run(&path, &LoadOptions::default()).unwrap()
}

#[test]
fn bundled_chirp_is_coherent_over_most_of_the_band() {
    let run = bundled("chirp.csv");
    let speed = run.output("shaft_speed_rpm").unwrap();
    let grid = log_space(BAND.0, BAND.1, 40);
    let est = welch_response(&run.input.values, &speed.values, run.dt_secs, &grid, &WelchOptions::default())
        .unwrap();
    let coherent = est.coherence.iter().filter(|c| **c > 0.9).count();
    // The band from the bottom up where every point is coherent.
    let top = est.coherence.iter().take_while(|c| **c > 0.9).count();
    let cutoff = est.cutoff_rad_s(LowFrequencyLevel::FirstPoint).unwrap();
    eprintln!(
        "chirp fuel→speed: L = {}, K = {}, {coherent}/40 points γ² > 0.9, all of {}–{:.2} rad/s; \
         |H| {:.1} → {:.1} dB; −3 dB below the first point at {cutoff:?} rad/s",
        est.segment_len,
        est.n_segments,
        BAND.0,
        grid[top.saturating_sub(1)],
        est.mag_db[0],
        est.mag_db[top.saturating_sub(1)]
    );
    assert!(coherent * 3 >= 2 * grid.len(), "{coherent} of {} coherent", grid.len());
}

#[test]
fn bundled_steady_run_noise_fits() {
    let run = bundled("steady.csv");
    for (name, values) in
        [("fuel", &run.input.values), ("speed", &run.output("shaft_speed_rpm").unwrap().values)]
    {
        let report = fit_all(values).unwrap();
        assert_eq!(report.fits.len(), 6, "{:?}", report.skipped);
        let normal = report.get(Family::Normal).unwrap();
        let best = report.best().unwrap();
        eprintln!("{name}: best {:?}", report.best_by_log_likelihood);
        for f in &report.fits {
            eprintln!(
                "  {:?}: ll {:.3}, {:?}",
                f.distribution.family(),
                f.log_likelihood,
                f.distribution.params()
            );
        }
        assert!(best.log_likelihood - normal.log_likelihood < 10.0);
        assert_eq!(report.best_by_aic, report.best_by_log_likelihood); // all families have two parameters
    }
}

#[test]
fn normal_fit_recovers_a_fuel_like_sample() {
    let (mean, std, n) = (5.43, 0.0033, 5000);
    let data = normal_draws(n, mean, std, 1);
    let Distribution::Normal { mean: m, std: s } = fit(Family::Normal, &data).unwrap() else { panic!() };
    let se_mean = std / (n as f64).sqrt();
    assert!((m - mean).abs() < 4.0 * se_mean, "mean {m}");
    assert!((s - std).abs() < 4.0 * std / (2.0 * n as f64).sqrt(), "std {s}");
    // So narrow a sample leaves inverse Gaussian and Nakagami almost normal: normal is best or close.
    let report = fit_all(&data).unwrap();
    let best = report.best().unwrap().log_likelihood;
    assert!(best - report.get(Family::Normal).unwrap().log_likelihood < 3.0);
}

#[test]
fn the_generating_family_ranks_best() {
    let normal = fit_all(&normal_draws(5000, 10.0, 2.0, 2)).unwrap();
    assert_eq!(normal.best_by_log_likelihood, Family::Normal, "{:?}", normal.fits);
    let uniform = fit_all(&draws(&Distribution::Uniform { lower: 2.0, upper: 3.0 }, 5000, 3)).unwrap();
    assert_eq!(uniform.best_by_log_likelihood, Family::Uniform, "{:?}", uniform.fits);
    assert_eq!(uniform.best_by_aic, Family::Uniform);
}

fn truths() -> [Distribution; 6] {
    [
        Distribution::Normal { mean: -1.0, std: 0.5 },
        Distribution::Logistic { location: 3.0, scale: 0.4 },
        Distribution::Uniform { lower: 2.0, upper: 5.0 },
        Distribution::ExtremeValue { location: 1.0, scale: 0.3 },
        Distribution::InverseGaussian { mean: 2.0, shape: 5.0 },
        Distribution::Nakagami { shape: 1.5, spread: 4.0 },
    ]
}

/// The log-likelihood along each parameter is at its peak: the parabola through ℓ(θ − h), ℓ(θ),
/// ℓ(θ + h) (h about a standard error) has its vertex within a few hundredths of h of θ.
fn assert_stationary(d: &Distribution, data: &[f64]) {
    let family = d.family();
    let p0 = d.params().map(|(_, v)| v);
    let ll = |p: [f64; 2]| Distribution::from_params(family, p).unwrap().log_likelihood(data);
    let l0 = ll(p0);
    for i in 0..2 {
        let at = |h: f64| {
            let mut p = p0;
            p[i] += h;
            ll(p)
        };
        let mut h = 1e-3 * p0[i].abs().max(1e-9);
        for _ in 0..200 {
            let drop = l0 - 0.5 * (at(h) + at(-h));
            if drop > 1.0 {
                h *= 0.5;
            } else if drop < 0.01 {
                h *= 2.0;
            } else {
                break;
            }
        }
        let (lp, lm) = (at(h), at(-h));
        assert!(lp < l0 && lm < l0, "{family:?} {}: not a maximum", d.params()[i].0);
        let vertex = h * (lp - lm) / (2.0 * (2.0 * l0 - lp - lm));
        assert!(vertex.abs() < 0.05 * h, "{family:?} {}: vertex {vertex} vs step {h}", d.params()[i].0);
    }
}

#[test]
fn each_fit_is_the_likelihood_maximum_and_recovers_its_parameters() {
    for (k, truth) in truths().iter().enumerate() {
        let data = draws(truth, 20_000, 10 + k as u64);
        let fitted = fit(truth.family(), &data).unwrap();
        for ((name, got), (_, want)) in fitted.params().iter().zip(truth.params()) {
            assert!((got / want - 1.0).abs() < 0.05, "{:?} {name}: {got} vs {want}", truth.family());
        }
        let n = data.len() as f64;
        let sd = (data.iter().map(|x| (x - truth.mean()).powi(2)).sum::<f64>() / n).sqrt();
        let sample_mean = data.iter().sum::<f64>() / n;
        assert!((sample_mean - truth.mean()).abs() < 4.0 * sd / n.sqrt(), "{:?} mean", truth.family());
        // The density integrates to one.
        let (lo, hi) = (truth.mean() - 12.0 * sd, truth.mean() + 12.0 * sd);
        let m = 20_000;
        let dx = (hi - lo) / m as f64;
        let area: f64 = (0..=m)
            .map(|j| truth.pdf(lo + j as f64 * dx) * if j == 0 || j == m { 0.5 } else { 1.0 })
            .sum::<f64>()
            * dx;
        assert!((area - 1.0).abs() < 0.01, "{:?}: ∫pdf = {area}", truth.family());
        if truth.family() != Family::Uniform {
            assert_stationary(&fitted, &data);
        }
    }
    // Uniform: the MLE is the sample range.
    let data = draws(&truths()[2], 1000, 5);
    let Distribution::Uniform { lower, upper } = fit(Family::Uniform, &data).unwrap() else { panic!() };
    let (min, max) = data.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(*x), b.max(*x)));
    assert!((lower - min).abs() < 1e-12 && (upper - max).abs() < 1e-12);
}

#[test]
fn fits_stay_accurate_on_narrow_raw_data() {
    for (mean, std) in [(5.43, 0.0033), (73_850.0, 51.0)] {
        let data = normal_draws(300, mean, std, 21);
        let report = fit_all(&data).unwrap();
        assert_eq!(report.fits.len(), 6);
        for f in report.fits.iter().filter(|f| f.distribution.family() != Family::Uniform) {
            assert!((f.distribution.mean() / mean - 1.0).abs() < 1e-3, "{:?}", f.distribution);
            assert_stationary(&f.distribution, &data);
        }
    }
}

#[test]
fn noise_fit_errors_name_the_cause() {
    assert_eq!(fit(Family::Normal, &[1.0, 2.0]), Err(NoiseFitError::TooFewSamples { found: 2, needed: 3 }));
    assert_eq!(fit(Family::Logistic, &[1.0, f64::NAN, 2.0]), Err(NoiseFitError::NonFinite { index: 1 }));
    assert_eq!(fit_all(&[4.0; 10]).unwrap_err(), NoiseFitError::ZeroSpread { value: 4.0 });
    let data = [1.0, -0.5, 2.0, 0.3];
    let non_positive = NoiseFitError::NonPositive { family: Family::Nakagami, index: 1, value: -0.5 };
    assert_eq!(fit(Family::Nakagami, &data), Err(non_positive));
    assert!(matches!(fit(Family::InverseGaussian, &data), Err(NoiseFitError::NonPositive { index: 1, .. })));
    let report = fit_all(&data).unwrap();
    let skipped: Vec<Family> = report.skipped.iter().map(|s| s.family).collect();
    assert_eq!(skipped, [Family::InverseGaussian, Family::Nakagami]);
    let bad = Distribution::from_params(Family::Uniform, [3.0, 2.0]);
    assert_eq!(bad, Err(NoiseFitError::BadParameter { family: Family::Uniform, name: "upper", value: 2.0 }));
    let bad = Distribution::Nakagami { shape: -1.0, spread: 1.0 }.check();
    assert_eq!(
        bad,
        Err(NoiseFitError::BadParameter { family: Family::Nakagami, name: "shape", value: -1.0 })
    );
}

/// Runs the first-order model K(1 − p)z⁻¹/(1 − p z⁻¹) from rest under Monte Carlo.
fn mc_first_order(
    cfg: &MonteCarloConfig,
    noise: &Distribution,
    progress: &mut dyn FnMut(f64) -> bool,
) -> Result<jetid::core::monte_carlo::MonteCarloResult, MonteCarloError> {
    let tf = first_order(2.0, 0.9);
    monte_carlo(cfg, noise, &|u: &[f64]| tf.simulate_with_history(u, 0.0, 0.0), progress)
}

#[test]
fn monte_carlo_matches_the_analytic_spread_of_a_first_order_model() {
    let (k, p, sigma_u) = (2.0, 0.9f64, 0.0033);
    let cfg = MonteCarloConfig { runs: 400, ..MonteCarloConfig::paper(5.43, DT) };
    let noise = Distribution::Normal { mean: 5.43, std: sigma_u };
    let result = mc_first_order(&cfg, &noise, &mut |_| true).unwrap();
    // d = G e from rest: var d_k = σ²K²(1 − p)²(1 − p^{2k})/(1 − p²) (d_0 = 0 by the delay); pooled over
    // k < n it averages to the stationary σ²K²(1 − p)/(1 + p) less the start-up transient.
    let n = cfg.samples_per_run();
    let var =
        |j: usize| sigma_u.powi(2) * k * k * (1.0 - p).powi(2) * (1.0 - p.powi(2 * j as i32)) / (1.0 - p * p);
    let pooled = ((0..n).map(var).sum::<f64>() / n as f64).sqrt();
    let stationary = sigma_u * k * ((1.0 - p) / (1.0 + p)).sqrt();
    assert!(pooled < stationary);
    assert!((result.std_difference / pooled - 1.0).abs() < 0.03, "{} vs {pooled}", result.std_difference);
    assert!(result.mean_difference.abs() < 4.0 * pooled / (cfg.runs as f64).sqrt());
    // Within a run the run's own mean is removed, which takes Var(d̄) with it: E[s²] = (Σ v_k − n Var(d̄))/(n − 1)
    // with Cov(d_i, d_j) = p^{j−i} v_i for i ≤ j.
    let var_mean = (0..n)
        .map(|i| var(i) * (1.0 + 2.0 * (i + 1..n).map(|j| p.powi((j - i) as i32)).sum::<f64>()))
        .sum::<f64>()
        / (n * n) as f64;
    let expected_s2 = ((0..n).map(var).sum::<f64>() - n as f64 * var_mean) / (n - 1) as f64;
    let per_run_s2 = result.std_per_run.iter().map(|s| s * s).sum::<f64>() / cfg.runs as f64;
    assert!((per_run_s2 / expected_s2 - 1.0).abs() < 0.05, "{per_run_s2} vs {expected_s2}");
    assert_eq!(result.samples_per_run, 177);
    assert_eq!(result.histogram.counts.iter().sum::<usize>(), cfg.runs * n);
    assert_eq!(result.histogram.edges.len(), cfg.bins + 1);
    let Distribution::Normal { std, .. } = result.normal_fit else { panic!() };
    assert!((std / result.std_difference - 1.0).abs() < 1e-3);
}

#[test]
fn monte_carlo_maps_draws_onto_the_level_explicitly() {
    // A logistic fitted around 5.43, used at u0 = 5.0: its spread (σ = sπ/√3) drives the output either
    // way; only `DrawsAreInput` carries its mean along and biases the output by K·(5.43 − 5.0).
    let noise = Distribution::Logistic { location: 5.43, scale: 0.002 };
    let sigma_u = 0.002 * PI / 3f64.sqrt();
    let cfg = MonteCarloConfig { runs: 200, ..MonteCarloConfig::paper(5.0, DT) };
    let centred = mc_first_order(&cfg, &noise, &mut |_| true).unwrap();
    let stationary = sigma_u * 2.0 * (0.1f64 / 1.9).sqrt();
    assert!(centred.mean_difference.abs() < 0.1 * stationary);
    assert!((centred.std_difference / stationary - 1.0).abs() < 0.08);
    let raw = MonteCarloConfig { mapping: InputNoise::DrawsAreInput, ..cfg };
    let biased = mc_first_order(&raw, &noise, &mut |_| true).unwrap();
    assert!(biased.mean_difference > 0.5 * 2.0 * 0.43, "{}", biased.mean_difference);
}

#[test]
fn monte_carlo_is_deterministic_and_cancellable() {
    let noise = Distribution::Normal { mean: 5.43, std: 0.0033 };
    let cfg = MonteCarloConfig { runs: 20, ..MonteCarloConfig::paper(5.43, DT) };
    let a = mc_first_order(&cfg, &noise, &mut |_| true).unwrap();
    let b = mc_first_order(&cfg, &noise, &mut |_| true).unwrap();
    assert_eq!(a, b);
    let c = mc_first_order(&MonteCarloConfig { seed: 2, ..cfg }, &noise, &mut |_| true).unwrap();
    assert_ne!(a.std_per_run, c.std_per_run);
    let mut seen = Vec::new();
    let cancelled = mc_first_order(&cfg, &noise, &mut |f| {
        seen.push(f);
        seen.len() < 4
    });
    assert_eq!(cancelled, Err(MonteCarloError::Cancelled));
    assert_eq!(seen, [0.0, 0.05, 0.1, 0.15]);
    let mut last = 0.0;
    mc_first_order(&cfg, &noise, &mut |f| {
        assert!(f >= last);
        last = f;
        true
    })
    .unwrap();
    assert!((last - 1.0).abs() < 1e-12);
}

#[test]
fn monte_carlo_errors_name_the_cause() {
    let noise = Distribution::Normal { mean: 5.43, std: 0.0033 };
    let cfg = MonteCarloConfig::paper(5.43, DT);
    let run = |c: &MonteCarloConfig| mc_first_order(c, &noise, &mut |_| true).unwrap_err();
    assert_eq!(run(&MonteCarloConfig { runs: 0, ..cfg }), MonteCarloError::ZeroRuns);
    assert_eq!(run(&MonteCarloConfig { bins: 0, ..cfg }), MonteCarloError::ZeroBins);
    assert_eq!(
        run(&MonteCarloConfig { dt_secs: -1.0, ..cfg }),
        MonteCarloError::BadSampleTime { dt_secs: -1.0 }
    );
    let short = MonteCarloConfig { duration_secs: 0.1, ..cfg };
    assert_eq!(run(&short), MonteCarloError::TooShort { duration_secs: 0.1, samples: 1 });
    assert_eq!(
        run(&MonteCarloConfig { u0: f64::NAN, ..cfg }).to_string(),
        "the input level must be finite, got NaN"
    );
    let bad_noise = Distribution::Normal { mean: 5.43, std: -1.0 };
    let err = mc_first_order(&cfg, &bad_noise, &mut |_| true).unwrap_err();
    assert!(matches!(err, MonteCarloError::BadNoise(NoiseFitError::BadParameter { name: "std", .. })));
    let mc = |f: &dyn Fn(&[f64]) -> Vec<f64>| monte_carlo(&cfg, &noise, f, &mut |_| true).unwrap_err();
    assert_eq!(mc(&|u| u[1..].to_vec()), MonteCarloError::LengthMismatch { expected: 177, got: 176 });
    let nan_at_3 =
        |u: &[f64]| u.iter().enumerate().map(|(i, v)| if i == 3 { f64::NAN } else { *v }).collect();
    assert_eq!(mc(&nan_at_3), MonteCarloError::NonFinite { run: RunKind::Nominal, index: 3 });
    let blows_up =
        |u: &[f64]| u.iter().map(|v| if (v - 5.43).abs() > 1e-12 { f64::INFINITY } else { *v }).collect();
    assert!(matches!(mc(&blows_up), MonteCarloError::NonFinite { run: RunKind::Noisy(0), .. }));
    assert_eq!(mc(&|u| vec![1.0; u.len()]), MonteCarloError::NoSpread);
}
