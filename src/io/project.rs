//! Project files (TOML): which runs play which role, how to read them, and per-output settings.
//!
//! ```toml
//! name = "SR-30 sample runs"
//! ident = "ident.csv"                      # paths are relative to the project file; a list
//!                                          # of runs is joined end to end (`core::run::join_runs`);
//! validate = ["validation.csv"]            # "$VAR/..." takes the folder from an environment variable
//! chirp = "chirp.csv"
//! steady = "steady.csv"
//! outputs = ["shaft_speed_rpm", "thrust_n"]  # default: every output of the identification run
//! add_effects = []
//! steps_from = "rpm_setpoint"             # detect the steps on this channel (default: the input)
//! clusters_from = "jetid-out/model.json"  # start from a saved model's clusters (per output; an
//!                                          # output's own `clusters` below take precedence)
//! [load]                                   # how to read every run (each run may override)
//! map = ["input=pump_V", "output=rpm"]
//! [[validate]]                             # a run may also be a table with its own options
//! path = "runA.csv"
//! window = "935:2603"
//! [output.shaft_speed_rpm]                 # per-output settings
//! na = 19
//! nb = 3
//! static_order = 2
//! segments = [[600, 626, 950], ...]        # optional manual segments: start, step, end (samples)
//! clusters = [{ kind = "Pole", centre = [0.936, 0.0], radius = 0.01 }]
//! dead_time_samples = 8                    # input dead time of a model built from `clusters`
//! initial_state = "estimated"              # or "steady": where scored runs start
//! polish = "within_clusters"               # or "free": where the polish may move a root
//! spool_schedule = "power_balance"         # or "exponential" (default): the form of a fitted
//!                                          # scheduled time constant
//! ```
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use serde::{Deserialize, Serialize};

use crate::core::effects::EffectId;
use crate::core::identification::arx::ArxOrders;
use crate::core::identification::cluster::Cluster;
use crate::core::identification::initial_state::InitialState;
use crate::core::identification::segment::{Segment, segment_label};
use crate::core::identification::settings::{OutputSettings, PolishRegion, SpoolSchedule};
use crate::io::csv_run::LoadOptions;

/// How to read runs: the command line's `--map`, `--sample-time`, `--window`, `--quality`, `--resample`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LoadSpec {
    pub map: Vec<String>,
    pub sample_time: Option<f64>,
    pub window: Option<String>,
    pub quality: Option<String>,
    pub resample: bool,
    /// Per channel, the values its logger writes for "no reading" (e.g. `T_inlet_C = [-3276.8,
    /// 3276.8]`): they become gaps.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub invalid: BTreeMap<String, Vec<f64>>,
    /// Per channel, its unit where the column name does not say it (`units = { PR = "-" }`).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub units: BTreeMap<String, String>,
}

impl LoadSpec {
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    pub fn to_options(&self) -> Result<LoadOptions> {
        let mut options = LoadOptions::from_cli(
            &self.map,
            self.sample_time,
            self.window.as_deref(),
            self.quality.as_deref(),
            self.resample,
        )?;
        options.invalid = self.invalid.clone();
        options.units = self.units.clone();
        Ok(options)
    }

    /// `self` with the command line's options over it: a `--map` role replaces the same role of
    /// `self`'s map (the outputs, or the auxiliary channels, as a list: giving one replaces them
    /// all), a sample time replaces `self`'s, and `--resample` is added; `self`'s window, quality
    /// column, sentinels and units stay.
    pub fn with_command_line(&self, cli: &LoadSpec) -> Result<LoadSpec> {
        use crate::io::csv_run::{MapSpec, Role};
        let role = |spec: &String| spec.parse::<MapSpec>().map(|m| m.role);
        let cli_roles = cli.map.iter().map(role).collect::<Result<Vec<Role>, _>>()?;
        let mut map = Vec::new();
        for spec in &self.map {
            if !cli_roles.contains(&role(spec)?) {
                map.push(spec.clone());
            }
        }
        map.extend(cli.map.iter().cloned());
        Ok(LoadSpec {
            map,
            sample_time: cli.sample_time.or(self.sample_time),
            resample: self.resample || cli.resample,
            ..self.clone()
        })
    }

