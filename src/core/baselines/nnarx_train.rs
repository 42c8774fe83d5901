//! Levenberg–Marquardt training with Bayesian regularisation (MacKay 1992; Foresee & Hagan 1997).
//!
//! The objective is `M(w) = β·E_D + α·E_W` with `E_D = ½Σe²` (e the one-step errors) and
//! `E_W = ½Σw²`. Every iteration takes the Gauss–Newton Hessian `A = β·JᵀJ + α·I` at the current
//! weights, re-estimates the hyper-parameters from the evidence,
//! `γ = N_w − α·tr(A⁻¹)`, `α = γ / (2E_W)`, `β = (N − γ) / (2E_D)`,
//! and then takes a damped step `(A + μI) δ = −∇M`, raising μ until M falls.
//!
//! `JᵀJ` is formed explicitly (as Foresee–Hagan do) by one matrix product, and `A` is factorised by
//! Cholesky: that gives `tr(A⁻¹)`, `ln det A` and each trial step cheaply. `αI` keeps `A` far better
//! conditioned than a plain least-squares normal matrix, so squaring the condition number of `J`
//! costs no accuracy that matters here.
use faer::Mat;

use super::BaselineError;
use super::mlp::MlpShape;
use super::spd::Cholesky;

const MU_START: f64 = 0.005;
const MU_MAX: f64 = 1e10;
/// Stop when an accepted step lowers M by less than this fraction.
const COST_TOL: f64 = 1e-9;

/// Regressor rows (row-major, `n_inputs` each) and one-step targets, all normalised.
pub(super) struct TrainData {
    pub x: Vec<f64>,
    pub t: Vec<f64>,
}

pub(super) struct TrainOutcome {
    pub weights: Vec<f64>,
    pub iterations: usize,
    pub alpha: f64,
    pub beta: f64,
    pub gamma: f64,
    pub log_evidence: f64,
}

/// The Gauss–Newton quantities at one set of weights.
struct Linearisation {
    e_d: f64,
    e_w: f64,
    /// `JᵀJ`, row-major `N_w × N_w`.
    jtj: Vec<f64>,
    /// `Jᵀe`.
    jte: Vec<f64>,
}

impl Linearisation {
    fn n_weights(&self) -> usize {
        self.jte.len()
    }

    /// `β·JᵀJ + (α + μ)·I`, factorised.
    fn hessian(&self, alpha: f64, beta: f64, mu: f64) -> Option<Cholesky> {
        let p = self.n_weights();
        let a: Vec<f64> = self
            .jtj
            .iter()
            .enumerate()
            .map(|(k, v)| beta * v + if k / p == k % p { alpha + mu } else { 0.0 })
            .collect();
        Cholesky::new(&a, p)
    }

    /// Effective number of parameters `γ = N_w − α·tr(A⁻¹)`.
    fn gamma(&self, alpha: f64, beta: f64) -> Result<f64, BaselineError> {
        let p = self.n_weights() as f64;
        let a = self
            .hessian(alpha, beta, 0.0)
            .ok_or(BaselineError::Factorisation { what: "Bayesian Hessian" })?;
        Ok((p - alpha * a.trace_inverse()).clamp(0.0, p))
    }

    /// MacKay's log evidence `ln p(D | α, β)` without the network-symmetry constant.
    fn log_evidence(&self, alpha: f64, beta: f64, n: usize) -> Result<f64, BaselineError> {
        let n_w = self.n_weights() as f64;
        let a = self
            .hessian(alpha, beta, 0.0)
            .ok_or(BaselineError::Factorisation { what: "Bayesian Hessian" })?;
        let n = n as f64;
        Ok(-beta * self.e_d - alpha * self.e_w - 0.5 * a.log_det()
            + 0.5 * n_w * alpha.ln()
            + 0.5 * n * beta.ln()
            - 0.5 * n * (2.0 * std::f64::consts::PI).ln())
    }

