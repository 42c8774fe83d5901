//! Stage 1 of the batch: the project's runs loaded and checked, the outputs to model chosen, saved
//! clusters taken over.
use std::collections::BTreeMap;

use anyhow::{Context, Result, bail};

use crate::core::run::Run;
use crate::io::csv_run::load_run_with_notes;
use crate::io::project::{Project, RunSource};

/// The loaded runs of a project, by role.
pub struct Runs {
    pub ident: Run,
    /// Where each further identification run starts when several were joined.
    pub ident_junctions: Vec<usize>,
    pub validate: Vec<Run>,
    /// Scored like the validation runs, never used to choose an effect or a refinement.
    pub held_out: Vec<Run>,
    pub chirp: Option<Run>,
    pub steady: Option<Run>,
    /// What reading the files changed, in words (resampled time axes, merged time stamps, repairs).
    pub notes: Vec<String>,
}

impl Runs {
    /// Runs the models are scored on: validation runs, held-out runs, then the chirp run.
    pub fn scored(&self) -> Vec<&Run> {
        self.compared().into_iter().chain(&self.chirp).collect()
    }

    /// Runs every model's traces are compared on: validation runs, then held-out runs.
    pub fn compared(&self) -> Vec<&Run> {
        self.validate.iter().chain(&self.held_out).collect()
    }

    /// The validation runs that record `output`.
    pub fn validation_of(&self, output: &str) -> Vec<&Run> {
        self.validate.iter().filter(|r| r.output(output).is_some()).collect()
    }

    /// The role of every run, as report.json `runs` has them.
    pub fn roles(&self) -> BTreeMap<String, String> {
        let mut roles = BTreeMap::new();
        roles.insert("identification".to_owned(), self.ident.name.clone());
        for (i, r) in self.validate.iter().enumerate() {
            roles.insert(format!("validation {}", i + 1), r.name.clone());
        }
        for (i, r) in self.held_out.iter().enumerate() {
            roles.insert(format!("held-out {}", i + 1), r.name.clone());
        }
        if let Some(r) = &self.chirp {
            roles.insert("chirp".into(), r.name.clone());
        }
        if let Some(r) = &self.steady {
            roles.insert("steady".into(), r.name.clone());
        }
        roles
    }
}

fn load_source(source: &RunSource, notes: &mut Vec<String>) -> Result<Run> {
    let opts = source.load.to_options()?;
    let (run, read) = load_run_with_notes(&source.path, &opts)?;
    if read.resampled || read.merged_repeats > 0 {
        notes.push(format!(
            "run '{}': time axis resampled onto a uniform {:.4} s grid ({} rows sharing a time stamp merged into their mean)",
            run.name, run.dt_secs, read.merged_repeats
        ));
    }
    notes.extend(read.reading_notes().into_iter().map(|n| format!("run '{}': {n}", run.name)));
    for dropped in &read.dropped_columns {
        notes.push(format!("run '{}': column '{}' left out: {}", run.name, dropped.name, dropped.reason));
    }
    if let Some(window) = &read.running_window {
        notes.push(format!("run '{}': running window found: {}", run.name, window.reason));
    }
    for (channel, count) in &read.invalid_samples {
        notes.push(format!(
            "run '{}': {count} samples of {channel} held its invalid-value sentinel and were interpolated",
            run.name
        ));
    }
    if read.repaired_samples > 0 {
        notes.push(format!(
            "run '{}': {} samples flagged bad were interpolated",
            run.name, read.repaired_samples
        ));
    }
    Ok(run)
}

