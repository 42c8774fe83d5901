//! `jetid --batch`: project → runs → gray-box model of each output → model.json, report.json,
//! report.md and figures. No egui. One module per stage, in the order the data flows:
//! [`load`] → [`identify`] → [`effects`] → [`diagnose`] → [`compare`] → [`residuals`] →
//! [`report`] and [`figures`]. The command line builds the [`Project`] (`cli::batch_args`).
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};

use crate::core::compare::{fit_baselines, noise_fits};
use crate::core::diagnose as core_diagnose;
use crate::core::numerics::noise_fit::Distribution;
use crate::core::residuals::steady_noise_sigma;
use crate::io::model_file::ModelFile;
use crate::io::project::Project;
use crate::io::report::Report;

mod compare;
mod control;
mod diagnose;
mod effects;
pub mod figures;
mod identify;
mod load;
mod manifest;
mod report;
pub mod residuals;

pub use identify::identify;
pub use load::{Runs, load_runs};

/// Stopwatch that records named phases in milliseconds; the progress lines are shared by the
/// outputs' threads.
#[derive(Default)]
pub struct Timings(pub BTreeMap<String, f64>, std::sync::Arc<std::sync::Mutex<Progress>>);

impl Timings {
    pub fn time<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        if let Ok(mut progress) = self.1.lock() {
            progress.stage(name);
        }
        let start = Instant::now();
        let out = f();
        *self.0.entry(name.to_owned()).or_default() += start.elapsed().as_secs_f64() * 1e3;
        out
    }
}

/// Stage lines on stderr while the batch works: one line per stage, or one line rewritten in place
/// on a terminal; nothing with `--quiet`.
#[derive(Default)]
struct Progress {
    quiet: bool,
    started: Option<Instant>,
    last: String,
}

impl Progress {
    fn new(quiet: bool) -> Self {
        Self { quiet, started: Some(Instant::now()), last: String::new() }
    }

    fn stage(&mut self, name: &str) {
        use std::io::{IsTerminal, Write};
        if self.quiet || self.last == name {
            return;
        }
        name.clone_into(&mut self.last);
        let secs = self.started.get_or_insert_with(Instant::now).elapsed().as_secs_f64();
        let what = stage_words(name);
        let mut err = std::io::stderr();
        let _ = if err.is_terminal() {
            write!(err, "\r\x1b[2K[{secs:6.1} s] {what}")
        } else {
            writeln!(err, "jetid: [{secs:6.1} s] {what}")
        };
        let _ = err.flush();
    }

    fn finish(&mut self) {
        use std::io::IsTerminal;
        if !self.quiet && std::io::stderr().is_terminal() {
            eprintln!();
        }
    }
}

/// A stage's timing key in words: "baselines_PR" → "fitting the baselines of PR".
fn stage_words(name: &str) -> String {
    const STAGES: [(&str, &str); 10] = [
        ("identify_", "identifying "),
        ("effects_", "adding the effects to "),
        ("baselines_", "fitting the baselines of "),
        ("diagnosis_", "diagnosing "),
        ("load_runs", "loading the runs"),
        ("validate", "scoring every model on the runs"),
        ("frequency", "comparing frequency responses on the chirp run"),
        ("monte_carlo", "the Monte Carlo study"),
        ("residuals", "analysing the residuals"),
        ("figures", "drawing the figures"),
    ];
    STAGES
        .iter()
        .find_map(|(key, words)| name.strip_prefix(key).map(|rest| format!("{words}{rest}")))
        .unwrap_or_else(|| name.replace('_', " "))
}

/// One output's share of the results, filled on its own thread.
struct OutputPart {
    model_file: ModelFile,
    report: Report,
    monte_carlo: BTreeMap<String, BTreeMap<String, crate::core::compare::MonteCarloSummary>>,
    timings: Timings,
}

/// What every output's stages share: the project, its runs and the steady run's input noise.
struct Batch<'a> {
    project: &'a Project,
    runs: &'a Runs,
    out_dir: &'a Path,
    /// The steady run's input noise, best family by likelihood (drives the Monte Carlo study).
    input_noise: Option<Distribution>,
}

