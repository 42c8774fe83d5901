//! `jetid fleet MANIFEST --out DIR`: every run of every engine against its engine's reference model
//! ([`reference`]): scored per output, its health deltas fitted with their intervals
//! (`core::health`), each delta and the error judged against the engine's normal band across its
//! runs, and the runs outside it flagged in physical words ([`flags`]); the runs the bands screen
//! are diagnosed against the reference, and an effect found is a reason of the flag
//! ([`diagnosis`]). The results — fleet.csv,
//! fleet.parquet ([`table`]), report.md and one trend figure per engine — are written into a
//! staging folder and moved into DIR only when every run was scored (`io::staging`).
//!
//! At the workflow's level: it reads files (`io`) and identifies a reference project with the
//! workflow's steps; the runs are scored on two threads, the output in manifest order.
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use crate::core::health::Estimate;
use crate::core::parallel::on_two_threads;
use crate::io::figures::{TrendPanel, TrendPoint, trend_png};
use crate::io::staging::Staging;

pub mod diagnosis;
pub mod finding;
pub mod flags;
pub mod manifest;
pub mod reference;
mod report;
pub mod score;
pub mod table;

use flags::EngineBands;
use manifest::{Engine, Manifest, load_manifest};
use reference::Reference;
use score::{RunScore, score_run};
use table::Row;

/// What a fleet run wrote, for the summary line and the tests.
#[derive(Clone, Debug)]
pub struct FleetSummary {
    pub engines: usize,
    pub runs: usize,
    /// (engine, run, reasons) of every flagged run.
    pub flagged: Vec<(String, String, String)>,
    pub out_dir: PathBuf,
    /// The table's rows, as fleet.csv holds them.
    pub rows: Vec<Row>,
}

/// One engine's results: its reference, its runs scored (in the manifest's trend order) and the
/// bands each run is judged against.
pub struct EngineResult<'a> {
    pub engine: &'a Engine,
    pub reference: Reference,
    pub scores: Vec<RunScore>,
    pub bands: EngineBands,
}

/// Runs scored between two reports of the fraction done: enough to keep both threads busy, few
/// enough that progress moves and a stop is heard within a second or two.
const RUNS_PER_REPORT: usize = 32;

/// The share of the progress bar the scoring takes; the diagnosis of the screened runs takes the
/// rest. Only the bar's pace: a fleet's screened runs are a few per cent of its runs, and each
/// diagnosis costs about as many scorings as there are per cent, so the two are of one order.
const SCORING_SHARE: f64 = 0.5;

/// Every engine of `manifest` against its reference: the references loaded (or identified) and the
/// runs scored on two threads, then each engine's bands, then the screened runs diagnosed
/// (`diagnosis`). `progress` hears the fraction done (the references and the runs count alike in
/// the scoring's share) and stops the work when it answers `false`: `Ok(None)`. `jetid fleet` and
/// the app's History view both evaluate a fleet here.
pub fn evaluate<'a>(
    manifest: &'a Manifest,
    progress: &mut dyn FnMut(f64) -> bool,
) -> Result<Option<Vec<EngineResult<'a>>>> {
    let jobs: Vec<(usize, usize)> = manifest
        .engines
        .iter()
        .enumerate()
        .flat_map(|(e, engine)| (0..engine.runs.len()).map(move |r| (e, r)))
        .collect();
    let steps = (manifest.engines.len() + jobs.len()).max(1) as f64 / SCORING_SHARE;
    let references = on_two_threads(&manifest.engines, |engine| {
        Reference::load(&engine.reference)
            .with_context(|| format!("the reference of engine '{}'", engine.name))
    });
    let references = references.into_iter().collect::<Result<Vec<_>>>()?;
    let mut done = manifest.engines.len();
    if !progress(done as f64 / steps) {
        return Ok(None);
    }
    let mut scored = Vec::with_capacity(jobs.len());
    for chunk in jobs.chunks(RUNS_PER_REPORT) {
        scored.extend(on_two_threads(chunk, |&(e, r)| {
            let (engine, reference) = (&manifest.engines[e], &references[e]);
            score_run(&engine.runs[r], reference)
                .with_context(|| format!("engine '{}', run '{}'", engine.name, engine.runs[r].name))
        }));
        done += chunk.len();
        if !progress(done as f64 / steps) {
            return Ok(None);
        }
    }
    let mut scored = scored.into_iter();
    let mut results = Vec::with_capacity(manifest.engines.len());
    for (engine, reference) in manifest.engines.iter().zip(references) {
        let scores = scored.by_ref().take(engine.runs.len()).collect::<Result<Vec<_>>>()?;
        results.push(EngineResult::of(engine, reference, scores));
    }
    let mut diagnosing = |f: f64| progress(SCORING_SHARE + (1.0 - SCORING_SHARE) * f);
    if !diagnosis::diagnose_screened(&mut results, &mut diagnosing)? {
        return Ok(None);
    }
    Ok(Some(results))
}

