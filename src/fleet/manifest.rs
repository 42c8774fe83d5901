//! The fleet manifest (TOML): engines, each with its reference and its runs. Paths are relative to
//! the manifest; a `[engine.load]` table reads the engine's runs like a project's `[load]`, and a run
//! may override its window and quality column.
//!
//! ```toml
//! name = "JetCat P300-PRO"
//! [[engine]]
//! name = "P300 #1"
//! reference = "p300/model.json"              # a saved model, or
//! # reference_project = "p300/project.toml"  # a project identified once
//! runs = [ { path = "runA.csv", date = "2023-01-09", name = "A", window = "935:2603" } ]
//! [engine.load]
//! map = ["time=t_est_s", "input=pump_V", "output=rpm"]
//! ```
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use serde::Deserialize;

use crate::io::project::{LoadSpec, RunSource, resolve_path};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ManifestFile {
    name: Option<String>,
    #[serde(default)]
    engine: Vec<EngineFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct EngineFile {
    name: String,
    reference: Option<String>,
    reference_project: Option<String>,
    #[serde(default)]
    load: LoadSpec,
    #[serde(default)]
    runs: Vec<RunFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RunFile {
    path: String,
    date: Option<String>,
    name: Option<String>,
    window: Option<String>,
    quality: Option<String>,
}

/// Where an engine's reference model comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum ReferenceSource {
    /// A saved model.json.
    Model(PathBuf),
    /// A project, identified once as the batch identifies it.
    Project(PathBuf),
}

/// A calendar date, `YYYY-MM-DD`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Date {
    pub year: u16,
    pub month: u8,
    pub day: u8,
}

impl std::fmt::Display for Date {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:04}-{:02}-{:02}", self.year, self.month, self.day)
    }
}

impl std::str::FromStr for Date {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let bad = || format!("date '{text}' is not a calendar date written YYYY-MM-DD");
        let parts: Vec<&str> = text.split('-').collect();
        let [y, m, d] = parts.as_slice() else { return Err(bad()) };
        let digits = |s: &str, n: usize| s.len() == n && s.bytes().all(|b| b.is_ascii_digit());
        if !(digits(y, 4) && digits(m, 2) && digits(d, 2)) {
            return Err(bad());
        }
        let (year, month, day): (u16, u8, u8) =
            (y.parse().map_err(|_| bad())?, m.parse().map_err(|_| bad())?, d.parse().map_err(|_| bad())?);
        let leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
        let days = match month {
            1 | 3 | 5 | 7 | 8 | 10 | 12 => 31,
            4 | 6 | 9 | 11 => 30,
            2 if leap => 29,
            2 => 28,
            _ => return Err(bad()),
        };
        if day == 0 || day > days {
            return Err(bad());
        }
        Ok(Self { year, month, day })
    }
}

/// One run of an engine.
#[derive(Clone, Debug, PartialEq)]
pub struct FleetRun {
    pub name: String,
    pub date: Option<Date>,
    pub source: RunSource,
}

/// One engine: its reference and its runs in trend order (by date where every run has one, else as
/// listed).
#[derive(Clone, Debug, PartialEq)]
pub struct Engine {
    pub name: String,
    pub reference: ReferenceSource,
    pub runs: Vec<FleetRun>,
}

/// A checked manifest: every path resolved and present, every date a date.
#[derive(Clone, Debug, PartialEq)]
pub struct Manifest {
    pub name: String,
    pub engines: Vec<Engine>,
}

/// Read and check the manifest at `path`.
pub fn load_manifest(path: &Path) -> Result<Manifest> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read fleet manifest {}", path.display()))?;
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    parse_manifest(&text, &base, &path.display().to_string())
}

/// Parse a manifest from TOML text; `base` is the folder relative paths start from, `origin` names
/// the file in errors.
pub fn parse_manifest(text: &str, base: &Path, origin: &str) -> Result<Manifest> {
    let file: ManifestFile = toml::from_str(text).with_context(|| format!("fleet manifest {origin}"))?;
    if file.engine.is_empty() {
        bail!(
            "fleet manifest {origin} names no engine: add an [[engine]] table with a name, a reference and runs"
        );
    }
    let mut names = BTreeSet::new();
    let mut engines = Vec::with_capacity(file.engine.len());
    for engine in &file.engine {
        if !names.insert(engine.name.as_str()) {
            bail!(
                "fleet manifest {origin}: two engines are named '{}'; each needs its own name",
                engine.name
            );
        }
        engines.push(
            engine_of(engine, base)
                .with_context(|| format!("fleet manifest {origin}, engine '{}'", engine.name))?,
        );
    }
    Ok(Manifest { name: file.name.unwrap_or_else(|| origin.to_owned()), engines })
}

fn engine_of(engine: &EngineFile, base: &Path) -> Result<Engine> {
    let existing = |raw: &str, what: &str| -> Result<PathBuf> {
        let path = resolve_path(raw, base)?;
        if !path.is_file() {
            bail!("{what} '{raw}' does not exist (looked for {})", path.display());
        }
        Ok(path)
    };
    let reference = match (&engine.reference, &engine.reference_project) {
        (Some(model), None) => ReferenceSource::Model(existing(model, "reference")?),
        (None, Some(project)) => ReferenceSource::Project(existing(project, "reference_project")?),
        (Some(_), Some(_)) => bail!("give either reference (a model.json) or reference_project, not both"),
        (None, None) => {
            bail!("no reference: give reference = \"model.json\" or reference_project = \"project.toml\"")
        }
    };
    engine.load.to_options().context("[engine.load]")?;
    if engine.runs.is_empty() {
        bail!("no runs: give runs = [ {{ path = \"run.csv\", date = \"2023-02-22\" }}, ... ]");
    }
    let mut runs = Vec::with_capacity(engine.runs.len());
    let mut seen = BTreeSet::new();
    for (i, run) in engine.runs.iter().enumerate() {
        let label = run.name.clone().unwrap_or_else(|| run.path.clone());
        let context = || format!("run {} ('{label}')", i + 1);
        let path = existing(&run.path, "run file").with_context(context)?;
        let date = run
            .date
            .as_deref()
            .map(str::parse::<Date>)
            .transpose()
            .map_err(anyhow::Error::msg)
            .with_context(context)?;
        let name = run.name.clone().unwrap_or_else(|| {
            path.file_stem().map_or_else(|| format!("run{}", i + 1), |s| s.to_string_lossy().into_owned())
        });
        if !seen.insert(name.clone()) {
            bail!("two runs are named '{name}': give each a name = \"...\"");
        }
        let load = LoadSpec {
            window: run.window.clone().or_else(|| engine.load.window.clone()),
            quality: run.quality.clone().or_else(|| engine.load.quality.clone()),
            ..engine.load.clone()
        };
        load.to_options().with_context(context)?;
        runs.push(FleetRun { name, date, source: RunSource { path, load } });
    }
    if runs.iter().all(|r| r.date.is_some()) {
        runs.sort_by_key(|r| r.date);
    }
    Ok(Engine { name: engine.name.clone(), reference, runs })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn dates_are_checked() {
        assert_eq!("2024-02-29".parse::<Date>().unwrap().to_string(), "2024-02-29");
        for bad in ["2023-02-29", "2023-13-01", "23-01-01", "2023-1-01", "2023-01-00", "today"] {
            assert!(bad.parse::<Date>().is_err(), "{bad}");
        }
    }
}
