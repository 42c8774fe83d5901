//! Stage 4 of the batch: every model of one output scored on the scored runs, beside the baselines,
//! with the chirp's frequency responses and the Monte Carlo study (`core::compare`).
use std::collections::BTreeMap;

use crate::core::compare::{
    FrequencyComparison, ModelKind, MonteCarloSummary, OutputModels, error_boxes, failure_reasons,
    frequency_comparison, monte_carlo_all,
};
use crate::core::identification::pipeline;
use crate::core::monte_carlo::MonteCarloResult;
use crate::core::numerics::noise_fit::Distribution;
use crate::core::run::Run;
use crate::io::report::OutputReport;

use super::Timings;
use crate::workflow::runs::Runs;

/// Every model simulated on every scored run that records `output`, into `report.models`; why a
/// failing one fails, into `report.failure_reasons`.
pub fn score_output(
    models: &OutputModels,
    runs: &Runs,
    output: &str,
    report: &mut OutputReport,
    notes: &mut Vec<String>,
) {
    let u = &runs.ident.input.values;
    let ident_input = crate::core::control::identified_range(u);
    for run in runs.scored() {
        if run.output(output).is_none() {
            notes.push(format!("run '{}' has no '{output}' column; not scored for it", run.name));
            continue;
        }
        for (kind, y_hat) in models.simulate_run(run) {
            match pipeline::score(run, output, y_hat) {
                Ok(p) => {
                    if p.metrics.fails()
                        && let Some(y) = run.output(output)
                    {
                        let why = failure_reasons(&y.values, &p.y_hat, &run.input.values, ident_input);
                        report
                            .failure_reasons
                            .entry(kind)
                            .or_default()
                            .insert(run.name.clone(), why.join("; "));
                    }
                    report.models.entry(kind).or_default().insert(run.name.clone(), p.metrics);
                }
                Err(e) => notes.push(format!("{kind} on '{}': {e}", run.name)),
            }
        }
    }
}

/// The studies beside the scores: error boxes and, when the runs allow, the chirp's frequency
/// responses and the Monte Carlo study of every model.
pub struct Studies {
    pub frequency: Option<FrequencyComparison>,
    pub monte_carlo: BTreeMap<ModelKind, MonteCarloResult>,
}

/// Score every model, then run the studies the runs allow; `input_noise` is the steady run's fitted
/// input noise (no Monte Carlo study without it).
pub fn compare(
    models: &OutputModels,
    runs: &Runs,
    output: &str,
    input_noise: Option<&Distribution>,
    report: &mut OutputReport,
    notes: &mut Vec<String>,
    timings: &mut Timings,
) -> Studies {
    timings.time("validate", || score_output(models, runs, output, report, notes));
    report.error_boxes = error_boxes(models, &runs.scored(), output);
    let frequency = timings.time("frequency", || {
        runs.chirp.as_ref().and_then(|chirp| frequency_comparison(models, chirp, output, notes))
    });
    report.cutoff_rad_s = frequency.as_ref().map(|f| f.cutoff_rad_s.clone()).unwrap_or_default();
    let monte_carlo = match (&runs.steady, input_noise) {
        (Some(steady), Some(noise)) => timings.time("monte_carlo", || {
            monte_carlo_all(models, mean_input(steady), steady.dt_secs, noise, notes)
        }),
        _ => BTreeMap::new(),
    };
    Studies { frequency, monte_carlo }
}

/// The steady run's mean input: the operating point of the Monte Carlo study.
fn mean_input(steady: &Run) -> f64 {
    crate::core::numerics::stats::mean(&steady.input.values)
}

/// What report.json carries of the Monte Carlo studies of one output.
pub fn monte_carlo_summaries(
    results: &BTreeMap<ModelKind, MonteCarloResult>,
) -> BTreeMap<ModelKind, MonteCarloSummary> {
    results.iter().map(|(k, r)| (*k, MonteCarloSummary::from_result(r))).collect()
}
