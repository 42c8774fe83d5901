//! The Compare view: the gray-box model against the linear block alone and the black-box baselines
//! (Hammerstein–Wiener, NNARX) as in the paper's sections 5.3–7 — Table 1, the traces of every
//! model, the chirp's frequency response and the Monte Carlo error propagation.
//!
//! Fitting the baselines and the Monte Carlo study take seconds, so they run as a [`Job`] off the UI
//! thread, one per output, started when the view is first shown for a model. A result is kept with
//! the model and runs it was computed for ([`CompareKey`]); when the model changes it stays visible,
//! marked stale, until the user asks for a recomputation.
pub mod plots;
pub mod table;
use crate::core::run::RunRole;
use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;

use egui::RichText;

use crate::core::compare::{CompareInput, OutputComparison, compare_output, compare_stage};
use crate::core::identification::fits::SegmentFits;
use crate::core::identification::initial_state::InitialState;
use crate::core::identification::wiener::WienerModel;
use crate::core::run::Run;
use crate::ui::derived::Derived;
use crate::ui::derived::jobs::{Job, JobError};
use crate::ui::state::session::Session;
use crate::ui::theme;
use crate::ui::views::compare::plots as compare_plots;
use crate::ui::views::compare::table as compare_table;
use crate::ui::widgets::model as model_ui;

/// What a comparison is computed for: the committed gray-box model, the segment fits it came from
/// and the runs (with their roles) it is compared on. Runs and fits are compared by pointer.
#[derive(Clone)]
pub struct CompareKey {
    wiener: WienerModel,
    /// The model's effects with their fitted parameters.
    effects: Vec<crate::core::effects::EffectRecord>,
    fits: Arc<SegmentFits>,
    runs: Vec<(RunRole, Arc<Run>)>,
    initial_state: InitialState,
}

impl CompareKey {
    fn same(&self, other: &Self) -> bool {
        self.wiener == other.wiener
            && self.effects == other.effects
            && Arc::ptr_eq(&self.fits, &other.fits)
            && self.initial_state == other.initial_state
            && self.runs.len() == other.runs.len()
            && self.runs.iter().zip(&other.runs).all(|(a, b)| a.0 == b.0 && Arc::ptr_eq(&a.1, &b.1))
    }
}

/// A finished comparison and what it was computed for.
pub struct CompareResult {
    pub key: CompareKey,
    pub comparison: OutputComparison,
    /// How long the job took.
    pub duration: Duration,
}

enum Phase {
    Idle,
    Running { job: Job<OutputComparison>, key: Box<CompareKey> },
    Cancelled,
    Failed(String),
}

/// One output's job and latest result.
struct OutputCompare {
    phase: Phase,
    result: Option<CompareResult>,
}

/// Where one output's comparison stands, for the view and for tests.
#[derive(Clone, Debug, PartialEq)]
pub enum CompareStatus {
    NotStarted,
    /// Running, with the fraction done.
    Running(f64),
    Cancelled,
    Failed(String),
    Done,
}

/// The Compare view's transient state: a job and a result per output, the run whose traces are shown.
#[derive(Default)]
pub struct CompareViewState {
    outputs: HashMap<String, OutputCompare>,
    /// The scored run shown in the traces plot (its name).
    pub run: Option<String>,
}

impl CompareViewState {
    /// Collect the results of finished jobs; call every frame, whichever view is shown.
    pub fn poll(&mut self) {
        for entry in self.outputs.values_mut() {
            let Phase::Running { job, key } = &entry.phase else { continue };
            let Some(outcome) = job.poll() else { continue };
            entry.phase = match outcome {
                Ok(comparison) => {
                    entry.result =
                        Some(CompareResult { key: (**key).clone(), comparison, duration: job.elapsed() });
                    Phase::Idle
                }
                Err(JobError::Cancelled) => Phase::Cancelled,
                Err(JobError::Failed(err)) => Phase::Failed(err),
            };
        }
    }

    /// True while any output's comparison is running.
    pub fn any_running(&self) -> bool {
        self.outputs.values().any(|e| matches!(e.phase, Phase::Running { .. }))
    }

    pub fn status(&self, output: &str) -> CompareStatus {
        match self.outputs.get(output).map(|e| &e.phase) {
            None => CompareStatus::NotStarted,
            Some(Phase::Running { job, .. }) => CompareStatus::Running(job.progress()),
            Some(Phase::Cancelled) => CompareStatus::Cancelled,
            Some(Phase::Failed(err)) => CompareStatus::Failed(err.clone()),
            Some(Phase::Idle) if self.result(output).is_some() => CompareStatus::Done,
            Some(Phase::Idle) => CompareStatus::NotStarted,
        }
    }

