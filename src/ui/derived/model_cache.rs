//! The identification as the model views draw it, recomputed from the session when it changes:
//! segments of the identification run, then per output the segment ARX fits (the expensive part,
//! redone only when the run, the segments or the orders change), the automatic cluster proposal,
//! and the live path (clusters → reduced model → static map → validation runs → Bode).
//!
//! The automatic proposal is a structure search (cross-validated across segments) that takes longer
//! than a frame, so it runs on a worker thread ([`Proposed`]); the model views say so meanwhile,
//! and the model follows it when it arrives. Edited clusters do not wait for it.
//!
//! How one output's model is built from these — the committed one on a worker thread, a drag's
//! preview every frame — is in [`model_build`](super::model_build).
use std::sync::Arc;

use crate::core::effects::ExtendedModel;
use crate::core::identification::cluster::{Cluster, ClusterEval};
use crate::core::identification::fits::SegmentFits;
use crate::core::identification::segment::Segment;
use crate::core::identification::settings::OutputSettings;
use crate::core::numerics::tf::BodePoint;
use crate::core::run::{Run, RunRole};

use crate::ui::derived::diagnosis_model::DiagnosisInput;
use crate::ui::derived::empirical_bode::EmpiricalBode;
use crate::ui::derived::ident_runs::{
    ScoredSource, detect_or_check, join_identification, scored_runs, within_fit_budget,
};
use crate::ui::derived::jobs::{Job, JobResult};
pub use crate::ui::derived::live_model::{LiveModel, ScoredRun, Unavailable};
pub use crate::ui::derived::model_build::Preview;
use crate::ui::derived::model_build::{Built, ModelInputs};
pub use crate::ui::derived::proposed::Proposed;
use crate::ui::state::session::{Session, SessionRun};
use crate::ui::state::setup::OutputSetup;
use crate::workflow::model::{self, EffectPlan, ModelSource};
use crate::workflow::products::bode_grid;
use crate::workflow::runs::{self, StepsFrom};

mod spool;

/// The identification run and everything identified from it.
pub struct IdentCache {
    /// Index of the identification run in the session.
    pub run_index: usize,
    /// The identification run: the session's identification runs joined end to end when there
    /// are several (as the batch joins a project's), each later one starting at a junction.
    pub run: Arc<Run>,
    /// The session's identification runs `run` was made from, and their indices in the session.
    sources: Vec<Arc<Run>>,
    source_indices: Vec<usize>,
    /// Where each later identification run starts in `run`.
    junctions: Vec<usize>,
    /// How `run` was made from several runs, or why it could not be, in words (and where a long run
    /// was cut to the part its model is fitted on).
    join_note: Option<String>,
    /// What the cut of a long run depends on: whether segments are given, and the setup's
    /// `steps_from` ([`runs::within_fit_budget`]).
    window_key: (bool, Option<String>),
    /// Where `run` starts in the joined identification runs: 0 unless a long run was cut.
    window_start: usize,
    given_segments: Option<Vec<Segment>>,
    /// The setup's `steps_from`, and where the steps are detected given it ([`runs::steps_from`]).
    named_steps_from: Option<String>,
    steps_from: StepsFrom,
    /// The segments in use: the user's (checked) or the detected ones.
    pub segments: Result<Vec<Segment>, Unavailable>,
    /// One entry per output of the identification run, in its column order.
    pub outputs: Vec<OutputCache>,
}

