//! The NNARX baseline: `ŷ(k) = NN(u(k), …, u(k−nu+1), y(k−1), …, y(k−ny))`, a one-hidden-layer
//! tanh network with a linear output on standardised signals (mean and standard deviation stored in
//! the model).
//!
//! Training is series-parallel (measured past outputs as regressors) by Levenberg–Marquardt with
//! Bayesian regularisation (see `nnarx_train`), from `restarts` seeded random initialisations.
//! Restarts are compared by their **output-error simulation** of the training data, not by their
//! evidence, because that is how the model is used and validated (on the SR-30 speed the restart
//! with the highest evidence simulates worst). Among the restarts within `OE_TOLERANCE` of the best
//! simulation error, the one with the fewest training-range inputs having several equilibria is
//! kept (a spurious equilibrium can capture the simulation), then the smallest error. Every
//! restart's log evidence, γ and errors are kept in the diagnostics.
//!
//! The model is then run in output-error form: its own past predictions are fed back. The simulation
//! starts at the network's own equilibrium for the constant input `u[0]` (see [`Equilibrium`]).
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::mlp::MlpShape;
use super::nnarx_train::{TrainData, TrainOutcome, train};
use super::{BaselineError, Scaling, check_signals, report, rms_error};

/// Points of the training input range at which the fitted network's equilibria are counted.
pub const EQUILIBRIUM_CHECKS: usize = 21;

/// Restarts whose training output-error RMS is within this factor of the best compete on the
/// uniqueness of their equilibria.
const OE_TOLERANCE: f64 = 2.0;

/// Iterations allowed to the fixed-point search for the equilibrium.
const FIXED_POINT_ITERATIONS: usize = 20_000;

/// Network structure and training settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NnarxOptions {
    /// Input lags: `u(k), …, u(k−nu+1)`.
    pub nu: usize,
    /// Output lags: `y(k−1), …, y(k−ny)`.
    pub ny: usize,
    /// Hidden tanh units.
    pub hidden: usize,
    /// Random initialisations to train.
    pub restarts: usize,
    /// Seed of the initialisations; the same seed gives the same model.
    pub seed: u64,
    /// Levenberg–Marquardt iterations per restart.
    pub max_iterations: usize,
}

impl Default for NnarxOptions {
    /// The paper's network: u(k), y(k−1..k−3), 10 hidden units; 5 restarts of 100 iterations.
    fn default() -> Self {
        Self { nu: 1, ny: 3, hidden: 10, restarts: 5, seed: 0, max_iterations: 100 }
    }
}

impl NnarxOptions {
    /// Checks the options: `nu`, `hidden`, `restarts`, `max_iterations` at least 1; lags at most 50;
    /// at most 100 hidden units.
    pub fn check(&self) -> Result<(), BaselineError> {
        let checks: [(&'static str, usize, bool, &'static str); 5] = [
            ("nu", self.nu, (1..=50).contains(&self.nu), "between 1 and 50"),
            ("ny", self.ny, self.ny <= 50, "at most 50"),
            ("hidden", self.hidden, (1..=100).contains(&self.hidden), "between 1 and 100"),
            ("restarts", self.restarts, self.restarts >= 1, "at least 1"),
            ("max_iterations", self.max_iterations, self.max_iterations >= 1, "at least 1"),
        ];
        match checks.into_iter().find(|c| !c.2) {
            Some((option, value, _, requirement)) => {
                Err(BaselineError::InvalidOption { option, value, requirement })
            }
            None => Ok(()),
        }
    }

    fn shape(&self) -> MlpShape {
        MlpShape { n_inputs: self.nu + self.ny, hidden: self.hidden }
    }

    /// First sample with all regressors inside the data.
    fn first_row(&self) -> usize {
        self.ny.max(self.nu.saturating_sub(1))
    }

    /// Samples needed: the first row plus two per weight.
    pub fn samples_needed(&self) -> usize {
        self.first_row() + 2 * self.shape().n_weights()
    }
}