/// Load every run of the project; runs sampled differently from the identification run are refused
/// (the models are discrete-time).
pub fn load_runs(project: &Project) -> Result<Runs> {
    if project.ident.is_empty() {
        bail!("the project names no identification run (give one with --ident FILE)");
    }
    let mut notes = Vec::new();
    let mut load = |source: &RunSource| load_source(source, &mut notes);
    let parts = project.ident.iter().map(&mut load).collect::<Result<Vec<_>>>()?;
    let (ident, ident_junctions) =
        crate::core::run::join_runs(&parts).context("joining the identification runs")?;
    crate::core::identification::pipeline::step_signal(&ident, project.steps_from.as_deref())?;
    let mut validate = project.validate.iter().map(&mut load).collect::<Result<Vec<_>>>()?;
    let mut held_out = project.held_out.iter().map(&mut load).collect::<Result<Vec<_>>>()?;
    let mut chirp = project.chirp.as_ref().map(&mut load).transpose()?;
    let mut steady = project.steady.as_ref().map(&mut load).transpose()?;
    let sources =
        project.validate.iter().chain(&project.held_out).chain(&project.chirp).chain(&project.steady);
    let runs = validate.iter_mut().chain(&mut held_out).chain(&mut chirp).chain(&mut steady);
    for (run, source) in runs.zip(sources) {
        let ratio = run.dt_secs / ident.dt_secs;
        if (ratio - 1.0).abs() > 0.02 && source.load.resample {
            // Both were resampled from irregular logs, each onto its own median step: put this one on
            // the identification run's grid.
            notes.push(format!(
                "run '{}': resampled again from {:.5} s onto the identification run's {:.5} s grid",
                run.name, run.dt_secs, ident.dt_secs
            ));
            *run = run.resampled(ident.dt_secs);
        } else if (ratio - 1.0).abs() > 0.02 {
            bail!(
                "run '{}' is sampled every {:.5} s but the identification run every {:.5} s; models are discrete-time, so resample it first",
                run.name,
                run.dt_secs,
                ident.dt_secs
            );
        }
    }
    Ok(Runs { ident, ident_junctions, validate, held_out, chirp, steady, notes })
}

/// Outputs to model: the project's list (each must exist), else every output of the ident run.
pub fn outputs_to_model(project: &Project, ident: &Run) -> Result<Vec<String>> {
    let sections = project.settings.keys().chain(project.segments.keys()).chain(project.clusters.keys());
    for name in sections {
        if ident.output(name).is_none() {
            let available: Vec<&str> = ident.outputs.iter().map(|c| c.name.as_str()).collect();
            bail!(
                "[output.{name}] in the project names no output of the identification run '{}' (outputs: {}): \
                 its settings would be ignored",
                ident.name,
                available.join(", ")
            );
        }
    }
    if project.outputs.is_empty() {
        return Ok(ident.outputs.iter().map(|c| c.name.clone()).collect());
    }
    for name in &project.outputs {
        if ident.output(name).is_none() {
            let available: Vec<&str> = ident.outputs.iter().map(|c| c.name.as_str()).collect();
            bail!(
                "output '{name}' is not in the identification run '{}' (outputs: {})",
                ident.name,
                available.join(", ")
            );
        }
    }
    Ok(project.outputs.clone())
}

/// Take the clusters of the project's saved model (`clusters_from` / `--clusters`) for every output
/// that has none of its own; say which outputs fall back to the automatic proposal.
pub fn apply_saved_clusters(project: &mut Project, dt_secs: f64, outputs: &[String]) -> Result<Vec<String>> {
    let Some(path) = &project.clusters_from else { return Ok(Vec::new()) };
    let saved = crate::io::model_file::clusters_from_model(path, dt_secs)?;
    let mut notes = Vec::new();
    for output in outputs {
        if project.clusters.contains_key(output) {
            notes.push(format!(
                "'{output}': the project's own clusters take precedence over {}",
                path.display()
            ));
        } else if let Some(clusters) = saved.get(output) {
            project.clusters.insert(output.clone(), clusters.clone());
            notes.push(format!("'{output}': {} clusters taken from {}", clusters.len(), path.display()));
        } else {
            notes.push(format!(
                "'{output}': {} holds no clusters for it; the automatic proposal is used",
                path.display()
            ));
        }
    }
    Ok(notes)
}