    /// The damped step `δ = −(β·JᵀJ + (α + μ)·I)⁻¹ (β·Jᵀe + α·w)`; `None` if not factorisable.
    fn step(&self, w: &[f64], alpha: f64, beta: f64, mu: f64) -> Option<Vec<f64>> {
        let a = self.hessian(alpha, beta, mu)?;
        let grad: Vec<f64> = self.jte.iter().zip(w).map(|(je, wi)| -(beta * je + alpha * wi)).collect();
        Some(a.solve(&grad))
    }
}

fn sum_sq_half(x: &[f64]) -> f64 {
    0.5 * x.iter().map(|v| v * v).sum::<f64>()
}

fn one_step_errors(shape: MlpShape, w: &[f64], data: &TrainData) -> Vec<f64> {
    data.x.chunks_exact(shape.n_inputs).zip(&data.t).map(|(x, t)| shape.output(w, x) - t).collect()
}

/// `[J e]ᵀ[J e]` in one product. The rows `[∂ŷ/∂w, e]` are stored as the columns of a faer matrix,
/// whose aligned allocation keeps the product's summation order, and so the result, the same from
/// run to run (a product over an arbitrary slice can round differently with its address).
fn linearise(shape: MlpShape, w: &[f64], data: &TrainData) -> Linearisation {
    let p = shape.n_weights();
    let n = data.t.len();
    let mut m = Mat::<f64>::zeros(p + 1, n);
    for (i, (x, t)) in data.x.chunks_exact(shape.n_inputs).zip(&data.t).enumerate() {
        let (grad, err) = m.col_as_slice_mut(i).split_at_mut(p);
        let y = shape.output_and_gradient(w, x, grad);
        if let Some(e) = err.first_mut() {
            *e = y - t;
        }
    }
    let gram = &m * m.transpose();
    let jtj = (0..p * p).map(|k| gram[(k / p, k % p)]).collect();
    let jte = (0..p).map(|j| gram[(j, p)]).collect();
    Linearisation { e_d: 0.5 * gram[(p, p)], e_w: sum_sq_half(w), jtj, jte }
}

/// Train from `w0`; `on_iteration(k)` is called after iteration `k` and may abort with its error.
pub(super) fn train(
    shape: MlpShape,
    data: &TrainData,
    w0: Vec<f64>,
    max_iterations: usize,
    on_iteration: &mut dyn FnMut(usize) -> Result<(), BaselineError>,
) -> Result<TrainOutcome, BaselineError> {
    let n = data.t.len();
    let mut w = w0;
    let (mut alpha, mut beta, mut mu) = (0.01, 1.0, MU_START);
    let mut iterations = 0;
    while iterations < max_iterations {
        iterations += 1;
        let lin = linearise(shape, &w, data);
        let gamma = lin.gamma(alpha, beta)?;
        alpha = (gamma / (2.0 * lin.e_w.max(f64::MIN_POSITIVE))).clamp(1e-10, 1e10);
        beta = ((n as f64 - gamma) / (2.0 * lin.e_d.max(f64::MIN_POSITIVE))).clamp(1e-10, 1e14);
        let objective = beta * lin.e_d + alpha * lin.e_w;
        let mut accepted = None;
        while mu <= MU_MAX {
            if let Some(step) = lin.step(&w, alpha, beta, mu) {
                let candidate: Vec<f64> = w.iter().zip(&step).map(|(a, b)| a + b).collect();
                let trial = beta * sum_sq_half(&one_step_errors(shape, &candidate, data))
                    + alpha * sum_sq_half(&candidate);
                if trial.is_finite() && trial < objective {
                    mu = (mu * 0.1).max(1e-20);
                    accepted = Some((candidate, trial));
                    break;
                }
            }
            mu *= 10.0;
        }
        on_iteration(iterations)?;
        let Some((candidate, trial)) = accepted else { break };
        w = candidate;
        if objective - trial < COST_TOL * objective {
            break;
        }
    }
    let lin = linearise(shape, &w, data);
    let gamma = lin.gamma(alpha, beta)?;
    let log_evidence = lin.log_evidence(alpha, beta, n)?;
    Ok(TrainOutcome { weights: w, iterations, alpha, beta, gamma, log_evidence })
}
