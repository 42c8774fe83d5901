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
use crate::core::run::Run;

mod edit;
mod held_out;
mod history;
mod loss;
mod report;
mod spool_witness;
mod witness;
pub use edit::{Edit, edit};
use held_out::{HeldOut, Recipe};
pub use history::{AutoRound, EffectSequence, HistoryStep, apply_in_order, auto_effects};
pub use report::{Diagnosis, DiagnosisKind, DiagnosisReport, SkippedEffect, TrialId};
pub use witness::{Comparison, HeldOutWitness, MIN_WITNESS_RESPONSES, p_text};
use witness::{Judge, Scores, Verdict};

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
    let before = Scores::of(current, validation, settings.initial_state)?;
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
        judge: Judge { yardstick: &yardstick, current: &before },
        traces: residual_traces(current, &data, validation, settings.initial_state)?,
        spool: spool_witness::spool_traces(
            current,
            &std::iter::once(&data.run).chain(validation.iter().copied()).collect::<Vec<_>>(),
        )?,
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
    /// The measured shaft speed against the current model's spool, when this output is another
    /// (see `spool_witness`): where effects that act before the spool are read.
    spool: Option<(String, Vec<ResidualTrace>)>,
}

/// The trials so far.
#[derive(Default)]
struct Trials {
    /// Each trial with its errors and how it is fitted (for the comparisons between trials).
    entries: Vec<(Diagnosis, Scores, Recipe)>,
    skipped: Vec<SkippedEffect>,
}

impl Bench<'_> {
    /// One structural refinement, refitted, scored and judged.
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