    /// `self` with the fields `over` sets taken from `over`.
    fn overridden_by(&self, over: &LoadSpec) -> LoadSpec {
        LoadSpec {
            map: if over.map.is_empty() { self.map.clone() } else { over.map.clone() },
            sample_time: over.sample_time.or(self.sample_time),
            window: over.window.clone().or_else(|| self.window.clone()),
            quality: over.quality.clone().or_else(|| self.quality.clone()),
            resample: self.resample || over.resample,
            invalid: if over.invalid.is_empty() { self.invalid.clone() } else { over.invalid.clone() },
            units: if over.units.is_empty() { self.units.clone() } else { over.units.clone() },
        }
    }
}

/// A run in a project: a path, or a table with a path and its own load options.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(
    untagged,
    expecting = "a run is a path in quotes (\"runA.csv\") or a table with a path and load options ({ path = \"runA.csv\", window = \"935:2603\" })"
)]
pub enum RunEntry {
    Path(String),
    Table {
        path: String,
        #[serde(flatten)]
        load: LoadSpec,
    },
}

/// The identification run, or several runs joined end to end.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(
    untagged,
    expecting = "ident is a run (a path in quotes, \"ident.csv\", or a table { path = \"ident.csv\", window = \"880:2400\" }) or a list of runs joined end to end ([\"runB.csv\", \"runD.csv\"])"
)]
pub enum IdentEntry {
    One(RunEntry),
    Many(Vec<RunEntry>),
}

/// Per-output settings as written in a project file.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OutputSpec {
    pub na: Option<usize>,
    pub nb: Option<usize>,
    pub nk: Option<usize>,
    pub static_order: Option<usize>,
    pub min_segments: Option<usize>,
    pub refine: Option<bool>,
    pub segments: Option<Vec<[usize; 3]>>,
    pub clusters: Option<Vec<Cluster>>,
    /// Input dead time (samples) of a model built from the given `clusters`.
    pub dead_time_samples: Option<usize>,
    /// Where scored runs are simulated from: "estimated" (default) or "steady".
    pub initial_state: Option<InitialState>,
    /// Where the polish may move a cluster's root: "within_clusters" (default) or "free".
    pub polish: Option<PolishRegion>,
    /// The form of a fitted scheduled time constant: "exponential" (default) or "power_balance".
    pub spool_schedule: Option<SpoolSchedule>,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ProjectFile {
    pub name: Option<String>,
    pub ident: Option<IdentEntry>,
    pub validate: Vec<RunEntry>,
    /// Held-out runs: scored beside the validation runs, never used to choose anything.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub held_out: Vec<RunEntry>,
    pub chirp: Option<RunEntry>,
    pub steady: Option<RunEntry>,
    pub outputs: Vec<String>,
    pub add_effects: Vec<EffectId>,
    /// Rounds of the missing-physics loop: take the top significant diagnosis, refit, repeat.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub auto_effects: Option<usize>,
    pub clusters_from: Option<String>,
    pub steps_from: Option<String>,
    pub load: LoadSpec,
    pub output: BTreeMap<String, OutputSpec>,
}

/// A run to load: its resolved path and options.
#[derive(Clone, Debug, PartialEq)]
pub struct RunSource {
    pub path: PathBuf,
    pub load: LoadSpec,
}

/// A project with paths resolved and settings checked.
#[derive(Clone, Debug, PartialEq)]
pub struct Project {
    pub name: String,
    /// The identification run(s); several are joined end to end.
    pub ident: Vec<RunSource>,
    /// Runs the effects and the diagnosis are scored on (and every model is compared on).
    pub validate: Vec<RunSource>,
    /// Runs every model is compared on but nothing is chosen by: a fair test of the final model.
    pub held_out: Vec<RunSource>,
    pub chirp: Option<RunSource>,
    pub steady: Option<RunSource>,
    pub outputs: Vec<String>,
    pub add_effects: Vec<EffectId>,
    /// Rounds of the missing-physics loop after `add_effects` (0: none): each round adds the
    /// diagnosis's top significant effect or refinement, refitted, and the next round diagnoses the
    /// result; it stops early when nothing is significant.
    pub auto_effects: usize,
    pub settings: BTreeMap<String, OutputSettings>,
    pub segments: BTreeMap<String, Vec<Segment>>,
    pub clusters: BTreeMap<String, Vec<Cluster>>,
    /// A saved model.json whose clusters are used for outputs without clusters of their own.
    pub clusters_from: Option<PathBuf>,
    /// Channel the identification steps are detected on (default: the input), e.g. a set-point
    /// when the input is a closed-loop controller's output.
    pub steps_from: Option<String>,
    /// How the project reads its runs unless a run says otherwise (its `[load]` table): runs
    /// added on the command line are read this way too.
    pub load: LoadSpec,
}

