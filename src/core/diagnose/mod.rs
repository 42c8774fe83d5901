//! Which physical effect is the model missing? For every effect of the catalog that applies, a
//! trial fit (extend the current model with the effect, refit on the identification data, score on
//! the validation runs) and one sentence of evidence from the current model's residuals. Effects
//! are ranked by the validation error they remove, best first.
//!
//! The trials start from the current model refitted on the identification data as it is (roots,
//! gain, map and existing effects moved by the same procedure, no new block): that refit is the
//! yardstick, so a trial is credited only with what its block adds, never with what refitting alone
//! gives (which matters when the current model was edited by hand or built for another output).
//!
//! **One footing: the error beyond the noise.** Every decision reads the residuals in units of
//! each run's measurement noise, `z = (y − ŷ)/σ`, never the percentage error: at idle thrust the
//! sensor noise alone is 10–20 % of the value, and a percentage loss is dominated by those samples
//! wherever the physics acts (see `loss`). The error a change must reduce is the error beyond the
//! noise, `√(mean z² − 1)` per run (an estimate of the RMS error against the noiseless truth),
//! averaged over the runs; the ranking follows it. RMSPE stays the metric the report shows.
//!
//! **When a trial beats the current model.** Validation residuals of simulated models are strongly
//! autocorrelated, so a plain comparison of error sums says little. Each trial is compared with the
//! refitted current model by a one-sided Diebold–Mariano test on the per-sample loss differences
//! `d_k = |z_refit,k| − |z_trial,k|`, with the Newey–West long-run variance (Bartlett kernel,
//! bandwidth read from the autocorrelation of `d`, lags kept inside each run; see
//! [`crate::core::effects::stats::diebold_mariano`]). The absolute loss is used rather than the
//! squared one because squared errors of a simulated model are dominated by a handful of large
//! transients, which leaves the test with a few effective observations and little power. A trial
//! beats the current model when `p < SIGNIFICANCE_LEVEL` (0.01) **and** it removes at least
//! `MIN_RELATIVE_REDUCTION` (10 %) of the refitted model's error beyond the noise on the validation
//! runs: a real effect must be both beyond what noise gives and large enough to matter. The second
//! condition also guards against the many-candidates problem (a dozen trials per diagnosis) and
//! against the small gains any extra parameter buys on an engine that is not exactly a Wiener
//! system.
//!
//! **The validation runs read two ways.** On a test design whose steps repeat, the loss
//! differences correlate with themselves a period later, the bandwidth reaches its cap, and a
//! change concentrated in transients (a rate limit) reads weak however consistently it helps. The
//! validation runs are therefore also cut into their step responses (`witness::ValidationResponses`)
//! and read as the held-out responses are, by a signed-rank test over the responses the trial
//! changes by more than the noise; where at least [`MIN_VALIDATION_RESPONSES`] are changed, the
//! validation runs' p-value is the smaller of the two, doubled (Bonferroni: valid however the two
//! readings of the same runs depend on each other).
//!
//! **Two witnesses.** A validation run can be short (a minute, a handful of steps) while the
//! identification data hold many more. Where they have at least six segments, a three-fold
//! cross-validation over them (see `held_out` and [`FitData::folds`]) refits the current model and
//! each trial without a third of the segment responses and simulates them through the responses it
//! never saw. Each response's RMS error over the noise, before minus after, goes into a one-sided
//! Wilcoxon signed-rank test (responses are the independent units; ranks let no single transient
//! carry it). It counts only over the responses the trial actually moves (its prediction differs
//! from the current model's by more than the measurement noise), and only when at least
//! [`MIN_WITNESS_RESPONSES`] do: a rate limit the identification steps never reach, or a drift
//! between test days, cannot be witnessed by them. The two one-sided p-values are then combined by
//! Stouffer's method (equal weights), under which a witness against the trial counts against it.
//! Structural refinements and physical effects are cross-validated alike, whenever their validation
//! error falls enough for the p-value to matter.
//!
//! **One decision** ([`decide`]). Structural refinements (one more real pole, pole pair or zero,
//! one more static-map order, a scheduled spool; see [`StructuralChange`]) and physical effects
//! are judged by the same test against the current model. A trial counts when it beats the current
//! model; a physical effect also needs its own evidence (read from the current model's residuals,
//! or from the spool's for effects that act before it: `spool_witness`) to show its signature, and
//! the data must prefer it to the best structural refinement. The trials that count are ranked by
//! their error beyond the noise, and the loop takes the first. There is no exception for any effect.
//!
//! **Attribution that says what it knows.** When the two best trials that count cannot be told
//! apart (the better does not beat the other beyond noise on the same witnesses), or when the best
//! physics is dropped because a structural refinement explains the same residual, the report says
//! so with the numbers and names the experiment that would separate them (`Trials::settle_tie`,
//! `Trials::prefer_physics_only_on_evidence`). Between two that count, the held-out responses
//! decide; without them the ranking stands.
use crate::core::effects::stats::ResidualTrace;
use crate::core::effects::{
    AmbientCorrection, EffectError, EffectId, Evidence, ExtendedModel, FOLDS, FitData, MIN_HELD_OUT_SEGMENTS,
    StructuralChange, apply_effect, refine_structure, refit,
};
use crate::core::identification::fits::SegmentFits;
use crate::core::identification::initial_state::InitialState;
use crate::core::identification::settings::OutputSettings;
use crate::core::parallel;
use crate::core::run::Run;

