//! The native half of the `jetid` Python package: the jetid crate's workflow behind a narrow
//! interface of text and bytes. Settings, models, reports and scores cross as JSON (the formats of
//! project files, model.json, report.json and fleet.csv); signals cross as little-endian `f64`
//! bytes, which numpy reads and writes without a copy per element. The Python half
//! (`python/jetid/__init__.py`) turns them into data frames, arrays and classes.
//!
//! Every call releases the GIL while the core computes, and every error jetid reports is raised as
//! `jetid.JetidError` with the message the command line prints.
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, anyhow};
use clap::Parser;
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

use jetid::core::effects::{EffectId, ExtendedModel};
use jetid::core::run::Run;
use jetid::io::csv_run::{LoadNotes, LoadOptions, RunFileError, load_run_with_notes, parse_run_with_notes};
use jetid::io::model_file::{ModelFile, parse_model, read_model, write_model};
use jetid::io::project::{Project, ProjectFile, RunSource, project_of};
use jetid::workflow::model::add_project_effects;
use jetid::workflow::project_model::{BuiltOutput, Covariance, build_project, share_the_spool, with_effects};
use jetid::workflow::runs::{Runs, load_runs_with, load_scored_runs};

mod fleet;

create_exception!(
    _jetid,
    JetidError,
    PyException,
    "An error jetid reports, with the command line's message."
);

/// `err` as the exception Python sees, worded as the command line words it.
fn raise(err: anyhow::Error) -> PyErr {
    JetidError::new_err(jetid::cli::error_message(&err))
}

/// Named columns as they cross from Python: each a name and its values as little-endian `f64`s.
type Columns = Vec<(String, Vec<u8>)>;

/// The values of a column from its bytes.
fn floats(name: &str, bytes: &[u8]) -> anyhow::Result<Vec<f64>> {
    if !bytes.len().is_multiple_of(8) {
        anyhow::bail!("column '{name}' holds {} bytes, not a whole number of 8-byte floats", bytes.len());
    }
    Ok(bytes
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]))
        .collect())
}

