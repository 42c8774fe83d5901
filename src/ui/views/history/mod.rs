//! The History view: a fleet of engines opened from its manifest (File > Open fleet manifest…, or
//! `jetid --fleet MANIFEST`), each engine's runs against its reference in date order — the errors, the
//! health deltas with their intervals, the runs outside the engine's normal band flagged in words —
//! the deltas' trends, and one run against its reference.
//!
//! The fleet is computed as a [`Job`] (references loaded or identified, every run scored) while the
//! frame goes on; its errors are shown here. The session is never touched: the fleet lives in this
//! view's state.
pub mod plots;
pub mod table;

use std::path::PathBuf;
use std::time::Duration;

use egui::RichText;

use crate::ui::derived::fleet_history::{FleetHistory, RunComparison, compare_run, compute_fleet};
use crate::ui::derived::jobs::{Job, JobError};
use crate::ui::state::command::{Command, FileAction};
use crate::ui::theme;
use crate::ui::views::history::plots::{comparison_ui, trends_ui};
use crate::ui::views::history::table::{engines_ui, runs_ui};
use crate::ui::widgets::hint;

/// How often a frame looks at the fleet job's progress while it runs.
const POLL: Duration = Duration::from_millis(100);
const ENGINE_LIST_WIDTH: f32 = 160.0;

/// Where the fleet stands, for the view and for tests.
#[derive(Clone, Debug, PartialEq)]
pub enum HistoryStatus {
    /// No fleet opened.
    Empty,
    /// Being computed, with the fraction done.
    Loading(f64),
    Failed(String),
    Ready,
}

/// A run against its reference: simulated on a worker (a long run takes a moment), then kept.
enum Comparison {
    Running(Job<RunComparison>),
    Done(Result<RunComparison, String>),
}

/// The History view's state: the fleet (computed or being computed), the engine and run selected,
/// and the selected run's comparison with its reference.
#[derive(Default)]
pub struct HistoryViewState {
    job: Option<(Job<FleetHistory>, PathBuf)>,
    fleet: Option<FleetHistory>,
    /// Why the last fleet opened could not be computed.
    error: Option<String>,
    pub engine: usize,
    pub run: Option<usize>,
    /// The comparison of (engine, run) with its reference: being computed, or done.
    comparison: Option<((usize, usize), Comparison)>,
    /// Where the first trend's points were drawn last frame (for tests).
    pub last_trend_transform: Option<egui_plot::PlotTransform>,
}

impl HistoryViewState {
    /// Compute the fleet of the manifest at `path` on a worker thread; the fleet shown so far stays
    /// until the new one is ready.
    pub fn open(&mut self, path: PathBuf) {
        let manifest = path.clone();
        let job = Job::spawn("Scoring the fleet", || {}, move |progress| compute_fleet(&manifest, progress));
        self.job = Some((job, path));
        self.error = None;
    }

    /// Collect the jobs' results; call every frame, whichever view is shown.
    pub fn poll(&mut self) {
        if let Some((_, comparison)) = &mut self.comparison
            && let Comparison::Running(job) = comparison
            && let Some(outcome) = job.poll()
        {
            *comparison = Comparison::Done(outcome.map_err(|e| e.to_string()));
        }
        let Some((job, path)) = &self.job else { return };
        let Some(outcome) = job.poll() else { return };
        let path = path.clone();
        self.job = None;
        self.finish(path, outcome);
    }

    fn finish(&mut self, path: PathBuf, outcome: Result<FleetHistory, JobError>) {
        match outcome {
            Ok(fleet) => {
                self.fleet = Some(fleet);
                self.engine = 0;
                self.run = None;
                self.comparison = None;
            }
            Err(JobError::Cancelled) => {}
            Err(JobError::Failed(message)) => {
                self.error = Some(format!("Could not open the fleet {}: {message}", path.display()));
            }
        }
    }

    /// True while the fleet or the selected run's comparison is computed.
    pub fn is_running(&self) -> bool {
        self.job.is_some() || matches!(self.comparison, Some((_, Comparison::Running(_))))
    }

