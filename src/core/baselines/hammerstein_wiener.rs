//! The Hammerstein–Wiener baseline `u → f_in → w → G(z) → v → f_out → y`: an input polynomial, a
//! linear discrete transfer function and an output polynomial, all fitted together by minimising the
//! simulation (output-error) error with Levenberg–Marquardt.
//!
//! The model works in normalised units (input and output ranges mapped onto `[−1, 1]`), so that
//! 70,000-rpm outputs and squared terms stay well conditioned. The blocks' scale and offset
//! ambiguities are fixed by `f_in(x) = x + c₂x² + …` (no constant, unit linear coefficient) and a unit
//! steady-state gain of `G`; `f_out(v) = d₀ + d₁v + d₂v² + …` is free. `G` has `n_poles` poles,
//! `n_zeros` zeros and the relative degree `n_poles − n_zeros` as an input delay, like the gray-box
//! model's `DiscreteTf::from_zpk`.
//!
//! Fitting: (1) ARX of the same orders with a constant term, by least squares, its poles pulled
//! inside the unit circle; (2) output-error Levenberg–Marquardt of the linear model `d₀ + d₁·G u`;
//! (3) output-error Levenberg–Marquardt of all parameters from that start with identity-like
//! polynomials. Parameter sets with a pole outside `|z| < MAX_POLE_MODULUS` are rejected during the
//! search. Simulation starts settled at the first input sample.
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::{BaselineError, Scaling, check_signals, report};
use crate::core::numerics::lm::{
    Damping, Jacobian, LeastSquares, LmOutcome, LmSettings, StepSolver, minimise,
};
use crate::core::numerics::lstsq::solve_lstsq;
use crate::core::numerics::poly;
use crate::core::numerics::tf::DiscreteTf;

/// Poles at or beyond this modulus are inadmissible during the search.
const MAX_POLE_MODULUS: f64 = 0.9999;
/// The ARX start has its poles pulled inside this modulus.
const START_POLE_MODULUS: f64 = 0.98;

/// Polynomial orders and pole/zero counts of a Hammerstein–Wiener model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct HwOrders {
    /// Order of the input polynomial (1 = linear).
    pub input_poly: usize,
    pub n_poles: usize,
    pub n_zeros: usize,
    /// Order of the output polynomial (1 = linear).
    pub output_poly: usize,
}

impl HwOrders {
    /// The paper's shaft-speed structure: quadratic polynomials around 3 poles and no zeros.
    pub fn paper_speed() -> Self {
        Self { input_poly: 2, n_poles: 3, n_zeros: 0, output_poly: 2 }
    }

    /// The paper's thrust structure: quadratic polynomials around 1 pole and no zeros.
    pub fn paper_thrust() -> Self {
        Self { input_poly: 2, n_poles: 1, n_zeros: 0, output_poly: 2 }
    }

    /// Input delay of the linear block in samples (its relative degree).
    pub fn delay(&self) -> usize {
        self.n_poles.saturating_sub(self.n_zeros)
    }

    /// Number of fitted parameters.
    pub fn n_params(&self) -> usize {
        self.n_poles + self.n_zeros + self.input_poly.saturating_sub(1) + self.output_poly + 1
    }

    /// Checks the orders: 1–10 poles, no more zeros than poles, polynomial orders 1–5.
    pub fn check(&self) -> Result<(), BaselineError> {
        let bad =
            |option, value, requirement| Err(BaselineError::InvalidOption { option, value, requirement });
        if !(1..=10).contains(&self.n_poles) {
            return bad("n_poles", self.n_poles, "between 1 and 10");
        }
        if self.n_zeros > self.n_poles {
            return bad("n_zeros", self.n_zeros, "at most n_poles (a causal model)");
        }
        if !(1..=5).contains(&self.input_poly) {
            return bad("input_poly", self.input_poly, "between 1 and 5");
        }
        if !(1..=5).contains(&self.output_poly) {
            return bad("output_poly", self.output_poly, "between 1 and 5");
        }
        Ok(())
    }