impl Project {
    /// Settings for an output: the project's, else the defaults for its name.
    pub fn settings_for(&self, output: &str) -> OutputSettings {
        self.settings.get(output).cloned().unwrap_or_else(|| OutputSettings::for_output(output))
    }
}

/// Expand a leading `$VAR` (or `${VAR}`) and resolve relative to `base`.
pub fn resolve_path(raw: &str, base: &Path) -> Result<PathBuf> {
    let expanded = if let Some(rest) = raw.strip_prefix('$') {
        let (var, tail) = if let Some(braced) = rest.strip_prefix('{') {
            let end = braced.find('}').ok_or_else(|| anyhow!("unclosed '${{' in path '{raw}'"))?;
            (&braced[..end], &braced[end + 1..])
        } else {
            let end = rest.find(['/', '\\']).unwrap_or(rest.len());
            (&rest[..end], &rest[end..])
        };
        let value = std::env::var(var)
            .map_err(|_| anyhow!("path '{raw}' needs the environment variable {var}, which is not set"))?;
        format!("{value}{tail}")
    } else {
        raw.to_owned()
    };
    let path = PathBuf::from(expanded);
    Ok(if path.is_absolute() { path } else { base.join(path) })
}

fn source(entry: &RunEntry, base: &Path, defaults: &LoadSpec) -> Result<RunSource> {
    let (raw, own) = match entry {
        RunEntry::Path(p) => (p.as_str(), LoadSpec::default()),
        RunEntry::Table { path, load } => (path.as_str(), load.clone()),
    };
    let load = defaults.overridden_by(&own);
    load.to_options().with_context(|| format!("load options of run '{raw}'"))?;
    Ok(RunSource { path: resolve_path(raw, base)?, load })
}

fn output_settings(name: &str, spec: &OutputSpec) -> Result<OutputSettings> {
    let mut s = OutputSettings::for_output(name);
    s.orders = ArxOrders {
        na: spec.na.unwrap_or(s.orders.na),
        nb: spec.nb.unwrap_or(s.orders.nb),
        nk: spec.nk.unwrap_or(s.orders.nk),
    };
    s.orders.check().with_context(|| format!("[output.{name}]"))?;
    if let Some(order) = spec.static_order {
        use crate::core::identification::static_map::MAX_ORDER;
        if !(1..=MAX_ORDER).contains(&order) {
            bail!(
                "[output.{name}] static_order = {order} is out of range: the static map's order is 1 (a gain) to \
                 {MAX_ORDER}; leave it out to let the steady points choose (leave-one-out, up to 3)"
            );
        }
        s.static_order = Some(order);
    }
    if let Some(m) = spec.min_segments {
        s.cluster.min_segments = Some(m);
    }
    if let Some(r) = spec.refine {
        s.refine = r;
    }
    // An input delay the project gives is the user's; the data's estimate is not wanted then.
    if spec.nk.is_some() {
        s.estimate_dead_time = false;
    }
    s.dead_time_samples = spec.dead_time_samples.or(s.dead_time_samples);
    s.initial_state = spec.initial_state.unwrap_or(s.initial_state);
    s.polish = spec.polish.unwrap_or(s.polish);
    s.spool_schedule = spec.spool_schedule.unwrap_or(s.spool_schedule);
    Ok(s)
}

/// Parse a project from TOML text; `base` is the folder relative paths start from.
pub fn parse_project(text: &str, base: &Path, origin: &str) -> Result<Project> {
    let file: ProjectFile = toml::from_str(text).with_context(|| format!("project file {origin}"))?;
    project_of(&file, base, origin)
}

