//! The Diagnosis view: which physical effect the model of the selected output is missing, the
//! error history of the effects applied, and where the model fails (residual pictures, see
//! [`diagnosis_residuals_ui`](super::diagnosis_residuals_ui)).
//!
//! The diagnosis ([`crate::core::diagnose`]) runs in a background [`Job`] for the committed model
//! it was started on; when the model changes (an effect applied, a cluster moved) the result is
//! kept but marked stale, with a button to run it again.
mod effects;
pub mod residuals;
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use egui::RichText;

use crate::core::diagnose::{self, DiagnosisKind, DiagnosisReport};
use crate::core::effects::EffectId;
use crate::ui::derived::Derived;
use crate::ui::derived::diagnosis_model::DiagnosisInput;
use crate::ui::derived::jobs::{Job, JobError, JobResult};
use crate::ui::derived::live_model::ModelKey;
use crate::ui::state::command::Command;
use crate::ui::state::session::Session;
use crate::ui::theme;
use crate::ui::views::diagnosis::residuals::{self as diagnosis_residuals_ui, ResidualsState};
use crate::ui::widgets::model::{self as model_ui, error_ui, hint};

/// The two halves of the view.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Section {
    #[default]
    WhichEffect,
    WhereItFails,
}

/// A diagnosis that has ended, for the model it was started on.
pub struct FinishedDiagnosis {
    /// The model diagnosed, by value: undoing back to it makes the diagnosis current again.
    pub model: ModelKey,
    pub outcome: Result<DiagnosisReport, String>,
    /// How long the diagnosis took on its worker thread.
    pub duration: Duration,
}

struct RunningDiagnosis {
    output: String,
    model: ModelKey,
    job: Job<(DiagnosisReport, Duration)>,
}

#[derive(Default)]
pub struct DiagnosisViewState {
    pub section: Section,
    running: Option<RunningDiagnosis>,
    /// The latest diagnosis of each output.
    results: BTreeMap<String, FinishedDiagnosis>,
    pub residuals: ResidualsState,
}

impl DiagnosisViewState {
    /// The latest diagnosis of `output`, if one has ended.
    pub fn result(&self, output: &str) -> Option<&FinishedDiagnosis> {
        self.results.get(output)
    }

    pub fn is_running(&self) -> bool {
        self.running.is_some()
    }

    /// Start diagnosing (a diagnosis still running is cancelled).
    pub fn start(&mut self, input: DiagnosisInput, repaint: impl Fn() + Send + 'static) {
        if let Some(old) = self.running.take() {
            old.job.cancel();
        }
        let (output, model) = (input.output.clone(), input.model.clone());
        let job = Job::spawn(format!("Diagnosing {output}"), repaint, move |progress| {
            let started = Instant::now();
            let report = input.run(progress).map_err(|e| JobError::Failed(e.to_string()))?;
            Ok((report, started.elapsed()))
        });
        self.running = Some(RunningDiagnosis { output, model, job });
    }

    /// Take the result of the running diagnosis when it has ended (call every frame).
    pub fn poll(&mut self) {
        let Some(running) = &self.running else { return };
        let Some(outcome) = running.job.poll() else { return };
        let duration = running.job.elapsed();
        self.finish(outcome, duration);
    }

    /// Block until the running diagnosis ends (tests and screenshots, never in a frame).
    pub fn wait(&mut self) {
        let Some(running) = self.running.take() else { return };
        let outcome = running.job.wait();
        self.store(running.output, running.model, outcome, Duration::ZERO);
    }

    fn finish(&mut self, outcome: JobResult<(DiagnosisReport, Duration)>, elapsed: Duration) {
        let Some(running) = self.running.take() else { return };
        self.store(running.output, running.model, outcome, elapsed);
    }

    fn store(
        &mut self,
        output: String,
        model: ModelKey,
        outcome: JobResult<(DiagnosisReport, Duration)>,
        elapsed: Duration,
    ) {
        if outcome.as_ref().err() == Some(&JobError::Cancelled) {
            return;
        }
        let duration = outcome.as_ref().map_or(elapsed, |(_, d)| *d);
        let outcome = outcome.map(|(report, _)| report).map_err(|e| e.to_string());
        self.results.insert(output, FinishedDiagnosis { model, outcome, duration });
    }

    fn cancel(&mut self) {
        if let Some(running) = self.running.take() {
            running.job.cancel();
        }
    }
}

pub fn diagnosis_ui(
    ui: &mut egui::Ui,
    output: &str,
    state: &mut DiagnosisViewState,
    session: &Session,
    cache: &Derived,
) -> Vec<Command> {
    state.poll();
    let Some(view) = cache.live_view(output) else { return Vec::new() };
    if !model_ui::model_state_ui(ui, &view) {
        return Vec::new();
    }
    let Ok(live) = &view.output.live else { return Vec::new() };
    ui.horizontal(|ui| {
        for (section, label) in
            [(Section::WhichEffect, "Which effect"), (Section::WhereItFails, "Where it fails")]
        {
            if ui.selectable_label(state.section == section, RichText::new(label).strong()).clicked() {
                state.section = section;
            }
        }
    });
    ui.separator();
    match state.section {
        Section::WhichEffect => {
            let shared_with = taken_from(output, cache);
            which_effect_ui(ui, output, state, view.output, live, view.is_preview, &shared_with)
        }
        Section::WhereItFails => {
            diagnosis_residuals_ui::where_it_fails_ui(ui, output, &mut state.residuals, session, live)
        }
    }
}

