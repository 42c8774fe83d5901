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
//! **When an effect counts as significant.** Validation residuals of simulated models are strongly
//! autocorrelated, so a plain comparison of error sums says little. Each trial is compared with the
//! refitted current model by a one-sided Diebold–Mariano test on the per-sample loss differences
//! `d_k = |p_refit,k| − |p_trial,k|` (`p` the percentage error), with the Newey–West long-run
//! variance (Bartlett kernel, bandwidth read from the autocorrelation of `d`, lags kept inside each
//! run; see [`crate::core::effects::stats::diebold_mariano`]). The absolute loss is used rather than
//! the squared one because squared errors of a simulated model are dominated by a handful of large
//! transients, which leaves the test with a few effective observations and little power; the
//! ranking itself stays on RMSPE. An effect is *significant* when `p < SIGNIFICANCE_LEVEL` (0.01)
//! **and** it removes at least `MIN_RELATIVE_REDUCTION` (10 %) of the refitted model's validation
//! RMSPE (and beats the current model): a real effect must be both beyond what noise gives and large
//! enough to matter. The second condition also guards against the many-candidates problem (ten
//! trials per diagnosis) and against the small structural gains any extra parameter buys on an
//! engine that is not exactly a Wiener system.
//!
//! **Two witnesses.** A validation run can be short (a minute, a handful of steps) while the
//! identification data hold many more. Where they have at least six segments, a three-fold
//! cross-validation over them (see `held_out` and [`FitData::folds`]) refits the current model and
//! each trial without a third of the segment responses and simulates them through the responses it
//! never saw. The held-out RMSPE of each response, before minus after, goes into a one-sided
//! Wilcoxon signed-rank test (responses are the independent units; ranks let no single transient
//! carry it). It counts only over the responses the trial actually moves (its prediction differs
//! from the current model's by more than the measurement noise), and only when at least
//! [`MIN_WITNESS_RESPONSES`] do: a rate limit the identification steps never reach, or a drift
//! between test days, cannot be witnessed by them. The two one-sided p-values are then combined by
//! Stouffer's method (equal weights), under which a witness against the trial counts against it.
//! The p-value of the rule above is that combination; the 10 % reduction stays on the validation
//! runs, the error a user sees. A structural refinement is a property of the engine and shows on
//! every step, so this is where the second witness matters most.
//!
//! **Structure before physics.** Before any effect is credited, the model's own structure is
//! refined the same way (one more real pole, pole pair or zero, one more static-map order; see
//! [`StructuralChange`]), judged by the same rule. A physical effect is significant only when it
//! also beats the best of these refinements by that rule (one-sided Diebold–Mariano on the loss
//! differences against the refinement, p < 0.01, and at least 10 % of its RMSPE removed): a lag
//! block or a dead time that only stands in for a missing pole pair is no evidence of physics. When
//! a refinement is significant the report says what the model needs, in words.
//!
//! **The evidence must agree.** A physical effect is significant only when the current model's
//! residuals also show its signature: its own evidence sentence does not say there is little or
//! nothing (see [`crate::core::effects::Evidence`]). A trial fit alone can buy a few percent with
//! any flexible block; the residual's signature is what tells which physics it is.
//!
//! **Dead time or lag: the ranking follows the evidence.** A dead time shifts the whole step
//! response late; a lag starts it on time but slower (see
//! [`crate::core::effects::transport_delay::Lateness`]). Poles can mimic either, so where the
//! measured responses show the whole response shifted, a dead time that fits the validation runs
//! better than the best structural refinement (and is significant against the current model) is
//! credited even when the refinement comes within 10 % of it.
use crate::core::effects::stats::ResidualTrace;
use crate::core::effects::{
    AmbientCorrection, EffectError, EffectId, Evidence, ExtendedModel, FOLDS, FitData, MIN_HELD_OUT_SEGMENTS,
    StructuralChange, apply_effect, refine_structure, refit,
};
use crate::core::identification::fits::SegmentFits;
use crate::core::identification::initial_state::InitialState;
use crate::core::identification::settings::OutputSettings;
use crate::core::run::Run;

mod edit;
mod held_out;
mod history;
mod report;
mod witness;
pub use edit::{Edit, edit};
use held_out::{HeldOut, Recipe};
pub use history::{AutoRound, EffectSequence, HistoryStep, apply_in_order, auto_effects};
pub use report::{Diagnosis, DiagnosisKind, DiagnosisReport, SkippedEffect, StructureRival, TrialId};
pub use witness::{Comparison, HeldOutWitness, MIN_WITNESS_RESPONSES, p_text};
use witness::{Judge, Scores, Verdict};

