//! The paper's comparison (sections 5.3–7): the Hammerstein–Wiener and NNARX baselines fitted on
//! the identification range, every model simulated from the input alone on each scored run, the
//! chirp's frequency response against each model's, the steady run's noise fit and the Monte Carlo
//! error propagation. The batch and the app's Compare view both call it.
use std::collections::BTreeMap;
use std::sync::Arc;

use crate::core::control::identified_range;
use crate::core::effects::ExtendedModel;
use crate::core::identification::fits::SegmentFits;
use crate::core::identification::initial_state::InitialState;
use crate::core::identification::wiener::WienerModel;
use crate::core::monte_carlo::{MonteCarloError, MonteCarloResult};
use crate::core::numerics::metrics::{Metrics, metrics};
use crate::core::numerics::noise_fit::{Distribution, NoiseFitReport};
use crate::core::run::Run;

mod failure;
mod model_kind;
mod models;
mod studies;

pub use failure::failure_reasons;
pub use model_kind::{Curve, ModelKind, PaperRow};
pub use models::{Cancelled, OutputModels, fit_baselines, fit_baselines_with_progress, scaled};
pub use studies::{
    FrequencyComparison, MonteCarloSummary, chirp_grid, chirp_welch_options, error_boxes,
    frequency_comparison, monte_carlo_all, monte_carlo_for, monte_carlo_with_progress, noise_fits,
};

/// The parts of [`compare_output`]'s progress: fitting the Hammerstein–Wiener model, training the
/// NNARX network, and (after the fast simulations) the Monte Carlo studies.
const HW_END: f64 = 0.2;
const NNARX_END: f64 = 0.8;

/// What [`compare_output`] is doing at `fraction` of its progress, for a progress indicator.
pub fn compare_stage(fraction: f64) -> &'static str {
    if fraction < HW_END {
        "fitting the Hammerstein–Wiener model"
    } else if fraction < NNARX_END {
        "training the NNARX network"
    } else {
        "simulating and running the Monte Carlo study"
    }
}

/// Everything [`compare_output`] needs: the gray-box model, the identification it came from and the
/// runs to compare on (shared, so the work can run on another thread).
#[derive(Clone)]
pub struct CompareInput {
    pub output: String,
    pub ident: Arc<Run>,
    pub fits: Arc<SegmentFits>,
    pub wiener: WienerModel,
    /// Runs every model is scored on: validation runs, then chirp runs (`true`).
    pub scored: Vec<(Arc<Run>, bool)>,
    /// The steady run for the noise fit and the Monte Carlo study.
    pub steady: Option<Arc<Run>>,
    /// The gray-box model with its effects, when it has any: the gray-box model on the runs (the
    /// input-only studies use `wiener`, as the batch does).
    pub extended: Option<ExtendedModel>,
    /// Where every model's simulation of a scored run starts (the output's setting).
    pub initial_state: InitialState,
}

/// One model's simulation of one run.
#[derive(Clone, Debug)]
pub struct ModelRun {
    pub model: ModelKind,
    pub y_hat: Vec<f64>,
    pub metrics: Result<Metrics, String>,
    /// Why the model fails on the run (fit below 50 %), in words; empty when it does not fail.
    pub failure_reasons: Vec<String>,
}

/// Every model on one scored run.
#[derive(Clone, Debug)]
pub struct RunComparison {
    pub run: Arc<Run>,
    pub is_chirp: bool,
    pub models: Vec<ModelRun>,
}

/// The input noise the Monte Carlo study drew from.
#[derive(Clone, Debug)]
pub struct InputNoiseFit {
    pub run: String,
    pub channel: String,
    pub report: NoiseFitReport,
    /// The best fit by log-likelihood (`None`: no family could be fitted).
    pub used: Option<Distribution>,
}

