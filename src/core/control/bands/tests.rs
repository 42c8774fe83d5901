#![allow(clippy::unwrap_used)]
use num_complex::Complex64;

use super::*;
use crate::core::control::covariance::{ParameterCovariance, estimate};
use crate::core::control::operating_point::operating_points;
use crate::core::effects::ExtendedModel;
use crate::core::identification::cluster::RootKind;
use crate::core::identification::reduce::{IdentData, RootGroup, polish, steady_windows};
use crate::core::identification::test_system::{DT_SECS, LEVELS, OUTPUT, TestSystem, static_map};
use crate::core::identification::wiener::unit_gain_tf;
use crate::core::run::{Channel, Run};

/// The test system of `truth_poles` (noise σ 0.05, `seed`) fitted from a real root and a pair
/// started away from the truth, and its parameter covariance.
fn fitted(truth_poles: &[Complex64], seed: u64) -> (ExtendedModel, ParameterCovariance) {
    let sys = TestSystem::with_poles(truth_poles, 0, 0.05, seed);
    let data = IdentData::new(&sys.fits, &sys.run, &sys.settings).unwrap();
    let start = [
        RootGroup::free_real(RootKind::Pole, 0.85),
        RootGroup::free_pair(RootKind::Pole, Complex64::new(0.7, 0.25)),
    ];
    let fitted = polish(&data, &start, 2).unwrap();
    let model = ExtendedModel::new(OUTPUT, fitted.assembled.wiener);
    let covariance = estimate(&model, &sys.run, &steady_windows(&data)).unwrap();
    (model, covariance)
}

/// A fresh run of the true system, noiseless: other levels than the identification run's,
/// inside its range.
fn fresh_truth(tf: &crate::core::numerics::tf::DiscreteTf) -> Run {
    let u: Vec<f64> = [1.2, 2.4, 1.6, 2.2, 1.1, 1.9].iter().flat_map(|l| [*l; 80]).collect();
    let y: Vec<f64> = tf.simulate_from_steady(&u).iter().map(|v| static_map(*v)).collect();
    Run {
        name: "fresh".to_owned(),
        dt_secs: DT_SECS,
        t_secs: (0..u.len()).map(|k| k as f64 * DT_SECS).collect(),
        input: Channel::new("u", u),
        outputs: vec![Channel::new(OUTPUT, y)],
        aux: Vec::new(),
    }
}

/// On engines that *are* a Wiener model (a real pole and a pair behind a unit-gain block, a
/// quadratic map, white noise), fitted from free roots started away from the truth at 40 seeds:
/// the operating points' 95 % intervals of the steady gain dy/du (at each of the 9 grid points),
/// of the real pole's τ and of the pair's ωn and ζ cover the true values at a rate between 85 and
/// 99 %, and the 95 % band of the noiseless output covers the true output on a fresh run for at
/// least 85 % of its samples. The truth is used only to score.
///
/// With 40 seeds a calibrated interval's count is Binomial(40, 0.95): 34 (85 %) is 2.9 standard
/// deviations below its mean of 38.
#[test]
fn operating_point_intervals_and_the_output_band_cover_the_truth() {
    let (real, pair) = (0.9, Complex64::new(0.75, 0.3));
    let truth_poles = [Complex64::new(real, 0.0), pair, pair.conj()];
    let truth_tf = unit_gain_tf(&truth_poles, &[], DT_SECS).unwrap();
    let fresh = fresh_truth(&truth_tf);
    let y_true = &fresh.outputs[0].values;
    let truth_s = |z: Complex64| Complex64::new(z.norm().ln(), z.arg()) / DT_SECS;
    let (tau_true, wn_true) = (-1.0 / truth_s(Complex64::new(real, 0.0)).re, truth_s(pair).norm());
    let zeta_true = -truth_s(pair).re / wn_true;
    let lo = LEVELS.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = LEVELS.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (mut gain_in, mut gains, mut tau_in, mut wn_in, mut zeta_in, mut seeds) = (0, 0, 0, 0, 0, 0);
    let (mut band_in, mut band_samples) = (0usize, 0usize);
    for seed in 0..40 {
        let (model, covariance) = fitted(&truth_poles, 5000 + seed);
        let mut points = operating_points(&model, (lo, hi), &[]).unwrap();
        with_intervals(&mut points, &model, &covariance, (lo, hi), &[]).unwrap();
        seeds += 1;
        let inside = |ci: Option<[f64; 2]>, x: f64| ci.is_some_and(|[a, b]| a <= x && x <= b);
        for p in &points {
            // The true steady gain: the map's slope at v* = u* (unit-gain block, no offset).
            gain_in += usize::from(inside(p.gain_ci95, 3.0 + p.u));
            gains += 1;
        }
        let mid = &points[points.len() / 2];
        let real_pole = mid.poles.iter().find(|p| p.tau_s.is_some()).unwrap();
        let pair_pole = mid.poles.iter().find(|p| p.tau_s.is_none()).unwrap();
        tau_in += usize::from(inside(real_pole.tau_s_ci95, tau_true));
        wn_in += usize::from(inside(pair_pole.wn_rad_s_ci95, wn_true));
        zeta_in += usize::from(inside(pair_pole.zeta_ci95, zeta_true));
        let half = output_half_widths(&model, &covariance, &fresh).unwrap();
        let predicted = model.simulate(&fresh).unwrap();
        band_in += (0..y_true.len()).filter(|&k| (predicted[k] - y_true[k]).abs() <= half[k]).count();
        band_samples += y_true.len();
    }
    let rates = [
        ("steady gain dy/du", gain_in as f64 / gains as f64),
        ("τ of the real pole", tau_in as f64 / seeds as f64),
        ("ωn of the pair", wn_in as f64 / seeds as f64),
        ("ζ of the pair", zeta_in as f64 / seeds as f64),
    ];
    let band = band_in as f64 / band_samples as f64;
    eprintln!("coverage: {rates:?}, output band {band:.3}");
    for (name, rate) in rates {
        assert!(
            (0.85..=0.99).contains(&rate),
            "{name}: the 95 % intervals cover the truth {rate:.3} of the time"
        );
    }
    assert!(band >= 0.85, "the output band covers the true output on {band:.3} of the fresh run's samples");
}