impl<'a> EngineResult<'a> {
    /// An engine's result from its reference and its runs' scores (in the manifest's order): the
    /// bands judged across them. [`evaluate`] gathers every engine's here, and so does a distributed
    /// engine that scored the runs one task each.
    pub fn of(engine: &'a Engine, reference: Reference, scores: Vec<RunScore>) -> Self {
        let outputs: Vec<String> = reference.models.iter().map(|m| m.output.clone()).collect();
        let bands = EngineBands::of(&scores.iter().collect::<Vec<_>>(), &outputs);
        Self { engine, reference, scores, bands }
    }
}

/// Run the fleet of the manifest at `manifest_path` and write the results into `out_dir`.
pub fn run(manifest_path: &Path, out_dir: &Path) -> Result<FleetSummary> {
    crate::io::staging::stop_on_interrupt();
    let manifest = load_manifest(manifest_path)?;
    let Some(results) = evaluate(&manifest, &mut progress_line())? else {
        anyhow::bail!("the fleet was stopped");
    };
    let runs = results.iter().map(|r| r.scores.len()).sum::<usize>();
    let staging = Staging::new(out_dir)?;
    let mut rows = Vec::new();
    let mut written = vec!["fleet.csv".to_owned(), "fleet.parquet".to_owned(), "report.md".to_owned()];
    let mut figures = Vec::new();
    for (i, result) in results.iter().enumerate() {
        let engine_rows = rows_of(result);
        let figure = format!("trend_{}.png", file_safe(&result.engine.name, i));
        let labels: Vec<String> = result.engine.runs.iter().map(|r| r.name.clone()).collect();
        let title = format!("Health of engine {}", result.engine.name);
        trend_png(
            &staging.path().join(&figure),
            &title,
            "run (in date order)",
            &labels,
            &panels(result, &engine_rows),
        )?;
        written.push(figure.clone());
        figures.push(figure);
        rows.extend(engine_rows);
    }
    table::write_csv(&staging.path().join("fleet.csv"), &rows)?;
    table::write_parquet(&staging.path().join("fleet.parquet"), &rows)?;
    let markdown = report::markdown(&manifest.name, &results, &rows, &figures);
    crate::io::atomic::write_atomic(&staging.path().join("report.md"), markdown.as_bytes())?;
    staging.commit(&written)?;
    let mut flagged: Vec<(String, String, String)> = Vec::new();
    for row in rows.iter().filter(|r| !r.flag.is_empty()) {
        if !flagged.iter().any(|(e, r, _)| *e == row.engine && *r == row.run) {
            flagged.push((row.engine.clone(), row.run.clone(), row.flag.clone()));
        }
    }
    Ok(FleetSummary { engines: results.len(), runs, flagged, out_dir: out_dir.to_owned(), rows })
}

/// The fraction done on stderr: rewritten in place on a terminal, a line every tenth in a log.
fn progress_line() -> impl FnMut(f64) -> bool {
    use std::io::{IsTerminal, Write};
    let (started, terminal) = (std::time::Instant::now(), std::io::stderr().is_terminal());
    let mut said = -1.0_f64;
    move |fraction| {
        let secs = started.elapsed().as_secs_f64();
        if terminal {
            eprint!("\r\x1b[2K[{secs:6.1} s] scoring the fleet: {:.0} %", 100.0 * fraction);
            if fraction >= 1.0 {
                eprintln!();
            }
        } else if fraction - said >= 0.1 || fraction >= 1.0 && said < 1.0 {
            said = fraction;
            eprintln!("jetid: [{secs:6.1} s] scoring the fleet: {:.0} %", 100.0 * fraction);
        }
        let _ = std::io::stderr().flush();
        true
    }
}