/// The paper's comparison of one output (sections 5.3–7), as the app shows it.
#[derive(Clone, Debug)]
pub struct OutputComparison {
    pub output: String,
    pub runs: Vec<RunComparison>,
    /// From the first chirp run; `None` without one.
    pub frequency: Option<FrequencyComparison>,
    /// `None` without a steady run.
    pub noise: Option<InputNoiseFit>,
    /// Per model; empty without a steady run or a usable noise fit.
    pub monte_carlo: BTreeMap<ModelKind, MonteCarloResult>,
    /// Parts that failed (a baseline, a frequency response, a Monte Carlo study), in words.
    pub notes: Vec<String>,
}

/// Fit the baselines, simulate every model on every scored run, compare frequency responses on the
/// chirp, fit the steady run's input noise and propagate it through every model. Progress: the
/// Hammerstein–Wiener fit 0–0.2, the NNARX training 0.2–0.8, the Monte Carlo studies 0.8–1.
pub fn compare_output(
    input: &CompareInput,
    progress: &mut dyn FnMut(f64) -> bool,
) -> Result<OutputComparison, Cancelled> {
    let output = input.output.as_str();
    let mut notes = Vec::new();
    let mut models = fit_baselines_with_progress(
        &input.fits,
        &input.wiener,
        &input.ident,
        output,
        &mut notes,
        &mut scaled(progress, 0.0, NNARX_END),
    )?;
    models.extended = input.extended.clone().filter(|m| !m.effects.is_empty());
    models.initial_state = input.initial_state;
    let runs = input
        .scored
        .iter()
        .map(|(run, is_chirp)| RunComparison {
            run: Arc::clone(run),
            is_chirp: *is_chirp,
            models: models_on_run(&models, run, output, identified_range(&input.ident.input.values)),
        })
        .collect();
    let frequency = input
        .scored
        .iter()
        .find(|(_, is_chirp)| *is_chirp)
        .and_then(|(chirp, _)| frequency_comparison(&models, chirp, output, &mut notes));
    let noise = input.steady.as_deref().and_then(|steady| {
        let mut fits = noise_fits(steady, &mut notes);
        let report = fits.remove(&steady.input.name)?;
        let used = report.best().map(|f| f.distribution);
        Some(InputNoiseFit { run: steady.name.clone(), channel: steady.input.name.clone(), report, used })
    });
    let mut monte_carlo = BTreeMap::new();
    if let (Some(steady), Some(noise)) = (input.steady.as_deref(), noise.as_ref().and_then(|n| n.used)) {
        let u0 = steady.input.values.iter().sum::<f64>() / steady.input.values.len().max(1) as f64;
        let share = (1.0 - NNARX_END) / ModelKind::MONTE_CARLO.len() as f64;
        for (k, kind) in ModelKind::MONTE_CARLO.into_iter().enumerate() {
            let (lo, hi) = (NNARX_END + share * k as f64, NNARX_END + share * (k + 1) as f64);
            let mut part = scaled(progress, lo, hi);
            match monte_carlo_with_progress(&models, kind, u0, steady.dt_secs, &noise, &mut part) {
                Some(Ok(r)) => {
                    monte_carlo.insert(kind, r);
                }
                Some(Err(MonteCarloError::Cancelled)) => return Err(Cancelled),
                Some(Err(e)) => notes.push(format!("Monte Carlo of {kind}: {e}")),
                None => {}
            }
        }
    }
    if !progress(1.0) {
        return Err(Cancelled);
    }
    Ok(OutputComparison { output: output.to_owned(), runs, frequency, noise, monte_carlo, notes })
}

/// Every model simulated on `run` from its input alone, scored against the measured output; a
/// failing one with its reasons (`ident_input`: the identification input's range).
fn models_on_run(models: &OutputModels, run: &Run, output: &str, ident_input: (f64, f64)) -> Vec<ModelRun> {
    let Some(y) = run.output(output) else { return Vec::new() };
    models
        .simulate_run(run)
        .into_iter()
        .map(|(model, y_hat)| {
            let metrics = metrics(&y.values, &y_hat).map_err(|e| e.to_string());
            let reasons = match &metrics {
                Ok(m) if m.fails() => failure_reasons(&y.values, &y_hat, &run.input.values, ident_input),
                _ => Vec::new(),
            };
            ModelRun { model, y_hat, metrics, failure_reasons: reasons }
        })
        .collect()
}
