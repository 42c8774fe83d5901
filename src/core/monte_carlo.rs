//! Monte Carlo error propagation (the paper's section 7): how much input noise moves a model's output.
//!
//! Each of `runs` simulations feeds the model a constant input `u0` plus noise drawn from the
//! distribution fitted to a steady run's input, from a zero initial condition, and compares the output
//! with the nominal (noise-free) run. The model is any closure, so the gray-box, Hammerstein–Wiener and
//! NNARX models are treated alike.
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::core::numerics::noise_fit::{self, Distribution, MIN_SAMPLES, NoiseFitError};

/// How a draw `x` of the fitted input distribution becomes the noisy input sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum InputNoise {
    /// `u = u0 + (x − E[x])`: the distribution's shape and spread around the nominal level. Right when
    /// the distribution was fitted to a steady input at (about) `u0`, and still right when it was not.
    CentredOnLevel,
    /// `u = x`: the draws are the input, so the distribution's mean should equal `u0`; any difference
    /// shows up as a bias in the output difference.
    DrawsAreInput,
}

/// Settings of [`monte_carlo`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MonteCarloConfig {
    pub runs: usize,
    pub duration_secs: f64,
    pub dt_secs: f64,
    /// The constant nominal input level.
    pub u0: f64,
    pub mapping: InputNoise,
    /// Bins of the difference histogram.
    pub bins: usize,
    pub seed: u64,
}

impl MonteCarloConfig {
    /// The paper's set-up: 100 runs of 20 s at level `u0`.
    pub fn paper(u0: f64, dt_secs: f64) -> Self {
        Self {
            runs: 100,
            duration_secs: 20.0,
            dt_secs,
            u0,
            mapping: InputNoise::CentredOnLevel,
            bins: 40,
            seed: 1,
        }
    }

    /// Samples per run, `round(duration / dt)`.
    pub fn samples_per_run(&self) -> usize {
        (self.duration_secs / self.dt_secs).round().max(0.0) as usize
    }
}

/// Counts of values in equal-width bins; `edges` has one more entry than `counts`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Histogram {
    pub edges: Vec<f64>,
    pub counts: Vec<usize>,
}

impl Histogram {
    /// Bin centres, one per count.
    pub fn centres(&self) -> Vec<f64> {
        self.edges.windows(2).map(|e| 0.5 * (e[0] + e[1])).collect()
    }
}

/// What the input noise does to the output.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MonteCarloResult {
    /// Standard deviation (n − 1) of noisy − nominal over every sample of every run.
    pub std_difference: f64,
    /// Mean of noisy − nominal over every sample of every run (≈ 0 unless the model or mapping biases).
    pub mean_difference: f64,
    /// The same standard deviation within each run.
    pub std_per_run: Vec<f64>,
    pub histogram: Histogram,
    /// The normal distribution fitted (maximum likelihood) to all differences.
    pub normal_fit: Distribution,
    /// The nominal (noise-free) output.
    pub nominal: Vec<f64>,
    pub samples_per_run: usize,
    /// Every noisy − nominal difference, run after run (for pictures; not serialised).
    #[serde(skip)]
    pub differences: Vec<f64>,
}

/// Why a Monte Carlo study cannot run or was stopped.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MonteCarloError {
    #[error("the number of runs must be at least one")]
    ZeroRuns,
    #[error("the histogram needs at least one bin")]
    ZeroBins,
    #[error("sample time must be positive and finite, got {dt_secs}")]
    BadSampleTime { dt_secs: f64 },
    #[error(
        "a run of {duration_secs} s at this sample time has {samples} samples; at least {MIN_SAMPLES} are needed"
    )]
    TooShort { duration_secs: f64, samples: usize },
    #[error("the input level must be finite, got {u0}")]
    BadLevel { u0: f64 },
    #[error("the noise distribution is unusable: {0}")]
    BadNoise(#[from] NoiseFitError),
    #[error("the model returned {got} samples for an input of {expected}")]
    LengthMismatch { expected: usize, got: usize },
    #[error("the model output of run {run} is not finite at sample {index}")]
    NonFinite { run: RunKind, index: usize },
    #[error("every run gave exactly the nominal output, so no spread can be fitted")]
    NoSpread,
    #[error("cancelled")]
    Cancelled,
}

/// Which simulation an error comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum RunKind {
    Nominal,
    Noisy(usize),
}

impl std::fmt::Display for RunKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Nominal => write!(f, "nominal"),
            Self::Noisy(run) => write!(f, "{run}"),
        }
    }
}

