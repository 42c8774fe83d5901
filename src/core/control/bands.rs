//! A model's parameter covariance carried to what people read off it: 95 % intervals of each
//! operating point's figures, and a 95 % band of the noiseless output on a run.
//!
//! **Operating points: Monte Carlo over the covariance.** Rise and settling times jump where a
//! step response's overshoot crosses the 2 % band, and the bandwidth where a resonance crosses
//! −3 dB, so a first-order (delta-method) propagation can be arbitrarily wrong for them. The
//! intervals are the 2.5 and 97.5 percentiles of each figure over [`DRAWS`] models drawn from the
//! covariance (as MATLAB's `simsd` does for outputs).
//!
//! **The output band: delta method.** The simulated output is a smooth function of the parameters
//! at every sample, and the first-order propagation needs two simulations per parameter where
//! percentiles would need hundreds: `var ŷₖ = gₖᵀ Σ gₖ`, `gₖ` the output's gradient at sample k.
use num_complex::Complex64;

use super::covariance::{CovarianceError, ParameterCovariance, Slot, model_at};
#[cfg(test)]
use super::operating_point::operating_points;
use super::operating_point::{LocalPole, OperatingPoint, operating_points_without_continuous};
use crate::core::effects::ExtendedModel;
use crate::core::parallel::on_two_threads;
use crate::core::run::Run;

/// Models drawn for the operating points' intervals. Each 2.5 % tail then holds 5 draws; the
/// binomial spread of the share of a distribution below the 2.5 % percentile of 200 draws is
/// √(0.025·0.975/200) ≈ 1.1 points, so a calibrated interval covers 95 ± 1.6 % of the time, well
/// inside the 85–99 % a user can rely on; 1,000 draws would cost five times the time for half that.
pub const DRAWS: usize = 200;
/// A figure gets an interval only when at least this share of the draws have it (a bandwidth
/// that some draws lose above Nyquist has no honest percentile).
const MIN_SHARE: f64 = 0.9;
/// Seed of the draws: a report must come out the same on every run.
const SEED: u64 = 0x6A65_7469_6400;
/// The two-sided 95 % quantile of the normal distribution.
const Z95: f64 = 1.959_963_985;

/// The 2.5 and 97.5 percentiles of `values` when they hold at least [`MIN_SHARE`] of `draws`.
fn percentile_interval(mut values: Vec<f64>, draws: usize) -> Option<[f64; 2]> {
    values.retain(|v| v.is_finite());
    if values.is_empty() || (values.len() as f64) < MIN_SHARE * draws as f64 {
        return None;
    }
    values.sort_by(f64::total_cmp);
    let at = |q: f64| {
        let pos = q * (values.len() - 1) as f64;
        let (i, f) = (pos.floor() as usize, pos - pos.floor());
        values[i] + f * (values[(i + 1).min(values.len() - 1)] - values[i])
    };
    Some([at(0.025), at(0.975)])
}

/// Each of `poles` with the drawn pole that is the same pole: the nearest in z of the same kind
/// (real with a time constant, or a pair), each drawn pole taken once, slowest first. The order by
/// modulus alone would swap two real poles whenever a draw moves one past the other.
fn match_poles<'a>(poles: &[LocalPole], drawn: &'a [LocalPole]) -> Vec<Option<&'a LocalPole>> {
    let mut used = vec![false; drawn.len()];
    poles
        .iter()
        .map(|p| {
            let best = (0..drawn.len())
                .filter(|&k| !used[k] && drawn[k].tau_s.is_some() == p.tau_s.is_some())
                .min_by(|&a, &b| (drawn[a].z - p.z).norm().total_cmp(&(drawn[b].z - p.z).norm()))?;
            used[best] = true;
            Some(&drawn[best])
        })
        .collect()
}