    fn first_row(&self) -> usize {
        self.n_poles.max(self.delay() + self.n_zeros)
    }

    /// Samples needed: the ARX start's first row plus ten per parameter.
    pub fn samples_needed(&self) -> usize {
        self.first_row() + 10 * self.n_params()
    }
}

/// Iteration limits and tolerance of the Levenberg–Marquardt stages.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HwOptions {
    /// Iterations of the linear output-error stage.
    pub linear_iterations: usize,
    /// Iterations of the joint stage.
    pub max_iterations: usize,
    /// Stop a stage when an accepted step lowers the cost by less than this fraction.
    pub cost_tol: f64,
}

impl Default for HwOptions {
    fn default() -> Self {
        Self { linear_iterations: 100, max_iterations: 200, cost_tol: 1e-9 }
    }
}

/// A polynomial in ascending powers: `coeffs[k]` multiplies `xᵏ`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AscendingPoly {
    pub coeffs: Vec<f64>,
}

impl AscendingPoly {
    pub fn eval(&self, x: f64) -> f64 {
        self.coeffs.iter().rev().fold(0.0, |acc, c| acc * x + c)
    }
}

/// How the fit went. Errors are RMS of the simulation error on the training data, in output units.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HwDiagnostics {
    /// The stabilised ARX start, simulated with a least-squares output gain and offset.
    pub arx_rms: f64,
    /// After the linear output-error stage: the joint stage's initial cost.
    pub initial_rms: f64,
    pub final_rms: f64,
    pub linear_iterations: usize,
    pub iterations: usize,
}

/// A fitted Hammerstein–Wiener model. The blocks act on normalised signals.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HwModel {
    pub orders: HwOrders,
    pub input_scaling: Scaling,
    pub output_scaling: Scaling,
    /// `w = f_in(u_n)` with `coeffs[0] = 0` and `coeffs[1] = 1`.
    pub input_poly: AscendingPoly,
    /// `v = G(z) w`, unit steady-state gain.
    pub linear: DiscreteTf,
    /// `y_n = f_out(v)`.
    pub output_poly: AscendingPoly,
    pub diagnostics: HwDiagnostics,
}

impl HwModel {
    /// Output-error simulation from the input alone, starting settled at `u[0]`.
    pub fn simulate(&self, u: &[f64]) -> Vec<f64> {
        let u_n = self.input_scaling.normalise_all(u);
        blocks_simulate(&self.input_poly, &self.linear, &self.output_poly, &u_n)
            .iter()
            .map(|y| self.output_scaling.physical_from_normalised(*y))
            .collect()
    }
}

impl HwModel {
    /// Output-error simulation with the linear block's free response that best fits the first
    /// seconds of the measured `y` (see `core::identification::initial_state`).
    pub fn simulate_estimated(&self, u: &[f64], y: &[f64]) -> Vec<f64> {
        let u_n = self.input_scaling.normalise_all(u);
        let w: Vec<f64> = u_n.iter().map(|x| self.input_poly.eval(*x)).collect();
        let w0 = w.first().copied().unwrap_or(0.0);
        let v = self.linear.simulate_with_history(&w, w0, w0);
        let poles = self.linear.poles().unwrap_or_default();
        let output = |v: &[f64]| -> Vec<f64> {
            v.iter()
                .map(|x| self.output_scaling.physical_from_normalised(self.output_poly.eval(*x)))
                .collect()
        };
        let v = crate::core::identification::initial_state::fit_free_response(&poles, &v, y, output);
        output(&v)
    }
}

fn blocks_simulate(f_in: &AscendingPoly, g: &DiscreteTf, f_out: &AscendingPoly, u_n: &[f64]) -> Vec<f64> {
    let w: Vec<f64> = u_n.iter().map(|x| f_in.eval(*x)).collect();
    // Unit steady-state gain: the settled state of w[0] has v = w[0].
    let w0 = w.first().copied().unwrap_or(0.0);
    g.simulate_with_history(&w, w0, w0).iter().map(|v| f_out.eval(*v)).collect()
}