/// How the output-error simulation found its starting output.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum EquilibriumMethod {
    /// Fixed-point iteration `y ← NN(u₀, y, …, y)` from the training mean converged.
    FixedPoint { iterations: usize },
    /// Fixed-point iteration did not converge (the equilibrium repels it, or the contraction is too
    /// slow); bisection on `NN(u₀, y, …, y) − y` found the root nearest the training mean.
    Bisection,
    /// Neither found an equilibrium (not expected: the network output is bounded); the training
    /// mean of the output is used.
    TrainingMean,
}

/// The output at which the network is at rest for a constant input.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Equilibrium {
    pub y: f64,
    pub method: EquilibriumMethod,
}

/// One restart's training result.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RestartSummary {
    pub iterations: usize,
    pub log_evidence: f64,
    pub gamma: f64,
    /// RMS one-step (series-parallel) error on the training data, output units.
    pub one_step_rms: f64,
    /// RMS output-error simulation error on the training data, output units.
    pub oe_rms: f64,
    /// How many of the `EQUILIBRIUM_CHECKS` training-range inputs have more than one equilibrium.
    pub several_equilibria: usize,
}

/// Training diagnostics of the kept restart, in normalised units unless stated.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NnarxDiagnostics {
    /// Index of the kept restart (see the module docs for the rule).
    pub chosen_restart: usize,
    pub iterations: usize,
    /// Weight-decay precision.
    pub alpha: f64,
    /// Noise precision of the standardised output.
    pub beta: f64,
    /// Effective number of parameters `γ = N_w − α·tr(A⁻¹)`.
    pub gamma: f64,
    pub n_weights: usize,
    /// `ln p(D | α, β)` without the network-symmetry constant.
    pub log_evidence: f64,
    pub one_step_rms: f64,
    pub oe_rms: f64,
    /// How the training simulation found its start (at the first training input).
    pub training_start: EquilibriumMethod,
    /// Inputs, on an evenly spaced grid of `EQUILIBRIUM_CHECKS` points over the training input range,
    /// at which the network has more than one equilibrium. A physical engine has one steady state per
    /// fuel flow; a spurious one can capture the output-error simulation, so a non-empty list is a
    /// warning that the model may lock up on inputs unlike the training data.
    pub several_equilibria_at: Vec<f64>,
    pub restarts: Vec<RestartSummary>,
}

/// A trained NNARX model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NnarxModel {
    pub nu: usize,
    pub ny: usize,
    pub hidden: usize,
    /// Standardisation of the input (mean, standard deviation).
    pub input_scaling: Scaling,
    /// Standardisation of the output (mean, standard deviation).
    pub output_scaling: Scaling,
    /// Network weights, laid out per hidden unit `[W₁ … W_n, b]`, then `[v₁ … v_H, c]`; regressor order
    /// `u(k), …, u(k−nu+1), y(k−1), …, y(k−ny)`.
    pub weights: Vec<f64>,
    pub diagnostics: NnarxDiagnostics,
}

/// Fill `x` with the regressor at time `k`; samples before 0 read as `past.0` (input) / `past.1` (output).
fn regressor(x: &mut Vec<f64>, u_n: &[f64], y_n: &[f64], k: usize, nu: usize, ny: usize, past: (f64, f64)) {
    x.clear();
    let lagged = |s: &[f64], lag: usize, before: f64| {
        k.checked_sub(lag).and_then(|i| s.get(i)).copied().unwrap_or(before)
    };
    x.extend((0..nu).map(|lag| lagged(u_n, lag, past.0)));
    x.extend((1..=ny).map(|lag| lagged(y_n, lag, past.1)));
}

impl NnarxModel {
    fn shape(&self) -> MlpShape {
        MlpShape { n_inputs: self.nu + self.ny, hidden: self.hidden }
    }

