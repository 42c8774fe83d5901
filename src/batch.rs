//! `jetid --batch`: project → runs → gray-box identification of each output → model.json,
//! report.json, report.md and figures. No egui.
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};

use crate::batch_compare::MonteCarloSummary;
use crate::cli::BatchArgs;
use crate::core::diagnose;
use crate::core::effects::ExtendedModel;
use crate::core::identification::pipeline::{self, Identified, PipelineError, segments_for};
use crate::core::identification::segment::{SegmentSettings, auto_segments_joined};
use crate::core::run::Run;
use crate::io::csv_run::load_run;
use crate::io::model_file::{ModelFile, SignalInfo, write_model};
use crate::io::project::{LoadSpec, Project, RunSource, bundled_project_path, load_project};
use crate::io::report::{
    DiagnosisEntry, HistoryStep, IdentSummary, OutputReport, Report, write_report_json, write_report_md,
};

/// The loaded runs of a project, by role.
pub struct Runs {
    pub ident: Run,
    /// Where each further identification run starts when several were joined.
    pub ident_junctions: Vec<usize>,
    pub validate: Vec<Run>,
    pub chirp: Option<Run>,
    pub steady: Option<Run>,
}

/// Stopwatch that records named phases in milliseconds.
#[derive(Default)]
pub struct Timings(pub BTreeMap<String, f64>);

impl Timings {
    pub fn time<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let out = f();
        *self.0.entry(name.to_owned()).or_default() += start.elapsed().as_secs_f64() * 1e3;
        out
    }
}

/// The project the command line asks for: the given file, else the bundled one, else none (when
/// runs are given on the command line), with the command line's overrides applied.
pub fn project_from_args(args: &BatchArgs) -> Result<Project> {
    let mut project = match (&args.project, &args.ident) {
        (Some(path), _) => load_project(path)?,
        (None, Some(_)) => Project {
            name: "command line".into(),
            ident: vec![],
            validate: vec![],
            chirp: None,
            steady: None,
            outputs: vec![],
            add_effects: vec![],
            settings: BTreeMap::new(),
            segments: BTreeMap::new(),
            clusters: BTreeMap::new(),
            clusters_from: None,
            steps_from: None,
        },
        (None, None) => load_project(&bundled_project_path()?)?,
    };
    let cli_load = LoadSpec { map: args.maps.clone(), sample_time: args.sample_time, ..LoadSpec::default() };
    cli_load.to_options().context("command-line load options")?;
    let cwd = PathBuf::from(".");
    let src = |p: &PathBuf| RunSource { path: cwd.join(p), load: cli_load.clone() };
    if let Some(p) = &args.ident {
        project.ident = vec![src(p)];
    }
    if !args.validate.is_empty() {
        project.validate = args.validate.iter().map(src).collect();
    }
    if let Some(p) = &args.chirp {
        project.chirp = Some(src(p));
    }
    if let Some(p) = &args.steady {
        project.steady = Some(src(p));
    }
    if !args.outputs.is_empty() {
        project.outputs = args.outputs.clone();
    }
    project.add_effects.extend(args.add_effects.iter().cloned());
    if let Some(p) = &args.clusters_from {
        project.clusters_from = Some(p.clone());
    }
    Ok(project)
}

pub fn load_source(source: &RunSource) -> Result<Run> {
    let opts = source.load.to_options()?;
    Ok(load_run(&source.path, &opts)?)
}