/// Values as little-endian bytes for numpy.
fn bytes_of(values: &[f64]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// Runs held in memory, as the text of the run file each would be, under the path a project names
/// it by: read through the same reader as a file, so the load options, repairs and checks apply
/// alike. A path that names no table is read from disk.
struct Tables(HashMap<PathBuf, String>);

impl Tables {
    fn new(tables: Vec<(String, Columns)>) -> anyhow::Result<Self> {
        let mut texts = HashMap::new();
        for (name, columns) in tables {
            let values = columns
                .iter()
                .map(|(c, bytes)| Ok((c.as_str(), floats(c, bytes)?)))
                .collect::<anyhow::Result<Vec<_>>>()?;
            let named: Vec<(&str, &[f64])> = values.iter().map(|(c, v)| (*c, v.as_slice())).collect();
            let text = jetid::io::csv_run::table_to_csv(&name, &named)?;
            if texts.insert(PathBuf::from(&name), text).is_some() {
                anyhow::bail!("two runs are called '{name}': give each run its own name");
            }
        }
        Ok(Self(texts))
    }

    fn read(&self, path: &Path, opts: &LoadOptions) -> Result<(Run, LoadNotes), RunFileError> {
        match self.0.get(path) {
            Some(text) => parse_run_with_notes(&path.to_string_lossy(), text.as_bytes(), opts),
            None => load_run_with_notes(path, opts),
        }
    }
}

/// Run jetid's command line in this process (`argv` without the program name): the same parsing,
/// checks and messages as the `jetid` program. Help and version are printed; a usage error raises.
#[pyfunction]
fn cli(py: Python<'_>, argv: Vec<String>) -> PyResult<()> {
    let parsed = jetid::cli::Cli::try_parse_from(std::iter::once("jetid".to_owned()).chain(argv));
    let parsed = match parsed {
        Ok(parsed) => parsed,
        Err(err) if !err.use_stderr() => {
            let _ = err.print();
            return Ok(());
        }
        Err(err) => return Err(JetidError::new_err(err.render().to_string().trim_end().to_owned())),
    };
    if parsed.command.is_none() && !parsed.batch {
        return Err(JetidError::new_err(
            "the Python package runs jetid's commands and --batch; the desktop app is the jetid program's",
        ));
    }
    py.detach(|| jetid::cli::run(parsed)).map_err(raise)
}

/// A model identified from a project's runs, with what it was built from: the runs by role and,
/// per output, the identified model and its effects. `add_effect` and `diagnose` work on it.
#[pyclass(frozen, module = "jetid._jetid")]
struct Session {
    inner: Arc<SessionData>,
}

struct SessionData {
    project: Project,
    runs: Arc<Runs>,
    built: Vec<BuiltOutput>,
    file: ModelFile,
    notes: Vec<String>,
}

/// The project the Python settings describe: a project file's keys as JSON, its runs named by the
/// tables held in memory or by paths.
fn project_from_json(settings: &str) -> anyhow::Result<Project> {
    // The JSON is made from keyword arguments: where in it an error sits means nothing to the user.
    let file: ProjectFile = serde_json::from_str(settings).map_err(|e| {
        let message = e.to_string();
        let message = message.split(" at line ").next().unwrap_or_default().to_owned();
        anyhow!("the settings of jetid.identify: {message}")
    })?;
    project_of(&file, Path::new(""), "jetid.identify")
}

/// Identify every output of the project `settings` describes (a project file's keys as JSON) from
/// `tables` and the files it names, as `jetid --batch` builds its model.json.
#[pyfunction]
fn identify(py: Python<'_>, settings: &str, tables: Vec<(String, Columns)>) -> PyResult<Session> {
    let data = py.detach(|| -> anyhow::Result<SessionData> {
        let mut project = project_from_json(settings)?;
        let tables = Tables::new(tables)?;
        let runs = load_runs_with(&project, &|path, opts| tables.read(path, opts))?;
        let (file, built, cluster_notes) = build_project(&mut project, &runs, Covariance::Estimate)?;
        let mut notes = runs.notes.clone();
        notes.extend(cluster_notes);
        notes.extend(built.iter().flat_map(|b| b.notes.iter().cloned()));
        Ok(SessionData { project, runs: Arc::new(runs), built, file, notes })
    });
    Ok(Session { inner: Arc::new(data.map_err(raise)?) })
}

#[pymethods]
impl Session {
    /// The model as model.json holds it (the JSON `jetid --batch` writes).
    fn model_json(&self) -> PyResult<String> {
        serde_json::to_string_pretty(&self.inner.file).map_err(|e| raise(e.into()))
    }

    /// What reading the runs and building the model said, in words.
    fn notes(&self) -> Vec<String> {
        self.inner.notes.clone()
    }

    /// The modelled outputs, in order.
    fn outputs(&self) -> Vec<String> {
        self.inner.built.iter().map(|b| b.plan.output.clone()).collect()
    }

    /// The model with the catalog effect `id` added after the project's own effects, refitted on
    /// the identification data, as `jetid --batch --add-effect ID` builds it.
    fn add_effect(&self, py: Python<'_>, id: &str) -> PyResult<Session> {
        let data = py.detach(|| -> anyhow::Result<SessionData> {
            let id: EffectId = id.parse()?;
            let old = &self.inner;
            let mut project = old.project.clone();
            project.add_effects.push(id);
            let mut stages: Vec<_> = old
                .built
                .iter()
                .map(|output| {
                    let mut plan = output.plan.clone();
                    plan.effects.by_hand.push(id);
                    let effects = add_project_effects(&plan, &old.runs, &output.identified, &mut |_| true);
                    (plan, output.identified.clone(), effects)
                })
                .collect();
            // The shaft speed's spool blocks shared with the other outputs, as the batch does.
            share_the_spool(
                &mut stages.iter_mut().map(|(plan, _, effects)| (&*plan, effects)).collect::<Vec<_>>(),
                &old.runs,
            );
            let built = stages
                .into_iter()
                .map(|(plan, identified, effects)| {
                    with_effects(plan, &old.runs, identified, effects, Covariance::Estimate)
                })
                .collect::<anyhow::Result<Vec<_>>>()?;
            let mut file = old.file.clone();
            file.outputs = built.iter().map(|b| b.entry.clone()).collect();
            let mut notes = old.notes.clone();
            notes.extend(built.iter().flat_map(|b| b.notes.iter().cloned()));
            Ok(SessionData { project, runs: Arc::clone(&old.runs), built, file, notes })
        });
        Ok(Session { inner: Arc::new(data.map_err(raise)?) })
    }

    /// The diagnosis of every output's model (report.json's `diagnosis` entries, best first, and
    /// the notes), judged on the session's validation runs, or on `validation` (tables or paths,
    /// read with the project's load options) when given.
    #[pyo3(signature = (validation=None, tables=Vec::new()))]
    fn diagnose(
        &self,
        py: Python<'_>,
        validation: Option<Vec<String>>,
        tables: Vec<(String, Columns)>,
    ) -> PyResult<String> {
        py.detach(|| -> anyhow::Result<String> {
            let data = &self.inner;
            let runs = match validation {
                None => None,
                Some(paths) => Some(runs_with_validation(data, paths, tables)?),
            };
            let runs = runs.as_ref().unwrap_or(&data.runs);
            let mut out = Vec::new();
            for b in &data.built {
                let (entries, notes) = jetid::batch::diagnose::diagnose_output(
                    &b.plan,
                    runs,
                    &b.identified,
                    b.effects.model(),
                    None,
                    &mut |_| true,
                )?;
                out.push(Diagnosed { output: &b.plan.output, entries, notes });
            }
            Ok(serde_json::to_string(&out)?)
        })
        .map_err(raise)
    }

    /// Every output's operating points and continuous-time linear block, as report.json gives them
    /// (across the identification run's range and at the steady run's plateau), with the notes.
    fn operating_points(&self, py: Python<'_>) -> PyResult<String> {
        py.detach(|| -> anyhow::Result<String> {
            let data = &self.inner;
            let mut out = Vec::new();
            for (b, entry) in data.built.iter().zip(&data.file.outputs) {
                let mut notes = Vec::new();
                let (points, continuous) = jetid::batch::control::control_report(
                    b.effects.model(),
                    entry.covariance.as_ref(),
                    jetid::batch::control::range_and_plateaus(&data.runs),
                    &mut notes,
                );
                out.push(ControlOf { output: &b.plan.output, points, continuous, notes });
            }
            Ok(serde_json::to_string(&out)?)
        })
        .map_err(raise)
    }
}

/// One output's diagnosis as it crosses to Python (fields in report.json's order).
#[derive(serde::Serialize)]
struct Diagnosed<'a> {
    output: &'a str,
    entries: Vec<jetid::io::report::DiagnosisEntry>,
    notes: Vec<String>,
}