    /// The network's equilibrium for a constant input `u0`: the `y` with `NN(u₀, …, y, …) = y`.
    pub fn equilibrium(&self, u0: f64) -> Equilibrium {
        let u0_n = self.input_scaling.normalised_from_physical(u0);
        let (y_n, method) = equilibrium_normalised(self.shape(), &self.weights, u0_n, self.nu, self.ny);
        Equilibrium { y: self.output_scaling.physical_from_normalised(y_n), method }
    }

    /// Every output at which the network rests for the constant input `u0`, ascending. A model fit
    /// for simulation should have exactly one; more mean the simulation can lock onto a spurious
    /// state.
    pub fn equilibria(&self, u0: f64) -> Vec<f64> {
        let u0_n = self.input_scaling.normalised_from_physical(u0);
        all_equilibria_normalised(self.shape(), &self.weights, u0_n, self.nu, self.ny)
            .iter()
            .map(|y| self.output_scaling.physical_from_normalised(*y))
            .collect()
    }

    /// Output-error simulation from the input alone: past inputs equal `u[0]`, past outputs the
    /// equilibrium for `u[0]`, then the network's own predictions are fed back.
    pub fn simulate(&self, u: &[f64]) -> Vec<f64> {
        let u_n = self.input_scaling.normalise_all(u);
        simulate_normalised(self.shape(), &self.weights, &u_n, self.nu, self.ny)
            .iter()
            .map(|y| self.output_scaling.physical_from_normalised(*y))
            .collect()
    }

    /// Output-error simulation started from the measured outputs: the network's first past outputs
    /// are the first measured samples (its own state at the start of the run), then its own
    /// predictions are fed back. The counterpart of an estimated initial state for a model whose
    /// state is its past outputs.
    pub fn simulate_from_measured(&self, u: &[f64], y: &[f64]) -> Vec<f64> {
        let u_n = self.input_scaling.normalise_all(u);
        let y_n = self.output_scaling.normalise_all(y);
        let shape = self.shape();
        let u0 = u_n.first().copied().unwrap_or(0.0);
        let (y0, _) = equilibrium_normalised(shape, &self.weights, u0, self.nu, self.ny);
        let first = self.ny.min(y_n.len());
        let mut out: Vec<f64> = y_n[..first].to_vec();
        let mut x = Vec::with_capacity(shape.n_inputs);
        for k in first..u_n.len() {
            regressor(&mut x, &u_n, &out, k, self.nu, self.ny, (u0, y0));
            out.push(shape.output(&self.weights, &x));
        }
        out.iter().map(|y| self.output_scaling.physical_from_normalised(*y)).collect()
    }

    /// One-step-ahead (series-parallel) prediction from measured past outputs. The first
    /// `max(ny, nu − 1)` samples have no complete regressor and repeat the measurement.
    pub fn predict_one_step(&self, u: &[f64], y: &[f64]) -> Vec<f64> {
        let (u_n, y_n) = (self.input_scaling.normalise_all(u), self.output_scaling.normalise_all(y));
        let shape = self.shape();
        let first = self.ny.max(self.nu.saturating_sub(1));
        let mut x = Vec::with_capacity(shape.n_inputs);
        y.iter()
            .take(u.len())
            .enumerate()
            .map(|(k, yk)| {
                if k < first {
                    return *yk;
                }
                regressor(&mut x, &u_n, &y_n, k, self.nu, self.ny, (0.0, 0.0));
                self.output_scaling.physical_from_normalised(shape.output(&self.weights, &x))
            })
            .collect()
    }
}

