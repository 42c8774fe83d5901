//! The paper's comparison (sections 5.3–7) for `jetid --batch`: the Hammerstein–Wiener and NNARX
//! baselines fitted on the identification run, every model simulated from the input alone on each
//! scored run, the chirp's frequency response against each model's, the steady run's noise fit and
//! the Monte Carlo error propagation. No egui.
use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::core::baselines::BaselineError;
use crate::core::baselines::hammerstein_wiener::{HwModel, HwOptions, HwOrders, fit_hammerstein_wiener};
use crate::core::baselines::nnarx::{NnarxModel, NnarxOptions, fit_nnarx};
use crate::core::effects::ExtendedModel;
use crate::core::identification::initial_state::InitialState;
use crate::core::identification::pipeline::{Identified, SegmentFits};
use crate::core::identification::wiener::WienerModel;
use crate::core::monte_carlo::{MonteCarloConfig, MonteCarloResult, monte_carlo};
use crate::core::numerics::metrics::{BoxStats, percentage_error_box};
use crate::core::numerics::noise_fit::{Distribution, NoiseFitReport, fit_all};
use crate::core::numerics::spectral::{EmpiricalResponse, LowFrequencyLevel, WelchOptions, welch_response};
use crate::core::numerics::tf::log_space;
use crate::core::run::Run;

/// Model names as report.json spells them (CONTRACT.md).
pub const GRAY_BOX: &str = "gray_box";
pub const LINEAR: &str = "linear";
pub const HAMMERSTEIN_WIENER: &str = "hammerstein_wiener";
pub const NNARX: &str = "nnarx";

/// Every model of one output that can be simulated from an input sequence.
pub struct OutputModels {
    /// The output modelled.
    pub output: String,
    /// Where every model's simulation of a scored run starts.
    pub initial_state: InitialState,
    pub wiener: WienerModel,
    /// The gray-box model with the applied effects, when there are any: it is what `gray_box` means
    /// on a run (effects may need the run's auxiliary channels); input-only studies (chirp frequency
    /// response, Monte Carlo) use the model without them.
    pub extended: Option<crate::core::effects::ExtendedModel>,
    pub hw: Option<HwModel>,
    pub nnarx: Option<NnarxModel>,
}

impl OutputModels {
    /// (report name, simulation of `u` from the steady state of `u[0]`) for every model present.
    pub fn simulate_all(&self, u: &[f64]) -> Vec<(&'static str, Vec<f64>)> {
        let mut out = vec![(GRAY_BOX, self.wiener.simulate(u).1), (LINEAR, self.wiener.linear.simulate(u))];
        if let Some(hw) = &self.hw {
            out.push((HAMMERSTEIN_WIENER, hw.simulate(u)));
        }
        if let Some(nn) = &self.nnarx {
            out.push((NNARX, nn.simulate(u)));
        }
        out
    }

    /// The gray-box model as the runs are scored: with its effects, when it has any.
    pub fn gray_box_model(&self) -> ExtendedModel {
        self.extended.clone().unwrap_or_else(|| ExtendedModel::new(&self.output, self.wiener.clone()))
    }

    /// Every model on a scored run, each started as [`Self::initial_state`] says (from the state that
    /// best fits the first seconds of the measured output, when the run has it): the gray-box model
    /// with its effects (left out when it fails, e.g. for a missing channel), its linear block, and
    /// the baselines.
    pub fn simulate_run(&self, run: &Run) -> Vec<(&'static str, Vec<f64>)> {
        let u = &run.input.values;
        let measured = run.output(&self.output).map(|c| c.values.as_slice());
        let estimated = measured.filter(|_| self.initial_state == InitialState::Estimated);
        let mut out = Vec::with_capacity(4);
        if let Ok(y) = self.gray_box_model().simulate_scored(run, self.initial_state) {
            out.push((GRAY_BOX, y));
        }
        let linear = match measured {
            Some(y) => self.wiener.linear.simulate_scored(u, y, self.initial_state),
            None => self.wiener.linear.simulate(u),
        };
        out.push((LINEAR, linear));
        if let Some(hw) = &self.hw {
            out.push((
                HAMMERSTEIN_WIENER,
                estimated.map_or_else(|| hw.simulate(u), |y| hw.simulate_estimated(u, y)),
            ));
        }
        if let Some(nn) = &self.nnarx {
            out.push((NNARX, estimated.map_or_else(|| nn.simulate(u), |y| nn.simulate_from_measured(u, y))));
        }
        out
    }