impl IdentCache {
    /// Bring `old` (the previous cache, if any) up to date with the session; `None` when the
    /// session has no identification run.
    pub fn refresh(old: Option<Self>, session: &Session) -> Option<Self> {
        let idents: Vec<(usize, &SessionRun)> =
            session.runs.iter().enumerate().filter(|(_, r)| r.role == RunRole::Identification).collect();
        let run_index = idents.first()?.0;
        let sources: Vec<Arc<Run>> = idents.iter().map(|(_, e)| Arc::clone(&e.run)).collect();
        let source_indices: Vec<usize> = idents.iter().map(|(i, _)| *i).collect();
        let same_sources = old.as_ref().is_some_and(|o| {
            o.sources.len() == sources.len() && o.sources.iter().zip(&sources).all(|(a, b)| Arc::ptr_eq(a, b))
        });
        let given = session.setup.segments.clone();
        let named_steps_from = session.setup.steps_from.clone();
        let segments_given = given.is_some() || session.setup.outputs.values().any(|o| o.segments.is_some());
        let window_key = (segments_given, named_steps_from.clone());
        let (run, junctions, join_note, window_start) = match &old {
            Some(o) if same_sources && o.window_key == window_key => {
                (Arc::clone(&o.run), o.junctions.clone(), o.join_note.clone(), o.window_start)
            }
            _ => within_fit_budget(join_identification(&sources)?, &window_key)?,
        };
        let same_run =
            old.as_ref().is_some_and(|o| Arc::ptr_eq(&o.run, &run) && o.named_steps_from == named_steps_from);
        let steps_from = match &old {
            Some(o) if same_run => o.steps_from.clone(),
            _ => runs::steps_from(&run, &junctions, named_steps_from.as_deref()),
        };
        let (segments, mut old_outputs) = match old {
            Some(old) if same_run && old.given_segments == given => (old.segments, old.outputs),
            Some(old) => {
                (detect_or_check(&run, &junctions, given.as_deref(), steps_from.channel()), old.outputs)
            }
            None => (detect_or_check(&run, &junctions, given.as_deref(), steps_from.channel()), Vec::new()),
        };
        let outputs = run
            .outputs
            .iter()
            .filter(|channel| session.setup.is_modelled(&channel.name))
            .map(|channel| {
                let mut cache = match old_outputs.iter().position(|o| o.name == channel.name) {
                    Some(i) => old_outputs.swap_remove(i),
                    None => OutputCache::new(&channel.name, &channel.unit),
                };
                let scored = scored_runs(session, &run, &channel.name, &mut cache.notes, &cache.scored);
                cache.notes.splice(0..0, join_note.iter().cloned().chain(steps_from.note()));
                let setup = session.setup.output(&channel.name);
                // An output with segments of its own (from a project) is fitted on those.
                let own = setup
                    .segments
                    .as_deref()
                    .map(|given| detect_or_check(&run, &junctions, Some(given), steps_from.channel()));
                cache.update(&run, own.as_ref().unwrap_or(&segments), setup, scored);
                if let Some(note) = cache.fits.as_ref().ok().and_then(|fits| model::few_segments_note(fits)) {
                    cache.notes.push(note);
                }
                cache.empirical_bode.refresh(session, &run, &channel.name);
                cache
            })
            .collect();
        let mut cache = Self {
            run_index,
            run,
            sources,
            source_indices,
            junctions,
            join_note,
            window_key,
            window_start,
            given_segments: given,
            named_steps_from,
            steps_from,
            segments,
            outputs,
        };
        cache.share_the_spool();
        Some(cache)
    }

    pub fn output(&self, name: &str) -> Option<&OutputCache> {
        self.outputs.iter().find(|o| o.name == name)
    }

    /// Where the identification run starts in the session's joined identification runs: 0 unless a
    /// long run was cut to the part its model is fitted on.
    pub fn window_start(&self) -> usize {
        self.window_start
    }

    /// Where the session's run `index` starts in the identification run, when it is part of it
    /// (the first identification run at 0, a later one at its junction).
    pub fn part_start(&self, index: usize) -> Option<usize> {
        let k = self.source_indices.iter().position(|&i| i == index)?;
        match k {
            0 => Some(0),
            _ => self.junctions.get(k - 1).copied(),
        }
    }

    /// Take every automatic proposal and finished model whose job has ended, and rebuild its
    /// output's model; true when any did (call every frame).
    pub fn poll_jobs(&mut self) -> bool {
        let mut any = false;
        for output in &mut self.outputs {
            any |= output.poll_proposal();
            any |= output.poll_finished();
        }
        if any {
            self.share_the_spool();
        }
        any
    }

