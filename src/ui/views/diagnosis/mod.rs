//! The Diagnosis view: which physical effect the model of the selected output is missing, the
//! error history of the effects applied, and where the model fails (residual pictures, see
//! [`diagnosis_residuals_ui`](super::diagnosis_residuals_ui)).
//!
//! The diagnosis ([`crate::core::diagnose`]) runs in a background [`Job`] for the committed model
//! it was started on; when the model changes (an effect applied, a cluster moved) the result is
//! kept but marked stale, with a button to run it again.
pub mod residuals;
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use egui::RichText;
use egui_plot::{Bar, BarChart, Plot, Text};

use crate::core::diagnose::HistoryStep;
use crate::core::diagnose::{self, DiagnosisKind, DiagnosisReport};
use crate::core::effects::EffectId;
use crate::ui::derived::Derived;
use crate::ui::derived::diagnosis_model::DiagnosisInput;
use crate::ui::derived::jobs::Job;
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
            input.run(progress).map(|report| (report, started.elapsed())).map_err(|e| e.to_string())
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

    fn finish(&mut self, outcome: Result<(DiagnosisReport, Duration), String>, elapsed: Duration) {
        let Some(running) = self.running.take() else { return };
        self.store(running.output, running.model, outcome, elapsed);
    }

    fn store(
        &mut self,
        output: String,
        model: ModelKey,
        outcome: Result<(DiagnosisReport, Duration), String>,
        elapsed: Duration,
    ) {
        if outcome.as_ref().err().is_some_and(|e| e == crate::ui::derived::jobs::CANCELLED) {
            return;
        }
        let duration = outcome.as_ref().map_or(elapsed, |(_, d)| *d);
        let outcome = outcome.map(|(report, _)| report);
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
        Section::WhichEffect => which_effect_ui(ui, output, state, view.output, live, view.is_preview),
        Section::WhereItFails => {
            diagnosis_residuals_ui::where_it_fails_ui(ui, output, &mut state.residuals, session, live)
        }
    }
}

fn which_effect_ui(
    ui: &mut egui::Ui,
    output: &str,
    state: &mut DiagnosisViewState,
    cache: &crate::ui::derived::model_cache::OutputCache,
    live: &crate::ui::derived::model_cache::LiveModel,
    is_preview: bool,
) -> Vec<Command> {
    let mut commands = Vec::new();
    ui.horizontal_top(|ui| {
        ui.vertical(|ui| {
            ui.set_width(460.0);
            ui.label(RichText::new("Error history (mean validation RMSPE)").strong());
            history_chart_ui(ui, output, &live.effects.history);
        });
        ui.vertical(|ui| {
            ui.label(RichText::new("Effects in the model").strong());
            if live.effects.requested.is_empty() {
                hint(ui, "None yet: the model is the paper's gray-box Wiener model.");
            }
            for id in &live.effects.requested {
                ui.horizontal(|ui| {
                    ui.label(RichText::new(id.name()).monospace());
                    if ui.button("Remove").on_hover_text("Take the effect out (undo: Ctrl+Z)").clicked() {
                        commands.push(Command::RemoveEffect {
                            output: output.to_owned(),
                            effect: id.name().to_owned(),
                        });
                    }
                });
            }
            if let Some(model) = &live.effects.model {
                for effect in &model.effects {
                    let params: Vec<String> =
                        effect.params().iter().map(|(name, value)| format!("{name} = {value:.4}")).collect();
                    hint(ui, &format!("{}: {}", effect.id(), params.join(", ")));
                }
            }
        });
    });
    ui.separator();
    job_status_ui(ui, output, state, cache, &live.key(), is_preview, live.finishing);
    let applied = &live.effects.requested;
    let Some(finished) = state.result(output) else { return commands };
    let report = match &finished.outcome {
        Ok(report) => report,
        Err(err) => {
            error_ui(ui, &format!("The diagnosis failed: {err}"));
            return commands;
        }
    };
    let physics_found = report.entries.iter().any(|e| e.significant && e.kind == DiagnosisKind::Physics);
    hint(ui, &format!("Judged on the validation runs; {}.", report.held_out_words()));
    if let Some(note) = report.structure_note.as_ref().filter(|_| physics_found) {
        hint(ui, &format!("The structure may also improve: {note}."));
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
            let finished =
                FinishedDiagnosis { model: model.clone(), outcome: Err(err), duration: Duration::ZERO };
            state.results.insert(output.to_owned(), finished);
        }
    };
    if let Some(running) = &state.running {
        let mut cancel = false;
        ui.horizontal(|ui| {
            let bar = egui::ProgressBar::new(running.job.progress() as f32)
                .desired_width(260.0)
                .text(format!("{} … {:.1} s", running.job.label(), running.job.elapsed().as_secs_f64()));
            ui.add(bar);
            cancel = ui.button("Cancel").clicked();
        });
        if cancel {
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
    match finished {
        None => start(state, ui),
        Some((stale, duration, ok)) => {
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
            hint(
                ui,
                &format!(
                    "Each effect is added to the current model, refitted on the identification run and \
                     scored on the validation runs. Significant: a one-sided Diebold–Mariano test on \
                     |% error| against the refitted current model, combined (Stouffer) with a signed-rank \
                     test over the identification steps a cross-validation held out when at least {} of \
                     them are changed by the effect, gives p < {} and the validation RMSPE falls by at \
                     least {:.0} %. Structural refinements (one more pole, pole pair or zero, \
                     the map's order, a scheduled time constant) are tried too; a physical effect counts \
                     only when it also beats the best of them by the same rule and its own evidence shows \
                     its signature.",
                    diagnose::MIN_WITNESS_RESPONSES,
                    diagnose::SIGNIFICANCE_LEVEL,
                    100.0 * diagnose::MIN_RELATIVE_REDUCTION
                ),
            );
        }
    }
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
                    "RMSPE {:.3} % → {:.3} %  ({:+.1} %)",
                    entry.rmspe_before_pct,
                    entry.rmspe_after_pct,
                    -100.0 * entry.relative_reduction()
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
                if applied.iter().any(|id| id.name() == entry.effect) {
                    ui.label(RichText::new("in the model").color(theme::OK));
                } else if entry.effect.parse::<EffectId>().is_err() {
                    ui.label(RichText::new("edit the clusters").color(theme::HINT)).on_hover_text(
                        "A change of the linear block or the map is made on the z-plane (add or move a \
                         cluster) or in the output's settings, not added as a block",
                    );
                } else if ui
                    .button("Apply")
                    .on_hover_text(format!("Add {} to the model of {output} (undo: Ctrl+Z)", entry.effect))
                    .clicked()
                {
                    command = Some(Command::ApplyEffect {
                        output: output.to_owned(),
                        effect: entry.effect.clone(),
                    });
                }
            });
        });
        ui.label(RichText::new(&entry.physics).italics());
        hint(ui, &entry.evidence);
        hint(ui, &entry.test.words());
        if let Some(rival) = &entry.rival {
            let versus = format!("the best structural refinement, {} ({:.3} %)", rival.id, rival.rmspe_pct);
            let p = diagnose::p_text(rival.test.p_value);
            let reduction = rival.test.reduction;
            let text = if reduction > 0.0 {
                format!("beats {versus} by {:.1} % (p = {p})", 100.0 * reduction)
            } else {
                format!("loses to {versus}: its error is {:.1} % higher (p = {p})", -100.0 * reduction)
            };
            hint(ui, &text);
        }
    });
    command
}

