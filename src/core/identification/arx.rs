//! High-order ARX models `A(q) y = B(q) u + e`, fitted by least squares (SVD, never the normal
//! equations) on deviations from a segment's starting steady state.
//!
//! Convention: `A = 1 + a1 z⁻¹ + … + a_na z⁻ⁿᵃ`, `B = z⁻ⁿᵏ (b0 + b1 z⁻¹ + … + b_nb z⁻ⁿᵇ)`: `na` poles,
//! `nb` finite zeros and an input delay of `nk` samples (default 1: a sampled physical plant has no
//! direct feed-through).
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use crate::core::numerics::lstsq::{LstsqError, solve_lstsq};
use crate::core::numerics::tf::{DiscreteTf, TfError};
use crate::core::numerics::{poly, tf};

/// Model orders: `na` poles, `nb` zeros, `nk` samples of input delay.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ArxOrders {
    pub na: usize,
    pub nb: usize,
    #[serde(default = "default_nk")]
    pub nk: usize,
}

fn default_nk() -> usize {
    1
}

impl ArxOrders {
    pub fn new(na: usize, nb: usize) -> Self {
        Self { na, nb, nk: 1 }
    }

    pub fn n_params(&self) -> usize {
        self.na + self.nb + 1
    }

    /// First sample index whose regressors are all inside the data.
    pub fn first_row(&self) -> usize {
        self.na.max(self.nk + self.nb)
    }