fn equilibrium_normalised(
    shape: MlpShape,
    w: &[f64],
    u0_n: f64,
    nu: usize,
    ny: usize,
) -> (f64, EquilibriumMethod) {
    let mut x = Vec::with_capacity(shape.n_inputs);
    let mut g = |y: f64| {
        x.clear();
        x.extend(std::iter::repeat_n(u0_n, nu));
        x.extend(std::iter::repeat_n(y, ny));
        shape.output(w, &x)
    };
    // Slow plants contract slowly (factor ≈ 0.995 per iteration for the SR-30 speed), hence the cap.
    let mut y = 0.0;
    for iterations in 1..=FIXED_POINT_ITERATIONS {
        let next = g(y);
        if !next.is_finite() {
            break;
        }
        if (next - y).abs() <= 1e-11 * (1.0 + y.abs()) {
            return (next, EquilibriumMethod::FixedPoint { iterations });
        }
        y = next;
    }
    match all_equilibria_normalised(shape, w, u0_n, nu, ny)
        .into_iter()
        .min_by(|a, b| a.abs().total_cmp(&b.abs()))
    {
        Some(root) => (root, EquilibriumMethod::Bisection),
        None => (0.0, EquilibriumMethod::TrainingMean),
    }
}

/// Every root of `NN(u₀, …, y, …) − y`, ascending. `|NN| ≤ bound`, so all roots lie in
/// `[−bound, bound]`: scan a grid there and bisect each sign change.
fn all_equilibria_normalised(shape: MlpShape, w: &[f64], u0_n: f64, nu: usize, ny: usize) -> Vec<f64> {
    let mut x = Vec::with_capacity(shape.n_inputs);
    let mut g = |y: f64| {
        x.clear();
        x.extend(std::iter::repeat_n(u0_n, nu));
        x.extend(std::iter::repeat_n(y, ny));
        shape.output(w, &x) - y
    };
    let bound = shape.output_bound(w) + 1.0;
    // Each grid value once: the scan is the cost of the equilibrium checks.
    let grid: Vec<(f64, f64)> =
        (0..=2000).map(|i| -bound + 2.0 * bound * i as f64 / 2000.0).map(|y| (y, g(y))).collect();
    let mut roots = Vec::new();
    for pair in grid.windows(2) {
        let &[(mut lo, f_lo), (mut hi, f_hi)] = pair else { continue };
        if f_lo.is_nan() || f_hi.is_nan() || (f_lo > 0.0) == (f_hi > 0.0) {
            continue;
        }
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if (g(mid) > 0.0) == (f_lo > 0.0) { lo = mid } else { hi = mid }
        }
        roots.push(0.5 * (lo + hi));
    }
    roots
}

fn simulate_normalised(shape: MlpShape, w: &[f64], u_n: &[f64], nu: usize, ny: usize) -> Vec<f64> {
    let u0 = u_n.first().copied().unwrap_or(0.0);
    let (y0, _) = equilibrium_normalised(shape, w, u0, nu, ny);
    let mut y_n: Vec<f64> = Vec::with_capacity(u_n.len());
    let mut x = Vec::with_capacity(shape.n_inputs);
    for k in 0..u_n.len() {
        regressor(&mut x, u_n, &y_n, k, nu, ny, (u0, y0));
        y_n.push(shape.output(w, &x));
    }
    y_n
}

/// The normalised inputs, on a grid over the range of `u_n`, with more than one equilibrium.
/// The kept restart: among those whose training output-error RMS is within `OE_TOLERANCE` times the
/// best, the one with the fewest inputs having several equilibria, then the smallest RMS.
fn choose_restart(summaries: &[RestartSummary]) -> Option<usize> {
    let best = summaries.iter().map(|s| s.oe_rms).filter(|r| r.is_finite()).fold(f64::INFINITY, f64::min);
    summaries
        .iter()
        .enumerate()
        .filter(|(_, s)| s.oe_rms <= OE_TOLERANCE * best)
        .min_by(|(_, a), (_, b)| {
            a.several_equilibria.cmp(&b.several_equilibria).then(a.oe_rms.total_cmp(&b.oe_rms))
        })
        .map(|(i, _)| i)
}