/// Largest one-sided p-value of a significant effect.
pub const SIGNIFICANCE_LEVEL: f64 = 0.01;
/// Smallest share of the validation RMSPE a significant effect must remove.
pub const MIN_RELATIVE_REDUCTION: f64 = 0.10;

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
    /// An effect could not be built, applied, removed or fitted.
    #[error(transparent)]
    Effect(#[from] EffectError),
}

/// Percentage errors of a model on each run.
pub(crate) fn pct_errors(
    model: &ExtendedModel,
    runs: &[&Run],
    initial: InitialState,
) -> Result<Vec<Vec<f64>>, DiagnoseError> {
    runs.iter()
        .map(|run| {
            let y = measured(run, &model.output)?;
            let y_hat = model
                .simulate_scored(run, initial)
                .map_err(|source| DiagnoseError::CurrentModel { run: run.name.clone(), source })?;
            Ok(y.iter().zip(&y_hat).map(|(y, yh)| 100.0 * (y - yh) / y).collect())
        })
        .collect()
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

/// The validation error: the RMSPE of each run, averaged over the runs, % (every test counts the
/// same, as the paper reports its time-domain validation and its chirp side by side).
pub(crate) fn mean_rmspe<E: AsRef<[f64]>>(errors: &[E]) -> f64 {
    let per_run: Vec<f64> = errors
        .iter()
        .map(AsRef::as_ref)
        .map(|e| (e.iter().map(|p| p * p).sum::<f64>() / e.len().max(1) as f64).sqrt())
        .collect();
    per_run.iter().sum::<f64>() / per_run.len().max(1) as f64
}

/// Validation error of a model: the runs' RMSPE averaged over the runs, %.
pub fn validation_rmspe(
    model: &ExtendedModel,
    validation: &[&Run],
    initial: InitialState,
) -> Result<f64, DiagnoseError> {
    Ok(mean_rmspe(&pct_errors(model, validation, initial)?))
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
    let steps = (EffectId::CATALOG.len() + StructuralChange::ALL.len()) as f64 + 1.0;
    let mut done = 0.0;
    let mut tick = |progress: &mut dyn FnMut(f64) -> bool| {
        let go_on = progress(done / steps);
        done += 1.0;
        if go_on { Ok(()) } else { Err(DiagnoseError::Cancelled) }
    };
    tick(progress)?;
    if validation.is_empty() {
        return Err(DiagnoseError::NoValidationRuns);
    }
    let data = FitData::new(ident, fits, settings)?;
    let before = pct_errors(current, validation, settings.initial_state)?;
    let reference = refit(current, &data)?;
    let folds = HeldOut::of(&data, current);
    let mut yardstick = Scores::of(&reference, validation, settings.initial_state)?;
    yardstick.cross_validate(Recipe::Current, folds.as_ref());
    let bench = Bench {
        current,
        reference: &reference,
        data: &data,
        validation,
        all_runs: std::iter::once(ident).chain(validation.iter().copied()).collect(),
        initial: settings.initial_state,
        folds: folds.as_ref(),
        judge: Judge { yardstick: &yardstick, rmspe_before_pct: mean_rmspe(&before) },
        traces: residual_traces(current, &data, validation, settings.initial_state)?,
    };
    let mut trials = Trials::default();
    // Structure first: what the model's own linear block and map can still do.
    for change in StructuralChange::ALL {
        tick(progress)?;
        bench.try_structure(change, &mut trials);
    }
    for id in EffectId::CATALOG {
        tick(progress)?;
        bench.try_effect(id, &mut trials);
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
    folds: Option<&'a HeldOut>,
    judge: Judge<'a>,
    /// The current model's residuals (the evidence is read from them).
    traces: Vec<ResidualTrace>,
}

/// The trials so far, and the best structural refinement a physical effect must beat.
#[derive(Default)]
struct Trials {
    entries: Vec<Diagnosis>,
    skipped: Vec<SkippedEffect>,
    rival: Option<(StructureRival, Scores, Recipe)>,
}

impl Bench<'_> {
    /// One structural refinement, refitted, scored and judged; the best becomes the rival.
    fn try_structure(&self, change: StructuralChange, trials: &mut Trials) {
        let trial = refine_structure(self.reference, change, self.data)
            .map_err(DiagnoseError::from)
            .and_then(|(model, words)| {
                let mut after = Scores::of(&model, self.validation, self.initial)?;
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
        let Verdict { test, rmspe_after_pct, significant } = self.judge.verdict(&after);
        let rmspe_before_pct = self.judge.rmspe_before_pct;
        let evidence = format!(
            "{words}: with it the validation error goes from {rmspe_before_pct:.3} % to {rmspe_after_pct:.3} %"
        );
        if trials.rival.as_ref().is_none_or(|(r, ..)| rmspe_after_pct < r.rmspe_pct) {
            let r = StructureRival { id: change, rmspe_pct: rmspe_after_pct, test };
            trials.rival = Some((r, after.clone(), Recipe::Structure(change)));
        }
        trials.entries.push(Diagnosis {
            effect: TrialId::Structure(change),
            kind: DiagnosisKind::Structure,
            physics: change.meaning().to_owned(),
            significant,
            rmspe_before_pct,
            rmspe_after_pct,
            test,
            evidence,
            model,
            rival: None,
            why_not: None,
        });
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
                let mut after = Scores::of(&model, self.validation, self.initial)?;
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
        let Verdict { test, rmspe_after_pct, significant: beats_current } = self.judge.verdict(&after);
        let evidence = id.evidence(&self.traces);
        let held = self.held_against_rival(trials, &after, beats_current && evidence.supports);
        // The ranking follows the evidence where a lag and a dead time compete: when the whole
        // response is shifted late (not only its later part), a dead time that fits better than the
        // best structural refinement is credited even if the refinement comes close: a pole placed
        // to mimic a dead time is no evidence against one.
        let evidence_says_dead_time = id == EffectId::TransportDelay
            && crate::core::effects::transport_delay::lateness(&self.traces).whole_response_late();
        let beats_structure = held
            .as_ref()
            .is_none_or(|r| r.test.passes() || (evidence_says_dead_time && r.test.reduction > 0.0));
        let why_not = match (beats_current, evidence.supports, beats_structure, &held) {
            (true, false, ..) => {
                Some("not counted: its own evidence does not show the effect's signature".to_owned())
            }
            (true, true, false, Some(rival)) => Some(format!(
                "not counted: it does not beat the best structural refinement, {} ({:.3} %), beyond noise (against \
                 it: {})",
                rival.id,
                rival.rmspe_pct,
                rival.test.words()
            )),
            _ => None,
        };
        trials.entries.push(Diagnosis {
            effect: TrialId::Effect(id),
            kind: DiagnosisKind::Physics,
            physics: id.physics().to_owned(),
            significant: beats_current && beats_structure && evidence.supports,
            rmspe_before_pct: self.judge.rmspe_before_pct,
            rmspe_after_pct,
            test,
            evidence: evidence.sentence,
            model,
            rival: held,
            why_not,
        });
    }

    /// The best structural refinement with the test of the effect `after` against it; its held-out
    /// errors are computed when an effect that could count (`could_count`) needs them.
    fn held_against_rival(
        &self,
        trials: &mut Trials,
        after: &Scores,
        could_count: bool,
    ) -> Option<StructureRival> {
        if let Some((_, errors, recipe)) = trials.rival.as_mut().filter(|_| could_count) {
            errors.cross_validate(*recipe, self.folds);
        }
        trials.rival.as_ref().map(|(r, errors, _)| StructureRival {
            test: Comparison::of(errors, after, self.judge.yardstick),
            ..r.clone()
        })
    }
}

impl Trials {
    /// The report: the trials ranked by validation RMSPE, and what the structure needs in words.
    fn into_report(mut self, bench: &Bench<'_>) -> DiagnosisReport {
        self.entries.sort_by(|a, b| a.rmspe_after_pct.total_cmp(&b.rmspe_after_pct));
        // The words follow the ranking: structure is "the missing piece" only when no physics ranks
        // above it (the table and the loop take the top significant entry).
        let yardstick = bench.judge.yardstick;
        let mut report = DiagnosisReport {
            output: bench.current.output.clone(),
            rmspe_current_pct: bench.judge.rmspe_before_pct,
            rmspe_refit_pct: mean_rmspe(&yardstick.validation),
            held_out_refit_pct: yardstick.held_out_rmspe(),
            held_out_segments: bench.folds.map_or(0, HeldOut::segments),
            entries: self.entries,
            skipped: self.skipped,
            structure_note: None,
        };
        let top_is_physics = report.top_is_physics();
        report.structure_note =
            report.entries.iter().find(|d| d.kind == DiagnosisKind::Structure && d.significant).map(|d| {
                if top_is_physics {
                    format!("below the physics ranked first, the structure may also improve: {}", d.evidence)
                } else {
                    format!("structure is the missing piece: {}", d.evidence)
                }
            });
        report
    }
}