/// The project a [`ProjectFile`] describes (however it was written: TOML, or the Python package's
/// keyword arguments), its paths resolved against `base` and its settings checked.
pub fn project_of(file: &ProjectFile, base: &Path, origin: &str) -> Result<Project> {
    let defaults = &file.load;
    defaults.to_options().with_context(|| format!("[load] of project file {origin}"))?;
    let mut settings = BTreeMap::new();
    let mut segments = BTreeMap::new();
    let mut clusters = BTreeMap::new();
    for (name, spec) in &file.output {
        settings.insert(
            name.clone(),
            output_settings(name, spec).with_context(|| format!("project file {origin}"))?,
        );
        if let Some(bounds) = &spec.segments {
            let segs = bounds
                .iter()
                .enumerate()
                .map(|(i, [start, step_at, end])| Segment {
                    label: segment_label(i),
                    start: *start,
                    step_at: *step_at,
                    end: *end,
                })
                .collect();
            segments.insert(name.clone(), segs);
        }
        if let Some(c) = &spec.clusters {
            clusters.insert(name.clone(), c.clone());
        }
    }
    let source = |e: &RunEntry| source(e, base, defaults).with_context(|| format!("project file {origin}"));
    let opt = |e: &Option<RunEntry>| e.as_ref().map(source).transpose();
    Ok(Project {
        name: file.name.clone().unwrap_or_else(|| origin.to_owned()),
        ident: match &file.ident {
            None => Vec::new(),
            Some(IdentEntry::One(e)) => vec![source(e)?],
            Some(IdentEntry::Many(list)) => list.iter().map(source).collect::<Result<_>>()?,
        },
        validate: file.validate.iter().map(source).collect::<Result<_>>()?,
        held_out: file.held_out.iter().map(source).collect::<Result<_>>()?,
        chirp: opt(&file.chirp)?,
        steady: opt(&file.steady)?,
        outputs: file.outputs.clone(),
        add_effects: file.add_effects.clone(),
        auto_effects: file.auto_effects.unwrap_or(0),
        settings,
        segments,
        clusters,
        clusters_from: file
            .clusters_from
            .as_deref()
            .map(|raw| resolve_path(raw, base))
            .transpose()
            .with_context(|| format!("project file {origin}"))?,
        steps_from: file.steps_from.clone(),
        load: file.load.clone(),
    })
}

pub fn load_project(path: &Path) -> Result<Project> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read project file {}", path.display()))?;
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    parse_project(&text, &base, &path.display().to_string())
}

/// The bundled sample runs: `sample_runs/` under the current folder, else beside the sources.
pub fn bundled_samples_dir() -> Option<PathBuf> {
    let candidates =
        [PathBuf::from("sample_runs"), Path::new(env!("CARGO_MANIFEST_DIR")).join("../sample_runs")];
    candidates.into_iter().find(|p| p.join("sr30").is_dir())
}

/// The default project of `jetid --batch`.
pub fn bundled_project_path() -> Result<PathBuf> {
    let Some(dir) = bundled_samples_dir() else {
        bail!(
            "no project given and the bundled sample runs (sample_runs/sr30) were not found; pass a project file or --ident"
        );
    };
    Ok(dir.join("sr30").join("project.toml"))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn parses_paths_tables_and_settings() {
        let text = r#"
            ident = "ident.csv"
            clusters_from = "out/model.json"
            validate = ["val.csv", { path = "/abs/runA.csv", window = "935:2603" }]
            [load]
            map = ["input=pump_V"]
            [output.rpm]
            na = 4
            nb = 1
            segments = [[10, 20, 60], [60, 70, 120]]
            clusters = [{ kind = "Pole", centre = [0.9, 0.0], radius = 0.02 }]
        "#;
        let p = parse_project(text, Path::new("/data"), "t.toml").unwrap();
        assert_eq!(p.ident[0].path, PathBuf::from("/data/ident.csv"));
        let two = parse_project(
            "ident = [\"b.csv\", { path = \"d.csv\", window = \"9:99\" }]",
            Path::new("/x"),
            "t",
        )
        .unwrap();
        assert_eq!(two.ident.len(), 2);
        assert_eq!(two.ident[1].load.window.as_deref(), Some("9:99"));
        assert_eq!(p.validate[1].path, PathBuf::from("/abs/runA.csv"));
        assert_eq!(p.validate[1].load.window.as_deref(), Some("935:2603"));
        assert_eq!(p.validate[1].load.map, vec!["input=pump_V".to_owned()]);
        assert_eq!(p.settings["rpm"].orders.na, 4);
        assert_eq!(p.segments["rpm"][1].label, "B");
        assert_eq!(p.clusters["rpm"].len(), 1);
        assert_eq!(p.clusters_from, Some(PathBuf::from("/data/out/model.json")));
    }

    #[test]
    fn bad_projects_are_errors() {
        assert!(parse_project("idnet = \"x.csv\"", Path::new("."), "t").is_err());
        assert!(parse_project("[output.y]\nna = 0", Path::new("."), "t").is_err());
        assert!(parse_project("[load]\nmap = [\"nonsense\"]", Path::new("."), "t").is_err());
        let err =
            parse_project("ident = \"$JETID_SURELY_UNSET_VAR/x.csv\"", Path::new("."), "t").unwrap_err();
        assert!(format!("{err:#}").contains("JETID_SURELY_UNSET_VAR"));
    }
}
