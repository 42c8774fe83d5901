//! The linear block's Bode band over drawn models, and each root's 95 % region in z.
use num_complex::Complex64;

use super::percentile_interval;
use crate::core::control::covariance::{CovarianceError, ParameterCovariance, Slot};
use crate::core::effects::ExtendedModel;

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
    let layout = crate::core::control::covariance::parameter_layout(model)?;
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