/// Run the whole pipeline on `project` and write the results to `out_dir`.
pub fn run(mut project: Project, out_dir: &Path, quiet: bool) -> Result<()> {
    let total = Instant::now();
    let progress = std::sync::Arc::new(std::sync::Mutex::new(Progress::new(quiet)));
    let mut timings = Timings(BTreeMap::new(), progress.clone());
    let runs = timings.time("load_runs", || load::load_runs(&project))?;
    let outputs = load::outputs_to_model(&project, &runs.ident)?;
    let cluster_notes = load::apply_saved_clusters(&mut project, runs.ident.dt_secs, &outputs)?;
    std::fs::create_dir_all(out_dir)
        .with_context(|| format!("cannot create output folder {}", out_dir.display()))?;

    let mut model_file = report::new_model_file(&runs);
    let mut report = report::new_report(&project, &runs, cluster_notes);
    report.diagnostics.splice(0..0, runs.notes.iter().cloned());
    let noise = runs.steady.as_ref().map(|s| noise_fits(s, &mut report.diagnostics));
    let input_noise = noise
        .as_ref()
        .and_then(|n| n.get(&runs.ident.input.name))
        .and_then(|r| r.best().map(|f| f.distribution));
    let batch = Batch { project: &project, runs: &runs, out_dir, input_noise };
    let mut monte_carlo = BTreeMap::new();
    // The outputs are independent: each runs on its own thread into its own part of the results,
    // merged in output order (so the files are the same as one output after another).
    let parts: Vec<Result<OutputPart>> = std::thread::scope(|scope| {
        let handles: Vec<_> = outputs
            .iter()
            .map(|output| {
                let (batch, progress) = (&batch, progress.clone());
                let mut part = OutputPart {
                    model_file: report::new_model_file(batch.runs),
                    report: Report { diagnostics: Vec::new(), ..report.clone() },
                    monte_carlo: BTreeMap::new(),
                    timings: Timings(BTreeMap::new(), progress),
                };
                scope.spawn(move || {
                    batch
                        .model_output(
                            output,
                            &mut part.model_file,
                            &mut part.report,
                            &mut part.monte_carlo,
                            &mut part.timings,
                        )
                        .map(|()| part)
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| {
                h.join().unwrap_or_else(|_| Err(anyhow::anyhow!("an output's thread stopped unexpectedly")))
            })
            .collect()
    });
    for part in parts {
        let part = part?;
        model_file.outputs.extend(part.model_file.outputs);
        report.outputs.extend(part.report.outputs);
        report.figures.extend(part.report.figures);
        report.diagnostics.extend(part.report.diagnostics);
        monte_carlo.extend(part.monte_carlo);
        for (stage, ms) in part.timings.0 {
            *timings.0.entry(stage).or_default() += ms;
        }
    }
    report.noise_fit = noise.map(serde_json::to_value).transpose().context("noise fit")?;
    if !monte_carlo.is_empty() {
        report.monte_carlo = Some(serde_json::to_value(monte_carlo).context("Monte Carlo summary")?);
    }
    timings.time("writing the results", || ());
    if let Ok(mut progress) = timings.1.lock() {
        progress.finish();
    }
    report.timings_ms = timings.0;
    report.timings_ms.remove("writing the results");
    report.timings_ms.insert("total".into(), total.elapsed().as_secs_f64() * 1e3);
    report::write_all(out_dir, &model_file, &report)
}

impl Batch<'_> {
    /// Every stage for one output: identify, add the effects, fit the baselines, diagnose, compare,
    /// analyse the residuals and draw the figures.
    fn model_output(
        &self,
        output: &str,
        model_file: &mut ModelFile,
        report: &mut Report,
        monte_carlo: &mut BTreeMap<String, BTreeMap<String, crate::core::compare::MonteCarloSummary>>,
        timings: &mut Timings,
    ) -> Result<()> {
        let (project, runs, notes) = (self.project, self.runs, &mut report.diagnostics);
        let identified = timings
            .time(&format!("identify_{output}"), || identify::identify(project, runs, output))
            .with_context(|| format!("identifying '{output}' from '{}'", runs.ident.name))?;
        let unit = runs.ident.output(output).map(|c| c.unit.clone()).unwrap_or_default();
        // The baselines need only the identified model, so they train on their own thread while the
        // effects loop and the diagnosis run; their notes keep their place in the report.
        let (sequence, diagnosis, baselines) = std::thread::scope(|scope| {
            let mut baseline_timings = Timings(BTreeMap::new(), timings.1.clone());
            let identified = &identified;
            let baselines = scope.spawn(move || {
                let mut notes = Vec::new();
                let models = baseline_timings.time(&format!("baselines_{output}"), || {
                    fit_baselines(identified, &runs.ident, output, &mut notes)
                });
                (models, notes, baseline_timings)
            });
            let mut sequence = timings.time(&format!("effects_{output}"), || {
                effects::apply_effects(project, runs, identified, output, notes)
            });
            let diagnosis = sequence.as_mut().ok().map(|sequence| {
                let final_diagnosis = sequence.final_diagnosis.take();
                timings.time(&format!("diagnosis_{output}"), || {
                    diagnose::diagnose_output(
                        project,
                        runs,
                        identified,
                        &sequence.model,
                        output,
                        final_diagnosis,
                    )
                })
            });
            (sequence, diagnosis, baselines.join())
        });
        let (mut models, baseline_notes, baseline_timings) = baselines
            .map_err(|_| anyhow::anyhow!("fitting the baselines of '{output}' stopped unexpectedly"))?;
        timings.0.extend(baseline_timings.0);
        let sequence = sequence?;
        notes.extend(baseline_notes);
        let extended = sequence.model;
        model_file.push(&identified.model, &unit);
        if let Some(last) = model_file.outputs.last_mut() {
            // Effects are fitted together with the gain and static map they sit beside.
            last.wiener = extended.wiener.clone();
            last.static_map_beta = extended.wiener.map.beta();
            last.effects = extended.records();
            // A structural refinement the loop added changes the roots.
            if let Ok((poles, zeros)) = extended.roots() {
                (last.poles, last.zeros) = (poles, zeros);
            }
        }
        models.initial_state = project.settings_for(output).initial_state;
        let mut out = report::output_report(&identified, &models, unit);
        out.effects_applied = extended.effect_ids();
        out.error_history = sequence.history;
        if !extended.effects.is_empty() {
            models.extended = Some(extended.clone());
        }
        match diagnosis {
            Some(Ok((entries, skipped))) => {
                out.diagnosis = entries;
                notes.extend(skipped);
            }
            Some(Err(e)) => notes.push(format!("diagnosis of '{output}': {e}")),
            None => {}
        }
        let described: Vec<&_> = std::iter::once(&runs.ident)
            .chain(runs.compared())
            .filter(|r| r.output(output).is_some())
            .collect();
        match core_diagnose::steady_state_agreement(
            &extended,
            &described,
            project.settings_for(output).initial_state,
        ) {
            Ok(evidence) => out.steady_states = Some(evidence.sentence),
            Err(e) => notes.push(format!("steady states of '{output}' across runs: {e}")),
        }
        let studies =
            compare::compare(&models, runs, output, self.input_noise.as_ref(), &mut out, notes, timings);
        let sigma = runs.steady.as_ref().and_then(|s| steady_noise_sigma(s, output));
        let (residuals, figs) = timings.time("residuals", || {
            residuals::residual_reports(self.out_dir, output, &models, &runs.scored(), sigma, notes)
        });
        out.residuals = residuals;
        out.failing = crate::io::report::failing_models(&out);
        (out.operating_points, out.continuous) = control::control_report(&extended, runs, notes);
        report.figures.extend(figs);
        let notes = &mut report.diagnostics;
        if runs.steady.is_some() && self.input_noise.is_some() {
            monte_carlo.insert(output.to_owned(), compare::monte_carlo_summaries(&studies.monte_carlo));
            let (figs, figure_notes) = timings
                .time("figures", || figures::monte_carlo_figures(self.out_dir, output, &studies.monte_carlo));
            report.figures.extend(figs);
            notes.extend(figure_notes);
        }
        let (figs, figure_notes) = timings.time("figures", || {
            figures::output_figures(
                self.out_dir,
                output,
                &identified,
                &models,
                &runs.compared(),
                studies.frequency.as_ref(),
                &out.error_boxes,
            )
        });
        report.figures.extend(figs);
        report.diagnostics.extend(figure_notes);
        report.outputs.insert(output.to_owned(), out);
        Ok(())
    }
}