    pub fn check(&self) -> Result<(), ArxError> {
        if self.na == 0 || self.na > 60 || self.nb > 60 || self.nk > 50 {
            return Err(ArxError::BadOrders { orders: *self });
        }
        Ok(())
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ArxError {
    #[error("ARX orders na={}, nb={}, nk={} are out of range (1 ≤ na ≤ 60, nb ≤ 60, nk ≤ 50)", orders.na, orders.nb, orders.nk)]
    BadOrders { orders: ArxOrders },
    #[error("input has {u} samples but output has {y}")]
    LengthMismatch { u: usize, y: usize },
    #[error("{samples} samples are too few for {params} ARX parameters (need at least {needed})")]
    TooFewSamples { samples: usize, params: usize, needed: usize },
    #[error(transparent)]
    Lstsq(#[from] LstsqError),
    #[error(transparent)]
    Tf(#[from] TfError),
    #[error(transparent)]
    Poly(#[from] poly::PolyError),
}

/// A fitted ARX model with its fit diagnostics and roots.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ArxModel {
    pub orders: ArxOrders,
    pub tf: DiscreteTf,
    /// Sorted poles (roots of A in powers of z).
    pub poles: Vec<Complex64>,
    /// Sorted finite zeros (roots of b0 zⁿᵇ + … + b_nb).
    pub zeros: Vec<Complex64>,
    pub rank: usize,
    pub cond: f64,
    /// One-step-ahead residual RMS.
    pub residual_rms: f64,
    pub n_samples: usize,
}

/// Fit an ARX model to `y` driven by `u` (both already deviations or raw, as the caller decides).
pub fn fit_arx(u: &[f64], y: &[f64], orders: ArxOrders, dt_secs: f64) -> Result<ArxModel, ArxError> {
    orders.check()?;
    if u.len() != y.len() {
        return Err(ArxError::LengthMismatch { u: u.len(), y: y.len() });
    }
    let start = orders.first_row();
    let params = orders.n_params();
    let needed = start + 2 * params;
    if y.len() < needed {
        return Err(ArxError::TooFewSamples { samples: y.len(), params, needed });
    }
    let rows = y.len() - start;
    let phi = faer::Mat::from_fn(rows, params, |r, c| {
        let k = r + start;
        if c < orders.na { -y[k - 1 - c] } else { u[k - orders.nk - (c - orders.na)] }
    });
    let sol = solve_lstsq(&phi, &y[start..])?;
    let mut den_zinv = Vec::with_capacity(orders.na + 1);
    den_zinv.push(1.0);
    den_zinv.extend_from_slice(&sol.x[..orders.na]);
    let b = &sol.x[orders.na..];
    let mut num_zinv = vec![0.0; orders.nk];
    num_zinv.extend_from_slice(b);
    let model_tf = DiscreteTf::new(num_zinv, den_zinv, dt_secs)?;
    let poles = poly::roots(&model_tf.den_zinv)?;
    let zeros = poly::roots(b)?;
    Ok(ArxModel {
        orders,
        tf: model_tf,
        poles,
        zeros,
        rank: sol.rank,
        cond: sol.cond,
        residual_rms: sol.residual_rms,
        n_samples: y.len(),
    })
}

/// The input dead time of a set of step segments, as the ARX models see it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DeadTime {
    /// Input delay of the ARX models, samples (1: no dead time beyond the sampling).
    pub nk: usize,
    /// Mean squared one-step error of the short-B ARX models for each delay tried.
    pub losses: Vec<(usize, f64)>,
}

impl DeadTime {
    /// Dead time beyond one sample, samples (what the reduced model carries as z^(−d)).
    pub fn extra_samples(&self) -> usize {
        self.nk.saturating_sub(1)
    }
}

/// B length of the ARX models that time the dead time: with only this many input coefficients the
/// model cannot stand a long delay in leading near-zero coefficients (as a long B does), so its
/// one-step error is least when the input is delayed by the real dead time.
pub const DEAD_TIME_NB: usize = 2;

/// Estimate the input dead time of step segments (each `(u, y)`, deviations): ARX models with `na`
/// poles and a short B ([`DEAD_TIME_NB`]) are fitted for every delay 1..=`max_nk` on the same rows
/// of every segment, and the shortest delay whose pooled mean squared one-step error is within two
/// standard errors of the least one is taken. The standard error of a mean square over N samples of
/// Gaussian error is √(2/N) of it; losses closer than that fit equally well, and a longer dead time
/// is then not what the data show. `None` when no delay can be fitted.
pub fn estimate_dead_time(segments: &[(Vec<f64>, Vec<f64>)], na: usize, max_nk: usize) -> Option<DeadTime> {
    let max_nk = max_nk.max(1);
    let common = na.max(max_nk + DEAD_TIME_NB);
    let params = na + DEAD_TIME_NB + 1;
    let mut sq = vec![0.0; max_nk];
    let mut rows_used = 0usize;
    for (u, y) in segments {
        let Some(losses) = segment_losses(u, y, na, max_nk, common, params) else { continue };
        for (total, loss) in sq.iter_mut().zip(&losses) {
            *total += loss;
        }
        rows_used += y.len().min(u.len()) - common;
    }
    if rows_used == 0 {
        return None;
    }
    let losses: Vec<(usize, f64)> =
        sq.iter().enumerate().map(|(i, s)| (i + 1, s / rows_used as f64)).collect();
    let least = losses.iter().map(|(_, l)| *l).fold(f64::INFINITY, f64::min);
    let tolerance = 2.0 * (2.0 / rows_used.max(1) as f64).sqrt();
    let nk = losses.iter().find(|(_, l)| *l <= least * (1.0 + tolerance)).map(|(nk, _)| *nk)?;
    Some(DeadTime { nk, losses })
}

/// One segment's sum of squared one-step errors for every delay 1..=`max_nk`, on the rows from
/// `common` on; `None` when the segment is too short or not finite (as a fit would refuse it).
///
/// Every delay shares the `na` output regressors, so their column space is factored once
/// (Householder QR) and each delay only adds its `DEAD_TIME_NB + 1` input columns in the orthogonal
/// complement: the residual of the full least-squares problem is the residual of the small one
/// there (block elimination). This is the same least-squares loss as fitting each delay's ARX model
/// on its own, at a fraction of the cost (no SVD per delay, no roots: the delay needs only losses).
fn segment_losses(
    u: &[f64],
    y: &[f64],
    na: usize,
    max_nk: usize,
    common: usize,
    params: usize,
) -> Option<Vec<f64>> {
    let n = y.len().min(u.len());
    let rows = n.checked_sub(common)?;
    if u.len() != y.len() || rows < 2 * params || u.iter().chain(y).any(|v| !v.is_finite()) {
        return None;
    }
    // Columns, each `rows` long: the output regressors, then the input at every shift, then y.
    let shifts = max_nk + DEAD_TIME_NB;
    let mut cols: Vec<Vec<f64>> = Vec::with_capacity(na + shifts + 1);
    cols.extend((0..na).map(|c| (common..n).map(|k| -y[k - 1 - c]).collect()));
    cols.extend((1..=shifts).map(|s| (common..n).map(|k| u[k - s]).collect()));
    cols.push(y[common..n].to_vec());
    let scale = cols[..na].iter().map(|c| norm(c)).fold(0.0, f64::max);
    // Householder QR of the output columns, applied to every other column.
    let mut pivot_rows = 0;
    for j in 0..na {
        let (head, tail) = cols.split_at_mut(j + 1);
        let col = &mut head[j];
        let x = &col[pivot_rows..];
        let alpha = norm(x);
        // A column dependent on the ones before (to rounding) spans nothing new, as the SVD's rank
        // cut-off would say: it is left out.
        if alpha <= f64::EPSILON * rows as f64 * scale.max(f64::MIN_POSITIVE) {
            continue;
        }
        let mut v = x.to_vec();
        v[0] += if v[0] >= 0.0 { alpha } else { -alpha };
        let vnorm2: f64 = v.iter().map(|a| a * a).sum();
        if vnorm2 <= 0.0 {
            continue;
        }
        for other in tail.iter_mut() {
            let seg = &mut other[pivot_rows..];
            let dot: f64 = v.iter().zip(seg.iter()).map(|(a, b)| a * b).sum();
            let f = 2.0 * dot / vnorm2;
            for (s, a) in seg.iter_mut().zip(&v) {
                *s -= f * a;
            }
        }
        pivot_rows += 1;
    }
    let perp = |c: &Vec<f64>| c[pivot_rows..].to_vec();
    let b = perp(&cols[na + shifts]);
    let b2: f64 = b.iter().map(|x| x * x).sum();
    Some(
        (1..=max_nk)
            .map(|nk| {
                // Input columns of delay nk: shifts nk ..= nk + DEAD_TIME_NB, orthonormalised.
                let mut basis: Vec<Vec<f64>> = Vec::with_capacity(DEAD_TIME_NB + 1);
                for s in nk..=nk + DEAD_TIME_NB {
                    let mut c = perp(&cols[na + s - 1]);
                    let size = norm(&c);
                    for _ in 0..2 {
                        for q in &basis {
                            let d: f64 = q.iter().zip(&c).map(|(a, b)| a * b).sum();
                            c.iter_mut().zip(q).for_each(|(x, q)| *x -= d * q);
                        }
                    }
                    let left = norm(&c);
                    if left > 1e-10 * size.max(f64::MIN_POSITIVE) && left > 0.0 {
                        basis.push(c.iter().map(|x| x / left).collect());
                    }
                }
                let explained: f64 =
                    basis.iter().map(|q| q.iter().zip(&b).map(|(a, c)| a * c).sum::<f64>().powi(2)).sum();
                (b2 - explained).max(0.0)
            })
            .collect(),
    )
}

fn norm(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

impl ArxModel {
    /// Bode data of this segment model.
    pub fn bode_response(&self, omegas_rad_s: &[f64]) -> Vec<tf::BodePoint> {
        self.tf.bode_response(omegas_rad_s)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use rand::{Rng, SeedableRng};

    fn prbs(n: usize, seed: u64) -> Vec<f64> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut level = 1.0;
        (0..n)
            .map(|_| {
                if rng.random::<f64>() < 0.15 {
                    level = -level;
                }
                level + 0.1 * rng.random::<f64>()
            })
            .collect()
    }

    #[test]
    fn dead_time_losses_are_the_least_squares_losses_of_each_delays_arx_fit() {
        // A slow pair behind 4 samples of dead time, with noise, as three step-like segments.
        let truth =
            DiscreteTf::from_zpk(&[], &[Complex64::new(0.9, 0.1), Complex64::new(0.9, -0.1)], 0.02, 0.1)
                .unwrap()
                .with_input_delay(3);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let segments: Vec<(Vec<f64>, Vec<f64>)> = (0..3u64)
            .map(|seed| {
                let u = prbs(300, seed + 20);
                let y = truth
                    .simulate_with_history(&u, 0.0, 0.0)
                    .iter()
                    .map(|v| v + 0.01 * rng.random::<f64>())
                    .collect();
                (u, y)
            })
            .collect();
        let (na, max_nk) = (6, 8);
        let found = estimate_dead_time(&segments, na, max_nk).unwrap();
        // Each delay's ARX model fitted on its own (SVD), on the same rows.
        let common = na.max(max_nk + DEAD_TIME_NB);
        for (nk, loss) in &found.losses {
            let orders = ArxOrders { na, nb: DEAD_TIME_NB, nk: *nk };
            let skip = common - orders.first_row();
            let (mut sq, mut rows) = (0.0, 0);
            for (u, y) in &segments {
                let m = fit_arx(&u[skip..], &y[skip..], orders, 0.1).unwrap();
                let r = m.n_samples - orders.first_row();
                sq += m.residual_rms * m.residual_rms * r as f64;
                rows += r;
            }
            let direct = sq / rows as f64;
            assert!((loss - direct).abs() <= 1e-8 * direct, "nk = {nk}: {loss} vs {direct}");
        }
        assert_eq!(found.nk, 5, "{found:?}");
    }

    #[test]
    fn noiseless_known_system_is_recovered_exactly() {
        let truth = DiscreteTf::from_zpk(
            &[Complex64::new(-0.4, 0.0)],
            &[Complex64::new(0.936, 0.0), Complex64::new(0.8, 0.21), Complex64::new(0.8, -0.21)],
            0.05,
            1.0 / 8.85,
        )
        .unwrap();
        let u = prbs(600, 3);
        let y = truth.simulate_with_history(&u, 0.0, 0.0);
        // Truth has relative degree 2 → nk = 2 and one zero.
        let model = fit_arx(&u, &y, ArxOrders { na: 3, nb: 1, nk: 2 }, truth.dt_secs).unwrap();
        for (a, b) in model.tf.den_zinv.iter().zip(&truth.den_zinv) {
            assert!((a - b).abs() < 1e-9, "{:?} vs {:?}", model.tf.den_zinv, truth.den_zinv);
        }
        for (a, b) in model.tf.num_zinv.iter().zip(&truth.num_zinv) {
            assert!((a - b).abs() < 1e-9);
        }
        assert!((model.poles[0] - Complex64::new(0.936, 0.0)).norm() < 1e-8);
        assert!((model.zeros[0] - Complex64::new(-0.4, 0.0)).norm() < 1e-8);
        assert_eq!(model.rank, 5);
        assert!(model.residual_rms < 1e-9);
    }

    #[test]
    fn over_parameterised_fit_keeps_true_poles() {
        let truth = DiscreteTf::from_zpk(&[], &[Complex64::new(0.9, 0.0)], 0.1, 0.1).unwrap();
        let u = prbs(500, 5);
        let y = truth.simulate_with_history(&u, 0.0, 0.0);
        let model = fit_arx(&u, &y, ArxOrders::new(6, 2), 0.1).unwrap();
        // The exact solution set is rank deficient; the minimum-norm answer still contains the pole.
        assert!(model.poles.iter().any(|p| (p - Complex64::new(0.9, 0.0)).norm() < 1e-6));
        assert!(model.residual_rms < 1e-9);
    }

    #[test]
    fn bad_inputs_are_errors() {
        assert!(matches!(
            fit_arx(&[1.0; 10], &[1.0; 10], ArxOrders::new(19, 3), 0.1),
            Err(ArxError::TooFewSamples { .. })
        ));
        assert!(matches!(
            fit_arx(&[1.0; 10], &[1.0; 9], ArxOrders::new(1, 0), 0.1),
            Err(ArxError::LengthMismatch { .. })
        ));
        assert!(matches!(
            fit_arx(&[1.0; 10], &[1.0; 10], ArxOrders::new(0, 0), 0.1),
            Err(ArxError::BadOrders { .. })
        ));
    }
}
