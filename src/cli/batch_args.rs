//! The arguments of `jetid --batch` and the project they describe.
use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::Args;

use crate::core::effects::EffectId;
use crate::io::project::Project;
use crate::workflow::Overrides;

/// Where results go unless `--out` says otherwise.
const DEFAULT_OUT: &str = "jetid-out";

#[derive(Debug, Args, Default, Clone)]
pub struct BatchArgs {
    /// Project file (default: the bundled sample project).
    pub project: Option<PathBuf>,
    /// Identification run.
    #[arg(long)]
    pub ident: Option<PathBuf>,
    /// Validation run (repeatable).
    #[arg(long = "validate")]
    pub validate: Vec<PathBuf>,
    /// Held-out run: scored beside the validation runs, never used to choose anything (repeatable).
    #[arg(long = "held-out", value_name = "RUN.csv")]
    pub held_out: Vec<PathBuf>,
    /// Frequency-domain validation (chirp) run.
    #[arg(long)]
    pub chirp: Option<PathBuf>,
    /// Steady-state run for the noise fit.
    #[arg(long)]
    pub steady: Option<PathBuf>,
    /// Output column to model (repeatable; default: all outputs present).
    #[arg(long = "output")]
    pub outputs: Vec<String>,
    /// Apply an effect from the catalog, parameters fitted (repeatable).
    #[arg(long = "add-effect", value_enum, value_name = "ID")]
    pub add_effects: Vec<EffectId>,
    /// Rounds of the missing-physics loop: diagnose, add the top significant effect or structural
    /// refinement (refitted), repeat; stops early when nothing is significant.
    #[arg(long = "auto-effects", value_name = "ROUNDS")]
    pub auto_effects: Option<usize>,
    /// Column mapping ROLE=COLUMN, roles time|input|output|aux (repeatable).
    #[arg(long = "map")]
    pub maps: Vec<String>,
    /// Start from the clusters of a saved model.json (e.g. one exported from the app) instead of
    /// the automatic proposal, for every output the model holds.
    #[arg(long = "clusters", value_name = "MODEL.json")]
    pub clusters_from: Option<PathBuf>,
    /// Sample time in seconds, for files without a time column.
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true, value_parser = super::positive_secs)]
    pub sample_time: Option<f64>,
    /// Read logs with repeated or irregular time stamps: rows sharing a time stamp are merged into
    /// their mean and the time axis is resampled onto a uniform grid (for every run).
    #[arg(long)]
    pub resample: bool,
    /// Where results go.
    #[arg(long, default_value = DEFAULT_OUT)]
    pub out: PathBuf,
    /// Print no stage lines on stderr while the batch works.
    #[arg(long)]
    pub quiet: bool,
}

impl BatchArgs {
    /// What the command line overrides in the project.
    pub fn overrides(&self) -> Overrides {
        Overrides {
            project: self.project.clone(),
            ident: self.ident.clone(),
            validate: self.validate.clone(),
            held_out: self.held_out.clone(),
            chirp: self.chirp.clone(),
            steady: self.steady.clone(),
            outputs: self.outputs.clone(),
            add_effects: self.add_effects.clone(),
            auto_effects: self.auto_effects,
            maps: self.maps.clone(),
            clusters_from: self.clusters_from.clone(),
            sample_time: self.sample_time,
            resample: self.resample,
        }
    }

    /// The project the command line asks for: the given file, else the bundled one, else none (when
    /// runs are given on the command line), with the command line's overrides applied.
    pub fn project(&self) -> Result<Project> {
        self.overrides().project()
    }

    /// The options given that only a batch reads (for refusing them elsewhere), by their flags.
    pub fn batch_only_flags(&self) -> Vec<&'static str> {
        let given = [
            ("--ident", self.ident.is_some()),
            ("--validate", !self.validate.is_empty()),
            ("--held-out", !self.held_out.is_empty()),
            ("--chirp", self.chirp.is_some()),
            ("--steady", self.steady.is_some()),
            ("--auto-effects", self.auto_effects.is_some()),
            ("--map", !self.maps.is_empty()),
            ("--clusters", self.clusters_from.is_some()),
            ("--sample-time", self.sample_time.is_some()),
            ("--resample", self.resample),
            ("--out", self.out != Path::new(DEFAULT_OUT)),
            ("--quiet", self.quiet),
        ];
        given.into_iter().filter(|(_, set)| *set).map(|(flag, _)| flag).collect()
    }
}
