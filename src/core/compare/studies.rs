//! The comparison's studies beyond the time-domain scores: the chirp's frequency response against
//! each model's, the error boxes, the steady run's noise fit and the Monte Carlo propagation.
use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::core::monte_carlo::{MonteCarloConfig, MonteCarloError, MonteCarloResult, monte_carlo};
use crate::core::numerics::metrics::{BoxStats, percentage_error_box};
use crate::core::numerics::noise_fit::{Distribution, NoiseFitReport, fit_all};
use crate::core::numerics::spectral::{EmpiricalResponse, LowFrequencyLevel, WelchOptions, welch_response};
use crate::core::numerics::tf::log_space;
use crate::core::run::Run;

use super::{Curve, ModelKind, OutputModels};

/// A model's frequency response as the chirp shows it: the same Welch estimate applied to the
/// model's simulation of the chirp input as to the measurement, so every model (the network too) is
/// judged at the same operating point by the same estimator.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrequencyComparison {
    pub run: String,
    /// −3 dB cut-off of the measured response and of each model's, rad/s (`None`: not reached in band).
    pub cutoff_rad_s: BTreeMap<Curve, Option<f64>>,
    #[serde(skip)]
    pub responses: BTreeMap<Curve, EmpiricalResponse>,
}

/// Lowest frequency of the chirp's response grid, rad/s: below it a chirp of the paper's band
/// (0.574–13.78 rad/s) holds too few periods for a Welch estimate.
const CHIRP_LOWEST_OMEGA_RAD_S: f64 = 0.3;
/// Points of the chirp's response grid, log-spaced to 0.9 × Nyquist.
const CHIRP_GRID_POINTS: usize = 120;

/// The frequencies the chirp's response is estimated at (those the chirp does not excite are
/// dropped by [`chirp_welch_options`]), rad/s.
pub fn chirp_grid(dt_secs: f64) -> Vec<f64> {
    log_space(CHIRP_LOWEST_OMEGA_RAD_S, 0.9 * std::f64::consts::PI / dt_secs, CHIRP_GRID_POINTS)
}

/// The Welch estimate of a chirp's response: only frequencies whose input power reaches 1 % of the
/// largest (outside the excited band the ratio of two noise spectra says nothing).
pub fn chirp_welch_options() -> WelchOptions {
    WelchOptions { excited_only: Some(0.01), ..WelchOptions::default() }
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
    let omegas = chirp_grid(chirp.dt_secs);
    let opts = chirp_welch_options();
    let mut responses = BTreeMap::new();
    let mut cutoff_rad_s = BTreeMap::new();
    let mut series = vec![(Curve::Measured, y.clone())];
    series.extend(models.simulate_all(u).into_iter().map(|(kind, y)| (Curve::Model(kind), y)));
    for (curve, y_model) in series {
        match welch_response(u, &y_model, chirp.dt_secs, &omegas, &opts) {
            Ok(resp) => {
                let cut = resp.cutoff_rad_s(LowFrequencyLevel::MeanOfFirst(3)).ok().flatten();
                cutoff_rad_s.insert(curve, cut);
                responses.insert(curve, resp);
            }
            Err(e) => notes.push(format!("frequency response of {} on '{}': {e}", curve.name(), chirp.name)),
        }
    }
    Some(FrequencyComparison { run: chirp.name.clone(), cutoff_rad_s, responses })
}

/// Box-plot statistics of the percentage error of every model on every scored run.
pub fn error_boxes(
    models: &OutputModels,
    runs: &[&Run],
    output: &str,
) -> BTreeMap<ModelKind, BTreeMap<String, BoxStats>> {
    let mut out: BTreeMap<ModelKind, BTreeMap<String, BoxStats>> = BTreeMap::new();
    for run in runs {
        let Some(y) = run.output(output) else { continue };
        for (name, y_hat) in models.simulate_run(run) {
            if let Ok(b) = percentage_error_box(&y.values, &y_hat) {
                out.entry(name).or_default().insert(run.name.clone(), b);
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
    model: ModelKind,
    u0: f64,
    dt_secs: f64,
    noise: &Distribution,
) -> Option<Result<MonteCarloResult, MonteCarloError>> {
    monte_carlo_with_progress(models, model, u0, dt_secs, noise, &mut |_| true)
}

/// [`monte_carlo_for`] reporting progress; `progress` answering `false` stops it.
pub fn monte_carlo_with_progress(
    models: &OutputModels,
    model: ModelKind,
    u0: f64,
    dt_secs: f64,
    noise: &Distribution,
    progress: &mut dyn FnMut(f64) -> bool,
) -> Option<Result<MonteCarloResult, MonteCarloError>> {
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
) -> BTreeMap<ModelKind, MonteCarloResult> {
    let mut out = BTreeMap::new();
    for kind in ModelKind::MONTE_CARLO {
        match monte_carlo_for(models, kind, u0, dt_secs, noise) {
            Some(Ok(r)) => {
                out.insert(kind, r);
            }
            Some(Err(e)) => notes.push(format!("Monte Carlo of {kind}: {e}")),
            None => {}
        }
    }
    out
}