    /// Block until the fleet job and the comparison end (tests and screenshots, never in a frame).
    pub fn wait(&mut self) {
        if let Some((job, path)) = self.job.take() {
            let outcome = job.wait();
            self.finish(path, outcome);
        }
        if let Some((key, comparison)) = self.comparison.take() {
            let comparison = match comparison {
                Comparison::Running(job) => Comparison::Done(job.wait().map_err(|e| e.to_string())),
                done @ Comparison::Done(_) => done,
            };
            self.comparison = Some((key, comparison));
        }
    }

    pub fn status(&self) -> HistoryStatus {
        match (&self.job, &self.error, &self.fleet) {
            (Some((job, _)), _, _) => HistoryStatus::Loading(job.progress()),
            (None, Some(error), _) => HistoryStatus::Failed(error.clone()),
            (None, None, Some(_)) => HistoryStatus::Ready,
            (None, None, None) => HistoryStatus::Empty,
        }
    }

    pub fn fleet(&self) -> Option<&FleetHistory> {
        self.fleet.as_ref()
    }

    /// The comparison shown, or why there is none.
    pub fn comparison(&self) -> Option<&Result<RunComparison, String>> {
        match &self.comparison {
            Some((_, Comparison::Done(result))) => Some(result),
            _ => None,
        }
    }

    /// Open the first flagged run of the first engine that has one, else the first run.
    pub fn select_first_flagged(&mut self) {
        let Some(fleet) = &self.fleet else { return };
        let first = fleet
            .engines
            .iter()
            .enumerate()
            .find_map(|(e, engine)| engine.runs.iter().position(|r| r.flagged()).map(|r| (e, r)));
        let (engine, run) = first.unwrap_or((0, 0));
        self.select_engine(engine);
        self.select_run(run);
    }

    /// Show engine `engine`, no run opened.
    pub fn select_engine(&mut self, engine: usize) {
        self.engine = engine;
        self.run = None;
        self.comparison = None;
    }

    /// Open run `run` of the selected engine against its reference.
    pub fn select_run(&mut self, run: usize) {
        self.run = Some(run);
        let key = (self.engine, run);
        if self.comparison.as_ref().is_some_and(|(k, _)| *k == key) {
            return;
        }
        let Some(engine) = self.fleet.as_ref().and_then(|f| f.engines.get(self.engine)) else { return };
        let Some(history) = engine.runs.get(run) else { return };
        let (run, reference) = (history.run.clone(), engine.reference.clone());
        let job = Job::spawn(
            format!("Simulating the reference on run {}", run.name),
            || {},
            move |_| compare_run(&run, &reference).map_err(|e| JobError::Failed(format!("{e:#}"))),
        );
        self.comparison = Some((key, Comparison::Running(job)));
    }
}

/// Draw the History view.
pub fn history_ui(ui: &mut egui::Ui, state: &mut HistoryViewState) -> Vec<Command> {
    let mut commands = Vec::new();
    if header_ui(ui, state) {
        commands.push(Command::ChooseFile(FileAction::OpenFleet));
    }
    if let Some(error) = &state.error {
        // Monospace: a TOML error's caret points at its column.
        ui.label(RichText::new(error).color(theme::ERROR).monospace());
    }
    let Some(fleet) = &state.fleet else {
        if !state.is_running() {
            hint(ui, "No fleet open: File > Open fleet manifest… (or `jetid --fleet MANIFEST`).");
        }
        return commands;
    };
    let mut engine_clicked = None;
    let mut run_clicked = None;
    let mut trend_transform = None;
    ui.horizontal_top(|ui| {
        ui.vertical(|ui| {
            ui.set_width(ENGINE_LIST_WIDTH);
            engine_clicked = engines_ui(ui, fleet, state.engine);
        });
        ui.separator();
        ui.vertical(|ui| {
            let Some(engine) = fleet.engines.get(state.engine) else { return };
            ui.label(format!("Engine {} — reference: {}", engine.name, engine.reference.described));
            egui::ScrollArea::both()
                .id_salt("history_run_table")
                .max_height(ui.available_height() * 0.32)
                .show(ui, |ui| run_clicked = runs_ui(ui, engine, state.run));
            ui.separator();
            let plot_height = ui.available_height();
            ui.columns(2, |columns| {
                let [left, right] = columns else { return };
                let panels = 2 + engine.outputs().len();
                let each = (plot_height / panels as f32 - 2.0 * left.spacing().interact_size.y).max(60.0);
                egui::ScrollArea::vertical().id_salt("history_trends").show(left, |ui| {
                    let (run, transform) = trends_ui(ui, engine, state.run, each);
                    run_clicked = run_clicked.or(run);
                    trend_transform = transform;
                });
                run_view_ui(right, state, plot_height);
            });
        });
    });
    state.last_trend_transform = trend_transform;
    if let Some(engine) = engine_clicked {
        state.select_engine(engine);
    }
    if let Some(run) = run_clicked {
        state.select_run(run);
    }
    commands
}