/// An engine's name as a file name: letters, digits, '-' and '_' kept, the rest '_' (the index
/// keeps two engines whose names differ only in other characters apart).
fn file_safe(name: &str, index: usize) -> String {
    let safe: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' })
        .collect();
    format!("{:02}_{safe}", index + 1)
}

/// The rows of one engine in fleet.csv: its runs in trend order, each output of each.
pub fn rows_of(result: &EngineResult<'_>) -> Vec<Row> {
    let mut rows = Vec::new();
    for (index, (run, score)) in result.engine.runs.iter().zip(&result.scores).enumerate() {
        let (shared, own) = result.bands.reasons(index, score);
        for o in &score.outputs {
            let mut reasons = shared.clone();
            reasons.extend(
                own.iter().filter(|(name, _)| *name == o.output).flat_map(|(_, r)| r.iter().cloned()),
            );
            let pct = |x: f64| 100.0 * x / o.range.max(f64::MIN_POSITIVE);
            rows.push(Row {
                engine: result.engine.name.clone(),
                run: run.name.clone(),
                date: run.date.map(|d| d.to_string()),
                output: o.output.clone(),
                rmse: o.rmse,
                rmspe_pct: o.rmspe_pct,
                input_gain: score.input_gain,
                input_offset: None,
                tau_scale: score.tau_scale,
                map_shift: o.map_shift,
                map_shift_pct: o
                    .map_shift
                    .map(|e| Estimate { value: pct(e.value), ci95: e.ci95.map(|[a, b]| [pct(a), pct(b)]) }),
                diagnosed: score.diagnosis.as_ref().is_some_and(|d| d.diagnosed.contains(&o.output)),
                effects: score
                    .diagnosis
                    .iter()
                    .flat_map(|d| &d.findings)
                    .filter(|f| f.output == o.output)
                    .map(|f| f.effect.name())
                    .collect::<Vec<_>>()
                    .join("; "),
                flag: reasons.join("; "),
            });
        }
    }
    rows
}

/// The trend figure's panels: the input gain, the time-constant scale and each output's map shift,
/// each run with the band it was judged against.
fn panels(result: &EngineResult<'_>, rows: &[Row]) -> Vec<TrendPanel> {
    let flagged = |run: &str| rows.iter().any(|r| r.run == run && !r.flag.is_empty());
    let runs = &result.engine.runs;
    let panel =
        |label: String, estimates: Vec<Option<Estimate>>, bands: &[Option<crate::core::health::Band>]| {
            let points = estimates
                .iter()
                .enumerate()
                .filter_map(|(i, e)| {
                    let e = (*e)?;
                    let band = bands.get(i).copied().flatten().map(|b| {
                        let [low, high] = b.limits_for(e.ci95);
                        [low, b.centre, high]
                    });
                    Some(TrendPoint {
                        x: i as f64,
                        value: e.value,
                        ci95: e.ci95,
                        band,
                        flagged: flagged(&runs[i].name),
                    })
                })
                .collect();
            TrendPanel { label, points }
        };
    let bands = &result.bands;
    let mut out = vec![
        panel("input gain".into(), result.scores.iter().map(|s| s.input_gain).collect(), &bands.input_gain),
        panel(
            "time-constant scale".into(),
            result.scores.iter().map(|s| s.tau_scale).collect(),
            &bands.tau_scale,
        ),
    ];
    for ((model, unit), (_, shift_bands)) in
        result.reference.models.iter().zip(&result.reference.units).zip(&bands.map_shift)
    {
        let output = &model.output;
        let estimates = result
            .scores
            .iter()
            .map(|s| s.outputs.iter().find(|o| o.output == *output).and_then(|o| o.map_shift))
            .collect();
        let label = if unit.is_empty() {
            format!("{output} map shift")
        } else {
            format!("{output} map shift ({unit})")
        };
        out.push(panel(label, estimates, shift_bands));
    }
    out
}