/// Each root's region is the covariance of its position: drawn from the covariance, the fitted
/// system's roots spread in z as the regions say (variances within 15 % with 4,000 draws, whose
/// own sampling spread is √(2/4000) ≈ 2 %; the rest allows for the delta method's curvature),
/// and the Bode band and every step band hold the model's own curve.
#[test]
fn root_regions_and_bands_match_the_drawn_models() {
    let pair = Complex64::new(0.75, 0.3);
    let (model, covariance) = fitted(&[Complex64::new(0.9, 0.0), pair, pair.conj()], 77);
    let regions = root_regions(&model, &covariance).unwrap();
    assert_eq!(regions.len(), 2, "a real pole and a pair");
    let draws = covariance.draw_models(&model, 4000, 3).unwrap();
    for region in &regions {
        let nearest = |m: &ExtendedModel| {
            let (poles, _) = m.roots().unwrap();
            poles
                .into_iter()
                .filter(|p| p.im >= 0.0)
                .min_by(|a, b| (a - region.centre).norm().total_cmp(&(b - region.centre).norm()))
                .unwrap()
        };
        let roots: Vec<Complex64> = draws.iter().map(nearest).collect();
        let n = roots.len() as f64;
        let mean = roots.iter().sum::<Complex64>() / n;
        let var_re = roots.iter().map(|r| (r.re - mean.re).powi(2)).sum::<f64>() / (n - 1.0);
        let var_im = roots.iter().map(|r| (r.im - mean.im).powi(2)).sum::<f64>() / (n - 1.0);
        let [[c_re, _], [_, c_im]] = region.covariance;
        assert!((var_re / c_re - 1.0).abs() < 0.15, "{region:?}: Re variance {var_re} against {c_re}");
        if region.centre.im > 0.0 {
            assert!((var_im / c_im - 1.0).abs() < 0.15, "{region:?}: Im variance {var_im} against {c_im}");
        }
    }
    let omegas = crate::core::numerics::tf::log_space(0.01, 30.0, 60);
    let band = bode_band(&draws, &omegas);
    let own = model.wiener.linear.tf.bode_response(&omegas);
    for (k, p) in own.iter().enumerate() {
        let [lo, hi] = band.mag_db[k];
        assert!(
            lo <= p.mag_db + 1e-9 && p.mag_db <= hi + 1e-9,
            "ω {}: {} outside {lo}..{hi}",
            p.omega_rad_s,
            p.mag_db
        );
    }
    let (lo, hi) = step_band(&draws, 2.0, 200).unwrap();
    let unit = crate::core::control::local_dynamics(&model, 2.0).unwrap();
    let own = unit.simulate_with_history(&[1.0; 200], 0.0, 0.0);
    assert!(
        (0..200).all(|k| lo[k] <= own[k] + 1e-9 && own[k] <= hi[k] + 1e-9),
        "the step band holds the model's own step"
    );
}