/// What the other outputs' models took of `output`'s spool blocks: "thrust_n: scheduled_time_constant".
fn taken_from(output: &str, cache: &Derived) -> Vec<String> {
    cache
        .output_names()
        .into_iter()
        .filter(|other| *other != output)
        .filter_map(|other| {
            let live = cache.output(other)?.live.as_ref().ok()?;
            let taken: Vec<&str> = live
                .effects
                .shared
                .iter()
                .filter(|b| b.taken && b.from == output)
                .map(|b| b.id.name())
                .collect();
            (!taken.is_empty()).then(|| format!("{other}: {}", taken.join(", ")))
        })
        .collect()
}

fn which_effect_ui(
    ui: &mut egui::Ui,
    output: &str,
    state: &mut DiagnosisViewState,
    cache: &crate::ui::derived::model_cache::OutputCache,
    live: &crate::ui::derived::model_cache::LiveModel,
    is_preview: bool,
    shared_with: &[String],
) -> Vec<Command> {
    let mut commands = effects::effects_panel_ui(ui, output, cache, live, shared_with);
    ui.separator();
    job_status_ui(ui, output, state, cache, &live.key(), is_preview, live.finishing);
    let Some(finished) = state.result(output) else { return commands };
    match &finished.outcome {
        Ok(report) => commands.extend(ranking_ui(ui, output, report, &live.current_model().effect_ids())),
        // Not a failure: an output read off the speed's model is diagnosed on the speed.
        Err(err) if live.current_model().read_off().is_some() => {
            ui.label(format!("The diagnosis is {err}"));
        }
        Err(err) => error_ui(ui, &format!("The diagnosis failed: {err}")),
    }
    commands
}

/// The trials best first, what the structure needs, and what was not tried.
fn ranking_ui(
    ui: &mut egui::Ui,
    output: &str,
    report: &DiagnosisReport,
    applied: &[EffectId],
) -> Vec<Command> {
    let mut commands = Vec::new();
    hint(ui, &format!("Judged on the validation runs; {}.", report.held_out_words()));
    if let Some(note) = report.structure_note.as_ref().filter(|_| report.top_is_physics()) {
        let mut chars = note.chars();
        let first = chars.next().map(|c| c.to_uppercase().collect::<String>()).unwrap_or_default();
        hint(ui, &format!("{first}{}.", chars.as_str()));
    } else if let Some(note) = &report.structure_note {
        egui::Frame::group(ui.style()).show(ui, |ui| {
            ui.set_width(ui.available_width());
            ui.label(RichText::new("Model structure first").strong().color(theme::WARNING));
            ui.label(format!(
                "{note}. Change the model's structure first (the clusters on the z-plane, the map's \
                 order, or the scheduled time constant below) before blaming a physical effect."
            ));
        });
    }
    if let Some(note) = &report.attribution_note {
        egui::Frame::group(ui.style()).show(ui, |ui| {
            ui.set_width(ui.available_width());
            ui.label(
                RichText::new("Two explanations the data cannot tell apart").strong().color(theme::WARNING),
            );
            ui.label(format!("{note}."));
        });
    }
    egui::ScrollArea::vertical().auto_shrink([false, false]).show(ui, |ui| {
        for (rank, entry) in report.entries.iter().enumerate() {
            if let Some(command) = entry_ui(ui, output, rank, entry, applied) {
                commands.push(command);
            }
        }
        if !report.skipped.is_empty() {
            ui.add_space(4.0);
            ui.label(RichText::new("Not tried").strong());
            for skipped in &report.skipped {
                hint(ui, &format!("{}: {}", skipped.effect, skipped.reason));
            }
        }
    });
    commands
}

/// Progress and Cancel while the diagnosis runs; Re-run when the model changed; the first run
/// starts by itself.
fn job_status_ui(
    ui: &mut egui::Ui,
    output: &str,
    state: &mut DiagnosisViewState,
    cache: &crate::ui::derived::model_cache::OutputCache,
    model: &ModelKey,
    is_preview: bool,
    finishing: bool,
) {
    let start = |state: &mut DiagnosisViewState, ui: &egui::Ui| match cache.diagnosis_input() {
        Ok(input) => {
            let ctx = ui.ctx().clone();
            state.start(input, move || ctx.request_repaint());
        }
        Err(err) => {
            let finished = FinishedDiagnosis {
                model: model.clone(),
                outcome: Err(err.to_string()),
                duration: Duration::ZERO,
            };
            state.results.insert(output.to_owned(), finished);
        }
    };
    if let Some(running) = &state.running {
        if progress_ui(ui, &running.job) {
            state.cancel();
        }
        return;
    }
    if is_preview {
        hint(ui, "A cluster is being dragged; the diagnosis waits for the committed model.");
        return;
    }
    if finishing {
        hint(
            ui,
            "The model is being finished (centroids polished, effects refitted); the diagnosis waits for it.",
        );
        return;
    }
    let finished = state.result(output).map(|f| (&f.model != model, f.duration, f.outcome.is_ok()));
    let Some((stale, duration, ok)) = finished else { return start(state, ui) };
    ui.horizontal_wrapped(|ui| {
        if stale {
            ui.label(
                RichText::new("The model changed since this diagnosis: the ranking below is stale.")
                    .color(theme::WARNING),
            );
        } else if ok && duration > Duration::ZERO {
            hint(ui, &format!("Diagnosed in {:.2} s.", duration.as_secs_f64()));
        }
        if ui.button(if stale { "Re-run diagnosis" } else { "Run again" }).clicked() {
            start(state, ui);
        }
    });
    method_hint(ui);
}