    /// Block until every automatic proposal and every model being finished has ended (tests,
    /// screenshots and the headless paths, never in a frame), the shaft speed's spool blocks shared
    /// with the others as the batch shares them.
    pub fn wait_for_jobs(&mut self) {
        loop {
            for output in &mut self.outputs {
                output.wait_for_proposal();
                output.wait_for_finished();
            }
            self.share_the_spool();
            if !self.is_busy() {
                break;
            }
        }
    }

    /// True while a proposal is computed on a worker thread.
    pub fn is_proposing(&self) -> bool {
        self.outputs.iter().any(|o| o.proposal.is_running())
    }

    /// True while a proposal is computed or a committed model is finished on a worker thread.
    pub fn is_busy(&self) -> bool {
        self.is_proposing() || self.is_finishing()
    }

    /// True while a committed model is finished on a worker thread.
    pub fn is_finishing(&self) -> bool {
        self.outputs.iter().any(|o| o.finishing.is_some())
    }

    /// Where the segments' steps are detected: the input, a named channel or a set-point found.
    pub fn steps_from(&self) -> &StepsFrom {
        &self.steps_from
    }

    /// True when the segments were detected (the user has not moved them).
    pub fn segments_are_automatic(&self) -> bool {
        self.given_segments.is_none()
    }
}

#[derive(Clone, PartialEq)]
struct FitsKey {
    segments: Vec<Segment>,
    orders: crate::core::identification::arx::ArxOrders,
}

/// Everything identified for one output.
pub struct OutputCache {
    pub name: String,
    pub unit: String,
    /// The setup the results below were computed for.
    pub setup: OutputSetup,
    source: Option<Arc<Run>>,
    fits_key: Option<FitsKey>,
    pub fits: Result<Arc<SegmentFits>, Unavailable>,
    pub omegas_rad_s: Arc<[f64]>,
    /// Bode of every segment's ARX model at `omegas_rad_s`, in segment order.
    pub segment_bode: Vec<Vec<BodePoint>>,
    /// The automatic proposal for the current fits.
    pub proposal: Proposed,
    /// The clusters in use: the user's, else the automatic proposal.
    pub clusters: Vec<Cluster>,
    pub evals: Result<Vec<ClusterEval>, Unavailable>,
    scored: Vec<ScoredSource>,
    pub live: Result<LiveModel, Unavailable>,
    /// The committed model being finished on a worker thread (centroids polished, effects
    /// refitted); `live` is its unpolished first look meanwhile.
    finishing: Option<Job<Built>>,
    /// The chirp run's measured frequency response; drawn on the Bode view when not empty.
    pub empirical_bode: EmpiricalBode,
    /// Runs that were not scored, and why.
    pub notes: Vec<String>,
    /// The shaft speed's finished model this output's model shares the spool blocks of (see
    /// [`IdentCache::share_the_spool`]).
    spool: Option<Arc<ExtendedModel>>,
}

impl OutputCache {
    fn new(name: &str, unit: &str) -> Self {
        Self {
            name: name.to_owned(),
            unit: unit.to_owned(),
            setup: OutputSetup::for_output(name),
            source: None,
            fits_key: None,
            fits: Err(Unavailable::NotYet),
            omegas_rad_s: Arc::from([]),
            segment_bode: Vec::new(),
            proposal: Proposed::Failed("not computed yet".into()),
            clusters: Vec::new(),
            evals: Err(Unavailable::NotYet),
            scored: Vec::new(),
            live: Err(Unavailable::NotYet),
            finishing: None,
            empirical_bode: EmpiricalBode::default(),
            notes: Vec::new(),
            spool: None,
        }
    }

    /// `name [unit]`, or the name alone when the unit is unknown or is the name.
    pub fn label(&self) -> String {
        crate::core::run::name_with_unit(&self.name, &self.unit)
    }

