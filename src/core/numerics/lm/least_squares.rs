//! Least squares `min ‖r(θ)‖²` as an [`LmProblem`], with a finite-difference Jacobian.
use faer::Mat;

use super::{LmError, LmProblem};
use crate::core::numerics::lstsq::solve_lstsq;
use crate::core::numerics::qr::{back_substitute, qr_reduce};
use crate::core::numerics::stats::sum_of_squares;

/// The finite-difference Jacobian: column j steps θⱼ by `rel_step · max(|θⱼ|, floor)`. Where the
/// forward point is not admissible, the column is a backward difference when `backward_fallback`,
/// else zero (the step then leaves that parameter alone).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jacobian {
    pub rel_step: f64,
    pub floor: f64,
    pub backward_fallback: bool,
}

impl Default for Jacobian {
    fn default() -> Self {
        Self { rel_step: 1e-6, floor: 1e-3, backward_fallback: false }
    }
}

/// How a damped step `[J; √λ·D] δ = [−r; 0]` (D the column norms of J) is solved. Both give the same
/// step up to rounding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StepSolver {
    /// An (n + p) × p SVD least-squares problem for every damping tried: the most robust for
    /// ill-conditioned Jacobians (the polish of nearly coincident roots, the baseline's ARX start).
    Svd,
    /// J reduced by Householder QR once per iteration, each damping a small 2p × p problem: for
    /// thousands of residuals and a few parameters tried at several dampings (the effect fits).
    QrOnce,
}

/// The residual `r(θ)` of a least-squares problem: any `FnMut(&[f64]) -> Option<Vec<f64>>`
/// (`None` where θ is not admissible), or a problem that evaluates several θ at once faster than one
/// by one.
pub trait Residual {
    fn at(&mut self, theta: &[f64]) -> Option<Vec<f64>>;

    /// `r` at each θ (what the finite-difference Jacobian's columns need), in order.
    fn at_each(&mut self, thetas: &[Vec<f64>]) -> Vec<Option<Vec<f64>>> {
        thetas.iter().map(|theta| self.at(theta)).collect()
    }
}

impl<F: FnMut(&[f64]) -> Option<Vec<f64>>> Residual for F {
    fn at(&mut self, theta: &[f64]) -> Option<Vec<f64>> {
        self(theta)
    }
}

/// `r(θ)` with its Jacobian options; `E` is the caller's error type.
pub struct LeastSquares<F, E> {
    residual: F,
    jacobian: Jacobian,
    solver: StepSolver,
    /// The last admissible residual and its θ (an accepted step is the last one evaluated).
    last: Option<(Vec<f64>, Vec<f64>)>,
    error: std::marker::PhantomData<E>,
}

impl<F: Residual, E> LeastSquares<F, E> {
    pub fn new(residual: F, jacobian: Jacobian, solver: StepSolver) -> Self {
        Self { residual, jacobian, solver, last: None, error: std::marker::PhantomData }
    }

    fn residual_at(&mut self, theta: &[f64]) -> Option<Vec<f64>> {
        match &self.last {
            Some((at, r)) if at.as_slice() == theta => Some(r.clone()),
            _ => self.residual.at(theta),
        }
    }

    /// The Jacobian's columns at θ, where the residual is `r`: every forward point evaluated at
    /// once ([`Residual::at_each`]), then the backward points where those are not admissible.
    fn columns(&mut self, theta: &[f64], r: &[f64]) -> Vec<Vec<f64>> {
        let opts = self.jacobian;
        let steps: Vec<f64> = theta.iter().map(|t| opts.rel_step * t.abs().max(opts.floor)).collect();
        let shifted = |j: usize, delta: f64| -> Vec<f64> {
            theta.iter().enumerate().map(|(i, t)| if i == j { t + delta } else { *t }).collect()
        };
        let forward_points: Vec<Vec<f64>> = steps.iter().enumerate().map(|(j, h)| shifted(j, *h)).collect();
        let forward = self.residual.at_each(&forward_points);
        forward
            .into_iter()
            .zip(&steps)
            .enumerate()
            .map(|(j, (rj, &h))| {
                let found = rj.map(|rj| (rj, h)).or_else(|| {
                    opts.backward_fallback
                        .then(|| self.residual.at(&shifted(j, -h)).map(|rj| (rj, -h)))
                        .flatten()
                });
                match found {
                    Some((rj, signed_h)) => rj.iter().zip(r).map(|(a, b)| (a - b) / signed_h).collect(),
                    None => vec![0.0; r.len()],
                }
            })
            .collect()
    }
}