    /// One model's simulation.
    pub fn simulate(&self, name: &str, u: &[f64]) -> Option<Vec<f64>> {
        match name {
            GRAY_BOX => Some(self.wiener.simulate(u).1),
            LINEAR => Some(self.wiener.linear.simulate(u)),
            HAMMERSTEIN_WIENER => self.hw.as_ref().map(|m| m.simulate(u)),
            NNARX => self.nnarx.as_ref().map(|m| m.simulate(u)),
            _ => None,
        }
    }
}

/// Fit both baselines on the identification range the gray-box model was fitted on; a baseline that
/// fails is a note, not a failed batch.
pub fn fit_baselines(
    identified: &Identified,
    ident: &Run,
    output: &str,
    notes: &mut Vec<String>,
) -> OutputModels {
    let wiener = &identified.model.wiener;
    fit_baselines_with_progress(&identified.fits, wiener, ident, output, notes, &mut |_| true).unwrap_or_else(
        |Cancelled| OutputModels {
            output: output.to_owned(),
            initial_state: InitialState::default(),
            wiener: wiener.clone(),
            extended: None,
            hw: None,
            nnarx: None,
        },
    )
}

/// The user stopped a long computation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cancelled;

/// [`fit_baselines`] for the gray-box model `wiener` fitted on `fits`, reporting progress (the
/// Hammerstein–Wiener fit is the first quarter, the NNARX training the rest); `progress` answering
/// `false` stops it with [`Cancelled`].
pub fn fit_baselines_with_progress(
    fits: &SegmentFits,
    wiener: &WienerModel,
    ident: &Run,
    output: &str,
    notes: &mut Vec<String>,
    progress: &mut dyn FnMut(f64) -> bool,
) -> Result<OutputModels, Cancelled> {
    let start = fits.segments.first().map_or(0, |s| s.start);
    let end = fits.segments.last().map_or(ident.len(), |s| s.end);
    let u = ident.input.values.get(start..end).unwrap_or(&[]);
    let y = ident.output(output).and_then(|c| c.values.get(start..end)).unwrap_or(&[]);
    let tf = &wiener.linear.tf;
    let orders = HwOrders {
        input_poly: 2,
        n_poles: tf.den_zinv.len().saturating_sub(1).max(1),
        n_zeros: tf.zeros().map_or(0, |z| z.len()),
        output_poly: 2,
    };
    let hw_options = HwOptions::default();
    let hw = match fit_hammerstein_wiener(
        u,
        y,
        ident.dt_secs,
        orders,
        &hw_options,
        &mut scaled(progress, 0.0, 0.25),
    ) {
        Ok(model) => Some(model),
        Err(BaselineError::Cancelled) => return Err(Cancelled),
        Err(e) => {
            notes.push(format!("Hammerstein–Wiener baseline for '{output}': {e}"));
            None
        }
    };
    let nnarx = match fit_nnarx(u, y, &NnarxOptions::default(), &mut scaled(progress, 0.25, 1.0)) {
        Ok(model) => Some(model),
        Err(BaselineError::Cancelled) => return Err(Cancelled),
        Err(e) => {
            notes.push(format!("NNARX baseline for '{output}': {e}"));
            None
        }
    };
    Ok(OutputModels {
        output: output.to_owned(),
        initial_state: InitialState::default(),
        wiener: wiener.clone(),
        extended: None,
        hw,
        nnarx,
    })
}

/// `progress` for a part of the work that spans `lo..=hi` of the whole.
pub fn scaled(progress: &mut dyn FnMut(f64) -> bool, lo: f64, hi: f64) -> impl FnMut(f64) -> bool + '_ {
    // Exactly `lo` at 0 and `hi` at 1, so consecutive parts never step back by a rounding error.
    move |fraction| {
        let f = fraction.clamp(0.0, 1.0);
        progress(lo * (1.0 - f) + hi * f)
    }
}

/// A model's frequency response as the chirp shows it: the same Welch estimate applied to the
/// model's simulation of the chirp input as to the measurement, so every model (the network too) is
/// judged at the same operating point by the same estimator.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrequencyComparison {
    pub run: String,
    /// −3 dB cut-off of the measured response and of each model's, rad/s (`None`: not reached in band).
    pub cutoff_rad_s: BTreeMap<String, Option<f64>>,
    #[serde(skip)]
    pub responses: BTreeMap<String, EmpiricalResponse>,
}