/// Fill the `*_ci95` fields of `points` (computed by [`operating_points`] from `model` over
/// `input_range` and `plateaus`) from the covariance. Returns how many draws gave operating points.
pub fn with_intervals(
    points: &mut [OperatingPoint],
    model: &ExtendedModel,
    covariance: &ParameterCovariance,
    input_range: (f64, f64),
    plateaus: &[(String, f64)],
) -> Result<usize, CovarianceError> {
    let models = covariance.draw_models(model, DRAWS, SEED)?;
    let drawn: Vec<Vec<OperatingPoint>> =
        on_two_threads(&models, |m| operating_points_without_continuous(m, input_range, plateaus).ok())
            .into_iter()
            .flatten()
            .filter(|ps| ps.len() == points.len())
            .collect();
    for (i, point) in points.iter_mut().enumerate() {
        let figure = |pick: &dyn Fn(&OperatingPoint) -> Option<f64>| {
            percentile_interval(drawn.iter().filter_map(|ps| pick(&ps[i])).collect(), DRAWS)
        };
        point.gain_ci95 = figure(&|p| Some(p.gain));
        point.bandwidth_rad_s_ci95 = figure(&|p| p.bandwidth_rad_s);
        point.step.rise_s_ci95 = figure(&|p| p.step.rise_s);
        point.step.settling_s_ci95 = figure(&|p| p.step.settling_s);
        let matched: Vec<Vec<Option<&LocalPole>>> =
            drawn.iter().map(|ps| match_poles(&point.poles, &ps[i].poles)).collect();
        for (j, pole) in point.poles.iter_mut().enumerate() {
            let of = |pick: &dyn Fn(&LocalPole) -> Option<f64>| {
                percentile_interval(matched.iter().filter_map(|m| m[j].and_then(pick)).collect(), DRAWS)
            };
            pole.tau_s_ci95 = pole.tau_s.and_then(|_| of(&|p| p.tau_s));
            if pole.tau_s.is_none() {
                pole.wn_rad_s_ci95 = of(&|p| p.wn_rad_s);
                pole.zeta_ci95 = of(&|p| p.zeta);
            }
        }
    }
    Ok(drawn.len())
}

/// The half-width of the 95 % band of `model`'s noiseless output on `run`, sample by sample, from
/// the covariance (delta method, see the module documentation).
pub fn output_half_widths(
    model: &ExtendedModel,
    covariance: &ParameterCovariance,
    run: &Run,
) -> Result<Vec<f64>, CovarianceError> {
    let theta0 = &covariance.values;
    let n = theta0.len();
    let simulate = |theta: &[f64], name: &str, step: f64| -> Result<Vec<f64>, CovarianceError> {
        let no_model = || CovarianceError::NoModel { name: name.to_owned(), step };
        model_at(model, theta).ok_or_else(no_model)?.simulate(run).map_err(|_| no_model())
    };
    let centre = simulate(theta0, "the fitted values", 0.0)?;
    let sd = covariance.std_devs();
    let mut gradients: Vec<Vec<f64>> = Vec::with_capacity(n);
    for i in 0..n {
        if sd[i] == 0.0 {
            gradients.push(vec![0.0; run.len()]);
            continue;
        }
        // A tenth of the parameter's own standard deviation: inside the region the band describes,
        // and far above rounding.
        let h = 0.1 * sd[i];
        let (mut up, mut down) = (theta0.clone(), theta0.clone());
        up[i] += h;
        down[i] -= h;
        let name = &covariance.names[i];
        // One-sided at a parameter's range bound (a fit that ended on it).
        let (a, b, width) = match (simulate(&up, name, h), simulate(&down, name, h)) {
            (Ok(a), Ok(b)) => (a, b, 2.0 * h),
            (Ok(a), Err(_)) => (a, centre.clone(), h),
            (Err(_), Ok(b)) => (centre.clone(), b, h),
            (Err(e), Err(_)) => return Err(e),
        };
        gradients.push(a.iter().zip(&b).map(|(a, b)| (a - b) / width).collect());
    }
    let len = gradients.first().map_or(run.len(), Vec::len);
    Ok((0..len)
        .map(|k| {
            let mut var = 0.0;
            for i in 0..n {
                for j in 0..n {
                    var += gradients[i][k] * covariance.matrix[i][j] * gradients[j][k];
                }
            }
            Z95 * var.max(0.0).sqrt()
        })
        .collect())
}

/// One number of the model with its 95 % interval (percentiles over models drawn from the
/// covariance); `None` where too few draws have the number.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ParameterInterval {
    pub name: String,
    pub value: f64,
    pub ci95: Option<[f64; 2]>,
}

/// Seed of the draws behind [`parameter_intervals`].
const PARAMETER_SEED: u64 = 0x6A65_7469_6403;