/// A least-squares problem linearised at θ, ready for damped steps.
pub enum Linearised {
    /// `[J; 0]` with room for the damping rows, the right-hand side `[−r; 0]` and J's column norms.
    Svd { augmented: Mat<f64>, rhs: Vec<f64>, scales: Vec<f64> },
    /// The triangular factor R of J (by columns), `Qᵀ(−r)` and J's column norms.
    Qr { factor: Vec<Vec<f64>>, projected: Vec<f64>, scales: Vec<f64> },
}

fn column_norms(cols: &[Vec<f64>]) -> Vec<f64> {
    cols.iter().map(|c| c.iter().map(|x| x * x).sum::<f64>().sqrt().max(1e-12)).collect()
}

impl<F, E> LmProblem for LeastSquares<F, E>
where
    F: Residual,
    E: From<LmError>,
{
    type Linearisation = Linearised;
    type Error = E;

    fn objective(&mut self, theta: &[f64]) -> Option<f64> {
        let r = self.residual.at(theta)?;
        let cost = sum_of_squares(&r);
        self.last = Some((theta.to_vec(), r));
        Some(cost)
    }

    fn linearise(&mut self, theta: &[f64], objective: f64) -> Result<(Linearised, f64), E> {
        let r = self.residual_at(theta).ok_or(LmError::BadStart)?;
        let cols = self.columns(theta, &r);
        let scales = column_norms(&cols);
        let neg_r: Vec<f64> = r.iter().map(|x| -x).collect();
        let lin = match self.solver {
            StepSolver::Svd => {
                let (n, p) = (r.len(), cols.len());
                let mut augmented = Mat::<f64>::zeros(n + p, p);
                for (j, col) in cols.iter().enumerate() {
                    for (i, v) in col.iter().enumerate() {
                        augmented[(i, j)] = *v;
                    }
                }
                let mut rhs = neg_r;
                rhs.extend(std::iter::repeat_n(0.0, p));
                Linearised::Svd { augmented, rhs, scales }
            }
            StepSolver::QrOnce => {
                let (factor, projected) = qr_reduce(cols, neg_r);
                Linearised::Qr { factor, projected, scales }
            }
        };
        Ok((lin, objective))
    }

    fn step(&mut self, lin: &mut Linearised, theta: &[f64], damping: f64) -> Result<Option<Vec<f64>>, E> {
        let p = theta.len();
        let delta = match lin {
            Linearised::Svd { augmented, rhs, scales } => {
                let n = augmented.nrows() - p;
                for (j, scale) in scales.iter().enumerate() {
                    augmented[(n + j, j)] = damping.sqrt() * scale;
                }
                solve_lstsq(augmented, rhs).map_err(LmError::from)?.x
            }
            Linearised::Qr { factor, projected, scales } => {
                let damped: Vec<Vec<f64>> = (0..p)
                    .map(|j| {
                        let mut col: Vec<f64> = factor.get(j).cloned().unwrap_or_default();
                        col.resize(2 * p, 0.0);
                        col[p + j] = damping.sqrt() * scales[j];
                        col
                    })
                    .collect();
                let mut rhs = projected.clone();
                rhs.resize(2 * p, 0.0);
                let (r2, c2) = qr_reduce(damped, rhs);
                back_substitute(&r2, &c2)
            }
        };
        Ok(Some(theta.iter().zip(&delta).map(|(t, d)| t + d).collect()))
    }
}
