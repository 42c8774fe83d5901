//! The session as a project file and back. `io::project` reads project files; this writes one
//! from the session (runs with roles and load options, per-output settings, segments, clusters,
//! effects as `add_effects`) in the same format, so `jetid --batch PROJECT` and File > Open
//! project read it.
use crate::core::run::RunRole;
use std::collections::BTreeSet;
use std::path::Path;

use anyhow::{Context, Result};

use crate::core::effects::EffectId;
use crate::io::csv_run::LoadOptions;
use crate::io::project::{IdentEntry, LoadSpec, OutputSpec, Project, ProjectFile, RunEntry, RunSource};
use crate::ui::state::session::{LoadFailure, Session, SessionRun};
use crate::ui::state::setup::{ModelSetup, OutputSetup};
use crate::workflow::OutputPlan;
use crate::workflow::model_file::take_saved_clusters;
use crate::workflow::runs::sources_by_role;

/// The project file text for `session`, to be written at `project_path`; the notes say what a
/// project file cannot hold (a second chirp or steady run).
pub fn project_text(session: &Session, project_path: &Path) -> Result<(String, Vec<String>)> {
    let base = project_path.parent().unwrap_or(Path::new(""));
    let mut notes = Vec::new();
    let mut single = |role: RunRole| -> Option<RunEntry> {
        let mut runs = session.runs.iter().filter(|r| r.role == role);
        let first = runs.next().map(|r| run_entry(r, base));
        for extra in runs {
            notes.push(format!(
                "a project holds one {} run: {} was not saved",
                role.label(),
                extra.display_name()
            ));
        }
        first
    };
    let idents: Vec<RunEntry> = session
        .runs
        .iter()
        .filter(|r| r.role == RunRole::Identification)
        .map(|r| run_entry(r, base))
        .collect();
    let chirp = single(RunRole::Chirp);
    let steady = single(RunRole::Steady);
    let validate =
        session.runs.iter().filter(|r| r.role == RunRole::Validation).map(|r| run_entry(r, base)).collect();
    let outputs: Vec<String> = session
        .ident_run()
        .map(|(_, r)| r.run.outputs.iter().map(|c| c.name.clone()).collect::<Vec<_>>())
        .unwrap_or_default()
        .into_iter()
        .filter(|name| session.setup.is_modelled(name))
        .collect();
    let add_effects = shared_effects(&session.setup, &outputs, &mut notes);
    let auto_effects = shared_rounds(&session.setup, &outputs, &mut notes);
    let names: BTreeSet<&String> = outputs.iter().chain(session.setup.outputs.keys()).collect();
    let output = names.into_iter().map(|name| (name.clone(), output_spec(&session.setup, name))).collect();
    let file = ProjectFile {
        name: project_path.file_stem().map(|s| s.to_string_lossy().into_owned()),
        ident: match idents.len() {
            0 => None,
            1 => idents.into_iter().next().map(IdentEntry::One),
            _ => Some(IdentEntry::Many(idents)),
        },
        validate,
        held_out: session
            .runs
            .iter()
            .filter(|r| r.role == RunRole::HeldOut)
            .map(|r| run_entry(r, base))
            .collect(),
        chirp,
        steady,
        outputs,
        add_effects,
        auto_effects: (auto_effects > 0).then_some(auto_effects),
        clusters_from: None,
        steps_from: session.setup.steps_from.clone(),
        load: LoadSpec::default(),
        output,
    };
    let text = toml::to_string_pretty(&file).context("writing the project as TOML")?;
    Ok((text, notes))
}

/// The effects to write as the project's `add_effects`. That list applies to every output (the
/// project format has no per-output effects), so only the effects every output has are written, in
/// the order of the first output; the notes name what could not be saved.
fn shared_effects(setup: &ModelSetup, outputs: &[String], notes: &mut Vec<String>) -> Vec<EffectId> {
    let lists: Vec<(&String, Vec<EffectId>)> = outputs.iter().map(|o| (o, setup.output(o).effects)).collect();
    let Some((_, first)) = lists.first() else { return Vec::new() };
    let shared: Vec<EffectId> =
        first.iter().filter(|id| lists.iter().all(|(_, list)| list.contains(id))).copied().collect();
    for (output, list) in &lists {
        let lost: Vec<&str> = list.iter().filter(|id| !shared.contains(id)).map(|id| id.name()).collect();
        if !lost.is_empty() {
            notes.push(format!(
                "a project's add_effects applies to every output: {output}'s {} was not saved",
                lost.join(", ")
            ));
        }
    }
    shared
}

/// The rounds of the missing-physics loop to write as the project's `auto_effects`, which applies to
/// every output: the most any output has, with a note when the outputs differ.
fn shared_rounds(setup: &ModelSetup, outputs: &[String], notes: &mut Vec<String>) -> usize {
    let rounds: Vec<usize> = outputs.iter().map(|o| setup.output(o).auto_effects).collect();
    let most = rounds.iter().copied().max().unwrap_or(0);
    if rounds.iter().any(|r| *r != most) {
        notes.push(format!(
            "a project's auto_effects applies to every output: saved as {most} rounds for all of them"
        ));
    }
    most
}

