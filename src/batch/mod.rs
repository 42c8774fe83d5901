//! `jetid --batch`: project → runs → gray-box model of each output → model.json, report.json,
//! report.md and figures. No egui. The models are built by [`crate::workflow`] (the app builds
//! them there too); the stages here describe and score them, in the order the data flows:
//! [`effects`] → [`diagnose`] → [`compare`] → [`residuals`] → [`report`] and [`figures`]. Every
//! file is written into a staging folder and moved into `--out` only when every output succeeded
//! (`io::staging`). The command line builds the [`Project`] (`workflow::Overrides`).
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};

use crate::core::compare::{ModelKind, MonteCarloSummary, OutputModels, fit_baselines, noise_fits};
use crate::core::diagnose::steady_state_agreement;
use crate::core::identification::pipeline::Identified;
use crate::core::numerics::noise_fit::Distribution;
use crate::core::residuals::steady_noise_sigma;
use crate::io::model_file::OutputModel;
use crate::io::project::Project;
use crate::io::report::OutputReport;
use crate::io::staging::Staging;
use crate::workflow::model::{self, OutputPlan};
use crate::workflow::model_file::{new_model_file, take_saved_clusters};
use crate::workflow::preparation::segmentation_choice;
use crate::workflow::project_model::{BuiltOutput, on_own_threads};
use crate::workflow::runs::{self, Runs};

mod compare;
pub mod control;
pub mod diagnose;
mod effects;
pub mod figures;
mod progress;
mod report;
pub mod residuals;

use progress::Progress;
pub use progress::Timings;

/// One output's share of the results, made on its own thread.
struct OutputPart {
    output: String,
    entry: OutputModel,
    report: OutputReport,
    /// Figure files written, in report order.
    figures: Vec<String>,
    notes: Vec<String>,
    monte_carlo: Option<BTreeMap<ModelKind, MonteCarloSummary>>,
    timings: Timings,
}

/// What every output's stages share: the project, its runs and the steady run's input noise.
struct Batch<'a> {
    project: &'a Project,
    runs: &'a Runs,
    /// Where the figures are drawn (the staging folder).
    out_dir: &'a Path,
    /// The steady run's input noise, best family by likelihood (drives the Monte Carlo study).
    input_noise: Option<Distribution>,
}

/// Run the whole pipeline on `project` and write the results to `out_dir`; nothing is written
/// there unless every output succeeds.
pub fn run(mut project: Project, out_dir: &Path, quiet: bool) -> Result<()> {
    let total = Instant::now();
    crate::io::staging::stop_on_interrupt();
    let progress = std::sync::Arc::new(std::sync::Mutex::new(Progress::new(quiet)));
    let mut timings = Timings(BTreeMap::new(), progress.clone());
    let ticker = (!quiet).then(|| progress::Ticker::start(&progress));
    let runs = timings.time("load_runs", || runs::load_runs(&project))?;
    let outputs = runs::outputs_to_model(&project, &runs.ident)?;
    let cluster_notes = take_saved_clusters(&mut project, runs.ident.dt_secs, &outputs)?;
    let staging = Staging::new(out_dir)?;

    let mut model_file = new_model_file(&runs.ident);
    let mut report = report::new_report(&project, &runs, cluster_notes);
    report.diagnostics.splice(0..0, runs.notes.iter().cloned());
    let noise = runs.steady.as_ref().map(|s| noise_fits(s, &mut report.diagnostics));
    let input_noise = noise
        .as_ref()
        .and_then(|n| n.get(&runs.ident.input.name))
        .and_then(|r| r.best().map(|f| f.distribution));
    let batch = Batch { project: &project, runs: &runs, out_dir: staging.path(), input_noise };
    let mut monte_carlo = BTreeMap::new();
    for part in batch.every_output(&outputs, &timings)? {
        model_file.outputs.push(part.entry);
        report.outputs.insert(part.output.clone(), part.report);
        report.figures.extend(part.figures);
        report.diagnostics.extend(part.notes);
        if let Some(summary) = part.monte_carlo {
            monte_carlo.insert(part.output, summary);
        }
        timings.absorb(part.timings);
    }
    report.noise_fit = noise.map(serde_json::to_value).transpose().context("noise fit")?;
    if !monte_carlo.is_empty() {
        report.monte_carlo = Some(serde_json::to_value(monte_carlo).context("Monte Carlo summary")?);
    }
    timings.time("writing the results", || ());
    drop(ticker);
    if let Ok(mut progress) = timings.1.lock() {
        progress.finish();
    }
    report.timings_ms = timings.0;
    report.timings_ms.remove("writing the results");
    report.timings_ms.insert("total".into(), total.elapsed().as_secs_f64() * 1e3);
    let written = report::write_all(staging.path(), &model_file, &report)?;
    let removed = staging.commit(&written)?;
    report::print_summary(&report, out_dir, &removed);
    Ok(())
}

