//! A fleet for the History view: every engine's reference loaded (or identified), every run scored
//! against it and judged against the engine's normal band, as `jetid fleet` does, but kept in memory
//! instead of written to files; and one run against its reference, for the view's comparison plot.
//!
//! The fleet is evaluated by the fleet's own `evaluate`, which `jetid fleet` calls too; the reasons
//! of a run are those `jetid fleet` writes in its rows' flag column. Nothing here touches the
//! session.
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use crate::core::identification::initial_state::InitialState;
use crate::core::numerics::metrics::metrics;
use crate::fleet::flags::EngineBands;
use crate::fleet::manifest::{FleetRun, load_manifest};
use crate::fleet::reference::Reference;
use crate::fleet::score::{RunScore, read_run};
use crate::ui::derived::jobs::{JobError, JobResult};

/// A fleet manifest and every engine's results.
pub struct FleetHistory {
    pub name: String,
    pub path: PathBuf,
    pub engines: Vec<EngineHistory>,
}

/// One engine: its reference, its runs in trend order (by date where every run has one), its bands
/// (each run's, from the engine's trend).
pub struct EngineHistory {
    pub name: String,
    pub reference: Reference,
    pub runs: Vec<RunHistory>,
    pub bands: EngineBands,
}

/// One run, scored, with the reasons it is flagged (none: inside the engine's normal band).
pub struct RunHistory {
    pub run: FleetRun,
    pub score: RunScore,
    pub reasons: Vec<String>,
}

impl RunHistory {
    pub fn flagged(&self) -> bool {
        !self.reasons.is_empty()
    }

    /// The run's date, else "—".
    pub fn date_text(&self) -> String {
        self.run.date.map_or_else(|| "—".to_owned(), |d| d.to_string())
    }
}

impl EngineHistory {
    pub fn flagged_runs(&self) -> usize {
        self.runs.iter().filter(|r| r.flagged()).count()
    }

    /// The reference's outputs with their units, in the reference's order.
    pub fn outputs(&self) -> Vec<(String, String)> {
        let units = self.reference.units.iter().cloned().chain(std::iter::repeat(String::new()));
        self.reference.models.iter().map(|m| m.output.clone()).zip(units).collect()
    }
}

/// Read the manifest at `path` and evaluate it as `jetid fleet` does ([`crate::fleet::evaluate`]);
/// `progress` gets the fraction done and stops the work when it says `false`.
pub fn compute_fleet(path: &Path, progress: &mut dyn FnMut(f64) -> bool) -> JobResult<FleetHistory> {
    let failed = |err: anyhow::Error| JobError::Failed(format!("{err:#}"));
    let manifest = load_manifest(path).map_err(failed)?;
    let results = crate::fleet::evaluate(&manifest, progress).map_err(failed)?.ok_or(JobError::Cancelled)?;
    let engines = results
        .into_iter()
        .map(|result| {
            let runs = (result.engine.runs.iter().cloned().zip(result.scores).enumerate())
                .map(|(index, (run, score))| {
                    let reasons = result.bands.all_reasons(index, &score);
                    RunHistory { run, score, reasons }
                })
                .collect();
            EngineHistory {
                name: result.engine.name.clone(),
                reference: result.reference,
                runs,
                bands: result.bands,
            }
        })
        .collect();
    Ok(FleetHistory { name: manifest.name.clone(), path: path.to_owned(), engines })
}

/// One output of a run against its reference.
pub struct OutputTrace {
    pub output: String,
    pub unit: String,
    pub measured: Vec<f64>,
    pub predicted: Vec<f64>,
    pub rmse: f64,
}

/// A run's measured outputs and the reference's prediction on its input.
pub struct RunComparison {
    pub run: String,
    pub t_secs: Vec<f64>,
    pub outputs: Vec<OutputTrace>,
}

/// Read `run` and simulate `reference` on it, each output from the initial state the fleet scores
/// it from (fitted to the run's first seconds), so the plot shows the error the table gives.
pub fn compare_run(run: &FleetRun, reference: &Reference) -> Result<RunComparison> {
    let data = read_run(run, reference, &mut Vec::new())?;
    let mut outputs = Vec::new();
    for (i, model) in reference.models.iter().enumerate() {
        let Some(measured) = data.output(&model.output) else { continue };
        let predicted = model
            .simulate_scored(&data, InitialState::Estimated)
            .with_context(|| format!("simulating '{}' on run '{}'", model.output, run.name))?;
        let rmse = metrics(&measured.values, &predicted).map(|m| m.rmse).unwrap_or(f64::NAN);
        outputs.push(OutputTrace {
            output: model.output.clone(),
            unit: reference.units.get(i).cloned().unwrap_or_default(),
            measured: measured.values.clone(),
            predicted,
            rmse,
        });
    }
    if outputs.is_empty() {
        anyhow::bail!("run '{}' holds none of the reference's outputs", run.name);
    }
    let t0 = data.t_secs.first().copied().unwrap_or(0.0);
    Ok(RunComparison { run: run.name.clone(), t_secs: data.t_secs.iter().map(|t| t - t0).collect(), outputs })
}