mod decision;
mod edit;
mod held_out;
mod history;
mod loss;
mod report;
mod shared_spool;
mod spool_witness;
mod witness;
use decision::{Trials, decide};
pub use edit::{Edit, edit};
use held_out::{HeldOut, Recipe};
pub use history::{
    AutoRound, EffectSequence, HistoryStep, apply_in_order, auto_effects, diagnose_admissible,
};
pub use report::{Diagnosis, DiagnosisKind, DiagnosisReport, SkippedEffect, TrialId};
pub use shared_spool::{SHARED_SPOOL_BLOCKS, SharedBlock, share_spool_dynamics};
pub use witness::{Comparison, HeldOutWitness, MIN_VALIDATION_RESPONSES, MIN_WITNESS_RESPONSES, p_text};
use witness::{Judge, Scores, ValidationResponses, Verdict};

/// Largest one-sided p-value of a significant effect: with a dozen trials per diagnosis, the chance
/// that noise alone makes one of them significant stays near 10 % (1 − 0.99¹²), and the 10 %
/// reduction below takes most of that away.
pub const SIGNIFICANCE_LEVEL: f64 = 0.01;
/// Smallest share of the refitted model's validation error beyond the noise a significant trial
/// must remove: a change of a few percent of the error against the truth is below what a user can
/// see in a trace or a controller design would notice.
pub const MIN_RELATIVE_REDUCTION: f64 = 0.10;

/// A structural refinement is an alternative explanation of the residual a physical effect must
/// beat when the witnesses lean its way against the current model: its one-sided p-value is below
/// one half (its combined normal score is positive, the evidence says it is more likely better
/// than the current model than not). One they lean against (worse on the held-out responses, say)
/// explains nothing, however its validation error compares; one that is better but not
/// significant still explains what a physical effect would, and the physics must then do better.
pub const RIVAL_LEVEL: f64 = 0.5;