/// Empirical responses of the measured chirp and of every model's simulation of it.
pub fn frequency_comparison(
    models: &OutputModels,
    chirp: &Run,
    output: &str,
    notes: &mut Vec<String>,
) -> Option<FrequencyComparison> {
    let y = &chirp.output(output)?.values;
    let u = &chirp.input.values;
    let nyquist = std::f64::consts::PI / chirp.dt_secs;
    let omegas = log_space(0.3, 0.9 * nyquist, 120);
    let opts = WelchOptions { excited_only: Some(0.01), ..WelchOptions::default() };
    let mut responses = BTreeMap::new();
    let mut cutoff_rad_s = BTreeMap::new();
    let mut series = vec![("measured".to_owned(), y.clone())];
    series.extend(models.simulate_all(u).into_iter().map(|(n, y)| (n.to_owned(), y)));
    for (name, y_model) in series {
        match welch_response(u, &y_model, chirp.dt_secs, &omegas, &opts) {
            Ok(resp) => {
                let cut = resp.cutoff_rad_s(LowFrequencyLevel::MeanOfFirst(3)).ok().flatten();
                cutoff_rad_s.insert(name.clone(), cut);
                responses.insert(name, resp);
            }
            Err(e) => notes.push(format!("frequency response of {name} on '{}': {e}", chirp.name)),
        }
    }
    Some(FrequencyComparison { run: chirp.name.clone(), cutoff_rad_s, responses })
}

/// Box-plot statistics of the percentage error of every model on every scored run.
pub fn error_boxes(
    models: &OutputModels,
    runs: &[&Run],
    output: &str,
) -> BTreeMap<String, BTreeMap<String, BoxStats>> {
    let mut out: BTreeMap<String, BTreeMap<String, BoxStats>> = BTreeMap::new();
    for run in runs {
        let Some(y) = run.output(output) else { continue };
        for (name, y_hat) in models.simulate_run(run) {
            if let Ok(b) = percentage_error_box(&y.values, &y_hat) {
                out.entry(name.to_owned()).or_default().insert(run.name.clone(), b);
            }
        }
    }
    out
}

/// Noise fit of every channel of the steady run (input and outputs).
pub fn noise_fits(steady: &Run, notes: &mut Vec<String>) -> BTreeMap<String, NoiseFitReport> {
    let mut out = BTreeMap::new();
    for ch in std::iter::once(&steady.input).chain(&steady.outputs) {
        match fit_all(&ch.values) {
            Ok(r) => {
                out.insert(ch.name.clone(), r);
            }
            Err(e) => notes.push(format!("noise fit of '{}' on '{}': {e}", ch.name, steady.name)),
        }
    }
    out
}

/// The Monte Carlo study of one model: `runs` × 20 s at the steady run's mean input, from a zero
/// initial condition (the input is zero before the run starts), input noise drawn from `noise`.
pub fn monte_carlo_for(
    models: &OutputModels,
    model: &str,
    u0: f64,
    dt_secs: f64,
    noise: &Distribution,
) -> Option<Result<MonteCarloResult, crate::core::monte_carlo::MonteCarloError>> {
    monte_carlo_with_progress(models, model, u0, dt_secs, noise, &mut |_| true)
}

/// [`monte_carlo_for`] reporting progress; `progress` answering `false` stops it.
pub fn monte_carlo_with_progress(
    models: &OutputModels,
    model: &str,
    u0: f64,
    dt_secs: f64,
    noise: &Distribution,
    progress: &mut dyn FnMut(f64) -> bool,
) -> Option<Result<MonteCarloResult, crate::core::monte_carlo::MonteCarloError>> {
    models.simulate(model, &[0.0])?;
    let simulate = |u: &[f64]| -> Vec<f64> {
        let mut with_rest = Vec::with_capacity(u.len() + 1);
        with_rest.push(0.0);
        with_rest.extend_from_slice(u);
        let y = models.simulate(model, &with_rest).unwrap_or_default();
        y.into_iter().skip(1).collect()
    };
    Some(monte_carlo(&MonteCarloConfig::paper(u0, dt_secs), noise, &simulate, progress))
}

/// What report.json carries of one Monte Carlo study (the nominal trace and raw histogram stay out).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MonteCarloSummary {
    pub std_difference: f64,
    pub mean_difference: f64,
    pub runs: usize,
    pub samples_per_run: usize,
    pub normal_fit: Distribution,
}

