//! The runs a model is identified on and scored on, by role: read with their load options, the
//! identification runs joined end to end, their segments, and the scored runs put on the
//! identification run's grid. The batch loads a project's runs here ([`load_runs`]); the app, which
//! keeps its runs in the session, calls the same steps one by one ([`join_identification`],
//! [`segments`], [`grid_of`]).
use std::collections::BTreeMap;

use anyhow::{Context, Result, bail};

use crate::core::identification::error::PipelineError;
use crate::core::identification::fits::{segments_for, step_signal};
use crate::core::identification::segment::{Segment, SegmentSettings, auto_segments_joined};
use crate::core::identification::set_point::{SetPoint, find_set_point};
use crate::core::numerics::stats::significant;
use crate::core::run::{Run, RunError, RunRole, join_runs};
use crate::io::csv_run::{LoadNotes, LoadOptions, RunFileError, load_run_with_notes};
use crate::io::project::{Project, RunSource};
use crate::workflow::long_runs::{FIT_SAMPLES, FitWindow};

/// Runs sampled more than this fraction off the identification run are on another grid: the
/// models are discrete-time, so a 2 % different sample time is a 2 % different time scale, beyond
/// the jitter a logger's clock has.
pub const DT_TOLERANCE: f64 = 0.02;

/// The loaded runs of a project, by role.
#[derive(Clone)]
pub struct Runs {
    pub ident: Run,
    /// Where each further identification run starts when several were joined.
    pub ident_junctions: Vec<usize>,
    /// The channel the identification run's steps are detected on.
    pub steps_from: StepsFrom,
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

/// How a run's table is read: from the file at its path ([`load_run_with_notes`]), or, for a host
/// that holds its runs in memory (the Python package's data frames), from the table it keeps
/// under that path. Either way the load options apply as to a file.
pub type ReadRun<'a> =
    dyn Fn(&std::path::Path, &LoadOptions) -> Result<(Run, LoadNotes), RunFileError> + Sync + 'a;

/// Read one run with its load options; what reading it changed goes to `notes`, in words.
pub fn load_source(source: &RunSource, notes: &mut Vec<String>) -> Result<Run> {
    load_source_with(source, notes, &load_run_with_notes)
}

/// [`load_source`] with the run's table read by `read`.
pub fn load_source_with(source: &RunSource, notes: &mut Vec<String>, read: &ReadRun<'_>) -> Result<Run> {
    let opts = source.load.to_options()?;
    let (run, read) = read(&source.path, &opts)?;
    if read.resampled || read.merged_repeats > 0 {
        notes.push(format!(
            "run '{}': time axis resampled onto a uniform {} s grid ({} rows sharing a time stamp merged into their mean)",
            run.name,
            significant(run.dt_secs, 4),
            read.merged_repeats
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

/// The identification run from one or several: the one, or all of them joined end to end with the
/// index where each later one starts (no segment may cross a join).
pub fn join_identification(parts: &[Run]) -> Result<(Run, Vec<usize>), RunError> {
    match parts {
        [one] => Ok((one.clone(), Vec::new())),
        _ => join_runs(parts),
    }
}

/// The identification run its model is fitted on: the run itself, or, when its segments (detected
/// as [`segments`] and [`steps_from`] would) span more than [`FIT_SAMPLES`], its first segments up to
/// that many samples ([`FitWindow`]), with the junctions inside, where the cut starts and a note
/// saying so. Runs whose segments are given keep them (they count samples of the whole run). The
/// batch and the app both cut here.
pub fn within_fit_budget(
    run: Run,
    junctions: Vec<usize>,
    named_steps_from: Option<&str>,
    segments_given: bool,
) -> (Run, Vec<usize>, Option<(usize, String)>) {
    if segments_given || run.len() <= FIT_SAMPLES {
        return (run, junctions, None);
    }
    let found = steps_from(&run, &junctions, named_steps_from);
    let Ok(all) = segments(&run, &junctions, None, found.channel()) else {
        return (run, junctions, None);
    };
    let Some(window) = FitWindow::of(&all, FIT_SAMPLES) else {
        return (run, junctions, None);
    };
    let (cut, inside) = window.apply(&run, &junctions);
    let cut_at = (window.range.start, window.words(&run));
    (cut, inside, Some(cut_at))
}

/// The segments of the identification run: the given ones (checked against the run), else the steps
/// detected on the input or on the `steps_from` channel, each joined run on its own.
pub fn segments(
    run: &Run,
    junctions: &[usize],
    given: Option<&[Segment]>,
    steps_from: Option<&str>,
) -> Result<Vec<Segment>, PipelineError> {
    if given.is_some() {
        return segments_for(run, given, &SegmentSettings::default());
    }
    let signal = step_signal(run, steps_from)?;
    auto_segments_joined(signal, junctions, run.dt_secs, &SegmentSettings::default())
        .map_err(|source| PipelineError::Segment { run: run.name.clone(), source })
}

/// The channel the identification run's steps are detected on.
#[derive(Clone, Debug, PartialEq)]
pub enum StepsFrom {
    /// The input: no channel named, no set-point found.
    Input,
    /// The channel the project or the user named (`steps_from`).
    Named(String),
    /// A set-point channel found in the log ([`find_set_point`]).
    Found(SetPoint),
}

impl StepsFrom {
    /// The channel other than the input, if any.
    pub fn channel(&self) -> Option<&str> {
        match self {
            Self::Input => None,
            Self::Named(name) => Some(name),
            Self::Found(set_point) => Some(&set_point.channel),
        }
    }

    /// What was found, for the notes: the set-point and the evidence for it.
    pub fn note(&self) -> Option<String> {
        let Self::Found(set_point) = self else { return None };
        Some(format!(
            "segments detected from the steps of '{}' instead of the input: {}; name the channel to split on with \
             steps_from (or give segments) to choose otherwise",
            set_point.channel,
            set_point.words()
        ))
    }
}

/// Where the identification run's steps are detected: on the channel `named` (the project's or the
/// user's `steps_from`), else on a set-point found in the log when its steps give segments, else on
/// the input. The batch and the app both ask here, so they split a run alike.
pub fn steps_from(run: &Run, junctions: &[usize], named: Option<&str>) -> StepsFrom {
    if let Some(name) = named {
        return StepsFrom::Named(name.to_owned());
    }
    match find_set_point(run, junctions) {
        Some(found) if segments(run, junctions, None, Some(&found.channel)).is_ok() => {
            StepsFrom::Found(found)
        }
        _ => StepsFrom::Input,
    }
}

/// A scored run whose sample time is not the identification run's.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error(
    "run '{run}' is sampled every {} s but the identification run every {} s; models are discrete-time, so resample it first",
    significant(*dt_secs, 5),
    significant(*ident_dt_secs, 5)
)]
pub struct OffGrid {
    pub run: String,
    pub dt_secs: f64,
    pub ident_dt_secs: f64,
}

/// Where a scored run stands against the identification run's grid.
#[derive(Clone, Debug, PartialEq)]
pub enum Grid {
    /// On it (within [`DT_TOLERANCE`]).
    On,
    /// Off it, but resampled from an irregular log (`resample`, each run onto its own median
    /// step): resampled again onto it ([`resampled_onto`]).
    Resample,
    Off(OffGrid),
}

/// Where `run` stands against the identification run's sample time `ident_dt_secs`.
pub fn grid_of(run: &Run, ident_dt_secs: f64, resample: bool) -> Grid {
    let off = (run.dt_secs / ident_dt_secs - 1.0).abs() > DT_TOLERANCE;
    match (off, resample) {
        (false, _) => Grid::On,
        (true, true) => Grid::Resample,
        (true, false) => Grid::Off(OffGrid { run: run.name.clone(), dt_secs: run.dt_secs, ident_dt_secs }),
    }
}

/// `run` resampled onto the identification run's grid, with the note saying so.
pub fn resampled_onto(run: &Run, ident_dt_secs: f64) -> (Run, String) {
    (run.resampled(ident_dt_secs), resample_note(run, ident_dt_secs))
}

/// What [`resampled_onto`] did to `run`, in words.
pub fn resample_note(run: &Run, ident_dt_secs: f64) -> String {
    format!(
        "run '{}': resampled again from {} s onto the identification run's {} s grid",
        run.name,
        significant(run.dt_secs, 5),
        significant(ident_dt_secs, 5)
    )
}

/// Load every run of the project; runs sampled differently from the identification run are put on
/// its grid when they were resampled, else refused (the models are discrete-time).
pub fn load_runs(project: &Project) -> Result<Runs> {
    load_runs_with(project, &load_run_with_notes)
}

/// A run that is scored on a model identified at `dt_secs`: put on that grid when its source says
/// to resample, else refused when sampled differently (the models are discrete-time).
fn put_on_grid(run: &mut Run, source: &RunSource, dt_secs: f64, notes: &mut Vec<String>) -> Result<()> {
    match grid_of(run, dt_secs, source.load.resample) {
        Grid::On => {}
        Grid::Resample => {
            let (on_grid, note) = resampled_onto(run, dt_secs);
            notes.push(note);
            *run = on_grid;
        }
        Grid::Off(off) => return Err(off.into()),
    }
    Ok(())
}

/// Runs to score on a model identified at `dt_secs` (validation runs given after the
/// identification), each read by `read` and put on its grid as [`load_runs`] puts a project's.
pub fn load_scored_runs(
    sources: &[RunSource],
    dt_secs: f64,
    read: &ReadRun<'_>,
    notes: &mut Vec<String>,
) -> Result<Vec<Run>> {
    sources
        .iter()
        .map(|source| {
            let mut run = load_source_with(source, notes, read)?;
            put_on_grid(&mut run, source, dt_secs, notes)?;
            Ok(run)
        })
        .collect()
}

/// [`load_runs`] with every run's table read by `read`.
pub fn load_runs_with(project: &Project, read: &ReadRun<'_>) -> Result<Runs> {
    if project.ident.is_empty() {
        bail!("the project names no identification run (give one with --ident FILE)");
    }
    let mut notes = Vec::new();
    let mut load = |source: &RunSource| load_source_with(source, &mut notes, read);
    let parts = project.ident.iter().map(&mut load).collect::<Result<Vec<_>>>()?;
    let (ident, ident_junctions) = join_identification(&parts).context("joining the identification runs")?;
    step_signal(&ident, project.steps_from.as_deref())?;
    let segments_given = !project.segments.is_empty();
    let (ident, ident_junctions, window_note) =
        within_fit_budget(ident, ident_junctions, project.steps_from.as_deref(), segments_given);
    let mut validate = project.validate.iter().map(&mut load).collect::<Result<Vec<_>>>()?;
    let mut held_out = project.held_out.iter().map(&mut load).collect::<Result<Vec<_>>>()?;
    let mut chirp = project.chirp.as_ref().map(&mut load).transpose()?;
    let mut steady = project.steady.as_ref().map(&mut load).transpose()?;
    let sources =
        project.validate.iter().chain(&project.held_out).chain(&project.chirp).chain(&project.steady);
    let runs = validate.iter_mut().chain(&mut held_out).chain(&mut chirp).chain(&mut steady);
    for (run, source) in runs.zip(sources) {
        put_on_grid(run, source, ident.dt_secs, &mut notes)?;
    }
    let steps_from = steps_from(&ident, &ident_junctions, project.steps_from.as_deref());
    notes.extend(window_note.map(|(_, note)| note));
    notes.extend(steps_from.note());
    let mut runs = Runs { ident, ident_junctions, steps_from, validate, held_out, chirp, steady, notes };
    runs.name_apart(project);
    runs.note_reused_identification(project);
    runs.note_coverage();
    Ok(runs)
}

impl Runs {
    /// Every run by role with its source, in the order the project lists them.
    fn with_sources<'a>(&'a mut self, project: &'a Project) -> Vec<(&'a mut Run, &'a RunSource)> {
        let sources =
            project.validate.iter().chain(&project.held_out).chain(&project.chirp).chain(&project.steady);
        let runs =
            self.validate.iter_mut().chain(&mut self.held_out).chain(&mut self.chirp).chain(&mut self.steady);
        runs.zip(sources).collect()
    }

    /// Runs of the same file name from different folders get the folder in their name ("dayA-run"),
    /// so that the reports, keyed by run name, tell them apart.
    fn name_apart(&mut self, project: &Project) {
        let ident_name = self.ident.name.clone();
        let mut notes = Vec::new();
        let mut runs = self.with_sources(project);
        let names: Vec<String> = runs.iter().map(|(run, _)| run.name.clone()).collect();
        for (i, (run, source)) in runs.iter_mut().enumerate() {
            let clashes =
                names.iter().enumerate().any(|(j, n)| j != i && *n == run.name) || run.name == ident_name;
            let folder =
                source.path.parent().and_then(|p| p.file_name()).map(|f| f.to_string_lossy().into_owned());
            if let (true, Some(folder)) = (clashes, folder) {
                let named = format!("{folder}-{}", run.name);
                notes.push(format!(
                    "run '{}' of {} is called '{named}': another run has the same file name",
                    run.name,
                    source.path.display()
                ));
                run.name = named;
            }
        }
        self.notes.extend(notes);
    }

    /// A run that is also the identification run says nothing about how the model generalises.
    fn note_reused_identification(&mut self, project: &Project) {
        let mut notes = Vec::new();
        for (run, source) in self.with_sources(project) {
            if project
                .ident
                .iter()
                .any(|i| crate::io::paths::same_file(&i.path, &source.path) && i.load == source.load)
            {
                notes.push(format!(
                    "run '{}' is also the identification run: its scores measure how the model fits the data it \
                     was identified on, not how it predicts a run it has not seen",
                    run.name
                ));
            }
        }
        self.notes.extend(notes);
    }

    /// The share of each scored run's input outside the identification run's range, in words.
    fn note_coverage(&mut self) {
        let Some(range) = crate::workflow::model_file::input_range(&self.ident.input.values) else { return };
        let unit = self.ident.input.unit.clone();
        let notes: Vec<String> = self
            .scored()
            .into_iter()
            .filter_map(|run| {
                let words = crate::core::run::InputCoverage::of(&run.input.values, range).words(&unit)?;
                Some(format!("run '{}': {words}", run.name))
            })
            .collect();
        self.notes.extend(notes);
    }
}

/// The runs of a project by role, in the order they are listed (for the app's session).
pub fn sources_by_role(project: &Project) -> Vec<(&RunSource, RunRole)> {
    let roles = project.ident.iter().map(|s| (s, RunRole::Identification));
    roles
        .chain(project.validate.iter().map(|s| (s, RunRole::Validation)))
        .chain(project.held_out.iter().map(|s| (s, RunRole::HeldOut)))
        .chain(project.chirp.iter().map(|s| (s, RunRole::Chirp)))
        .chain(project.steady.iter().map(|s| (s, RunRole::Steady)))
        .collect()
}

/// Outputs to model: the project's list (each must exist), else every output of the ident run.
pub fn outputs_to_model(project: &Project, ident: &Run) -> Result<Vec<String>> {
    let sections = project.settings.keys().chain(project.segments.keys()).chain(project.clusters.keys());
    for name in sections {
        if ident.output(name).is_none() {
            bail!(
                "[output.{name}] in the project names no output of the identification run '{}' (outputs: {}): \
                 its settings would be ignored",
                ident.name,
                output_names(ident)
            );
        }
    }
    if project.outputs.is_empty() {
        return Ok(ident.outputs.iter().map(|c| c.name.clone()).collect());
    }
    for name in &project.outputs {
        if ident.output(name).is_none() {
            bail!(
                "output '{name}' is not in the identification run '{}' (outputs: {})",
                ident.name,
                output_names(ident)
            );
        }
    }
    Ok(project.outputs.clone())
}

fn output_names(run: &Run) -> String {
    run.outputs.iter().map(|c| c.name.as_str()).collect::<Vec<_>>().join(", ")
}