pub fn load_runs(project: &Project) -> Result<Runs> {
    if project.ident.is_empty() {
        bail!("the project names no identification run (give one with --ident FILE)");
    }
    let parts = project.ident.iter().map(load_source).collect::<Result<Vec<_>>>()?;
    let (ident, ident_junctions) =
        crate::core::run::join_runs(&parts).context("joining the identification runs")?;
    if let Some(name) = &project.steps_from
        && ident.channel(name).is_none()
    {
        bail!(
            "steps_from = \"{name}\": the identification run '{}' has no such channel (map it with aux={name})",
            ident.name
        );
    }
    let validate = project.validate.iter().map(load_source).collect::<Result<Vec<_>>>()?;
    let chirp = project.chirp.as_ref().map(load_source).transpose()?;
    let steady = project.steady.as_ref().map(load_source).transpose()?;
    for run in validate.iter().chain(&chirp).chain(&steady) {
        let ratio = run.dt_secs / ident.dt_secs;
        if (ratio - 1.0).abs() > 0.02 {
            bail!(
                "run '{}' is sampled every {:.5} s but the identification run every {:.5} s; models are discrete-time, so resample it first",
                run.name,
                run.dt_secs,
                ident.dt_secs
            );
        }
    }
    Ok(Runs { ident, ident_junctions, validate, chirp, steady })
}

/// Outputs to model: the project's list (each must exist), else every output of the ident run.
pub fn outputs_to_model(project: &Project, ident: &Run) -> Result<Vec<String>> {
    if project.outputs.is_empty() {
        return Ok(ident.outputs.iter().map(|c| c.name.clone()).collect());
    }
    for name in &project.outputs {
        if ident.output(name).is_none() {
            let available: Vec<&str> = ident.outputs.iter().map(|c| c.name.as_str()).collect();
            bail!(
                "output '{name}' is not in the identification run '{}' (outputs: {})",
                ident.name,
                available.join(", ")
            );
        }
    }
    Ok(project.outputs.clone())
}

/// Identify one output as the project says: the project's segments, else steps detected on the
/// input (or the project's `steps_from` channel) of each joined identification run.
pub fn identify(project: &Project, runs: &Runs, output: &str) -> Result<Identified, PipelineError> {
    let ident = &runs.ident;
    let settings = project.settings_for(output);
    let segments = match project.segments.get(output) {
        Some(given) => segments_for(ident, Some(given), &SegmentSettings::default())?,
        None => {
            let signal = project
                .steps_from
                .as_deref()
                .and_then(|name| ident.channel(name))
                .map_or(ident.input.values.as_slice(), |c| c.values.as_slice());
            auto_segments_joined(signal, &runs.ident_junctions, ident.dt_secs, &SegmentSettings::default())
                .map_err(|source| PipelineError::Segment { run: ident.name.clone(), source })?
        }
    };
    pipeline::identify_output(
        ident,
        output,
        &settings,
        &segments,
        project.clusters.get(output).map(Vec::as_slice),
    )
}

/// Runs the models are scored on: validation runs, then the chirp run.
pub fn scored_runs(runs: &Runs) -> Vec<&Run> {
    runs.validate.iter().chain(&runs.chirp).collect()
}

fn score_output(
    models: &crate::batch_compare::OutputModels,
    runs: &Runs,
    output: &str,
    report: &mut OutputReport,
    notes: &mut Vec<String>,
) {
    for run in scored_runs(runs) {
        if run.output(output).is_none() {
            notes.push(format!("run '{}' has no '{output}' column; not scored for it", run.name));
            continue;
        }
        for (name, y_hat) in models.simulate_run(run) {
            match pipeline::score(run, output, y_hat) {
                Ok(p) => {
                    report.models.entry(name.to_owned()).or_default().insert(run.name.clone(), p.metrics);
                }
                Err(e) => notes.push(format!("{name} on '{}': {e}", run.name)),
            }
        }
    }
}

/// Mean RMSPE of a model over the validation runs (the error-history figure of merit).
pub fn mean_validation_rmspe(report: &OutputReport, runs: &Runs, model: &str) -> Option<f64> {
    let scores = report.models.get(model)?;
    let vals: Vec<f64> =
        runs.validate.iter().filter_map(|r| scores.get(&r.name)).map(|m| m.rmspe_pct).collect();
    (!vals.is_empty()).then(|| vals.iter().sum::<f64>() / vals.len() as f64)
}

