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
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::{Accum, Mat, Par};

use super::BaselineError;
use super::mlp::MlpShape;
use super::spd::Cholesky;
use crate::core::numerics::lm::{Damping, LmProblem, LmSettings, Scale, minimise};

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

/// The hidden activations of every regressor row (row-major, `hidden` each) at weights `w`.
fn activations(shape: MlpShape, w: &[f64], data: &TrainData) -> Vec<f64> {
    let mut h = vec![0.0; data.t.len() * shape.hidden];
    for (x, hk) in data.x.chunks_exact(shape.n_inputs).zip(h.chunks_exact_mut(shape.hidden.max(1))) {
        shape.hidden_activations(w, x, hk);
    }
    h
}

fn one_step_errors(shape: MlpShape, w: &[f64], h: &[f64], data: &TrainData) -> Vec<f64> {
    h.chunks_exact(shape.hidden.max(1))
        .zip(&data.t)
        .map(|(hk, t)| shape.output_from_hidden(w, hk) - t)
        .collect()
}

/// `[J e]ᵀ[J e]` in one product, from the hidden activations `h` at `w`. The rows `[∂ŷ/∂w, e]` are
/// stored as the columns of a faer matrix, whose aligned allocation keeps the product's summation
/// order, and so the result, the same from run to run (a product over an arbitrary slice can round
/// differently with its address).
fn linearise(shape: MlpShape, w: &[f64], h: &[f64], data: &TrainData) -> Linearisation {
    let p = shape.n_weights();
    let n = data.t.len();
    let mut m = Mat::<f64>::zeros(p + 1, n);
    let rows = data.x.chunks_exact(shape.n_inputs).zip(h.chunks_exact(shape.hidden.max(1))).zip(&data.t);
    for (i, ((x, hk), t)) in rows.enumerate() {
        let (grad, err) = m.col_as_slice_mut(i).split_at_mut(p);
        let y = shape.output_and_gradient_from_hidden(w, x, hk, grad);
        if let Some(e) = err.first_mut() {
            *e = y - t;
        }
    }
    // The product is symmetric: only its lower triangle is computed (half the multiplications),
    // and the upper read from it.
    let mut gram = Mat::<f64>::zeros(p + 1, p + 1);
    triangular::matmul(
        gram.as_mut(),
        BlockStructure::TriangularLower,
        Accum::Replace,
        &m,
        BlockStructure::Rectangular,
        m.transpose(),
        BlockStructure::Rectangular,
        1.0,
        Par::Seq,
    );
    let jtj = (0..p * p).map(|k| (k / p, k % p)).map(|(i, j)| gram[(i.max(j), i.min(j))]).collect();
    let jte = (0..p).map(|j| gram[(p, j)]).collect();
    Linearisation { e_d: 0.5 * gram[(p, p)], e_w: sum_sq_half(w), jtj, jte }
}

/// The regularised objective `M(w) = β·E_D + α·E_W` as a Levenberg–Marquardt problem: every
/// linearisation re-estimates α and β from the evidence (MacKay's update) before the step.
struct Bayesian<'a> {
    shape: MlpShape,
    data: &'a TrainData,
    alpha: f64,
    beta: f64,
    /// The weights of the last objective evaluation and their hidden activations: Levenberg–
    /// Marquardt linearises next at the step it just accepted, whose tanh values (most of a pass's
    /// cost) are then already known. Reused only for bit-identical weights, so results are unchanged.
    last: Option<(Vec<f64>, Vec<f64>)>,
}

impl Bayesian<'_> {
    /// The hidden activations at `w`, from the last evaluation when it was at `w`.
    fn activations_at(&mut self, w: &[f64]) -> Vec<f64> {
        match self.last.take() {
            Some((last_w, h)) if last_w == w => h,
            _ => activations(self.shape, w, self.data),
        }
    }
}

impl LmProblem for Bayesian<'_> {
    type Linearisation = Linearisation;
    type Error = BaselineError;

    fn objective(&mut self, w: &[f64]) -> Option<f64> {
        let h = activations(self.shape, w, self.data);
        let m = self.beta * sum_sq_half(&one_step_errors(self.shape, w, &h, self.data))
            + self.alpha * sum_sq_half(w);
        self.last = Some((w.to_vec(), h));
        m.is_finite().then_some(m)
    }

    fn linearise(&mut self, w: &[f64], _objective: f64) -> Result<(Linearisation, f64), BaselineError> {
        let n = self.data.t.len() as f64;
        let h = self.activations_at(w);
        let lin = linearise(self.shape, w, &h, self.data);
        let gamma = lin.gamma(self.alpha, self.beta)?;
        self.alpha = (gamma / (2.0 * lin.e_w.max(f64::MIN_POSITIVE))).clamp(1e-10, 1e10);
        self.beta = ((n - gamma) / (2.0 * lin.e_d.max(f64::MIN_POSITIVE))).clamp(1e-10, 1e14);
        let objective = self.beta * lin.e_d + self.alpha * lin.e_w;
        Ok((lin, objective))
    }

    fn step(
        &mut self,
        lin: &mut Linearisation,
        w: &[f64],
        mu: f64,
    ) -> Result<Option<Vec<f64>>, BaselineError> {
        let step = lin.step(w, self.alpha, self.beta, mu);
        Ok(step.map(|step| w.iter().zip(&step).map(|(a, b)| a + b).collect()))
    }
}

/// μ from [`MU_START`], ×0.1 after a step that lowers M (not below 10⁻²⁰), ×10 after one that does
/// not, up to [`MU_MAX`] (Foresee & Hagan's schedule).
const DAMPING: Damping = Damping {
    start: MU_START,
    on_accept: Scale::Times(0.1),
    floor: 1e-20,
    on_reject: Scale::Times(10.0),
    max_tries: usize::MAX,
    ceiling: MU_MAX,
};

/// Train from `w0`; `on_iteration(k)` is called after iteration `k` and may abort with its error.
pub(super) fn train(
    shape: MlpShape,
    data: &TrainData,
    w0: Vec<f64>,
    max_iterations: usize,
    on_iteration: &mut dyn FnMut(usize) -> Result<(), BaselineError>,
) -> Result<TrainOutcome, BaselineError> {
    let mut problem = Bayesian { shape, data, alpha: 0.01, beta: 1.0, last: None };
    let settings = LmSettings { max_iterations, cost_tol: COST_TOL, damping: DAMPING };
    let fitted = minimise(&mut problem, &w0, &settings, on_iteration)?;
    let (alpha, beta, w) = (problem.alpha, problem.beta, fitted.theta);
    let h = problem.activations_at(&w);
    let lin = linearise(shape, &w, &h, data);
    let gamma = lin.gamma(alpha, beta)?;
    let log_evidence = lin.log_evidence(alpha, beta, data.t.len())?;
    Ok(TrainOutcome { weights: w, iterations: fitted.iterations, alpha, beta, gamma, log_evidence })
}