/// Where each block's parameters sit in θ: `[a₁..aₙ, s₀..s_{m−1}, c₂..c_p, d₀..d_q]`, where the
/// numerator is `A(1)·[s₀, …, s_{m−1}, 1 − Σs]` (unit steady-state gain).
struct Layout {
    orders: HwOrders,
    dt_secs: f64,
    /// The linear stage fits `d₀ + d₁ v` only: no `c`, no `d₂…`.
    linear_only: bool,
}

struct Blocks {
    f_in: AscendingPoly,
    g: DiscreteTf,
    f_out: AscendingPoly,
}

impl Layout {
    fn n_in(&self) -> usize {
        if self.linear_only { 0 } else { self.orders.input_poly.saturating_sub(1) }
    }

    fn n_out(&self) -> usize {
        if self.linear_only { 2 } else { self.orders.output_poly + 1 }
    }

    /// The blocks for θ, or `None` when θ is inadmissible (a pole too close to the unit circle).
    fn blocks(&self, theta: &[f64]) -> Option<Blocks> {
        let (n, m) = (self.orders.n_poles, self.orders.n_zeros);
        let a = theta.get(..n)?;
        let s = theta.get(n..n + m)?;
        let c = theta.get(n + m..n + m + self.n_in())?;
        let d = theta.get(n + m + self.n_in()..)?;
        let mut den_zinv = vec![1.0];
        den_zinv.extend_from_slice(a);
        let roots = poly::roots(&den_zinv).ok()?;
        if roots.iter().any(|p| p.norm() >= MAX_POLE_MODULUS) {
            return None;
        }
        let a_at_one: f64 = den_zinv.iter().sum();
        let mut num_zinv = vec![0.0; self.orders.delay()];
        num_zinv.extend(s.iter().map(|sk| a_at_one * sk));
        num_zinv.push(a_at_one * (1.0 - s.iter().sum::<f64>()));
        let g = DiscreteTf::new(num_zinv, den_zinv, self.dt_secs).ok()?;
        let mut f_in = vec![0.0, 1.0];
        f_in.extend_from_slice(c);
        Some(Blocks { f_in: AscendingPoly { coeffs: f_in }, g, f_out: AscendingPoly { coeffs: d.to_vec() } })
    }

    /// Normalised simulation-error residuals `(ŷ − y)/√N`.
    fn residual(&self, theta: &[f64], u_n: &[f64], y_n: &[f64]) -> Option<Vec<f64>> {
        let b = self.blocks(theta)?;
        let scale = 1.0 / (y_n.len().max(1) as f64).sqrt();
        let r: Vec<f64> = blocks_simulate(&b.f_in, &b.g, &b.f_out, u_n)
            .iter()
            .zip(y_n)
            .map(|(yhat, y)| (yhat - y) * scale)
            .collect();
        r.iter().all(|x| x.is_finite()).then_some(r)
    }
}