    fn update(
        &mut self,
        run: &Arc<Run>,
        segments: &Result<Vec<Segment>, Unavailable>,
        setup: OutputSetup,
        scored: Vec<ScoredSource>,
    ) {
        let same_run = self.source.as_ref().is_some_and(|s| Arc::ptr_eq(s, run));
        let key =
            segments.as_ref().ok().map(|s| FitsKey { segments: s.clone(), orders: setup.settings.orders });
        let refit = !same_run || key != self.fits_key || self.fits_key.is_none();
        if refit {
            self.fits = match segments {
                Ok(segments) => model::fit_segments(run, &self.name, segments, &setup.settings)
                    .map(Arc::new)
                    .map_err(Unavailable::from),
                Err(err) => Err(Unavailable::NoSegments(Box::new(err.clone()))),
            };
            self.omegas_rad_s = bode_grid(run.dt_secs).into();
            self.segment_bode = match &self.fits {
                Ok(fits) => fits.models.iter().map(|m| m.bode_response(&self.omegas_rad_s)).collect(),
                Err(_) => Vec::new(),
            };
        }
        let same_scored = scored.len() == self.scored.len()
            && scored
                .iter()
                .zip(&self.scored)
                .all(|(a, b)| a.index == b.index && Arc::ptr_eq(&a.run, &b.run));
        if !refit && same_scored && setup == self.setup {
            return;
        }
        if refit || setup.settings.cluster != self.setup.settings.cluster {
            self.proposal = match &self.fits {
                Ok(fits) => Proposed::start(fits, run, &setup.settings),
                Err(err) => Proposed::Failed(err.to_string()),
            };
        }
        self.source = Some(Arc::clone(run));
        self.fits_key = key;
        self.scored = scored;
        self.setup = setup;
        self.rebuild();
    }

    /// The clusters in use, their evaluation and the committed model (with its effects), from the
    /// current fits, setup and proposal.
    ///
    /// Polishing the centroids by simulation error and refitting the effects take longer than a
    /// frame (tens of milliseconds for a polish, seconds for some effects), so they run on a worker
    /// thread ([`Self::finishing`]). Meanwhile the model is the one a drag previews (not polished,
    /// without its effects), marked [`LiveModel::finishing`]; [`Self::poll_finished`] puts the
    /// finished model in its place.
    fn rebuild(&mut self) {
        let Some(run) = self.source.clone() else { return };
        // A job for an older setup is dropped: its result is for a model nobody shows any more.
        self.finishing = None;
        let source = match (&self.setup.clusters, &self.proposal) {
            (Some(clusters), _) => ModelSource::Clusters(clusters.clone()),
            (None, Proposed::Ready(proposal)) => ModelSource::Proposal(Arc::clone(proposal)),
            (None, Proposed::Running(_)) => {
                (self.clusters, self.evals, self.live) =
                    (Vec::new(), Ok(Vec::new()), Err(Unavailable::Proposing));
                return;
            }
            (None, Proposed::Failed(err)) => {
                let why = Unavailable::ProposalFailed(err.clone());
                (self.clusters, self.evals, self.live) = (Vec::new(), Ok(Vec::new()), Err(why));
                return;
            }
        };
        let inputs = self.inputs(&run);
        let settings = self.setup.settings.clone();
        self.clusters = source.clusters();
        if !settings.refine && inputs.effects.is_empty() {
            (self.evals, self.live) = inputs.finish(&source, &settings, &mut |_| true);
            return;
        }
        let quick = OutputSettings { refine: false, ..settings.clone() };
        let (evals, mut live) = inputs.build(&source, &quick);
        if let Ok(live) = &mut live {
            live.finishing = true;
            live.effects.left_out_for_preview = !live.effects.requested.is_empty();
        }
        (self.evals, self.live) = (evals, live);
        let label = match inputs.effects.auto_rounds {
            0 => format!("Finishing the model of {}", self.name),
            rounds => format!("Running the missing-physics loop on {} ({rounds} rounds)", self.name),
        };
        self.finishing =
            Some(Job::spawn(label, || {}, move |progress| Ok(inputs.finish(&source, &settings, progress))));
    }