    /// The latest finished comparison of `output` (possibly stale).
    pub fn result(&self, output: &str) -> Option<&CompareResult> {
        self.outputs.get(output)?.result.as_ref()
    }

    /// Whether the latest result of `output` was computed for its current model and runs (`None`
    /// when there is no result or no current model).
    pub fn result_is_current(&self, output: &str, session: &Session, cache: &Derived) -> Option<bool> {
        let result = self.result(output)?;
        let (key, _) = current_input(session, cache, output).ok()?;
        Some(result.key.same(&key))
    }

    /// Stop `output`'s job; its result is dropped.
    pub fn cancel(&mut self, output: &str) {
        if let Some(entry) = self.outputs.get_mut(output)
            && let Phase::Running { job, .. } = &entry.phase
        {
            job.cancel();
            entry.phase = Phase::Cancelled;
        }
    }

    /// Start (or restart) `output`'s comparison on its current model.
    pub fn start(&mut self, output: &str, session: &Session, cache: &Derived, ctx: &egui::Context) {
        let entry = self
            .outputs
            .entry(output.to_owned())
            .or_insert(OutputCompare { phase: Phase::Idle, result: None });
        if let Phase::Running { job, .. } = &entry.phase {
            job.cancel();
        }
        entry.phase = match current_input(session, cache, output) {
            Ok((key, input)) => {
                let ctx = ctx.clone();
                let job = Job::spawn(
                    format!("Comparing models of {output}"),
                    move || ctx.request_repaint(),
                    move |progress| compare_output(&input, progress).map_err(|_| JobError::Cancelled),
                );
                Phase::Running { job, key: Box::new(key) }
            }
            Err(err) => Phase::Failed(err),
        };
    }
}

/// Why a model cannot be compared yet.
const FINISHING: &str = "the model is being finished (centroids polished, effects refitted)";

/// The comparison's input for `output`'s committed model (not a drag preview).
fn current_input(
    session: &Session,
    cache: &Derived,
    output: &str,
) -> Result<(CompareKey, CompareInput), String> {
    let ident = cache.ident.as_ref().ok_or("there is no identification run")?;
    let out = ident.output(output).ok_or_else(|| format!("{output} is not identified"))?;
    let fits = out.fits.as_ref().map_err(|e| format!("no segment fits: {e}"))?;
    let live = out.live.as_ref().map_err(|e| format!("no model: {e}"))?;
    if live.finishing {
        return Err(FINISHING.to_owned());
    }
    let mut runs = Vec::new();
    let mut scored = Vec::new();
    for run in &live.runs {
        let Some(entry) = session.runs.get(run.index) else { continue };
        runs.push((run.role, Arc::clone(&entry.run)));
        scored.push((Arc::clone(&entry.run), run.role == RunRole::Chirp));
    }
    let steady = session.first_with_role(RunRole::Steady).and_then(|i| session.runs.get(i));
    let steady = steady.map(|entry| Arc::clone(&entry.run));
    if let Some(run) = &steady {
        runs.push((RunRole::Steady, Arc::clone(run)));
    }
    let wiener = live.model.wiener.clone();
    let extended = live.effects.model.clone().filter(|m| !m.effects.is_empty());
    let effects = extended.as_ref().map(|m| m.records()).unwrap_or_default();
    let initial_state = out.setup.settings.initial_state;
    let key = CompareKey { wiener: wiener.clone(), effects, fits: Arc::clone(fits), runs, initial_state };
    let input = CompareInput {
        output: output.to_owned(),
        ident: Arc::clone(&ident.run),
        fits: Arc::clone(fits),
        wiener,
        scored,
        steady,
        extended,
        initial_state,
    };
    Ok((key, input))
}