fn several_equilibria(shape: MlpShape, w: &[f64], u_n: &[f64], opts: &NnarxOptions) -> Vec<f64> {
    let lo = u_n.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = u_n.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let step = (hi - lo) / (EQUILIBRIUM_CHECKS - 1) as f64;
    (0..EQUILIBRIUM_CHECKS)
        .map(|i| lo + step * i as f64)
        .filter(|u0| all_equilibria_normalised(shape, w, *u0, opts.nu, opts.ny).len() > 1)
        .collect()
}

/// Train one network from each start, on two threads (the restarts are independent): the calling
/// thread trains every other restart and reports progress over all of them; the helper stops when
/// the caller cancels. Outcomes in the order of `starts`.
fn train_restarts(
    shape: MlpShape,
    data: &TrainData,
    starts: Vec<Vec<f64>>,
    max_iterations: usize,
    progress: &mut dyn FnMut(f64) -> bool,
) -> Result<Vec<TrainOutcome>, BaselineError> {
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    let total = (starts.len() * max_iterations).max(1) as f64;
    let iterations = AtomicUsize::new(0);
    let cancelled = AtomicBool::new(false);
    let (mine, helpers): (Vec<_>, Vec<_>) = starts.into_iter().enumerate().partition(|(i, _)| i % 2 == 0);
    let (mine_out, helper_out) = std::thread::scope(|scope| {
        let helper = scope.spawn(|| {
            helpers
                .into_iter()
                .map(|(i, w0)| {
                    let out = train(shape, data, w0, max_iterations, &mut |_| {
                        iterations.fetch_add(1, Ordering::Relaxed);
                        if cancelled.load(Ordering::Relaxed) { Err(BaselineError::Cancelled) } else { Ok(()) }
                    });
                    (i, out)
                })
                .collect::<Vec<_>>()
        });
        let mine_out: Vec<_> = mine
            .into_iter()
            .map(|(i, w0)| {
                let out = train(shape, data, w0, max_iterations, &mut |_| {
                    let done = iterations.fetch_add(1, Ordering::Relaxed) + 1;
                    let reported = report(progress, done as f64 / total);
                    if reported.is_err() {
                        cancelled.store(true, Ordering::Relaxed);
                    }
                    reported
                });
                if out.is_err() {
                    cancelled.store(true, Ordering::Relaxed);
                }
                (i, out)
            })
            .collect();
        (mine_out, helper.join())
    });
    let helper_out =
        helper_out.map_err(|_| BaselineError::Diverged { stage: "NNARX", rms_normalised: f64::NAN })?;
    let mut all: Vec<(usize, Result<TrainOutcome, BaselineError>)> =
        mine_out.into_iter().chain(helper_out).collect();
    all.sort_by_key(|(i, _)| *i);
    all.into_iter().map(|(_, out)| out).collect()
}

/// The regressor rows and targets the network is trained on, from the normalised signals.
fn training_data(u_n: &[f64], y_n: &[f64], shape: MlpShape, opts: &NnarxOptions) -> TrainData {
    let mut data = TrainData { x: Vec::new(), t: Vec::new() };
    let mut x = Vec::with_capacity(shape.n_inputs);
    for (k, t) in y_n.iter().enumerate().skip(opts.first_row()) {
        regressor(&mut x, u_n, y_n, k, opts.nu, opts.ny, (0.0, 0.0));
        data.x.extend_from_slice(&x);
        data.t.push(*t);
    }
    data
}