/// A job's progress bar with its label and time, and a Cancel button; true when it was clicked.
pub(crate) fn progress_ui<T>(ui: &mut egui::Ui, job: &Job<T>) -> bool {
    let mut cancel = false;
    ui.horizontal(|ui| {
        let bar = egui::ProgressBar::new(job.progress() as f32).desired_width(260.0).text(format!(
            "{} … {:.1} s",
            job.label(),
            job.elapsed().as_secs_f64()
        ));
        ui.add(bar);
        cancel = ui.button("Cancel").clicked();
    });
    cancel
}

/// How a trial is judged, in words.
fn method_hint(ui: &mut egui::Ui) {
    hint(
        ui,
        &format!(
            "Each effect and structural refinement (one more pole, pole pair or zero, the map's \
             order, a scheduled time constant) is added to the current model, refitted on the \
             identification run and scored on the validation runs by its error beyond the \
             measurement noise (in units of σ; the ranking follows it). Significant: the validation \
             runs against the refitted current model (a one-sided Diebold–Mariano test on \
             |error|/σ, or where at least {} of their steps' responses are changed, the better of it \
             and a signed-rank test over those responses, doubled), combined (Stouffer) with a \
             signed-rank test over the identification steps a cross-validation held out when at \
             least {} of them are changed, give p < {} and at least {:.0} % of the error beyond the \
             noise is removed. A physical effect counts only when its own \
             evidence shows its signature and the data prefer it to the best refinement; effects \
             before the spool are read on the shaft speed when this output is another.",
            diagnose::MIN_VALIDATION_RESPONSES,
            diagnose::MIN_WITNESS_RESPONSES,
            diagnose::SIGNIFICANCE_LEVEL,
            100.0 * diagnose::MIN_RELATIVE_REDUCTION
        ),
    );
}

/// One ranked effect: numbers, verdict, Apply; its physics and evidence below.
fn entry_ui(
    ui: &mut egui::Ui,
    output: &str,
    rank: usize,
    entry: &diagnose::Diagnosis,
    applied: &[EffectId],
) -> Option<Command> {
    let mut command = None;
    egui::Frame::group(ui.style()).show(ui, |ui| {
        ui.set_width(ui.available_width());
        ui.horizontal(|ui| {
            ui.label(RichText::new(format!("{}. {}", rank + 1, entry.effect)).strong().monospace());
            ui.label(RichText::new(entry.kind.label()).small().color(theme::HINT));
            ui.label(
                RichText::new(format!(
                    "RMSPE {:.3} % → {:.3} %   beyond noise {:.2} σ → {:.2} σ",
                    entry.rmspe_before_pct,
                    entry.rmspe_after_pct,
                    entry.beyond_noise_before,
                    entry.beyond_noise_after
                ))
                .monospace(),
            );
            ui.label(RichText::new(format!("p = {}", diagnose::p_text(entry.test.p_value))).monospace());
            match (entry.significant, entry.kind) {
                (true, DiagnosisKind::Physics) => {
                    ui.label(RichText::new("significant").color(theme::OK).strong());
                }
                (true, DiagnosisKind::Structure) => {
                    ui.label(RichText::new("structure needed").color(theme::WARNING).strong());
                }
                (false, _) => {
                    ui.label(RichText::new("not significant").color(theme::HINT));
                }
            }
            ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                let effect = entry.effect.as_effect();
                if effect.is_some_and(|id| applied.contains(&id)) {
                    ui.label(RichText::new("in the model").color(theme::OK));
                } else if effect.is_none() {
                    ui.label(RichText::new("edit the clusters").color(theme::HINT)).on_hover_text(
                        "A change of the linear block or the map is made on the z-plane (add or move a \
                         cluster) or in the output's settings, not added as a block",
                    );
                } else if ui
                    .button("Apply")
                    .on_hover_text(format!("Add {} to the model of {output} (undo: Ctrl+Z)", entry.effect))
                    .clicked()
                {
                    command = Some(Command::ApplyEffect { output: output.to_owned(), trial: entry.effect });
                }
            });
        });
        ui.label(RichText::new(&entry.physics).italics());
        hint(ui, &entry.evidence);
        hint(ui, &entry.significance_words());
    });
    command
}
