//! The fleet from Python: the whole of `jetid fleet` in one call, and its three steps as functions
//! a distributed engine calls as tasks — an engine's reference ([`fleet_reference`], one task per
//! engine), one run scored against it ([`fleet_score`], one task per run) and the table gathered
//! from the scores ([`fleet_rows`]: each engine's bands across its runs, then the rows and flags).
//! References and scores cross between tasks as JSON, which round-trips every number exactly, so
//! the gathered table is `jetid fleet`'s row for row.
use std::collections::HashMap;
use std::path::PathBuf;

use anyhow::{Context, anyhow};
use pyo3::prelude::*;
use serde::{Deserialize, Serialize};

use jetid::fleet::diagnosis::diagnose_screened;
use jetid::fleet::manifest::{Engine, Manifest, load_manifest};
use jetid::fleet::reference::Reference;
use jetid::fleet::score::{RunScore, score_run};
use jetid::fleet::table::{Row, columns};
use jetid::fleet::{EngineResult, evaluate, rows_of};
use jetid::io::model_file::ModelFile;

use super::raise;

/// An engine's reference as it crosses between tasks: its model file and how it is described.
#[derive(Serialize, Deserialize)]
struct ReferenceJson {
    model: ModelFile,
    described: String,
}

/// The table as it crosses to Python: fleet.csv's columns and its rows (text, numbers, or null for
/// an empty cell).
fn table_json(rows: &[Row]) -> String {
    let records: Vec<Vec<serde_json::Value>> = rows
        .iter()
        .map(|row| {
            let mut cells: Vec<serde_json::Value> = vec![
                row.engine.clone().into(),
                row.run.clone().into(),
                row.date.clone().map_or(serde_json::Value::Null, Into::into),
                row.output.clone().into(),
            ];
            cells.extend(row.numbers().into_iter().map(|c| c.map_or(serde_json::Value::Null, Into::into)));
            cells.extend([row.diagnosed.into(), row.effects.clone().into(), row.flag.clone().into()]);
            cells
        })
        .collect();
    serde_json::json!({ "columns": columns(), "rows": records }).to_string()
}

fn engine<'a>(manifest: &'a Manifest, name: &str) -> anyhow::Result<&'a Engine> {
    manifest.engines.iter().find(|e| e.name == name).ok_or_else(|| {
        let names: Vec<&str> = manifest.engines.iter().map(|e| e.name.as_str()).collect();
        anyhow!("the manifest has no engine '{name}' (its engines: {})", names.join(", "))
    })
}

/// Every engine of the manifest and its runs' names, in the manifest's (trend) order, as JSON.
#[pyfunction]
fn fleet_engines(manifest: PathBuf) -> PyResult<String> {
    let manifest = load_manifest(&manifest).map_err(raise)?;
    let engines: Vec<serde_json::Value> = manifest
        .engines
        .iter()
        .map(|e| {
            let runs: Vec<&str> = e.runs.iter().map(|r| r.name.as_str()).collect();
            serde_json::json!({ "engine": e.name, "runs": runs })
        })
        .collect();
    Ok(serde_json::json!({ "name": manifest.name, "engines": engines }).to_string())
}

/// `jetid fleet MANIFEST` as a table (JSON); with `out`, its files are written there too, as the
/// command line writes them.
#[pyfunction]
#[pyo3(signature = (manifest, out=None))]
fn fleet(py: Python<'_>, manifest: PathBuf, out: Option<PathBuf>) -> PyResult<String> {
    py.detach(|| -> anyhow::Result<String> {
        if let Some(out) = out {
            return Ok(table_json(&jetid::fleet::run(&manifest, &out)?.rows));
        }
        let manifest = load_manifest(&manifest)?;
        let results = evaluate(&manifest, &mut |_| true)?.ok_or_else(|| anyhow!("the fleet was stopped"))?;
        let rows: Vec<Row> = results.iter().flat_map(rows_of).collect();
        Ok(table_json(&rows))
    })
    .map_err(raise)
}