/// Errors of a diagnosis that stop it as a whole (a single effect that cannot be tried is skipped).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DiagnoseError {
    /// The effects need at least one validation run to be scored on.
    #[error("no validation run to score the effects on")]
    NoValidationRuns,
    /// A run lacks the model's output.
    #[error("run '{run}' has no output column '{output}'")]
    MissingOutput { run: String, output: String },
    /// Percentage errors need a non-zero measurement.
    #[error(
        "the measurement of '{output}' in run '{run}' is zero at sample {index}; percentage errors are undefined"
    )]
    ZeroMeasurement { run: String, output: String, index: usize },
    /// The current model fails on a run (typically a channel its effects need).
    #[error("the current model cannot be simulated on run '{run}': {source}")]
    CurrentModel { run: String, source: EffectError },
    /// The caller's progress callback asked to stop.
    #[error("the diagnosis was cancelled")]
    Cancelled,
    /// The model is read off the shaft speed's model: every candidate would be fitted on this
    /// output's data into the speed's blocks, which are fitted on the speed.
    #[error(
        "not run: '{output}' is read off the shaft speed's model, and the speed's diagnosis is the spool's \
         (its candidates would be fitted on this output into the speed's blocks)"
    )]
    ReadOff { output: String },
    /// An effect could not be built, applied, removed or fitted.
    #[error(transparent)]
    Effect(#[from] EffectError),
}

fn measured<'a>(run: &'a Run, output: &str) -> Result<&'a [f64], DiagnoseError> {
    let y = run
        .output(output)
        .map(|c| c.values.as_slice())
        .ok_or_else(|| DiagnoseError::MissingOutput { run: run.name.clone(), output: output.to_owned() })?;
    if let Some(index) = y.iter().position(|v| v.abs() <= f64::MIN_POSITIVE) {
        return Err(DiagnoseError::ZeroMeasurement {
            run: run.name.clone(),
            output: output.to_owned(),
            index,
        });
    }
    Ok(y)
}

/// Validation error of a model: the runs' RMSPE averaged over the runs, %.
pub fn validation_rmspe(
    model: &ExtendedModel,
    validation: &[&Run],
    initial: InitialState,
) -> Result<f64, DiagnoseError> {
    Ok(Scores::of(model, validation, initial, &ValidationResponses::default())?.rmspe())
}

/// Why an effect cannot be tried on these runs, if it cannot.
fn not_applicable(id: EffectId, current: &ExtendedModel, runs: &[&Run]) -> Option<String> {
    if current.effect(id).is_some() {
        return Some("already in the model".to_owned());
    }
    if id == EffectId::AmbientCorrection {
        return runs.iter().find_map(|run| AmbientCorrection::conditions(run).err().map(|e| e.to_string()));
    }
    None
}

/// Whether `runs` (the identification run first) agree on the steady state under `current`: the
/// sentence of the calibration-drift evidence ("runs disagree on the steady state by X %: …"). A
/// description of the runs, so held-out runs may be among them: nothing is chosen from it.
pub fn steady_state_agreement(
    current: &ExtendedModel,
    runs: &[&Run],
    initial: InitialState,
) -> Result<Evidence, DiagnoseError> {
    let traces = run_traces(current, runs.iter().copied(), initial)?;
    Ok(crate::core::effects::steady_state_agreement(&traces))
}

/// The current model's residual traces: identification range first, then the validation runs.
fn residual_traces(
    current: &ExtendedModel,
    data: &FitData,
    validation: &[&Run],
    initial: InitialState,
) -> Result<Vec<ResidualTrace>, DiagnoseError> {
    run_traces(current, std::iter::once(&data.run).chain(validation.iter().copied()), initial)
}

fn run_traces<'a>(
    current: &ExtendedModel,
    runs: impl Iterator<Item = &'a Run>,
    initial: InitialState,
) -> Result<Vec<ResidualTrace>, DiagnoseError> {
    runs.map(|run| {
        let y = measured(run, &current.output)?.to_vec();
        let y_hat = current
            .simulate_scored(run, initial)
            .map_err(|source| DiagnoseError::CurrentModel { run: run.name.clone(), source })?;
        Ok(ResidualTrace {
            run: run.name.clone(),
            dt_secs: run.dt_secs,
            u: run.input.values.clone(),
            y,
            y_hat,
            aux: run.aux.clone(),
        })
    })
    .collect()
}

