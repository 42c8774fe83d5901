//! The arguments of `jetid --batch` and the project they describe.
use std::collections::BTreeMap;
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

use crate::core::effects::EffectId;
use crate::io::project::{LoadSpec, Project, RunSource, bundled_project_path, load_project};

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
    #[arg(long)]
    pub sample_time: Option<f64>,
    /// Read logs with repeated or irregular time stamps: rows sharing a time stamp are merged into
    /// their mean and the time axis is resampled onto a uniform grid (for every run).
    #[arg(long)]
    pub resample: bool,
    /// Where results go.
    #[arg(long, default_value = "jetid-out")]
    pub out: PathBuf,
    /// Print no stage lines on stderr while the batch works.
    #[arg(long)]
    pub quiet: bool,
}

impl BatchArgs {
    /// The project the command line asks for: the given file, else the bundled one, else none (when
    /// runs are given on the command line), with the command line's overrides applied.
    pub fn project(&self) -> Result<Project> {
        let mut project = match (&self.project, &self.ident) {
            (Some(path), _) => load_project(path)?,
            (None, Some(_)) => Project {
                name: "command line".into(),
                ident: vec![],
                validate: vec![],
                held_out: vec![],
                chirp: None,
                steady: None,
                outputs: vec![],
                add_effects: vec![],
                auto_effects: 0,
                settings: BTreeMap::new(),
                segments: BTreeMap::new(),
                clusters: BTreeMap::new(),
                clusters_from: None,
                steps_from: None,
            },
            (None, None) => load_project(&bundled_project_path()?)?,
        };
        let cli_load = LoadSpec {
            map: self.maps.clone(),
            sample_time: self.sample_time,
            resample: self.resample,
            ..LoadSpec::default()
        };
        cli_load.to_options().context("command-line load options")?;
        let cwd = PathBuf::from(".");
        let src = |p: &PathBuf| RunSource { path: cwd.join(p), load: cli_load.clone() };
        if let Some(p) = &self.ident {
            project.ident = vec![src(p)];
        }
        if !self.validate.is_empty() {
            project.validate = self.validate.iter().map(src).collect();
        }
        if !self.held_out.is_empty() {
            project.held_out = self.held_out.iter().map(src).collect();
        }
        if let Some(rounds) = self.auto_effects {
            project.auto_effects = rounds;
        }
        if let Some(p) = &self.chirp {
            project.chirp = Some(src(p));
        }
        if let Some(p) = &self.steady {
            project.steady = Some(src(p));
        }
        if !self.outputs.is_empty() {
            project.outputs = self.outputs.clone();
        }
        project.add_effects.extend(self.add_effects.iter().cloned());
        if let Some(p) = &self.clusters_from {
            project.clusters_from = Some(p.clone());
        }
        if self.resample {
            let sources = project.ident.iter_mut().chain(&mut project.validate).chain(&mut project.held_out);
            for source in sources.chain(&mut project.chirp).chain(&mut project.steady) {
                source.load.resample = true;
            }
        }
        Ok(project)
    }
}