pub fn run(args: &BatchArgs) -> Result<()> {
    let total = Instant::now();
    let mut timings = Timings::default();
    let project = project_from_args(args)?;
    for id in &project.add_effects {
        crate::core::effects::check_id(id).with_context(|| format!("--add-effect {id}"))?;
    }
    let runs = timings.time("load_runs", || load_runs(&project))?;
    let outputs = outputs_to_model(&project, &runs.ident)?;
    let mut project = project;
    let cluster_notes = apply_saved_clusters(&mut project, runs.ident.dt_secs, &outputs)?;
    let out_dir = &args.out;
    std::fs::create_dir_all(out_dir)
        .with_context(|| format!("cannot create output folder {}", out_dir.display()))?;

    let mut model_file = ModelFile::new(
        runs.ident.dt_secs,
        SignalInfo { name: runs.ident.input.name.clone(), unit: runs.ident.input.unit.clone() },
    );
    let mut report = Report {
        format_version: crate::io::report::REPORT_FORMAT_VERSION,
        project: project.name.clone(),
        input: runs.ident.input.name.clone(),
        runs: run_roles(&runs),
        outputs: BTreeMap::new(),
        noise_fit: None,
        monte_carlo: None,
        timings_ms: BTreeMap::new(),
        figures: Vec::new(),
        diagnostics: cluster_notes,
    };
    let noise = runs.steady.as_ref().map(|s| crate::batch_compare::noise_fits(s, &mut report.diagnostics));
    let input_noise = noise
        .as_ref()
        .and_then(|n| n.get(&runs.ident.input.name))
        .and_then(|r| r.best().map(|f| f.distribution));
    let mut monte_carlo = BTreeMap::new();
    for output in &outputs {
        let identified = timings
            .time(&format!("identify_{output}"), || identify(&project, &runs, output))
            .with_context(|| format!("identifying '{output}' from '{}'", runs.ident.name))?;
        let unit = runs.ident.output(output).map(|c| c.unit.clone()).unwrap_or_default();
        let (extended, history, notes) = timings
            .time(&format!("effects_{output}"), || apply_effects(&project, &runs, &identified, output))?;
        report.diagnostics.extend(notes);
        model_file.push(&identified.model, &unit);
        if let Some(last) = model_file.outputs.last_mut() {
            // Effects are fitted together with the gain and static map they sit beside.
            last.wiener = extended.wiener.clone();
            last.static_map_beta = extended.wiener.map.beta();
            last.effects = extended.records();
        }
        let mut out = OutputReport {
            unit,
            models: BTreeMap::new(),
            identified: IdentSummary::of(&identified),
            diagnosis: Vec::new(),
            effects_applied: Vec::new(),
            error_history: Vec::new(),
            error_boxes: BTreeMap::new(),
            cutoff_rad_s: BTreeMap::new(),
            residuals: Vec::new(),
            initial_state: String::new(),
            initial_state_meaning: String::new(),
        };
        let mut models = timings.time(&format!("baselines_{output}"), || {
            crate::batch_compare::fit_baselines(&identified, &runs.ident, output, &mut report.diagnostics)
        });
        models.initial_state = project.settings_for(output).initial_state;
        out.initial_state = serde_json::to_value(models.initial_state)
            .ok()
            .and_then(|v| v.as_str().map(str::to_owned))
            .unwrap_or_default();
        out.initial_state_meaning = models.initial_state.describe().to_owned();
        if !extended.effects.is_empty() {
            models.extended = Some(extended.clone());
        }
        out.effects_applied = extended.effect_ids().iter().map(|s| (*s).to_owned()).collect();
        out.error_history = history;
        let diagnosis = timings.time(&format!("diagnosis_{output}"), || {
            diagnose_output(&project, &runs, &identified, &extended, output)
        });
        match diagnosis {
            Ok((entries, skipped)) => {
                out.diagnosis = entries;
                report.diagnostics.extend(skipped);
            }
            Err(e) => report.diagnostics.push(format!("diagnosis of '{output}': {e}")),
        }
        timings.time("validate", || score_output(&models, &runs, output, &mut out, &mut report.diagnostics));
        let scored = scored_runs(&runs);
        out.error_boxes = crate::batch_compare::error_boxes(&models, &scored, output);
        let sigma = crate::batch_residuals::noise_sigma(noise.as_ref(), output);
        let (residuals, figs) = timings.time("residuals", || {
            crate::batch_residuals::residual_reports(
                out_dir,
                output,
                &models,
                &scored,
                sigma,
                &mut report.diagnostics,
            )
        });
        out.residuals = residuals;
        report.figures.extend(figs);
        let freq = timings.time("frequency", || {
            runs.chirp.as_ref().and_then(|chirp| {
                crate::batch_compare::frequency_comparison(&models, chirp, output, &mut report.diagnostics)
            })
        });
        out.cutoff_rad_s = freq.as_ref().map(|f| f.cutoff_rad_s.clone()).unwrap_or_default();
        if let (Some(steady), Some(input_fit)) = (&runs.steady, &input_noise) {
            let u0 = steady.input.values.iter().sum::<f64>() / steady.input.values.len().max(1) as f64;
            let mc = timings.time("monte_carlo", || {
                crate::batch_compare::monte_carlo_all(
                    &models,
                    u0,
                    steady.dt_secs,
                    input_fit,
                    &mut report.diagnostics,
                )
            });
            monte_carlo.insert(
                output.clone(),
                mc.iter()
                    .map(|(k, r)| (k.clone(), MonteCarloSummary::from_result(r)))
                    .collect::<BTreeMap<_, _>>(),
            );
            let (figs, notes) =
                timings.time("figures", || crate::batch_figures::monte_carlo_figures(out_dir, output, &mc));
            report.figures.extend(figs);
            report.diagnostics.extend(notes);
        }
        let (figs, notes) = timings.time("figures", || {
            crate::batch_figures::output_figures(
                out_dir,
                output,
                &identified,
                &models,
                &runs.validate,
                freq.as_ref(),
                &out.error_boxes,
            )
        });
        report.figures.extend(figs);
        report.diagnostics.extend(notes);
        report.outputs.insert(output.clone(), out);
    }
    report.noise_fit = noise.map(serde_json::to_value).transpose().context("noise fit")?;
    if !monte_carlo.is_empty() {
        report.monte_carlo = Some(serde_json::to_value(monte_carlo).context("Monte Carlo summary")?);
    }
    write_model(&out_dir.join("model.json"), &model_file)?;
    report.timings_ms = timings.0;
    report.timings_ms.insert("total".into(), total.elapsed().as_secs_f64() * 1e3);
    write_report_json(&out_dir.join("report.json"), &report)?;
    write_report_md(&out_dir.join("report.md"), &report)?;
    print_summary(&report, out_dir);
    Ok(())
}