/// One trained restart's figures (errors in output units, `output_scale` per normalised unit), and
/// the normalised inputs at which it has several equilibria.
fn summarise_restart(
    shape: MlpShape,
    out: &TrainOutcome,
    data: &TrainData,
    (u_n, y_n): (&[f64], &[f64]),
    opts: &NnarxOptions,
    output_scale: f64,
) -> (RestartSummary, Vec<f64>) {
    let several = several_equilibria(shape, &out.weights, u_n, opts);
    let one_step: Vec<f64> =
        data.x.chunks_exact(shape.n_inputs).map(|x| shape.output(&out.weights, x)).collect();
    let oe_rms = rms_error(&simulate_normalised(shape, &out.weights, u_n, opts.nu, opts.ny), y_n);
    let summary = RestartSummary {
        iterations: out.iterations,
        log_evidence: out.log_evidence,
        gamma: out.gamma,
        one_step_rms: rms_error(&one_step, &data.t) * output_scale,
        oe_rms: if oe_rms.is_finite() { oe_rms * output_scale } else { f64::INFINITY },
        several_equilibria: several.len(),
    };
    (summary, several)
}

/// Train an NNARX model on `y` driven by `u` (see the module docs for the algorithm). `progress`
/// receives the fraction done; returning `false` cancels.
pub fn fit_nnarx(
    u: &[f64],
    y: &[f64],
    opts: &NnarxOptions,
    progress: &mut dyn FnMut(f64) -> bool,
) -> Result<NnarxModel, BaselineError> {
    opts.check()?;
    check_signals(u, y, opts.samples_needed())?;
    let input_scaling = Scaling::standardise(u).ok_or(BaselineError::ConstantSignal { what: "input" })?;
    let output_scaling = Scaling::standardise(y).ok_or(BaselineError::ConstantSignal { what: "output" })?;
    let (u_n, y_n) = (input_scaling.normalise_all(u), output_scaling.normalise_all(y));
    let shape = opts.shape();
    let data = training_data(&u_n, &y_n, shape, opts);
    report(progress, 0.0)?;

    // Every restart's start is drawn first, in order, so the result does not depend on how the
    // restarts are spread over threads.
    let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
    let starts: Vec<Vec<f64>> = (0..opts.restarts).map(|_| shape.random_weights(&mut rng)).collect();
    let trained = train_restarts(shape, &data, starts, opts.max_iterations, progress)?;
    let mut outcomes = Vec::with_capacity(opts.restarts);
    let mut summaries = Vec::with_capacity(opts.restarts);
    let mut equilibria_checks = Vec::with_capacity(opts.restarts);
    for out in trained {
        let (summary, several) =
            summarise_restart(shape, &out, &data, (&u_n, &y_n), opts, output_scaling.scale);
        summaries.push(summary);
        outcomes.push(out);
        equilibria_checks.push(several);
    }
    let chosen = choose_restart(&summaries)
        .ok_or(BaselineError::Diverged { stage: "NNARX", rms_normalised: f64::INFINITY })?;
    let (Some(out), Some(chosen_summary)) =
        (outcomes.into_iter().nth(chosen), summaries.get(chosen).cloned())
    else {
        return Err(BaselineError::Diverged { stage: "NNARX", rms_normalised: f64::INFINITY });
    };
    let u0 = u_n.first().copied().unwrap_or(0.0);
    let (_, training_start) = equilibrium_normalised(shape, &out.weights, u0, opts.nu, opts.ny);
    let several_equilibria_at = equilibria_checks
        .into_iter()
        .nth(chosen)
        .unwrap_or_default()
        .into_iter()
        .map(|u| input_scaling.physical_from_normalised(u))
        .collect();
    report(progress, 1.0)?;
    Ok(NnarxModel {
        nu: opts.nu,
        ny: opts.ny,
        hidden: opts.hidden,
        input_scaling,
        output_scaling,
        diagnostics: NnarxDiagnostics {
            chosen_restart: chosen,
            iterations: out.iterations,
            alpha: out.alpha,
            beta: out.beta,
            gamma: out.gamma,
            n_weights: shape.n_weights(),
            log_evidence: out.log_evidence,
            one_step_rms: chosen_summary.one_step_rms,
            oe_rms: chosen_summary.oe_rms,
            training_start,
            several_equilibria_at,
            restarts: summaries,
        },
        weights: out.weights,
    })
}