/// Fit a Hammerstein–Wiener model of the given orders to `y` driven by `u` (see the module docs for
/// the algorithm). `progress` receives the fraction done; returning `false` cancels.
pub fn fit_hammerstein_wiener(
    u: &[f64],
    y: &[f64],
    dt_secs: f64,
    orders: HwOrders,
    opts: &HwOptions,
    progress: &mut dyn FnMut(f64) -> bool,
) -> Result<HwModel, BaselineError> {
    orders.check()?;
    check_signals(u, y, orders.samples_needed())?;
    let input_scaling = Scaling::unit_range(u).ok_or(BaselineError::ConstantSignal { what: "input" })?;
    let output_scaling = Scaling::unit_range(y).ok_or(BaselineError::ConstantSignal { what: "output" })?;
    let (u_n, y_n) = (input_scaling.normalise_all(u), output_scaling.normalise_all(y));
    // A bad sample time is a caller error; catch it before any work.
    DiscreteTf::new(vec![1.0], vec![1.0], dt_secs)?;
    report(progress, 0.0)?;

    let linear = Layout { orders, dt_secs, linear_only: true };
    let start = arx_start(&u_n, &y_n, orders)?;
    let mut theta_lin = start.clone();
    theta_lin.extend(output_gain_offset(&linear, &start, &u_n, &y_n)?);
    let arx_cost = cost(&linear, &theta_lin, &u_n, &y_n);
    report(progress, 0.02)?;

    let settings = hw_settings(opts.linear_iterations, opts.cost_tol);
    let max_lin = opts.linear_iterations.max(1) as f64;
    let lin = fit_stage(
        &theta_lin,
        |th| linear.residual(th, &u_n, &y_n),
        &settings,
        "linear output-error",
        &mut |k| report(progress, 0.02 + 0.28 * k as f64 / max_lin),
    )?;
    check_not_diverged("linear output-error", lin.cost, &y_n)?;

    let full = Layout { orders, dt_secs, linear_only: false };
    let n_lin = orders.n_poles + orders.n_zeros;
    let mut theta = lin.theta.get(..n_lin).map(<[f64]>::to_vec).unwrap_or_default();
    theta.extend(std::iter::repeat_n(0.0, full.n_in()));
    theta.extend(lin.theta.get(n_lin..).unwrap_or_default());
    theta.extend(std::iter::repeat_n(0.0, full.n_out().saturating_sub(2)));
    let settings = hw_settings(opts.max_iterations, opts.cost_tol);
    let max_full = opts.max_iterations.max(1) as f64;
    let fit =
        fit_stage(&theta, |th| full.residual(th, &u_n, &y_n), &settings, "Hammerstein–Wiener", &mut |k| {
            report(progress, 0.3 + 0.7 * k as f64 / max_full)
        })?;
    check_not_diverged("Hammerstein–Wiener", fit.cost, &y_n)?;
    let Some(blocks) = full.blocks(&fit.theta) else {
        return Err(BaselineError::Diverged { stage: "Hammerstein–Wiener", rms_normalised: f64::INFINITY });
    };
    report(progress, 1.0)?;
    let rms = |c: f64| c.sqrt() * output_scaling.scale;
    Ok(HwModel {
        orders,
        input_scaling,
        output_scaling,
        input_poly: blocks.f_in,
        linear: blocks.g,
        output_poly: blocks.f_out,
        diagnostics: HwDiagnostics {
            arx_rms: rms(arx_cost),
            initial_rms: rms(lin.cost),
            final_rms: rms(fit.cost),
            linear_iterations: lin.iterations,
            iterations: fit.iterations,
        },
    })
}

fn cost(layout: &Layout, theta: &[f64], u_n: &[f64], y_n: &[f64]) -> f64 {
    layout.residual(theta, u_n, y_n).map_or(f64::INFINITY, |r| r.iter().map(|x| x * x).sum())
}

/// A fit is a failure when it is no better than the output's mean (a non-finite cost included).
fn check_not_diverged(stage: &'static str, cost: f64, y_n: &[f64]) -> Result<(), BaselineError> {
    let n = y_n.len().max(1) as f64;
    let mean = y_n.iter().sum::<f64>() / n;
    let variance = y_n.iter().map(|y| (y - mean).powi(2)).sum::<f64>() / n;
    if cost.is_finite() && cost < variance {
        Ok(())
    } else {
        Err(BaselineError::Diverged { stage, rms_normalised: cost.sqrt() })
    }
}