    /// Take the finished model when its job has ended; true when it did.
    fn poll_finished(&mut self) -> bool {
        let Some(result) = self.finishing.as_ref().and_then(Job::poll) else { return false };
        self.finishing = None;
        self.take_finished(result);
        true
    }

    fn take_finished(&mut self, result: JobResult<Built>) {
        match result {
            Ok((evals, live)) => (self.evals, self.live) = (evals, live),
            Err(err) => self.live = Err(Unavailable::NotFinished(err)),
        }
    }

    fn wait_for_finished(&mut self) {
        if let Some(job) = self.finishing.take() {
            self.take_finished(job.wait());
        }
    }

    /// What building this output's model needs, owned (for a worker thread).
    pub(super) fn inputs(&self, run: &Arc<Run>) -> ModelInputs {
        ModelInputs {
            run: Arc::clone(run),
            fits: self.fits.clone(),
            scored: self.scored.clone(),
            omegas_rad_s: Arc::clone(&self.omegas_rad_s),
            effects: EffectPlan { by_hand: self.setup.effects.clone(), auto_rounds: self.setup.auto_effects },
            spool: self.spool.clone(),
        }
    }

    /// The job finishing the committed model (polish, effects, the missing-physics loop), while it
    /// runs: its label, progress and time, for the views to show.
    pub fn finishing_job(&self) -> Option<&Job<Built>> {
        self.finishing.as_ref()
    }

    /// Take the proposal when its job has ended, and rebuild the model when it follows it.
    fn poll_proposal(&mut self) -> bool {
        let Some(result) = self.proposal.job().and_then(Job::poll) else { return false };
        self.proposal = match result {
            Ok(proposal) => Proposed::Ready(proposal),
            Err(err) => Proposed::Failed(err.to_string()),
        };
        self.rebuild();
        true
    }

    fn wait_for_proposal(&mut self) {
        if !self.proposal.is_running() {
            return;
        }
        let Proposed::Running(job) = std::mem::replace(&mut self.proposal, Proposed::Failed(String::new()))
        else {
            return;
        };
        self.proposal = match job.wait() {
            Ok(proposal) => Proposed::Ready(proposal),
            Err(err) => Proposed::Failed(err.to_string()),
        };
        self.rebuild();
    }

    /// The settings a drag of the clusters in use is previewed with: while the clusters follow the
    /// proposal, with its dead time (committing the edit carries it into the settings).
    pub(super) fn preview_settings(&self) -> OutputSettings {
        let carried = match self.setup.clusters {
            None => self.setup.settings.dead_time_samples.or_else(|| self.proposal.dead_time_samples()),
            Some(_) => self.setup.settings.dead_time_samples,
        };
        OutputSettings { refine: false, dead_time_samples: carried, ..self.setup.settings.clone() }
    }

    /// What a diagnosis of the committed model needs; an error when there is no model or no
    /// validation run.
    pub fn diagnosis_input(&self) -> Result<DiagnosisInput, Unavailable> {
        let live = self.live.as_ref().map_err(|e| Unavailable::NoModel(Box::new(e.clone())))?;
        if live.finishing {
            return Err(Unavailable::Finishing);
        }
        let fits = self.fits.as_ref().map_err(|e| Unavailable::NoFits(Box::new(e.clone())))?;
        let ident = self.source.as_ref().ok_or(Unavailable::NoIdentificationRun)?;
        if let Some(problem) = live.effects.problems.first().filter(|_| live.effects.model.is_none()) {
            return Err(Unavailable::EffectsNotAdded(problem.clone()));
        }
        let validation: Vec<Arc<Run>> = self
            .scored
            .iter()
            .filter(|s| s.role == RunRole::Validation)
            .map(|s| Arc::clone(&s.run))
            .collect();
        if validation.is_empty() {
            return Err(Unavailable::NoValidationRun);
        }
        Ok(DiagnosisInput {
            model: live.key(),
            output: self.name.clone(),
            current: live.current_model(),
            ident: Arc::clone(ident),
            fits: Arc::clone(fits),
            validation,
            settings: self.setup.settings.clone(),
        })
    }
}