/// The numbers of `model` a user reads, each with its 95 % interval over [`DRAWS`] models drawn
/// from the covariance:
/// - the static map's plain coefficients β0, β1, … of f(v);
/// - each effect's parameters in physical units, as its record names them;
/// - the coefficients of the linear block's zero-order-hold continuous equivalent (descending
///   powers of s, denominator monic), when the block has one.
pub fn parameter_intervals(
    model: &ExtendedModel,
    covariance: &ParameterCovariance,
) -> Result<Vec<ParameterInterval>, CovarianceError> {
    let draws = covariance.draw_models(model, DRAWS, PARAMETER_SEED)?;
    let numbers = |m: &ExtendedModel| -> Vec<(String, f64)> {
        let mut out: Vec<(String, f64)> = m
            .wiener
            .map
            .beta()
            .into_iter()
            .enumerate()
            .map(|(k, b)| (format!("static map β{k}"), b))
            .collect();
        for record in m.records() {
            out.extend(record.params.iter().map(|(name, v)| (format!("{}.{name}", record.id), *v)));
        }
        if let Ok(c) = super::d2c::d2c_zoh(&m.wiener.linear.tf) {
            let n = c.num_s.len();
            out.extend(
                c.num_s.iter().enumerate().map(|(k, b)| (format!("G(s) numerator s^{}", n - 1 - k), *b)),
            );
            let d = c.den_s.len();
            out.extend(
                c.den_s
                    .iter()
                    .enumerate()
                    .skip(1)
                    .map(|(k, a)| (format!("G(s) denominator s^{}", d - 1 - k), *a)),
            );
        }
        out
    };
    let drawn: Vec<Vec<(String, f64)>> = draws.iter().map(numbers).collect();
    Ok(numbers(model)
        .into_iter()
        .map(|(name, value)| {
            let values: Vec<f64> =
                drawn.iter().filter_map(|d| d.iter().find(|(n, _)| *n == name).map(|(_, v)| *v)).collect();
            ParameterInterval { ci95: percentile_interval(values, DRAWS), name, value }
        })
        .collect())
}

/// The 2.5 and 97.5 percentiles, sample by sample, of the unit step responses of the drawn
/// models' local dynamics at the steady input `u` (each normalised by its final value, as the
/// operating points' step figures are), over `samples` samples; `None` when too few draws have
/// local dynamics there.
pub fn step_band(draws: &[ExtendedModel], u: f64, samples: usize) -> Option<(Vec<f64>, Vec<f64>)> {
    let responses: Vec<Vec<f64>> = draws
        .iter()
        .filter_map(|m| super::operating_point::local_dynamics(m, u).ok())
        .map(|unit| unit.simulate_with_history(&vec![1.0; samples], 0.0, 0.0))
        .collect();
    let mut lo = Vec::with_capacity(samples);
    let mut hi = Vec::with_capacity(samples);
    for k in 0..samples {
        let [a, b] = percentile_interval(responses.iter().map(|r| r[k]).collect(), draws.len())?;
        lo.push(a);
        hi.push(b);
    }
    Some((lo, hi))
}

/// The 2.5 and 97.5 percentiles of the drawn models' linear-block frequency response.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BodeBand {
    pub omega_rad_s: Vec<f64>,
    /// `[low, high]` magnitude, dB.
    pub mag_db: Vec<[f64; 2]>,
    /// `[low, high]` phase, degrees (each draw's phase unwrapped from the lowest frequency).
    pub phase_deg: Vec<[f64; 2]>,
}

/// The band of the linear block's Bode plot over `draws` (models drawn from the covariance) at
/// `omegas_rad_s`; empty without draws.
pub fn bode_band(draws: &[ExtendedModel], omegas_rad_s: &[f64]) -> BodeBand {
    if draws.is_empty() {
        return BodeBand::default();
    }
    let curves: Vec<Vec<crate::core::numerics::tf::BodePoint>> =
        draws.iter().map(|m| m.wiener.linear.tf.bode_response(omegas_rad_s)).collect();
    let at = |k: usize, pick: &dyn Fn(&crate::core::numerics::tf::BodePoint) -> f64| {
        percentile_interval(curves.iter().map(|c| pick(&c[k])).collect(), curves.len())
            .unwrap_or([f64::NAN; 2])
    };
    BodeBand {
        omega_rad_s: omegas_rad_s.to_vec(),
        mag_db: (0..omegas_rad_s.len()).map(|k| at(k, &|p| p.mag_db)).collect(),
        phase_deg: (0..omegas_rad_s.len()).map(|k| at(k, &|p| p.phase_deg)).collect(),
    }
}

/// The 95 % region of one root of the model in the z-plane: its position and the covariance of
/// its real and imaginary parts (a pair's upper root; a real root's imaginary variance is zero).
#[derive(Clone, Debug, PartialEq)]
pub struct RootRegion {
    pub centre: Complex64,
    pub is_pole: bool,
    /// Covariance of (Re z, Im z).
    pub covariance: [[f64; 2]; 2],
}