/// The reference of engine `engine` (read, or identified from its project), as JSON for the tasks
/// that score its runs.
#[pyfunction]
fn fleet_reference(py: Python<'_>, manifest: PathBuf, engine: &str) -> PyResult<String> {
    py.detach(|| -> anyhow::Result<String> {
        let manifest = load_manifest(&manifest)?;
        let engine = self::engine(&manifest, engine)?;
        let (model, described) = Reference::model_file(&engine.reference)
            .with_context(|| format!("the reference of engine '{}'", engine.name))?;
        Ok(serde_json::to_string(&ReferenceJson { model, described })?)
    })
    .map_err(raise)
}

fn reference_of(json: &str) -> anyhow::Result<Reference> {
    let parsed: ReferenceJson =
        serde_json::from_str(json).context("an engine's reference (from jetid.fleet_reference)")?;
    Reference::of_model_file(&parsed.model, parsed.described)
}

/// Run `run` of engine `engine` scored against `reference` (from [`fleet_reference`]), as JSON.
#[pyfunction]
fn fleet_score(
    py: Python<'_>,
    manifest: PathBuf,
    engine: &str,
    run: &str,
    reference: &str,
) -> PyResult<String> {
    py.detach(|| -> anyhow::Result<String> {
        let manifest = load_manifest(&manifest)?;
        let engine = self::engine(&manifest, engine)?;
        let fleet_run = engine
            .runs
            .iter()
            .find(|r| r.name == run)
            .ok_or_else(|| anyhow!("engine '{}' has no run '{run}'", engine.name))?;
        let reference = reference_of(reference)?;
        let score = score_run(fleet_run, &reference)
            .with_context(|| format!("engine '{}', run '{}'", engine.name, fleet_run.name))?;
        Ok(serde_json::to_string(&score)?)
    })
    .map_err(raise)
}

/// The table gathered from every engine's reference and every run's score (each `(engine, run,
/// score)`), as `jetid fleet` makes it: each engine's bands across its runs in the manifest's
/// order, then the rows and flags. Every run of the manifest must have its score.
#[pyfunction]
fn fleet_rows(
    py: Python<'_>,
    manifest: PathBuf,
    references: Vec<(String, String)>,
    scores: Vec<(String, String, String)>,
) -> PyResult<String> {
    py.detach(|| -> anyhow::Result<String> {
        let manifest = load_manifest(&manifest)?;
        let references: HashMap<String, String> = references.into_iter().collect();
        let mut scores: HashMap<(String, String), String> =
            scores.into_iter().map(|(e, r, s)| ((e, r), s)).collect();
        let mut rows = Vec::new();
        for engine in &manifest.engines {
            let reference = references
                .get(&engine.name)
                .ok_or_else(|| anyhow!("no reference was given for engine '{}'", engine.name))?;
            let mut engine_scores = Vec::with_capacity(engine.runs.len());
            for run in &engine.runs {
                let json = scores.remove(&(engine.name.clone(), run.name.clone())).ok_or_else(|| {
                    anyhow!("no score was given for engine '{}', run '{}'", engine.name, run.name)
                })?;
                let score: RunScore = serde_json::from_str(&json)
                    .with_context(|| format!("the score of engine '{}', run '{}'", engine.name, run.name))?;
                engine_scores.push(score);
            }
            let mut result = EngineResult::of(engine, reference_of(reference)?, engine_scores);
            diagnose_screened(std::slice::from_mut(&mut result), &mut |_| true)?;
            rows.extend(rows_of(&result));
        }
        if let Some((engine, run)) = scores.keys().next() {
            anyhow::bail!(
                "a score was given for engine '{engine}', run '{run}', which the manifest does not list"
            );
        }
        Ok(table_json(&rows))
    })
    .map_err(raise)
}

pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    for f in [
        wrap_pyfunction!(fleet_engines, m)?,
        wrap_pyfunction!(fleet, m)?,
        wrap_pyfunction!(fleet_reference, m)?,
        wrap_pyfunction!(fleet_score, m)?,
        wrap_pyfunction!(fleet_rows, m)?,
    ] {
        m.add_function(f)?;
    }
    Ok(())
}