/// Try every applicable effect of the catalog on `current`: refit on the identification data of
/// `fits`, score on `validation`, rank by validation RMSPE (lowest first) and test significance
/// (see the module documentation).
pub fn diagnose(
    current: &ExtendedModel,
    ident: &Run,
    fits: &SegmentFits,
    validation: &[&Run],
    settings: &OutputSettings,
) -> Result<DiagnosisReport, DiagnoseError> {
    diagnose_with_progress(current, ident, fits, validation, settings, &mut |_| true)
}

/// [`diagnose`] that reports the fraction done (0..=1) before every trial; when `progress`
/// returns false the diagnosis stops with [`DiagnoseError::Cancelled`] (the app's background job).
pub fn diagnose_with_progress(
    current: &ExtendedModel,
    ident: &Run,
    fits: &SegmentFits,
    validation: &[&Run],
    settings: &OutputSettings,
    progress: &mut dyn FnMut(f64) -> bool,
) -> Result<DiagnosisReport, DiagnoseError> {
    if current.read_off().is_some() {
        return Err(DiagnoseError::ReadOff { output: current.output.clone() });
    }
    let steps = (EffectId::CATALOG.len() + StructuralChange::ALL.len()) as f64 + 1.0;
    if !progress(0.0) {
        return Err(DiagnoseError::Cancelled);
    }
    if validation.is_empty() {
        return Err(DiagnoseError::NoValidationRuns);
    }
    let data = FitData::new(ident, fits, settings)?;
    let responses = ValidationResponses::of(validation);
    let before = Scores::of(current, validation, settings.initial_state, &responses)?;
    let reference = refit(current, &data)?;
    let folds = HeldOut::of(&data, current);
    let mut yardstick = Scores::of(&reference, validation, settings.initial_state, &responses)?;
    yardstick.cross_validate(Recipe::Current, folds.as_ref());
    let bench = Bench {
        current,
        reference: &reference,
        data: &data,
        validation,
        all_runs: std::iter::once(ident).chain(validation.iter().copied()).collect(),
        initial: settings.initial_state,
        responses: &responses,
        folds: folds.as_ref(),
        judge: Judge { yardstick: &yardstick, current: &before },
        traces: residual_traces(current, &data, validation, settings.initial_state)?,
        spool: spool_witness::spool_traces(
            current,
            &std::iter::once(&data.run).chain(validation.iter().copied()).collect::<Vec<_>>(),
        )?,
    };
    // Structure first: what the model's own linear block and map can still do. The trials are
    // independent of each other; they are fitted on two threads and gathered in this order.
    let order: Vec<TrialId> = (StructuralChange::ALL.into_iter().map(TrialId::Structure))
        .chain(EffectId::CATALOG.into_iter().map(TrialId::Effect))
        .collect();
    let one = |id: &TrialId| {
        let mut trial = Trials::default();
        match *id {
            TrialId::Structure(change) => bench.try_structure(change, &mut trial),
            TrialId::Effect(id) => bench.try_effect(id, &mut trial),
        }
        trial
    };
    let mut go_on = |finished: usize| progress((1.0 + finished as f64) / steps);
    let each =
        parallel::taking_turns_on_two_threads(&order, one, &mut go_on).ok_or(DiagnoseError::Cancelled)?;
    let mut trials = Trials::default();
    for trial in each {
        trials.entries.extend(trial.entries);
        trials.skipped.extend(trial.skipped);
    }
    progress(1.0);
    Ok(trials.into_report(&bench))
}

