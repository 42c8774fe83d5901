//! The session: what the user has loaded and decided (runs, their roles and load options, and the
//! identification setup: segments, per-output settings and clusters).
//!
//! It is the only app state that is saved. The run data itself is not saved: on start the runs are
//! read again from their files with the saved options.
use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::core::run::{Run, RunRole};
use crate::io::csv_run::{ColumnMap, LoadOptions, RunFileError, load_run};
use crate::ui::state::setup::ModelSetup;

/// A first guess of a run's role from its file name; the user can change it in the run list.
pub fn guess_role(path: &Path, session: &Session) -> RunRole {
    let stem = path.file_stem().map(|s| s.to_string_lossy().to_lowercase()).unwrap_or_default();
    if stem.contains("chirp") {
        RunRole::Chirp
    } else if stem.contains("steady") {
        RunRole::Steady
    } else if stem.contains("held") {
        RunRole::HeldOut
    } else if stem.contains("valid") {
        RunRole::Validation
    } else if stem.contains("ident") || !session.runs.iter().any(|r| r.role == RunRole::Identification) {
        RunRole::Identification
    } else {
        RunRole::Validation
    }
}

/// [`LoadOptions`] in a form that can be saved.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SavedLoadOptions {
    pub time: Option<String>,
    pub input: Option<String>,
    pub outputs: Vec<String>,
    pub aux: Vec<String>,
    pub sample_time_secs: Option<f64>,
    /// `START:END` as on the command line (`--window`).
    pub window: Option<String>,
    pub quality: Option<String>,
    pub resample: bool,
    /// Per channel, its invalid-value sentinels.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub invalid: std::collections::BTreeMap<String, Vec<f64>>,
    /// Per channel, a unit given by the user.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub units: std::collections::BTreeMap<String, String>,
}

impl From<&LoadOptions> for SavedLoadOptions {
    fn from(opts: &LoadOptions) -> Self {
        Self {
            time: opts.map.time.clone(),
            input: opts.map.input.clone(),
            outputs: opts.map.outputs.clone(),
            aux: opts.map.aux.clone(),
            sample_time_secs: opts.sample_time_secs,
            window: opts.window.as_ref().map(ToString::to_string),
            quality: opts.quality.clone(),
            resample: opts.resample,
            invalid: opts.invalid.clone(),
            units: opts.units.clone(),
        }
    }
}

impl From<&SavedLoadOptions> for LoadOptions {
    fn from(saved: &SavedLoadOptions) -> Self {
        Self {
            map: ColumnMap {
                time: saved.time.clone(),
                input: saved.input.clone(),
                outputs: saved.outputs.clone(),
                aux: saved.aux.clone(),
            },
            sample_time_secs: saved.sample_time_secs,
            // A window that no longer parses is dropped rather than losing the whole run.
            window: saved.window.as_deref().and_then(|w| w.parse().ok()),
            quality: saved.quality.clone(),
            resample: saved.resample,
            invalid: saved.invalid.clone(),
            units: saved.units.clone(),
            input_only: false,
        }
    }
}

/// Where a run comes from: enough to read it again.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunSource {
    pub path: PathBuf,
    pub role: RunRole,
    #[serde(default)]
    pub options: SavedLoadOptions,
}

/// A loaded run in the session.
#[derive(Clone, Debug)]
pub struct SessionRun {
    pub path: PathBuf,
    pub role: RunRole,
    pub options: LoadOptions,
    /// Shared with the derived caches and worker threads; replaced, never mutated.
    pub run: Arc<Run>,
}

impl SessionRun {
    /// Read a run file; the session is not touched, so a failure loses nothing.
    pub fn load(path: &Path, role: RunRole, options: LoadOptions) -> Result<Self, Box<LoadFailure>> {
        match load_run(path, &options) {
            Ok(run) => Ok(Self { path: path.to_owned(), role, options, run: Arc::new(run) }),
            Err(err) => Err(Box::new(LoadFailure {
                path: path.to_owned(),
                role,
                options,
                message: err.to_string(),
                column_problem: is_column_problem(&err),
                existing: None,
            })),
        }
    }

    /// A display name: the run's own name, else the file name.
    pub fn display_name(&self) -> String {
        if self.run.name.is_empty() { file_label(&self.path) } else { self.run.name.clone() }
    }