/// One output after its first phase: identified, with its effects (the shaft speed's spool blocks
/// not yet shared) and its baselines.
struct Stage {
    plan: OutputPlan,
    identified: Identified,
    effects: model::Effects,
    models: OutputModels,
    preparation: Option<crate::io::report::preparation::SegmentationChoice>,
    baseline_notes: Vec<String>,
    timings: Timings,
}

impl Batch<'_> {
    /// Every output in two phases, each output on its own thread in each: identified with its
    /// effects and baselines; then, once the shaft speed's spool blocks are shared with the others
    /// (`workflow::project_model::share_the_spool`), built, diagnosed, scored and drawn. Returned in
    /// output order (so the files are the same as one output after another).
    fn every_output(&self, outputs: &[String], timings: &Timings) -> Result<Vec<OutputPart>> {
        let mut stages = on_own_threads(outputs.iter().map(|o| (o, timings.sibling())), |(output, mut t)| {
            self.first_phase(output, &mut t).map(|stage| Stage { timings: t, ..stage })
        })
        .into_iter()
        .collect::<Result<Vec<_>>>()?;
        let mut shared: Vec<_> = stages.iter_mut().map(|s| (&s.plan, &mut s.effects)).collect();
        crate::workflow::project_model::share_the_spool(&mut shared, self.runs);
        on_own_threads(stages, |mut stage| {
            let mut t = std::mem::take(&mut stage.timings);
            let part = self.second_phase(stage, &mut t);
            part.map(|part| OutputPart { timings: t, ..part })
        })
        .into_iter()
        .collect()
    }

    /// The first phase for one output: identify, then the effects (the workflow's loop) while the
    /// baselines and the segmentation choice's second model, which need only the identified model,
    /// are fitted on their own thread.
    fn first_phase(&self, output: &str, timings: &mut Timings) -> Result<Stage> {
        let (project, runs) = (self.project, self.runs);
        let plan = OutputPlan::of_project(project, output).with_steps_from(&runs.steps_from);
        let identified = timings
            .time(&format!("identify_{output}"), || {
                model::identify(&runs.ident, &runs.ident_junctions, &plan)
            })
            .with_context(|| format!("identifying '{output}' from '{}'", runs.ident.name))?;
        let (effects, baselines) = std::thread::scope(|scope| {
            let mut baseline_timings = timings.sibling();
            let (plan, identified) = (&plan, &identified);
            let baselines = scope.spawn(move || {
                let mut notes = Vec::new();
                let models = baseline_timings
                    .time_with_fraction(&format!("baselines_{output}"), |progress| {
                        fit_baselines(identified, &runs.ident, output, &mut notes, progress)
                    });
                let preparation = baseline_timings
                    .time(&format!("preparation_{output}"), || segmentation_choice(runs, plan, identified));
                (models, preparation, notes, baseline_timings)
            });
            let effects = effects::effects_of(plan, runs, identified, timings);
            (effects, baselines.join())
        });
        let (models, preparation, baseline_notes, baseline_timings) = baselines
            .map_err(|_| anyhow::anyhow!("fitting the baselines of '{output}' stopped unexpectedly"))?;
        timings.0.extend(baseline_timings.0);
        Ok(Stage {
            plan,
            identified,
            effects,
            models,
            preparation,
            baseline_notes,
            timings: Timings::default(),
        })
    }

    /// The second phase for one output: the output built from its effects and diagnosed, compared,
    /// its residuals analysed and its figures drawn.
    fn second_phase(&self, stage: Stage, timings: &mut Timings) -> Result<OutputPart> {
        let Stage { plan, identified, effects, mut models, preparation, baseline_notes, .. } = stage;
        let output = plan.output.as_str();
        let built = effects::built_and_diagnosed(&plan, self.runs, &identified, effects, timings)?;
        let effects::Built { output: built_output, diagnosis, diagnosis_notes } = built;
        let BuiltOutput { effects, entry, mut notes, .. } = built_output;
        let extended = effects.model();
        notes.extend(baseline_notes);
        notes.extend(diagnosis_notes);
        models.initial_state = plan.settings.initial_state;
        let mut out = report::output_report(&identified, &models, entry.unit.clone());
        out.effects_applied = extended.effect_ids();
        out.error_history = effects.sequence.history.clone();
        out.shared_spool = effects.shared.clone();
        if !extended.effects.is_empty() {
            models.extended = Some(extended.clone());
        }
        out.diagnosis = diagnosis;
        out.preparation = preparation;
        self.describe_steady_states(&plan, extended, &mut out, &mut notes);
        let mut part = OutputPart {
            output: output.to_owned(),
            entry,
            report: out,
            figures: Vec::new(),
            notes,
            monte_carlo: None,
            timings: Timings::default(),
        };
        self.score_and_draw(&identified, &models, extended, &mut part, timings);
        Ok(part)
    }

    /// Whether the runs agree on the steady state under the final model (report.json
    /// `steady_states`).
    fn describe_steady_states(
        &self,
        plan: &OutputPlan,
        extended: &crate::core::effects::ExtendedModel,
        out: &mut OutputReport,
        notes: &mut Vec<String>,
    ) {
        let output = &plan.output;
        let described: Vec<&_> = std::iter::once(&self.runs.ident)
            .chain(self.runs.compared())
            .filter(|r| r.output(output).is_some())
            .collect();
        match steady_state_agreement(extended, &described, plan.settings.initial_state) {
            Ok(evidence) => out.steady_states = Some(evidence.sentence),
            Err(e) => notes.push(format!("steady states of '{output}' across runs: {e}")),
        }
    }

    /// Score every model on the scored runs, analyse the residuals, the control-oriented views,
    /// and draw the figures.
    fn score_and_draw(
        &self,
        identified: &Identified,
        models: &OutputModels,
        extended: &crate::core::effects::ExtendedModel,
        part: &mut OutputPart,
        timings: &mut Timings,
    ) {
        let (runs, output) = (self.runs, part.output.clone());
        let (out, notes, entry) = (&mut part.report, &mut part.notes, &part.entry);
        let studies = compare::compare(models, runs, &output, self.input_noise.as_ref(), out, notes, timings);
        let sigma = runs.steady.as_ref().and_then(|s| steady_noise_sigma(s, &output));
        let (residuals, figs) = timings.time("residuals", || {
            residuals::residual_reports(self.out_dir, &output, models, &runs.scored(), sigma, notes)
        });
        out.residuals = residuals;
        out.failing = crate::io::report::markdown::failing_models(out);
        (out.operating_points, out.continuous) = timings.time(&format!("control_{output}"), || {
            control::control_report(
                extended,
                entry.covariance.as_ref(),
                control::range_and_plateaus(runs),
                notes,
            )
        });
        out.parameter_intervals = control::parameter_report(extended, entry.covariance.as_ref(), notes);
        part.figures.extend(figs);
        if runs.steady.is_some() && self.input_noise.is_some() {
            part.monte_carlo = Some(compare::monte_carlo_summaries(&studies.monte_carlo));
            let (figs, figure_notes) = timings.time("figures", || {
                figures::monte_carlo_figures(self.out_dir, &output, &studies.monte_carlo)
            });
            part.figures.extend(figs);
            part.notes.extend(figure_notes);
        }
        let uncertain = part.entry.covariance.as_ref().map(|cov| (extended, cov));
        let (figs, figure_notes) = timings.time("figures", || {
            let curves = figures::OutputCurves::of(
                identified,
                models,
                uncertain,
                &runs.compared(),
                studies.frequency.as_ref(),
            );
            let report = &part.report;
            figures::output_figures(self.out_dir, &output, &report.unit, &curves, &report.error_boxes)
        });
        part.figures.extend(figs);
        part.notes.extend(figure_notes);
    }
}