/// One output's operating points and continuous-time linear block as they cross to Python.
#[derive(serde::Serialize)]
struct ControlOf<'a> {
    output: &'a str,
    points: Vec<jetid::core::control::OperatingPoint>,
    continuous: Option<jetid::core::control::ContinuousTf>,
    notes: Vec<String>,
}

/// The session's runs with the validation runs replaced by `paths` (tables in memory or files),
/// read with the project's load options and put on the identification grid.
fn runs_with_validation(
    data: &SessionData,
    paths: Vec<String>,
    tables: Vec<(String, Columns)>,
) -> anyhow::Result<Runs> {
    let tables = Tables::new(tables)?;
    let sources: Vec<RunSource> = paths
        .into_iter()
        .map(|p| RunSource { path: PathBuf::from(p), load: data.project.load.clone() })
        .collect();
    let mut runs = (*data.runs).clone();
    runs.validate = load_scored_runs(
        &sources,
        runs.ident.dt_secs,
        &|path, opts| tables.read(path, opts),
        &mut runs.notes,
    )?;
    Ok(runs)
}

/// What `jetid predict` writes for the run `table` (or, without one, the run file at `name`), read
/// with `load` (a project's `[load]` keys as JSON), under `model_json`: the columns (time, input,
/// outputs) and the input-coverage warning.
#[pyfunction]
#[pyo3(signature = (model_json, name, table, load, initial_state, strict))]
fn predict(
    py: Python<'_>,
    model_json: &str,
    name: &str,
    table: Option<Columns>,
    load: &str,
    initial_state: &str,
    strict: bool,
) -> PyResult<(Columns, Option<String>)> {
    py.detach(|| -> anyhow::Result<(Columns, Option<String>)> {
        use jetid::core::identification::initial_state::InitialState;
        let model = parse_model(model_json, Path::new("the model"))?;
        let initial = match initial_state {
            "steady" => InitialState::Steady,
            "estimated" => InitialState::Estimated,
            other => anyhow::bail!("initial_state is \"steady\" or \"estimated\", got \"{other}\""),
        };
        let spec: jetid::io::project::LoadSpec = serde_json::from_str(load).context("the load options")?;
        let mut opts = spec.to_options()?;
        opts.input_only = initial == InitialState::Steady && opts.map.outputs.is_empty();
        let tables = Tables::new(table.map(|t| (name.to_owned(), t)).into_iter().collect())?;
        let (run, _) = tables.read(Path::new(name), &opts)?;
        let target = jetid::cli::predict::Target {
            model: Path::new("the model"),
            input: Path::new(name),
            initial_state: initial,
            strict,
        };
        let (prediction, coverage) = jetid::cli::predict::predict(&model, &run, &target)?;
        let mut columns = vec![("time_s".to_owned(), bytes_of(&prediction.t_secs))];
        columns.push((prediction.input.name.clone(), bytes_of(&prediction.input.values)));
        columns.extend(prediction.outputs.iter().map(|c| (c.name.clone(), bytes_of(&c.values))));
        Ok((columns, coverage))
    })
    .map_err(raise)
}

