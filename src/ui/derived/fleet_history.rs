//! A fleet for the History view: every engine's reference loaded (or identified), every run scored
//! against it and judged against the engine's normal band, as `jetid fleet` does, but kept in memory
//! instead of written to files; and one run against its reference, for the view's comparison plot.
//!
//! Composed from the fleet's public pieces (`load_manifest`, `Reference::load`, `score_run`,
//! `EngineBands`); the reasons of a run are those `jetid fleet` writes in its rows' flag column.
//! Nothing here touches the session.
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use crate::core::identification::initial_state::InitialState;
use crate::core::numerics::metrics::metrics;
use crate::fleet::flags::EngineBands;
use crate::fleet::manifest::{FleetRun, load_manifest};
use crate::fleet::reference::Reference;
use crate::fleet::score::{RunScore, score_run};
use crate::ui::derived::jobs::{JobError, JobResult};
use crate::workflow::runs::load_source;

/// Relative difference of sample times below which a run is on the reference's grid.
const DT_TOLERANCE: f64 = 1e-6;

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

/// Read the manifest at `path`, load every engine's reference and score every run; `progress`
/// gets the fraction done (references and runs count alike) and stops the work when it says `false`.
pub fn compute_fleet(path: &Path, progress: &mut dyn FnMut(f64) -> bool) -> JobResult<FleetHistory> {
    let failed = |err: anyhow::Error| JobError::Failed(format!("{err:#}"));
    let manifest = load_manifest(path).map_err(failed)?;
    let steps = manifest.engines.iter().map(|e| 1 + e.runs.len()).sum::<usize>().max(1);
    let mut done = 0usize;
    let mut step = |done: &mut usize| {
        *done += 1;
        if progress(*done as f64 / steps as f64) { Ok(()) } else { Err(JobError::Cancelled) }
    };
    let mut engines = Vec::with_capacity(manifest.engines.len());
    for engine in manifest.engines {
        let reference = Reference::load(&engine.reference)
            .with_context(|| format!("the reference of engine '{}'", engine.name))
            .map_err(failed)?;
        step(&mut done)?;
        let mut scores = Vec::with_capacity(engine.runs.len());
        for run in &engine.runs {
            let score = score_run(run, &reference)
                .with_context(|| format!("engine '{}', run '{}'", engine.name, run.name))
                .map_err(failed)?;
            scores.push(score);
            step(&mut done)?;
        }
        let outputs: Vec<String> = reference.models.iter().map(|m| m.output.clone()).collect();
        let bands = EngineBands::of(&scores.iter().collect::<Vec<_>>(), &outputs);
        let runs = engine
            .runs
            .into_iter()
            .zip(scores)
            .enumerate()
            .map(|(index, (run, score))| {
                let reasons = reasons_of(&bands, index, &score);
                RunHistory { run, score, reasons }
            })
            .collect();
        engines.push(EngineHistory { name: engine.name, reference, runs, bands });
    }
    Ok(FleetHistory { name: manifest.name, path: path.to_owned(), engines })
}

/// The reasons of every output's flag, each once: the shared ones first, then each output's own.
fn reasons_of(bands: &EngineBands, index: usize, score: &RunScore) -> Vec<String> {
    let (mut reasons, own) = bands.reasons(index, score);
    for reason in own.into_iter().flat_map(|(_, r)| r) {
        if !reasons.contains(&reason) {
            reasons.push(reason);
        }
    }
    reasons
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
    let mut notes = Vec::new();
    let mut data = load_source(&run.source, &mut notes)?;
    data.name = run.name.clone();
    if (data.dt_secs / reference.dt_secs - 1.0).abs() > DT_TOLERANCE {
        data = data.resampled(reference.dt_secs);
    }
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