/// The χ² quantile with two degrees of freedom at 95 %: `−2 ln 0.05`.
const CHI2_2DOF_95: f64 = 5.991_464_547;

impl RootRegion {
    /// The 95 % ellipse as `n` points (a segment along the real axis for a real root): the
    /// points `centre + L·(cos t, sin t)·√χ²₂(0.95)`, `L Lᵀ` the covariance.
    pub fn outline(&self, n: usize) -> Vec<[f64; 2]> {
        let [[a, b], [_, d]] = self.covariance;
        // Cholesky of the 2 × 2 covariance, a zero variance allowed.
        let l11 = a.max(0.0).sqrt();
        let l21 = if l11 > 0.0 { b / l11 } else { 0.0 };
        let l22 = (d - l21 * l21).max(0.0).sqrt();
        let r = CHI2_2DOF_95.sqrt();
        (0..=n)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / n as f64;
                let (c, s) = (r * t.cos(), r * t.sin());
                [self.centre.re + l11 * c, self.centre.im + l21 * c + l22 * s]
            })
            .collect()
    }
}

/// The 95 % region of each root of `model` (poles, then zeros; one per real root and per pair)
/// from the covariance, by the delta method through each root's coordinates.
pub fn root_regions(
    model: &ExtendedModel,
    covariance: &ParameterCovariance,
) -> Result<Vec<RootRegion>, CovarianceError> {
    let layout = super::covariance::parameter_layout(model)?;
    let (x, cov) = (&covariance.values, &covariance.matrix);
    if x.len() < layout.poles.len() + layout.zeros.len() {
        return Err(CovarianceError::Mismatch {
            stored: x.len(),
            model: layout.poles.len() + layout.zeros.len(),
        });
    }
    let mut regions = Vec::new();
    let mut at = 0;
    for (slot, is_pole) in
        layout.poles.iter().map(|s| (s, true)).chain(layout.zeros.iter().map(|s| (s, false)))
    {
        // The Jacobian of (Re z, Im z) in the root's coordinates (see `core::control::covariance`).
        let (centre, jac, k): (Complex64, [[f64; 2]; 2], usize) = match (slot, is_pole) {
            (Slot::Real, true) => {
                let z = x[at].tanh();
                (Complex64::new(z, 0.0), [[1.0 - z * z, 0.0], [0.0, 0.0]], 1)
            }
            (Slot::Real, false) => (Complex64::new(x[at], 0.0), [[1.0, 0.0], [0.0, 0.0]], 1),
            (Slot::Pair, true) => {
                let (r, phi) = (x[at].tanh(), x[at + 1]);
                let dr = 1.0 - r * r;
                (
                    Complex64::from_polar(r, phi),
                    [[dr * phi.cos(), -r * phi.sin()], [dr * phi.sin(), r * phi.cos()]],
                    2,
                )
            }
            (Slot::Pair, false) => (Complex64::new(x[at], x[at + 1]), [[1.0, 0.0], [0.0, 1.0]], 2),
        };
        let c = |i: usize, j: usize| if i < k && j < k { cov[at + i][at + j] } else { 0.0 };
        let mut out = [[0.0; 2]; 2];
        for (r, row) in out.iter_mut().enumerate() {
            for (s, cell) in row.iter_mut().enumerate() {
                *cell = (0..2)
                    .flat_map(|i| (0..2).map(move |j| (i, j)))
                    .map(|(i, j)| jac[r][i] * c(i, j) * jac[s][j])
                    .sum();
            }
        }
        regions.push(RootRegion { centre, is_pole, covariance: out });
        at += k;
    }
    Ok(regions)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use num_complex::Complex64;

    use super::*;
    use crate::core::control::covariance::estimate;
    use crate::core::identification::cluster::RootKind;
    use crate::core::identification::reduce::{IdentData, RootGroup, polish, steady_windows};
    use crate::core::identification::test_system::{DT_SECS, LEVELS, OUTPUT, TestSystem, static_map};
    use crate::core::identification::wiener::unit_gain_tf;
    use crate::core::run::Channel;

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
        assert!(
            band >= 0.85,
            "the output band covers the true output on {band:.3} of the fresh run's samples"
        );
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
                assert!(
                    (var_im / c_im - 1.0).abs() < 0.15,
                    "{region:?}: Im variance {var_im} against {c_im}"
                );
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
}