/// The operating points of a saved model, which carries no runs: across its whole input range.
#[pyfunction]
fn model_operating_points(py: Python<'_>, model_json: &str) -> PyResult<String> {
    py.detach(|| -> anyhow::Result<String> {
        let model = parse_model(model_json, Path::new("the model"))?;
        let [lo, hi] = model.input_range.ok_or_else(|| {
            anyhow!(
                "the model file records no input range: identify the model again to get its operating points"
            )
        })?;
        let mut out = Vec::new();
        for entry in &model.outputs {
            let extended = ExtendedModel::from_records(&entry.name, entry.wiener.clone(), &entry.effects)
                .with_context(|| format!("output '{}'", entry.name))?;
            let mut notes = Vec::new();
            let (points, continuous) = jetid::batch::control::control_report(
                &extended,
                entry.covariance.as_ref(),
                ((lo, hi), Vec::new()),
                &mut notes,
            );
            out.push(ControlOf { output: &entry.name, points, continuous, notes });
        }
        Ok(serde_json::to_string(&out)?)
    })
    .map_err(raise)
}

/// The model as the Python program `jetid export --format python` writes.
#[pyfunction]
fn export_python(model_json: &str, source: &str) -> PyResult<String> {
    let model = parse_model(model_json, Path::new(source)).map_err(raise)?;
    jetid::io::export::export(&model, source, jetid::io::export::Format::Python, "jetid_model")
        .map_err(|e| raise(e.into()))
}

/// Write `model_json` to `path` as jetid writes model.json (checked first).
#[pyfunction]
fn save_model(model_json: &str, path: PathBuf) -> PyResult<()> {
    let model = parse_model(model_json, &path).map_err(raise)?;
    write_model(&path, &model).map_err(raise)
}

/// The model file at `path`, checked as `jetid predict` checks it, as JSON.
#[pyfunction]
fn load_model(path: PathBuf) -> PyResult<String> {
    let model = read_model(&path).map_err(raise)?;
    serde_json::to_string_pretty(&model).map_err(|e| raise(e.into()))
}

/// The catalog effects' names, in catalog order.
#[pyfunction]
fn effect_ids() -> Vec<String> {
    EffectId::ALL.iter().map(|id| id.name().to_owned()).collect()
}

#[pymodule]
fn _jetid(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // Ctrl+C belongs to Python here: a staging folder is still removed when its work fails.
    jetid::io::staging::leave_signals_to_host();
    m.add("JetidError", m.py().get_type::<JetidError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<Session>()?;
    for f in [
        wrap_pyfunction!(cli, m)?,
        wrap_pyfunction!(identify, m)?,
        wrap_pyfunction!(predict, m)?,
        wrap_pyfunction!(model_operating_points, m)?,
        wrap_pyfunction!(export_python, m)?,
        wrap_pyfunction!(save_model, m)?,
        wrap_pyfunction!(load_model, m)?,
        wrap_pyfunction!(effect_ids, m)?,
    ] {
        m.add_function(f)?;
    }
    fleet::register(m)
}