pub fn compare_ui(
    ui: &mut egui::Ui,
    output: &str,
    state: &mut CompareViewState,
    session: &Session,
    cache: &Derived,
) {
    let Some(view) = cache.live_view(output) else { return };
    if !model_ui::model_state_ui(ui, &view) {
        return;
    }
    // A model still being finished is not compared: the comparison would be stale on arrival.
    let finishing = view.live.as_ref().is_ok_and(|l| l.finishing);
    if state.status(output) == CompareStatus::NotStarted && !finishing {
        state.start(output, session, cache, ui.ctx());
    }
    let current = current_input(session, cache, output).ok().map(|(key, _)| key);
    status_ui(ui, output, state, session, cache, current.as_ref());
    let Some(result) = state.result(output) else { return };
    let comparison = &result.comparison;
    let unit = view.output.unit.as_str();
    let shown_run = state.run.clone();
    let viewport_height = ui.available_height();
    let scroll = egui::ScrollArea::vertical().auto_shrink([false, false]).show(ui, |ui| {
        let top = ui.cursor().top();
        notes_ui(ui, comparison);
        ui.horizontal_top(|ui| {
            compare_table::table1_ui(ui, comparison, unit);
            ui.add_space(28.0);
            ui.vertical(|ui| compare_table::summary_ui(ui, comparison));
        });
        ui.separator();
        // The plots take what the table leaves above the Monte Carlo row, so the whole view fits
        // the window; on a short window they keep a readable height and the view scrolls.
        let used = ui.cursor().top() - top;
        let rest = viewport_height - used - compare_plots::monte_carlo_height(ui, comparison);
        let plot_height = (rest - 2.0 * ui.spacing().item_spacing.y - SEPARATOR_HEIGHT)
            .clamp(compare_plots::MIN_PLOT_HEIGHT, compare_plots::PLOT_HEIGHT);
        let label = view.output.label();
        let bands: Vec<(&str, &[f64])> = match view.live.as_ref() {
            Ok(live) => live
                .uncertainty
                .as_ref()
                .map(|u| {
                    live.runs
                        .iter()
                        .zip(&u.run_bands)
                        .filter_map(|(run, band)| Some((run.name.as_str(), band.as_deref().ok()?)))
                        .collect()
                })
                .unwrap_or_default(),
            Err(_) => Vec::new(),
        };
        let selected = compare_plots::traces_and_frequency_ui(
            ui,
            &compare_plots::Row {
                comparison,
                shown_run: shown_run.as_deref(),
                output_label: &label,
                height: plot_height,
                bands: &bands,
            },
        );
        ui.separator();
        compare_plots::monte_carlo_ui(ui, comparison, unit);
        selected
    });
    if let Some(run) = scroll.inner {
        state.run = Some(run);
    }
}

/// Height of a separator with its spacing, points (egui's default).
const SEPARATOR_HEIGHT: f32 = 6.0;

/// The job's progress with Cancel, or what happened to it, or a stale-result warning with Recompute.
fn status_ui(
    ui: &mut egui::Ui,
    output: &str,
    state: &mut CompareViewState,
    session: &Session,
    cache: &Derived,
    current: Option<&CompareKey>,
) {
    let mut restart = false;
    let mut cancel = false;
    let stale = state.result(output).zip(current).is_some_and(|(r, key)| !r.key.same(key));
    ui.horizontal(|ui| match state.outputs.get(output).map(|e| &e.phase) {
        Some(Phase::Running { job, key }) => {
            let fraction = job.progress();
            let text = format!(
                "{} — {} — {:.0} %, {:.1} s",
                job.label(),
                compare_stage(fraction),
                100.0 * fraction,
                job.elapsed().as_secs_f64()
            );
            ui.add(egui::ProgressBar::new(fraction as f32).text(text).desired_width(640.0).animate(true));
            cancel = ui.button("Cancel").clicked();
            if current.is_some_and(|c| !c.same(key)) {
                ui.label(RichText::new("the model changed since this started").color(theme::WARNING));
                restart = ui.button("Recompute").clicked();
            }
        }
        Some(Phase::Cancelled) => {
            ui.label(RichText::new("The comparison was cancelled.").color(theme::WARNING));
            restart = ui.button("Run again").clicked();
        }
        Some(Phase::Failed(err)) => {
            model_ui::error_ui(ui, &format!("The comparison failed: {err}"));
            restart = ui.button("Run again").clicked();
        }
        _ if stale => {
            ui.label(
                RichText::new("Stale: computed for an earlier model or set of runs.").color(theme::WARNING),
            );
            restart = ui.button("Recompute").clicked();
        }
        _ => {
            if let Some(result) = state.result(output) {
                model_ui::hint(
                    ui,
                    &format!(
                        "Baselines fitted on the identification range; computed in {:.1} s.",
                        result.duration.as_secs_f64()
                    ),
                );
            }
        }
    });
    if cancel {
        state.cancel(output);
    }
    if restart {
        state.start(output, session, cache, ui.ctx());
    }
}

/// Runs or studies that are missing, and parts that failed.
fn notes_ui(ui: &mut egui::Ui, comparison: &OutputComparison) {
    if !comparison.runs.iter().any(|r| !r.is_chirp) {
        model_ui::hint(ui, "No validation run: give a run the role validation to score the models on it.");
    }
    if comparison.frequency.is_none() {
        model_ui::hint(ui, "No chirp run: the frequency-domain comparison is skipped.");
    }
    if comparison.noise.is_none() {
        ui.label(
            RichText::new(
                "No steady run: the noise fit and the Monte Carlo error propagation are skipped \
                 (give a run the role steady).",
            )
            .color(theme::WARNING),
        );
    }
    for note in &comparison.notes {
        model_ui::error_ui(ui, note);
    }
}