/// Bars of the validation RMSPE after each step, each labelled with its value.
fn history_chart_ui(ui: &mut egui::Ui, output: &str, history: &[HistoryStep]) {
    if history.is_empty() {
        hint(ui, "No validation run: give a run the role validation to see the error.");
        return;
    }
    let steps = history.len();
    let top = history.iter().map(|s| s.rmspe_pct).fold(0.0, f64::max);
    let bars: Vec<Bar> = history
        .iter()
        .enumerate()
        .map(|(i, s)| Bar::new(i as f64, s.rmspe_pct).width(0.6).name(&s.step))
        .collect();
    Plot::new(("diagnosis_history", output))
        .height(170.0)
        .allow_drag(false)
        .allow_zoom(false)
        .allow_scroll(false)
        .allow_boxed_zoom(false)
        .show_x(false)
        .include_y(0.0)
        .include_y(top * 1.25)
        .include_x(-0.6)
        .include_x(history.len() as f64 - 0.4)
        .y_axis_label("RMSPE [%]")
        .show_grid([false, true])
        // The steps are numbered on the axis and named below the chart: egui_plot drops tick labels
        // that would overlap, and step names ("+scheduled_time_constant (auto)") are long.
        .x_axis_formatter(move |mark, _| {
            let i = mark.value.round();
            if (mark.value - i).abs() > 1e-6 || i < 0.0 || i as usize >= steps {
                return String::new();
            }
            format!("{}", i as usize + 1)
        })
        .show(ui, |plot_ui| {
            plot_ui.bar_chart(BarChart::new("validation RMSPE", bars).color(theme::MODEL));
            for (i, step) in history.iter().enumerate() {
                let at = egui_plot::PlotPoint::new(i as f64, step.rmspe_pct + top * 0.04);
                let label = Text::new(
                    "value",
                    at,
                    RichText::new(format!("{:.3} %", step.rmspe_pct)).size(14.0).strong(),
                )
                .anchor(egui::Align2::CENTER_BOTTOM);
                plot_ui.text(label);
            }
        });
    let names: Vec<String> =
        history.iter().enumerate().map(|(i, s)| format!("{} {}", i + 1, s.step)).collect();
    hint(ui, &names.join("    "));
}
