//! Models drawn from a covariance: parameter vectors from its normal distribution, each turned back
//! into a model with its effects kept in their admissible ranges.
use nalgebra::DMatrix;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};

use super::{CovarianceError, Layout, ParameterCovariance, layout, slot_len, with_parameters};
use crate::core::effects::ExtendedModel;

/// Halvings of an effect's step back towards its fitted values before a draw is given up.
const MAX_HALVINGS: usize = 30;

/// [`with_parameters`] for a draw: an effect whose drawn parameters leave its admissible range is
/// moved back towards its fitted values `centre` until it is inside, so a fit that ended on its
/// range's bound (as a scheduled time constant's ratio may) stays near the bound in the draws that
/// would push it out, as the fit itself would have.
fn drawn_model(
    model: &ExtendedModel,
    layout: &Layout,
    theta: &[f64],
    centre: &[f64],
) -> Option<ExtendedModel> {
    let mut theta = theta.to_vec();
    let mut at = slot_len(&layout.poles) + slot_len(&layout.zeros) + layout.map;
    for (block, &n) in model.effects.iter().zip(&layout.effects) {
        let mut t = 1.0;
        for _ in 0..MAX_HALVINGS {
            let slice: Vec<f64> = (at..at + n).map(|i| centre[i] + t * (theta[i] - centre[i])).collect();
            if block.with_free_params(&slice, layout.dt_secs).is_some() {
                theta[at..at + n].copy_from_slice(&slice);
                break;
            }
            t *= 0.5;
        }
        at += n;
    }
    with_parameters(model, layout, &theta)
}

impl ParameterCovariance {
    /// The standard deviation of each parameter.
    pub fn std_devs(&self) -> Vec<f64> {
        (0..self.values.len()).map(|i| self.matrix[i][i].max(0.0).sqrt()).collect()
    }

    /// A square root `L` of the covariance (`L Lᵀ = Σ`): the Cholesky factor, or from the
    /// eigenvalues (negative rounding clamped to zero) when the matrix is only semi-definite.
    fn root(&self) -> DMatrix<f64> {
        let n = self.values.len();
        let sigma = DMatrix::from_fn(n, n, |i, j| self.matrix[i][j]);
        if let Some(ch) = sigma.clone().cholesky() {
            return ch.l();
        }
        let eig = sigma.symmetric_eigen();
        let scale = DMatrix::from_diagonal(&eig.eigenvalues.map(|l| l.max(0.0).sqrt()));
        &eig.eigenvectors * scale
    }

    /// `n` parameter vectors drawn from the normal distribution of the covariance, reproducibly
    /// from `seed`.
    pub fn draw_parameters(&self, n: usize, seed: u64) -> Vec<Vec<f64>> {
        let root = self.root();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let dim = self.values.len();
        (0..n)
            .map(|_| {
                let z = nalgebra::DVector::from_fn(dim, |_, _| StandardNormal.sample(&mut rng));
                let dx = &root * z;
                self.values.iter().zip(dx.iter()).map(|(v, d)| v + d).collect()
            })
            .collect()
    }

    /// `n` models drawn from the covariance around `model` (whose parameters it must describe);
    /// draws that give no model (an effect parameter out of its range, a zero at z = 1) are left out, so fewer
    /// than `n` may come back.
    pub fn draw_models(
        &self,
        model: &ExtendedModel,
        n: usize,
        seed: u64,
    ) -> Result<Vec<ExtendedModel>, CovarianceError> {
        let (layout, _, values) = layout(model)?;
        if values.len() != self.values.len() {
            return Err(CovarianceError::Mismatch { stored: self.values.len(), model: values.len() });
        }
        Ok(self
            .draw_parameters(n, seed)
            .iter()
            .filter_map(|theta| drawn_model(model, &layout, theta, &self.values))
            .collect())
    }
}