/// What every trial of one diagnosis is judged against.
struct Bench<'a> {
    current: &'a ExtendedModel,
    /// The current model refitted on the identification data as it is: every trial starts here.
    reference: &'a ExtendedModel,
    data: &'a FitData,
    validation: &'a [&'a Run],
    /// The identification run, then the validation runs (where an effect's channels are checked).
    all_runs: Vec<&'a Run>,
    initial: InitialState,
    /// The validation runs' step responses (see `witness::ValidationResponses`).
    responses: &'a ValidationResponses,
    folds: Option<&'a HeldOut>,
    judge: Judge<'a>,
    /// The current model's residuals (the evidence is read from them).
    traces: Vec<ResidualTrace>,
    /// The measured shaft speed against the current model's spool, when this output is another
    /// (see `spool_witness`): where effects that act before the spool are read.
    spool: Option<(String, Vec<ResidualTrace>)>,
}

impl Bench<'_> {
    /// One structural refinement, refitted, scored and judged.
    fn try_structure(&self, change: StructuralChange, trials: &mut Trials) {
        let trial = refine_structure(self.reference, change, self.data)
            .map_err(DiagnoseError::from)
            .and_then(|(model, words)| {
                let mut after = Scores::of(&model, self.validation, self.initial, self.responses)?;
                self.judge.consult(&mut after, Recipe::Structure(change), self.folds);
                Ok((model, words, after))
            });
        let (model, words, after) = match trial {
            Ok(t) => t,
            Err(e) => {
                trials
                    .skipped
                    .push(SkippedEffect { effect: TrialId::Structure(change), reason: e.to_string() });
                return;
            }
        };
        let Verdict { test, rmspe_after_pct, beyond_noise_after, significant } = self.judge.verdict(&after);
        let rmspe_before_pct = self.judge.current.rmspe();
        let evidence = format!(
            "{words}: with it the validation error goes from {rmspe_before_pct:.3} % to {rmspe_after_pct:.3} %"
        );
        trials.entries.push((
            Diagnosis {
                effect: TrialId::Structure(change),
                kind: DiagnosisKind::Structure,
                physics: change.meaning().to_owned(),
                significant,
                rmspe_before_pct,
                rmspe_after_pct,
                beyond_noise_before: self.judge.current.beyond_noise(),
                beyond_noise_after,
                test,
                evidence,
                model,
                why_not: None,
            },
            after,
            Recipe::Structure(change),
        ));
    }

    /// One effect of the catalog, refitted, scored and judged against the current model and the
    /// best structural refinement.
    fn try_effect(&self, id: EffectId, trials: &mut Trials) {
        if let Some(reason) = not_applicable(id, self.current, &self.all_runs) {
            trials.skipped.push(SkippedEffect { effect: TrialId::Effect(id), reason });
            return;
        }
        let trial =
            apply_effect(self.reference, id, self.data).map_err(DiagnoseError::from).and_then(|model| {
                let mut after = Scores::of(&model, self.validation, self.initial, self.responses)?;
                self.judge.consult(&mut after, Recipe::Effect(id), self.folds);
                Ok((model, after))
            });
        let (model, after) = match trial {
            Ok(t) => t,
            Err(e) => {
                trials.skipped.push(SkippedEffect { effect: TrialId::Effect(id), reason: e.to_string() });
                return;
            }
        };
        let Verdict { test, rmspe_after_pct, beyond_noise_after, significant: beats_current } =
            self.judge.verdict(&after);
        let evidence = spool_witness::evidence(id, &self.traces, self.spool.as_ref());
        let (significant, why_not) = decide(beats_current, evidence.supports);
        trials.entries.push((
            Diagnosis {
                effect: TrialId::Effect(id),
                kind: DiagnosisKind::Physics,
                physics: id.physics().to_owned(),
                significant,
                rmspe_before_pct: self.judge.current.rmspe(),
                rmspe_after_pct,
                beyond_noise_before: self.judge.current.beyond_noise(),
                beyond_noise_after,
                test,
                evidence: evidence.sentence,
                model,
                why_not,
            },
            after,
            Recipe::Effect(id),
        ));
    }
}