/// The manifest's name and path, the progress while it is computed; true when "Open fleet
/// manifest…" was clicked.
fn header_ui(ui: &mut egui::Ui, state: &mut HistoryViewState) -> bool {
    let mut open = false;
    ui.horizontal(|ui| {
        open = ui.button("Open fleet manifest…").clicked();
        if let Some(fleet) = &state.fleet {
            ui.strong(&fleet.name);
            ui.label(RichText::new(fleet.path.display().to_string()).color(theme::HINT));
        }
    });
    let mut cancel = false;
    if let Some((job, path)) = &state.job {
        ui.horizontal(|ui| {
            ui.add(egui::ProgressBar::new(job.progress() as f32).desired_width(240.0).text(format!(
                "{} ({:.0} s)",
                job.label(),
                job.elapsed().as_secs_f64()
            )));
            ui.label(RichText::new(path.display().to_string()).color(theme::HINT));
            cancel = ui.button("Cancel").clicked();
        });
        ui.ctx().request_repaint_after(POLL);
    }
    if cancel {
        // Dropping the job stops its work; the fleet shown so far stays.
        state.job = None;
    }
    open
}

/// The selected run against its reference, with its flag's reasons.
fn run_view_ui(ui: &mut egui::Ui, state: &HistoryViewState, height: f32) {
    let Some(fleet) = &state.fleet else { return };
    let Some(engine) = fleet.engines.get(state.engine) else { return };
    let Some(run) = state.run.and_then(|r| engine.runs.get(r)) else {
        hint(ui, "Click a run (a row or a trend point) to see it against its reference.");
        return;
    };
    ui.strong(format!("Run {} ({}) against the reference of {}", run.run.name, run.date_text(), engine.name));
    if run.flagged() {
        for reason in &run.reasons {
            ui.label(RichText::new(format!("• {reason}")).color(theme::ERROR));
        }
    } else {
        ui.label(RichText::new("Within the engine's normal band.").color(theme::OK));
    }
    for note in &run.score.notes {
        ui.label(RichText::new(note).small().color(theme::HINT));
    }
    if let Some(diagnosis) = &run.score.diagnosis {
        let clean: Vec<&str> = (diagnosis.diagnosed.iter())
            .filter(|o| !diagnosis.findings.iter().any(|f| f.output == **o))
            .map(String::as_str)
            .collect();
        if !clean.is_empty() {
            let text = format!("Diagnosed against the reference: no missing effect on {}.", clean.join(", "));
            ui.label(RichText::new(text).small().color(theme::HINT));
        }
        for note in &diagnosis.notes {
            ui.label(RichText::new(note).small().color(theme::HINT));
        }
    }
    if let Some((_, Comparison::Running(job))) = &state.comparison {
        ui.horizontal(|ui| {
            ui.spinner();
            ui.label(job.label());
        });
        ui.ctx().request_repaint_after(POLL);
    }
    match state.comparison() {
        Some(Ok(comparison)) => {
            let outputs = comparison.outputs.len().max(1) as f32;
            let used = ui.min_rect().height();
            let each = ((height - used) / outputs - 2.0 * ui.spacing().interact_size.y).max(80.0);
            comparison_ui(ui, comparison, each);
        }
        Some(Err(error)) => {
            ui.label(RichText::new(error).color(theme::ERROR));
        }
        None => {}
    }
}