fn run_entry(run: &SessionRun, base: &Path) -> RunEntry {
    let relative = run.path.strip_prefix(base).ok().filter(|p| !p.as_os_str().is_empty());
    let path = relative.unwrap_or(&run.path).to_string_lossy().into_owned();
    let load = load_spec(&run.options);
    if load.is_default() { RunEntry::Path(path) } else { RunEntry::Table { path, load } }
}

/// Load options as the command line (and project files) spell them.
fn load_spec(options: &LoadOptions) -> LoadSpec {
    LoadSpec {
        map: options.map.entries().into_iter().map(|(role, column)| format!("{role}={column}")).collect(),
        sample_time: options.sample_time_secs,
        window: options.window.as_ref().map(ToString::to_string),
        quality: options.quality.clone(),
        resample: options.resample,
        invalid: options.invalid.clone(),
        units: options.units.clone(),
    }
}

fn output_spec(setup: &ModelSetup, name: &str) -> OutputSpec {
    let OutputSetup { settings, clusters, segments, effects: _, auto_effects: _ } = setup.output(name);
    let segments = segments.or_else(|| setup.segments.clone());
    OutputSpec {
        na: Some(settings.orders.na),
        nb: Some(settings.orders.nb),
        // The input delay is written only when the user fixed it; otherwise it is estimated again.
        nk: (!settings.estimate_dead_time).then_some(settings.orders.nk),
        static_order: settings.static_order,
        min_segments: settings.cluster.min_segments,
        refine: Some(settings.refine),
        segments: segments.map(|s| s.iter().map(|s| [s.start, s.step_at, s.end]).collect()),
        dead_time_samples: settings.dead_time_samples.filter(|_| clusters.is_some()),
        clusters,
        initial_state: Some(settings.initial_state),
        polish: Some(settings.polish),
        spool_schedule: Some(settings.spool_schedule),
    }
}

/// A session from a project: its runs read with their roles (those that fail are returned as
/// failures) and its segments, settings, clusters and effects (`add_effects` and `auto_effects`
/// for every output the batch models); a saved model's clusters (`clusters_from`) are taken as the
/// batch takes them, checked against the identification run's sample time.
pub fn session_from_project(project: &Project) -> Result<(Session, Vec<LoadFailure>)> {
    let mut session = Session::default();
    let mut failures = Vec::new();
    for (source, role) in sources_by_role(project) {
        match load_source(source, role) {
            Ok(run) => session.runs.push(run),
            Err(failure) => failures.push(*failure),
        }
    }
    let outputs: Vec<String> = session
        .ident_run()
        .map(|(_, r)| r.run.outputs.iter().map(|c| c.name.clone()).collect())
        .unwrap_or_default();
    let mut project = project.clone();
    if let Some((_, ident)) = session.ident_run() {
        take_saved_clusters(&mut project, ident.run.dt_secs, &outputs)?;
    }
    session.setup = setup_from_project(&project, &outputs);
    Ok((session, failures))
}

/// The setup a project describes; `ident_outputs` are the outputs of its identification run.
fn setup_from_project(project: &Project, ident_outputs: &[String]) -> ModelSetup {
    let mut setup = ModelSetup {
        segments: project.segments.values().next().cloned(),
        modelled: project.outputs.clone(),
        steps_from: project.steps_from.clone(),
        ..ModelSetup::default()
    };
    let sections = project.settings.keys().chain(project.clusters.keys()).chain(project.segments.keys());
    let names: BTreeSet<&String> = sections.collect();
    for name in names {
        let plan = OutputPlan::of_project(project, name);
        // Segments of its own only when they are not the ones the Data view shows.
        let segments = plan.segments.filter(|s| Some(s) != setup.segments.as_ref());
        let output = OutputSetup {
            settings: plan.settings,
            clusters: plan.clusters,
            segments,
            ..OutputSetup::for_output(name)
        };
        setup.outputs.insert(name.clone(), output);
    }
    // The effects apply to every output the batch models: the project's list, else every output of
    // the identification run.
    if !project.add_effects.is_empty() || project.auto_effects > 0 {
        let outputs = if project.outputs.is_empty() { ident_outputs } else { &project.outputs[..] };
        for output in outputs {
            let output = setup.output_mut(output);
            output.effects = project.add_effects.clone();
            output.auto_effects = project.auto_effects;
        }
    }
    setup
}

fn load_source(source: &RunSource, role: RunRole) -> Result<SessionRun, Box<LoadFailure>> {
    match source.load.to_options() {
        Ok(options) => SessionRun::load(&source.path, role, options),
        Err(err) => Err(Box::new(LoadFailure {
            path: source.path.clone(),
            role,
            options: LoadOptions::default(),
            message: format!("load options: {err:#}"),
            column_problem: false,
            existing: None,
        })),
    }
}
