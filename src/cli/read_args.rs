//! How a command reads a run file: the options `inspect` and `predict` share with a project's
//! `[load]` table (`--map`, `--sample-time`, `--window`, `--quality`, `--resample`, `--invalid`),
//! and a project whose options (the run's own entry, else its `[load]`) they start from.
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Args;

use crate::io::csv_run::LoadOptions;
use crate::io::paths::same_file;
use crate::io::project::{LoadSpec, load_project};

#[derive(Debug, Args, Default, Clone)]
pub struct ReadArgs {
    /// Column mapping ROLE=COLUMN, roles time|input|output|aux (repeatable).
    #[arg(long = "map", value_name = "ROLE=COLUMN")]
    pub maps: Vec<String>,
    /// Sample time in seconds, for files without a time column.
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true, value_parser = super::positive_secs)]
    pub sample_time: Option<f64>,
    /// Keep only samples START:END (0-based, END excluded), or seconds with `s`: 12.5s:80s; or
    /// `auto`: from the end of the start-up run-up to the fuel cut, found from the signals.
    #[arg(long, value_name = "START:END")]
    pub window: Option<String>,
    /// A 0/1 column marking good samples; bad ones are interpolated.
    #[arg(long, value_name = "COLUMN")]
    pub quality: Option<String>,
    /// Resample a non-uniform time axis onto a uniform grid (repeated time stamps merged).
    #[arg(long)]
    pub resample: bool,
    /// Values a channel's logger writes for "no reading", which become gaps (repeatable).
    #[arg(long = "invalid", value_name = "CHANNEL=V1,V2")]
    pub invalid: Vec<String>,
    /// Read the run as this project reads it: the project's own entry for the file when it lists
    /// it (its window, say), else its `[load]` table; the options above go over them.
    #[arg(long, value_name = "PROJECT.toml")]
    pub project: Option<PathBuf>,
}

impl ReadArgs {
    /// The options `file` is read with.
    pub fn options(&self, file: &Path) -> Result<LoadOptions> {
        let own = LoadSpec {
            map: self.maps.clone(),
            sample_time: self.sample_time,
            window: self.window.clone(),
            quality: self.quality.clone(),
            resample: self.resample,
            ..LoadSpec::default()
        };
        let spec = match &self.project {
            Some(path) => project_spec(path, file)?.with_command_line(&own)?,
            None => own,
        };
        let mut options = spec.to_options()?;
        if let Some(window) = &self.window {
            options.window = Some(window.parse().context("--window")?);
        }
        if let Some(quality) = &self.quality {
            options.quality = Some(quality.clone());
        }
        options.with_invalid_specs(&self.invalid).context("--invalid")
    }
}

/// How `project` reads `file`: the options of its entry for that file, else its `[load]` table.
fn project_spec(project: &Path, file: &Path) -> Result<LoadSpec> {
    let project = load_project(project)?;
    let sources = project.ident.iter().chain(&project.validate).chain(&project.held_out);
    let entry = sources.chain(&project.chirp).chain(&project.steady).find(|s| same_file(&s.path, file));
    Ok(entry.map_or(project.load, |source| source.load.clone()))
}