/// The linear part `[a₁..aₙ, s₀..s_{m−1}]` of θ from an ARX fit with a constant term, its poles
/// pulled inside `START_POLE_MODULUS`.
fn arx_start(u_n: &[f64], y_n: &[f64], orders: HwOrders) -> Result<Vec<f64>, BaselineError> {
    let (n, m, delay) = (orders.n_poles, orders.n_zeros, orders.delay());
    let first = orders.first_row();
    let rows = y_n.len().saturating_sub(first);
    let cols = n + m + 2;
    let value = |r: usize, c: usize| {
        let k = r + first;
        let sample =
            |x: &[f64], lag: usize| k.checked_sub(lag).and_then(|i| x.get(i)).copied().unwrap_or(0.0);
        if c < n {
            -sample(y_n, c + 1)
        } else if c < n + m + 1 {
            sample(u_n, delay + c - n)
        } else {
            1.0
        }
    };
    let phi = faer::Mat::from_fn(rows, cols, value);
    let sol = solve_lstsq(&phi, y_n.get(first..).unwrap_or_default())?;
    let mut den_zinv = vec![1.0];
    den_zinv.extend(sol.x.iter().take(n));
    let poles: Vec<Complex64> = poly::roots(&den_zinv)?
        .into_iter()
        .map(|p| if p.norm() > START_POLE_MODULUS { p * (START_POLE_MODULUS / p.norm()) } else { p })
        .collect();
    let mut theta: Vec<f64> = poly::poly_from_roots(&poles).into_iter().skip(1).collect();
    let b: Vec<f64> = sol.x.iter().skip(n).take(m + 1).copied().collect();
    let (sum, size) = (b.iter().sum::<f64>(), b.iter().map(|x| x.abs()).sum::<f64>());
    if sum.abs() > 1e-6 * size && sum.is_finite() {
        theta.extend(b.iter().take(m).map(|bk| bk / sum));
    } else {
        theta.extend(std::iter::repeat_n(1.0 / (m + 1) as f64, m));
    }
    Ok(theta)
}

/// Least-squares `d₀, d₁` of `y ≈ d₀ + d₁ v` for the unit-gain linear block given by `linear_theta`.
fn output_gain_offset(
    layout: &Layout,
    linear_theta: &[f64],
    u_n: &[f64],
    y_n: &[f64],
) -> Result<[f64; 2], BaselineError> {
    let mut theta = linear_theta.to_vec();
    theta.extend([0.0, 1.0]);
    let Some(blocks) = layout.blocks(&theta) else {
        let mut den_zinv = vec![1.0];
        den_zinv.extend(linear_theta.iter().take(layout.orders.n_poles));
        let modulus = poly::roots(&den_zinv)?.iter().map(|p| p.norm()).fold(0.0, f64::max);
        return Err(BaselineError::Unstable { stage: "ARX", modulus });
    };
    let v = blocks.g.simulate_from_steady(u_n);
    let a =
        faer::Mat::from_fn(v.len(), 2, |r, c| if c == 0 { 1.0 } else { v.get(r).copied().unwrap_or(0.0) });
    let sol = solve_lstsq(&a, y_n)?;
    match sol.x.as_slice() {
        [d0, d1] => Ok([*d0, *d1]),
        _ => Err(BaselineError::Diverged { stage: "ARX", rms_normalised: f64::INFINITY }),
    }
}

/// The baseline's Levenberg–Marquardt: 16 damping tries, a forward-difference Jacobian with steps of
/// 10⁻⁷·max(|θ|, 1) (the normalised parameters are of order one) that falls back to a backward
/// difference at the edge of the admissible region (a pole near the unit circle).
fn hw_settings(max_iterations: usize, cost_tol: f64) -> LmSettings {
    LmSettings { max_iterations, cost_tol, damping: Damping::marquardt(16) }
}

/// One stage of the fit (`stage` names it in errors); `on_iteration` reports progress and cancels.
fn fit_stage(
    theta0: &[f64],
    residual: impl FnMut(&[f64]) -> Option<Vec<f64>>,
    settings: &LmSettings,
    stage: &'static str,
    on_iteration: &mut dyn FnMut(usize) -> Result<(), BaselineError>,
) -> Result<LmOutcome, BaselineError> {
    let jacobian = Jacobian { rel_step: 1e-7, floor: 1.0, backward_fallback: true };
    let mut problem: LeastSquares<_, BaselineError> = LeastSquares::new(residual, jacobian, StepSolver::Svd);
    minimise(&mut problem, theta0, settings, on_iteration).map_err(|e| match e {
        BaselineError::Lm(crate::core::numerics::lm::LmError::BadStart) => {
            BaselineError::Diverged { stage, rms_normalised: f64::INFINITY }
        }
        other => other,
    })
}