impl MonteCarloSummary {
    pub fn from_result(r: &MonteCarloResult) -> Self {
        Self {
            std_difference: r.std_difference,
            mean_difference: r.mean_difference,
            runs: r.std_per_run.len(),
            samples_per_run: r.samples_per_run,
            normal_fit: r.normal_fit,
        }
    }
}

/// The Monte Carlo study of every model of one output; a model whose study fails is a note.
pub fn monte_carlo_all(
    models: &OutputModels,
    u0: f64,
    dt_secs: f64,
    noise: &Distribution,
    notes: &mut Vec<String>,
) -> BTreeMap<String, MonteCarloResult> {
    let mut out = BTreeMap::new();
    for name in [GRAY_BOX, LINEAR, HAMMERSTEIN_WIENER, NNARX] {
        match monte_carlo_for(models, name, u0, dt_secs, noise) {
            Some(Ok(r)) => {
                out.insert(name.to_owned(), r);
            }
            Some(Err(e)) => notes.push(format!("Monte Carlo of {name}: {e}")),
            None => {}
        }
    }
    out
}

/// The paper's Monte Carlo standard deviations (section 7): (report model name, shaft speed [rpm],
/// thrust [N]).
pub const PAPER_MONTE_CARLO_STD: [(&str, f64, f64); 3] =
    [(GRAY_BOX, 6.035, 0.0136), (HAMMERSTEIN_WIENER, 14.08, 0.0352), (NNARX, 26.5, 0.1064)];

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
    pub ident: std::sync::Arc<Run>,
    pub fits: std::sync::Arc<SegmentFits>,
    pub wiener: WienerModel,
    /// Runs every model is scored on: validation runs, then chirp runs (`true`).
    pub scored: Vec<(std::sync::Arc<Run>, bool)>,
    /// The steady run for the noise fit and the Monte Carlo study.
    pub steady: Option<std::sync::Arc<Run>>,
    /// The gray-box model with its effects, when it has any: the gray-box model on the runs (the
    /// input-only studies use `wiener`, as the batch does).
    pub extended: Option<crate::core::effects::ExtendedModel>,
    /// Where every model's simulation of a scored run starts (the output's setting).
    pub initial_state: InitialState,
}

/// One model's simulation of one run.
#[derive(Clone, Debug)]
pub struct ModelRun {
    /// Report name: [`GRAY_BOX`], [`LINEAR`], [`HAMMERSTEIN_WIENER`] or [`NNARX`].
    pub model: &'static str,
    pub y_hat: Vec<f64>,
    pub metrics: Result<crate::core::numerics::metrics::Metrics, String>,
}

/// Every model on one scored run.
#[derive(Clone, Debug)]
pub struct RunComparison {
    pub run: std::sync::Arc<Run>,
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
    pub monte_carlo: BTreeMap<String, MonteCarloResult>,
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
            run: std::sync::Arc::clone(run),
            is_chirp: *is_chirp,
            models: models_on_run(&models, run, output),
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
        let names = [GRAY_BOX, LINEAR, HAMMERSTEIN_WIENER, NNARX];
        let share = (1.0 - NNARX_END) / names.len() as f64;
        for (k, name) in names.into_iter().enumerate() {
            let (lo, hi) = (NNARX_END + share * k as f64, NNARX_END + share * (k + 1) as f64);
            let mut part = scaled(progress, lo, hi);
            match monte_carlo_with_progress(&models, name, u0, steady.dt_secs, &noise, &mut part) {
                Some(Ok(r)) => {
                    monte_carlo.insert(name.to_owned(), r);
                }
                Some(Err(crate::core::monte_carlo::MonteCarloError::Cancelled)) => return Err(Cancelled),
                Some(Err(e)) => notes.push(format!("Monte Carlo of {name}: {e}")),
                None => {}
            }
        }
    }
    if !progress(1.0) {
        return Err(Cancelled);
    }
    Ok(OutputComparison { output: output.to_owned(), runs, frequency, noise, monte_carlo, notes })
}

/// Every model simulated on `run` from its input alone, scored against the measured output.
fn models_on_run(models: &OutputModels, run: &Run, output: &str) -> Vec<ModelRun> {
    let Some(y) = run.output(output) else { return Vec::new() };
    models
        .simulate_run(run)
        .into_iter()
        .map(|(model, y_hat)| {
            let metrics =
                crate::core::numerics::metrics::metrics(&y.values, &y_hat).map_err(|e| e.to_string());
            ModelRun { model, y_hat, metrics }
        })
        .collect()
}
