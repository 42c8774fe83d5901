//! The paper's comparison (sections 5.3–7) for `jetid --batch`: the Hammerstein–Wiener and NNARX
//! baselines fitted on the identification run, every model simulated from the input alone on each
//! scored run, the chirp's frequency response against each model's, the steady run's noise fit and
//! the Monte Carlo error propagation. No egui.
use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::core::baselines::hammerstein_wiener::{HwModel, HwOptions, HwOrders, fit_hammerstein_wiener};
use crate::core::baselines::nnarx::{NnarxModel, NnarxOptions, fit_nnarx};
use crate::core::metrics::{BoxStats, percentage_error_box};
use crate::core::monte_carlo::{MonteCarloConfig, MonteCarloResult, monte_carlo};
use crate::core::noise_fit::{Distribution, NoiseFitReport, fit_all};
use crate::core::pipeline::Identified;
use crate::core::run::Run;
use crate::core::spectral::{EmpiricalResponse, LowFrequencyLevel, WelchOptions, welch_response};
use crate::core::tf::log_space;
use crate::core::wiener::WienerModel;

/// Model names as report.json spells them (CONTRACT.md).
pub const GRAY_BOX: &str = "gray_box";
pub const LINEAR: &str = "linear";
pub const HAMMERSTEIN_WIENER: &str = "hammerstein_wiener";
pub const NNARX: &str = "nnarx";

/// Every model of one output that can be simulated from an input sequence.
pub struct OutputModels {
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

    /// Every model on a run: like [`Self::simulate_all`] on its input, with the gray-box model's
    /// effects applied (a gray-box simulation that fails, e.g. for a missing channel, is left out).
    pub fn simulate_run(&self, run: &Run) -> Vec<(&'static str, Vec<f64>)> {
        let mut all = self.simulate_all(&run.input.values);
        if let Some(ext) = &self.extended {
            match ext.simulate(run) {
                Ok(y) => {
                    if let Some(g) = all.iter_mut().find(|(n, _)| *n == GRAY_BOX) {
                        g.1 = y;
                    }
                }
                Err(_) => all.retain(|(n, _)| *n != GRAY_BOX),
            }
        }
        all
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
    let fits = &identified.fits;
    let start = fits.segments.first().map_or(0, |s| s.start);
    let end = fits.segments.last().map_or(ident.len(), |s| s.end);
    let u = ident.input.values.get(start..end).unwrap_or(&[]);
    let y = ident.output(output).and_then(|c| c.values.get(start..end)).unwrap_or(&[]);
    let tf = &identified.model.wiener.linear.tf;
    let orders = HwOrders {
        input_poly: 2,
        n_poles: tf.den_zinv.len().saturating_sub(1).max(1),
        n_zeros: tf.zeros().map_or(0, |z| z.len()),
        output_poly: 2,
    };
    let hw = fit_hammerstein_wiener(u, y, ident.dt_secs, orders, &HwOptions::default(), &mut |_| true)
        .map_err(|e| notes.push(format!("Hammerstein–Wiener baseline for '{output}': {e}")))
        .ok();
    let nnarx = fit_nnarx(u, y, &NnarxOptions::default(), &mut |_| true)
        .map_err(|e| notes.push(format!("NNARX baseline for '{output}': {e}")))
        .ok();
    OutputModels { wiener: identified.model.wiener.clone(), extended: None, hw, nnarx }
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
    models.simulate(model, &[0.0])?;
    let simulate = |u: &[f64]| -> Vec<f64> {
        let mut with_rest = Vec::with_capacity(u.len() + 1);
        with_rest.push(0.0);
        with_rest.extend_from_slice(u);
        let y = models.simulate(model, &with_rest).unwrap_or_default();
        y.into_iter().skip(1).collect()
    };
    Some(monte_carlo(&MonteCarloConfig::paper(u0, dt_secs), noise, &simulate, &mut |_| true))
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