impl Trials {
    /// The report: the trials ranked by validation RMSPE, and what the structure needs in words.
    fn into_report(mut self, bench: &Bench<'_>) -> DiagnosisReport {
        self.entries.sort_by(|a, b| a.0.beyond_noise_after.total_cmp(&b.0.beyond_noise_after));
        let preference_note = self.prefer_physics_only_on_evidence(bench);
        let attribution_note = self.settle_tie(bench).or(preference_note);
        // The words follow the ranking: structure is "the missing piece" only when no physics ranks
        // above it (the table and the loop take the top significant entry).
        let yardstick = bench.judge.yardstick;
        let mut report = DiagnosisReport {
            output: bench.current.output.clone(),
            rmspe_current_pct: bench.judge.current.rmspe(),
            rmspe_refit_pct: yardstick.rmspe(),
            held_out_refit_pct: yardstick.held_out_rmspe(),
            held_out_segments: bench.folds.map_or(0, HeldOut::segments),
            entries: self.entries.into_iter().map(|(d, ..)| d).collect(),
            skipped: self.skipped,
            structure_note: None,
            attribution_note,
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

    /// Rule 3 of [`decide`]: the data must prefer a physical effect that counts by rules 1 and 2
    /// to the best structural refinement (lowest error beyond the noise among those the witnesses
    /// lean towards, see [`RIVAL_LEVEL`]).
    ///
    /// - It beats the refinement beyond noise on the same witnesses: it is preferred.
    /// - The refinement beats it so: it is not counted.
    /// - Neither beats the other: the two explain the same residual, and the held-out
    ///   identification responses decide, as between any two trials that cannot be told apart
    ///   (see [`Trials::settle_tie`]): the physics keeps its place only when its held-out witness
    ///   against the current model is counted and at least as strong as the refinement's. Where
    ///   the held-out responses support both alike (seven responses all better give both the
    ///   floor p = 1/128), the physics' own evidence, which agrees or it would not count, is the
    ///   support the refinement lacks. Without a held-out witness of its own, a block with more
    ///   freedom has not shown it explains more, and the physics is not counted.
    ///
    /// The note names both with the numbers and the experiment that would separate them, for the
    /// first physics this touches among the trials that count.
    fn prefer_physics_only_on_evidence(&mut self, bench: &Bench<'_>) -> Option<String> {
        if !self.entries.iter().any(|e| e.0.significant && e.0.kind == DiagnosisKind::Physics) {
            return None;
        }
        // The entries are ranked: the first structural refinement the witnesses lean towards, all
        // of them consulted (its own test may have spared the held-out refits).
        let yardstick = bench.judge.yardstick;
        let rival = (0..self.entries.len()).find(|&i| {
            let (d, scores, recipe) = &mut self.entries[i];
            if d.kind != DiagnosisKind::Structure || d.test.p_value >= RIVAL_LEVEL {
                return false;
            }
            scores.cross_validate(*recipe, bench.folds);
            Comparison::of(yardstick, scores, yardstick).p_value < RIVAL_LEVEL
        })?;
        let (rival_entry, rival_scores) = (self.entries[rival].0.clone(), self.entries[rival].1.clone());
        let rival_support = held_out_support(&Comparison::of(yardstick, &rival_scores, yardstick));
        let mut note = None;
        let first_counting = self.entries.iter().position(|e| e.0.significant);
        for (i, (d, scores, _)) in self.entries.iter_mut().enumerate() {
            if !(d.significant && d.kind == DiagnosisKind::Physics) {
                continue;
            }
            let against = Comparison::of(&rival_scores, scores, yardstick);
            if against.p_value < SIGNIFICANCE_LEVEL && against.reduction > 0.0 {
                continue;
            }
            let rival_better = Comparison::of(scores, &rival_scores, yardstick).p_value < SIGNIFICANCE_LEVEL;
            let own_support = held_out_support(&d.test);
            let held_out_prefers =
                own_support.is_some_and(|own| rival_support.is_none_or(|theirs| own <= theirs));
            let support_words = format!(
                "held-out support against the current model: {} for {}, {} for {}",
                support_text(own_support),
                d.effect,
                support_text(rival_support),
                rival_entry.effect
            );
            let kept = !rival_better && held_out_prefers;
            if !kept {
                d.significant = false;
                d.why_not = Some(format!(
                    "not counted: the data do not prefer it to the best structural refinement, {} ({:.2} σ beyond \
                     the noise): {}; {support_words}",
                    rival_entry.effect,
                    rival_entry.beyond_noise_after,
                    against.words()
                ));
            }
            if note.is_none() && first_counting == Some(i) {
                note = Some(format!(
                    "{} and {} explain the same residual: error beyond the noise {:.2} σ against {:.2} σ (RMSPE \
                     {:.3} % against {:.3} %), and the physics does not beat the structure beyond noise ({}); \
                     {support_words}. {}. A test that would separate them: {}; {}",
                    d.effect,
                    rival_entry.effect,
                    d.beyond_noise_after,
                    rival_entry.beyond_noise_after,
                    d.rmspe_after_pct,
                    rival_entry.rmspe_after_pct,
                    against.words(),
                    if kept {
                        format!("{} is counted: the held-out responses prefer it", d.effect)
                    } else {
                        format!(
                            "{} is not counted: the physics is taken only when the data prefer it",
                            d.effect
                        )
                    },
                    d.effect.separating_test(),
                    rival_entry.effect.separating_test()
                ));
            }
        }
        note
    }

    /// When the two best significant trials cannot be told apart (the better does not beat the
    /// other beyond noise, [`SIGNIFICANCE_LEVEL`], on the same witnesses), the data do not say
    /// which explains the residual, and the note says so with the numbers and the experiment that
    /// would separate them. The held-out identification responses then decide: the runner-up is
    /// put first (where the loop takes it) only when its held-out witness is the stronger (a lower
    /// signed-rank p-value against the current model; a trial whose held-out responses do not
    /// witness has no such support). Otherwise the ranking stands. The evidence cannot decide
    /// here: a physical effect that counts already has its signature, and a structural refinement
    /// claims no physics to have one of.
    fn settle_tie(&mut self, bench: &Bench<'_>) -> Option<String> {
        let mut significant =
            self.entries.iter().enumerate().filter(|(_, e)| e.0.significant).map(|(i, _)| i);
        let (first, second) = (significant.next()?, significant.next()?);
        for i in [first, second] {
            let (_, scores, recipe) = &mut self.entries[i];
            scores.cross_validate(*recipe, bench.folds);
        }
        let apart = Comparison::of(&self.entries[second].1, &self.entries[first].1, bench.judge.yardstick);
        if apart.p_value < SIGNIFICANCE_LEVEL {
            return None;
        }
        let (a, b) = (&self.entries[first].0, &self.entries[second].0);
        let support = |d: &Diagnosis| held_out_support(&d.test);
        let held_out_words = |d: &Diagnosis| {
            support(d)
                .map_or_else(|| "no held-out witness".to_owned(), |p| format!("held-out p = {}", p_text(p)))
        };
        let runner_up_first = support(b).is_some_and(|pb| support(a).is_none_or(|pa| pb < pa));
        let why = if runner_up_first {
            format!(
                "the held-out identification responses support it more ({} against {})",
                held_out_words(b),
                held_out_words(a)
            )
        } else if support(a).is_some() {
            format!(
                "it ranks first and the held-out responses support it at least as well ({} against {})",
                held_out_words(a),
                held_out_words(b)
            )
        } else {
            "it ranks first and the held-out responses witness neither".to_owned()
        };
        let note = format!(
            "{} and {} explain the same residual and cannot be told apart: error beyond the noise {:.2} σ \
             against {:.2} σ (RMSPE {:.3} % against {:.3} %), and the better does not beat the other beyond \
             noise ({}). Taken: {}, because {why}. A test that would separate them: {}; {}",
            a.effect,
            b.effect,
            a.beyond_noise_after,
            b.beyond_noise_after,
            a.rmspe_after_pct,
            b.rmspe_after_pct,
            apart.words(),
            if runner_up_first { b.effect } else { a.effect },
            a.effect.separating_test(),
            b.effect.separating_test()
        );
        if runner_up_first {
            self.entries.swap(first, second);
        }
        Some(note)
    }
}

/// The held-out witness's signed-rank p-value, when it counted.
fn held_out_support(test: &Comparison) -> Option<f64> {
    test.held_out.filter(|h| h.counted).map(|h| h.test.p_value)
}

/// "p = 0.0068", or "none" when the held-out responses do not witness.
fn support_text(support: Option<f64>) -> String {
    support.map_or_else(|| "none".to_owned(), |p| format!("p = {}", p_text(p)))
}

/// Whether a trial counts by the first two conditions (the third needs every trial; see below);
/// with the ranking and `Trials::settle_tie` this is the whole decision.
///
/// 1. It beats the refitted current model beyond noise and by enough to matter
///    ([`Comparison::passes`]: p < [`SIGNIFICANCE_LEVEL`] over the validation runs and the held-out
///    responses, and at least [`MIN_RELATIVE_REDUCTION`] of the error beyond the noise removed).
/// 2. A physical effect's own evidence, read from the current model's residuals, shows its
///    signature: a flexible block buys a few percent anywhere; the signature says which physics
///    it is.
///
/// 3. The data prefer it to the best structural refinement: it beats that refinement beyond noise
///    on the same witnesses (see `Trials::prefer_physics_only_on_evidence`; no share is asked
///    there: between two explanations of the same residual only which one the data prefer
///    counts). A lag block or a dead time that only stands in for a missing pole pair is no
///    evidence of physics.
///
/// The trials that count then compete on the same terms: the ranking by error beyond the noise,
/// and where the two best cannot be told apart, the held-out responses. There is no exception for
/// any effect.
///
/// Returns whether it counts, and why not when it beats the current model and still does not.
fn decide(beats_current: bool, evidence_supports: bool) -> (bool, Option<String>) {
    match (beats_current, evidence_supports) {
        (true, true) => (true, None),
        (true, false) => {
            (false, Some("not counted: its own evidence does not show the effect's signature".to_owned()))
        }
        (false, _) => (false, None),
    }
}