/// The project's effects (`--add-effect`, `add_effects`) added one after another to the gray-box
/// model, each refitted on the identification data, with the validation error after each step.
fn apply_effects(
    project: &Project,
    runs: &Runs,
    identified: &Identified,
    output: &str,
) -> Result<(ExtendedModel, Vec<HistoryStep>, Vec<String>)> {
    let settings = project.settings_for(output);
    let validation: Vec<&Run> = runs.validate.iter().filter(|r| r.output(output).is_some()).collect();
    let mut notes = Vec::new();
    let mut model = ExtendedModel::from_gray_box(&identified.model);
    let mut history = Vec::new();
    let mut record = |step: String, model: &ExtendedModel, history: &mut Vec<HistoryStep>| {
        if validation.is_empty() {
            return;
        }
        match diagnose::validation_rmspe(model, &validation, settings.initial_state) {
            Ok(rmspe_pct) => history.push(HistoryStep { step, rmspe_pct }),
            Err(e) => notes.push(format!("'{output}' {step}: {e}")),
        }
    };
    record("base".into(), &model, &mut history);
    for id in &project.add_effects {
        model = diagnose::apply(&model, id, &runs.ident, &identified.fits, &settings)
            .with_context(|| format!("adding the effect '{id}' to '{output}'"))?;
        record(format!("+{id}"), &model, &mut history);
    }
    Ok((model, history, notes))
}