/// Runs the Monte Carlo study.
///
/// `simulate` maps an input sequence to the output sequence of the same length, starting from the
/// zero initial condition (the caller arranges it). `progress` gets the fraction done before the first
/// run and after each run; returning `false` cancels with [`MonteCarloError::Cancelled`].
/// The same `seed` gives the same result.
pub fn monte_carlo(
    cfg: &MonteCarloConfig,
    noise: &Distribution,
    simulate: &dyn Fn(&[f64]) -> Vec<f64>,
    progress: &mut dyn FnMut(f64) -> bool,
) -> Result<MonteCarloResult, MonteCarloError> {
    let n = check_config(cfg, noise)?;
    if !progress(0.0) {
        return Err(MonteCarloError::Cancelled);
    }
    let nominal = checked_run(simulate, &vec![cfg.u0; n], RunKind::Nominal)?;
    let offset = match cfg.mapping {
        InputNoise::CentredOnLevel => cfg.u0 - noise.mean(),
        InputNoise::DrawsAreInput => 0.0,
    };
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let mut differences = Vec::with_capacity(n * cfg.runs);
    let mut std_per_run = Vec::with_capacity(cfg.runs);
    for run in 0..cfg.runs {
        let u: Vec<f64> = (0..n).map(|_| offset + noise.sample(&mut rng)).collect();
        let y = checked_run(simulate, &u, RunKind::Noisy(run))?;
        let d: Vec<f64> = y.iter().zip(&nominal).map(|(a, b)| a - b).collect();
        std_per_run.push(mean_std(&d).1);
        differences.extend(d);
        if !progress((run + 1) as f64 / cfg.runs as f64) {
            return Err(MonteCarloError::Cancelled);
        }
    }
    let (mean_difference, std_difference) = mean_std(&differences);
    let normal_fit = noise_fit::fit(noise_fit::Family::Normal, &differences).map_err(|e| match e {
        NoiseFitError::ZeroSpread { .. } => MonteCarloError::NoSpread,
        other => MonteCarloError::BadNoise(other),
    })?;
    Ok(MonteCarloResult {
        std_difference,
        mean_difference,
        std_per_run,
        histogram: histogram(&differences, cfg.bins),
        normal_fit,
        nominal,
        samples_per_run: n,
        differences,
    })
}

fn check_config(cfg: &MonteCarloConfig, noise: &Distribution) -> Result<usize, MonteCarloError> {
    if cfg.runs == 0 {
        return Err(MonteCarloError::ZeroRuns);
    }
    if cfg.bins == 0 {
        return Err(MonteCarloError::ZeroBins);
    }
    if !(cfg.dt_secs.is_finite() && cfg.dt_secs > 0.0) {
        return Err(MonteCarloError::BadSampleTime { dt_secs: cfg.dt_secs });
    }
    let n = cfg.samples_per_run();
    if !(cfg.duration_secs.is_finite() && n >= MIN_SAMPLES) {
        return Err(MonteCarloError::TooShort { duration_secs: cfg.duration_secs, samples: n });
    }
    if !cfg.u0.is_finite() {
        return Err(MonteCarloError::BadLevel { u0: cfg.u0 });
    }
    noise.check()?;
    Ok(n)
}

fn checked_run(
    simulate: &dyn Fn(&[f64]) -> Vec<f64>,
    u: &[f64],
    run: RunKind,
) -> Result<Vec<f64>, MonteCarloError> {
    let y = simulate(u);
    if y.len() != u.len() {
        return Err(MonteCarloError::LengthMismatch { expected: u.len(), got: y.len() });
    }
    if let Some(index) = y.iter().position(|v| !v.is_finite()) {
        return Err(MonteCarloError::NonFinite { run, index });
    }
    Ok(y)
}

/// Mean and sample standard deviation (n − 1; 0 for fewer than two values).
fn mean_std(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n.max(1.0);
    let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, var.sqrt())
}

/// `bins` equal-width bins spanning the values' range.
pub fn histogram(values: &[f64], bins: usize) -> Histogram {
    let lo = values.iter().fold(f64::INFINITY, |m, v| m.min(*v));
    let hi = values.iter().fold(f64::NEG_INFINITY, |m, v| m.max(*v));
    if bins == 0 || !(lo.is_finite() && hi.is_finite()) {
        return Histogram { edges: vec![], counts: vec![] };
    }
    let width = if hi > lo { (hi - lo) / bins as f64 } else { 1.0 };
    let edges = (0..=bins).map(|i| lo + width * i as f64).collect();
    let mut counts = vec![0; bins];
    for v in values {
        let bin = (((v - lo) / width).floor().max(0.0) as usize).min(bins - 1);
        if let Some(c) = counts.get_mut(bin) {
            *c += 1;
        }
    }
    Histogram { edges, counts }
}