    pub fn source(&self) -> RunSource {
        RunSource { path: self.path.clone(), role: self.role, options: (&self.options).into() }
    }
}

/// A run file that could not be read, kept so the user can see the whole message and retry with a
/// column mapping.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadFailure {
    pub path: PathBuf,
    pub role: RunRole,
    pub options: LoadOptions,
    pub message: String,
    /// The error is about columns (missing, unmapped), so a column mapping is the likely fix.
    pub column_problem: bool,
    /// The index of the session run this was a reload of, if any.
    pub existing: Option<usize>,
}

impl LoadFailure {
    /// Where the failed file is, to try again later.
    pub fn source(&self) -> RunSource {
        RunSource { path: self.path.clone(), role: self.role, options: (&self.options).into() }
    }
}

/// The user's work: loaded runs with their roles and options, and the identification setup.
/// `revision` changes whenever the session does, so derived data can tell it is stale.
#[derive(Clone, Debug, Default)]
pub struct Session {
    pub runs: Vec<SessionRun>,
    pub setup: ModelSetup,
    pub revision: u64,
}

impl Session {
    /// The saved form (paths, roles, options, setup; no data).
    pub fn to_saved(&self) -> SavedSession {
        SavedSession {
            format_version: SavedSession::FORMAT_VERSION,
            runs: self.runs.iter().map(SessionRun::source).collect(),
            setup: self.setup.clone(),
        }
    }

    /// Read every saved run again. Runs that fail to load are returned as failures (the user sees
    /// them and can remap them); the others make up the session.
    pub fn restore(saved: &SavedSession) -> (Self, Vec<LoadFailure>) {
        let mut session = Self { setup: saved.setup.clone(), ..Self::default() };
        let mut failures = Vec::new();
        for source in &saved.runs {
            match SessionRun::load(&source.path, source.role, (&source.options).into()) {
                Ok(run) => session.runs.push(run),
                Err(failure) => failures.push(*failure),
            }
        }
        (session, failures)
    }

    /// The bundled sample runs, when they are present.
    pub fn bundled() -> Option<(Self, Vec<LoadFailure>)> {
        let dir = crate::ui::bundled_sample_dir()?;
        let runs = BUNDLED_RUNS
            .iter()
            .map(|(file, role)| RunSource {
                path: dir.join(file),
                role: *role,
                options: SavedLoadOptions::default(),
            })
            .filter(|source| source.path.is_file())
            .collect();
        Some(Self::restore(&SavedSession {
            format_version: SavedSession::FORMAT_VERSION,
            runs,
            setup: ModelSetup::default(),
        }))
    }

    /// The first run with this role.
    pub fn first_with_role(&self, role: RunRole) -> Option<usize> {
        self.runs.iter().position(|r| r.role == role)
    }

    /// The identification run (the first with that role), with its index.
    pub fn ident_run(&self) -> Option<(usize, &SessionRun)> {
        self.runs.iter().enumerate().find(|(_, r)| r.role == RunRole::Identification)
    }
}

fn is_column_problem(err: &RunFileError) -> bool {
    matches!(
        err,
        RunFileError::MissingColumn { .. }
            | RunFileError::MapColumnNotFound { .. }
            | RunFileError::BadMap { .. }
            | RunFileError::NoOutput { .. }
            | RunFileError::TimeGivenTwice { .. }
    )
}

/// The bundled sample runs under `sample_runs/sr30`, with their roles.
pub const BUNDLED_RUNS: [(&str, RunRole); 4] = [
    ("ident.csv", RunRole::Identification),
    ("validation.csv", RunRole::Validation),
    ("chirp.csv", RunRole::Chirp),
    ("steady.csv", RunRole::Steady),
];

/// What is written to eframe's storage.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SavedSession {
    pub format_version: u32,
    pub runs: Vec<RunSource>,
    /// Segments, settings and clusters (absent in sessions saved before they existed).
    pub setup: ModelSetup,
}

impl SavedSession {
    pub const FORMAT_VERSION: u32 = 1;
}

/// The file name of a path, for labels.
pub fn file_label(path: &Path) -> String {
    path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned())
}