/// Which missing effect would help most (report.json `diagnosis`, best first).
fn diagnose_output(
    project: &Project,
    runs: &Runs,
    identified: &Identified,
    current: &ExtendedModel,
    output: &str,
) -> Result<(Vec<DiagnosisEntry>, Vec<String>)> {
    let validation: Vec<&Run> = runs.validate.iter().filter(|r| r.output(output).is_some()).collect();
    let settings = project.settings_for(output);
    let report = diagnose::diagnose(current, &runs.ident, &identified.fits, &validation, &settings)?;
    let skipped = report
        .skipped
        .iter()
        .map(|s| format!("diagnosis of '{output}': {} not tried: {}", s.effect, s.reason))
        .chain(report.structure_note.iter().map(|n| format!("diagnosis of '{output}': {n}")))
        .collect();
    let entries = report
        .entries
        .iter()
        .map(|d| DiagnosisEntry {
            effect: d.effect.clone(),
            kind: d.kind.label().to_owned(),
            significant: d.significant,
            rmspe_before_pct: d.rmspe_before_pct,
            rmspe_after_pct: d.rmspe_after_pct,
            evidence: d.evidence.clone(),
            p_value: Some(d.test.p_value),
        })
        .collect();
    Ok((entries, skipped))
}

/// Take the clusters of the project's saved model (`clusters_from` / `--clusters`) for every output
/// that has none of its own; say which outputs fall back to the automatic proposal.
fn apply_saved_clusters(project: &mut Project, dt_secs: f64, outputs: &[String]) -> Result<Vec<String>> {
    let Some(path) = &project.clusters_from else { return Ok(Vec::new()) };
    let saved = crate::io::model_file::clusters_from_model(path, dt_secs)?;
    let mut notes = Vec::new();
    for output in outputs {
        if project.clusters.contains_key(output) {
            notes.push(format!(
                "'{output}': the project's own clusters take precedence over {}",
                path.display()
            ));
        } else if let Some(clusters) = saved.get(output) {
            project.clusters.insert(output.clone(), clusters.clone());
            notes.push(format!("'{output}': {} clusters taken from {}", clusters.len(), path.display()));
        } else {
            notes.push(format!(
                "'{output}': {} holds no clusters for it; the automatic proposal is used",
                path.display()
            ));
        }
    }
    Ok(notes)
}

fn run_roles(runs: &Runs) -> BTreeMap<String, String> {
    let mut roles = BTreeMap::new();
    roles.insert("identification".to_owned(), runs.ident.name.clone());
    for (i, r) in runs.validate.iter().enumerate() {
        roles.insert(format!("validation {}", i + 1), r.name.clone());
    }
    if let Some(r) = &runs.chirp {
        roles.insert("chirp".into(), r.name.clone());
    }
    if let Some(r) = &runs.steady {
        roles.insert("steady".into(), r.name.clone());
    }
    roles
}

fn print_summary(report: &Report, out_dir: &Path) {
    for (output, o) in &report.outputs {
        for (model, runs) in &o.models {
            for (run, m) in runs {
                println!(
                    "{output:>18} {model:<10} {run:<14} RMSPE {:>8.4} %  fit {:>7.2} %",
                    m.rmspe_pct, m.fit_pct
                );
            }
        }
    }
    println!("wrote model.json, report.json and report.md to {}", out_dir.display());
}
