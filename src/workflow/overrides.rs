//! A project and what the command line changes in it. Every option applies to the runs however
//! they were named (in the project file or on the command line) or is refused with the reason:
//! nothing given is silently ignored.
use std::path::PathBuf;

use anyhow::{Context, Result};

use crate::core::effects::EffectId;
use crate::io::project::{LoadSpec, Project, RunSource, bundled_project_path, load_project};

/// What the command line says about a batch: the project file, runs by role, and options.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Overrides {
    /// The project file; without one (and without `ident`) the bundled sample project.
    pub project: Option<PathBuf>,
    pub ident: Option<PathBuf>,
    pub validate: Vec<PathBuf>,
    pub held_out: Vec<PathBuf>,
    pub chirp: Option<PathBuf>,
    pub steady: Option<PathBuf>,
    pub outputs: Vec<String>,
    /// Added after the project's own `add_effects`.
    pub add_effects: Vec<EffectId>,
    pub auto_effects: Option<usize>,
    /// `--map ROLE=COLUMN`: over every run's own map, role by role.
    pub maps: Vec<String>,
    pub clusters_from: Option<PathBuf>,
    /// Over every run's own sample time (a run whose time column is mapped then refuses to load:
    /// its time would be given twice).
    pub sample_time: Option<f64>,
    /// Resample every run.
    pub resample: bool,
}

impl Overrides {
    /// The load options the command line gives every run.
    fn load(&self) -> LoadSpec {
        LoadSpec {
            map: self.maps.clone(),
            sample_time: self.sample_time,
            resample: self.resample,
            ..LoadSpec::default()
        }
    }

    /// The project the command line asks for: the given file, else the bundled one (unless runs are
    /// given on the command line), with every override applied.
    pub fn project(&self) -> Result<Project> {
        let mut project = match (&self.project, &self.ident) {
            (Some(path), _) => load_project(path)?,
            (None, Some(_)) => empty_project(),
            (None, None) => load_project(&bundled_project_path()?)?,
        };
        let cli_load = self.load();
        cli_load.to_options().context("command-line load options")?;
        let runs = project.ident.iter_mut().chain(&mut project.validate).chain(&mut project.held_out);
        for source in runs.chain(&mut project.chirp).chain(&mut project.steady) {
            source.load = source
                .load
                .with_command_line(&cli_load)
                .with_context(|| format!("the load options of {}", source.path.display()))?;
        }
        let run_load = project.load.with_command_line(&cli_load).context("command-line load options")?;
        let cwd = PathBuf::from(".");
        let src = |p: &PathBuf| RunSource { path: cwd.join(p), load: run_load.clone() };
        if let Some(p) = &self.ident {
            project.ident = vec![src(p)];
        }
        if !self.validate.is_empty() {
            project.validate = self.validate.iter().map(src).collect();
        }
        if !self.held_out.is_empty() {
            project.held_out = self.held_out.iter().map(src).collect();
        }
        if let Some(p) = &self.chirp {
            project.chirp = Some(src(p));
        }
        if let Some(p) = &self.steady {
            project.steady = Some(src(p));
        }
        self.apply_model_options(&mut project);
        Ok(project)
    }

    /// The options about the models rather than the runs.
    fn apply_model_options(&self, project: &mut Project) {
        if let Some(rounds) = self.auto_effects {
            project.auto_effects = rounds;
        }
        if !self.outputs.is_empty() {
            project.outputs = self.outputs.clone();
        }
        project.add_effects.extend(self.add_effects.iter().copied());
        if let Some(p) = &self.clusters_from {
            project.clusters_from = Some(p.clone());
        }
    }
}

/// The project of a command line that names its runs without a project file.
fn empty_project() -> Project {
    Project {
        name: "command line".into(),
        ident: vec![],
        validate: vec![],
        held_out: vec![],
        chirp: None,
        steady: None,
        outputs: vec![],
        add_effects: vec![],
        auto_effects: 0,
        settings: Default::default(),
        segments: Default::default(),
        clusters: Default::default(),
        clusters_from: None,
        steps_from: None,
        load: LoadSpec::default(),
    }
}
