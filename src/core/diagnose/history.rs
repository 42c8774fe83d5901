//! The model's effects added one after another, each refitted on the identification data, with the
//! validation error after every step: the error history the batch reports and the app draws.
use serde::{Deserialize, Serialize};

use crate::core::effects::{
    ALTERNATING_POLE_SHARE, Alternating, EffectId, ExtendedModel, FitData, admissible,
};
use crate::core::identification::fits::SegmentFits;
use crate::core::identification::settings::OutputSettings;
use crate::core::run::Run;

use super::{
    DiagnoseError, Diagnosis, DiagnosisKind, DiagnosisReport, Edit, MIN_RELATIVE_REDUCTION, TrialId,
    diagnose_with_progress, edit, validation_rmspe,
};

/// The mean validation RMSPE of the model after one step ("base", "+thermal_soak", …).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HistoryStep {
    pub step: String,
    pub rmspe_pct: f64,
}

/// The model after adding a list of effects in order.
#[derive(Clone, Debug)]
pub struct EffectSequence {
    /// The model after the last effect that could be added.
    pub model: ExtendedModel,
    /// The validation error after each step, base first; a step whose error cannot be computed
    /// (or with no validation run) has none.
    pub history: Vec<HistoryStep>,
    /// Why a step has no validation error, in words.
    pub history_gaps: Vec<String>,
    /// The effect that could not be added, and why; the effects after it were not tried.
    pub failed: Option<(EffectId, DiagnoseError)>,
    /// The diagnosis of `model` on the validation runs, when the missing-physics loop ended on it
    /// (nothing further significant, or a round refused): the same report a diagnosis of the final
    /// model would give.
    pub final_diagnosis: Option<DiagnosisReport>,
    /// What was done about sample-alternating poles, in words: the trials the missing-physics loop
    /// refused (their fits need such a pole), each with its round and why, and the effects added by
    /// hand whose fit gave the pole up for the admissible form or keeps it (see [`apply_in_order`]).
    pub admissibility: Vec<String>,
}

/// Add `ids` to `base` in order, each refitted on the identification data (`ident`, `fits`), and
/// score the model on `validation` after every step.
///
/// An effect asked for by hand is added whatever it does to the error, but not with a
/// sample-alternating pole when the data can do without one: a fit that grows one takes the
/// admissible fit when that keeps within [`ALTERNATING_POLE_SHARE`] of its error on the
/// identification data (see [`admissible`]); otherwise it keeps the pole, and says so in
/// [`EffectSequence::admissibility`], as for every other outcome.
pub fn apply_in_order(
    base: &ExtendedModel,
    ids: &[EffectId],
    ident: &Run,
    fits: &SegmentFits,
    settings: &OutputSettings,
    validation: &[&Run],
) -> EffectSequence {
    let mut sequence = EffectSequence {
        model: base.clone(),
        history: Vec::new(),
        history_gaps: Vec::new(),
        failed: None,
        final_diagnosis: None,
        admissibility: Vec::new(),
    };
    sequence.record("base", validation, settings);
    for &id in ids {
        match edit(&sequence.model, Edit::Add(id), ident, fits, settings) {
            Ok(next) => {
                let (model, words) = admissible_by_hand(next, ident, fits, settings);
                sequence.model = model;
                sequence.admissibility.extend(words.map(|w| format!("+{id}: {w}")));
            }
            Err(err) => {
                sequence.failed = Some((id, err));
                break;
            }
        }
        sequence.record(&format!("+{id}"), validation, settings);
    }
    sequence
}

/// A diagnosis of `model` whose significant trials are each checked as the missing-physics loop
/// checks the one it takes (see [`admissible_pick`]): a trial whose fit needs a sample-alternating
/// pole that no admissible fit can stand in for stops counting, with why. The batch and the app
/// diagnose the model they show through this, so a trial the loop refused is refused everywhere.
pub fn diagnose_admissible(
    model: &ExtendedModel,
    ident: &Run,
    fits: &SegmentFits,
    validation: &[&Run],
    settings: &OutputSettings,
    progress: &mut dyn FnMut(f64) -> bool,
) -> Result<DiagnosisReport, DiagnoseError> {
    let mut report = diagnose_with_progress(model, ident, fits, validation, settings, progress)?;
    let context = RoundContext { round: 0, ident, fits, scored_on: validation, settings };
    for index in 0..report.entries.len() {
        if !report.entries[index].significant {
            continue;
        }
        if let Admissibility::Refused(why) = without_alternating_poles(&report.entries[index], &context) {
            report.refuse(index, format!("not taken: {why}"));
        }
    }
    Ok(report)
}

/// `model` in its admissible form when its fit grew a sample-alternating pole and the data can do
/// without it; what was done, in words (`None` when there was no such pole).
fn admissible_by_hand(
    model: ExtendedModel,
    ident: &Run,
    fits: &SegmentFits,
    settings: &OutputSettings,
) -> (ExtendedModel, Option<String>) {
    let list = |poles: &[f64]| poles.iter().map(|p| format!("{p:.3}")).collect::<Vec<_>>().join(", ");
    let keeps = |poles: &[f64], why: String| {
        format!(
            "its fit keeps a sample-alternating pole at {} ({why}): a mode no engine sampled behind a \
             zero-order hold has, which leaves the model no continuous-time form",
            list(poles)
        )
    };
    match FitData::new(ident, fits, settings).and_then(|data| admissible(&model, &data)) {
        Ok(None) => (model, None),
        Ok(Some(Alternating::Replaced { model: fit, poles })) => (
            fit,
            Some(format!(
                "the fit's sample-alternating pole at {} gave way to a zero that gives the same phase lead, real \
                 poles kept positive",
                list(&poles)
            )),
        ),
        Ok(Some(Alternating::Kept { poles, more_error: Some(ratio) })) => {
            let why = format!("without it the identification error is {ratio:.2}× as large");
            (model, Some(keeps(&poles, why)))
        }
        Ok(Some(Alternating::Kept { poles, more_error: None })) => {
            (model, Some(keeps(&poles, "no fit without it could be had".to_owned())))
        }
        Err(e) => {
            (model, Some(format!("whether its fit has a sample-alternating pole cannot be checked: {e}")))
        }
    }
}

/// One round of the missing-physics loop: what the diagnosis ranked first among the significant
/// entries and was added, with its evidence.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AutoRound {
    /// The effect or structural refinement added.
    pub added: TrialId,
    /// Physics or structure.
    pub kind: DiagnosisKind,
    /// Validation RMSPE before and after, %.
    pub rmspe_before_pct: f64,
    pub rmspe_after_pct: f64,
    /// The evidence sentence the diagnosis gave for it.
    pub evidence: String,
    /// What made it significant: the witnesses' tests, in words (see [`super::Comparison::words`]).
    pub significance: String,
    /// When that round's diagnosis could not tell it from another explanation: both, with the
    /// numbers, why this one was taken and the experiment that would separate them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub attribution: Option<String>,
    /// When the trial's fit had a sample-alternating pole: whether it gave way to the admissible
    /// fit (the round's validation error is then that fit's) or was kept, and why, in words.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub admissibility: Option<String>,
}

/// The missing-physics loop run on `sequence`'s model for up to `rounds` rounds: diagnose, add the
/// top significant entry (physics or structure, already refitted on the identification data by the
/// diagnosis), record the validation error, repeat. Stops early when nothing is significant; every
/// choice is made on `validation`, so held-out runs stay a fair test. Returns the rounds taken.
/// `progress` gets the fraction of the rounds done (0..=1); when it returns false the loop stops
/// with [`DiagnoseError::Cancelled`].
pub fn auto_effects(
    sequence: &mut EffectSequence,
    rounds: usize,
    ident: &Run,
    fits: &SegmentFits,
    settings: &OutputSettings,
    validation: &[&Run],
    progress: &mut dyn FnMut(f64) -> bool,
) -> Result<Vec<AutoRound>, DiagnoseError> {
    let mut taken = Vec::new();
    for round in 0..rounds {
        let mut round_progress = |f: f64| progress((round as f64 + f) / rounds as f64);
        let mut report =
            diagnose_with_progress(&sequence.model, ident, fits, validation, settings, &mut round_progress)?;
        let context = RoundContext { round, ident, fits, scored_on: validation, settings };
        let Some((pick, model, admissibility)) =
            admissible_pick(&mut report, &context, &mut sequence.admissibility)
        else {
            sequence.final_diagnosis = Some(report);
            break;
        };
        let top = &report.entries[pick];
        sequence.model = model;
        sequence.record(&format!("+{} (auto)", top.effect), validation, settings);
        let rmspe_after_pct = match (&admissibility, sequence.history.last()) {
            (Some(_), Some(step)) => step.rmspe_pct,
            _ => top.rmspe_after_pct,
        };
        taken.push(AutoRound {
            added: top.effect,
            kind: top.kind,
            rmspe_before_pct: top.rmspe_before_pct,
            rmspe_after_pct,
            evidence: top.evidence.clone(),
            significance: top.significance_words(),
            attribution: report.attribution_note.clone(),
            admissibility: admissibility
                .map(|words| format!("{words} (the fit with it scored {:.3} %)", top.rmspe_after_pct)),
        });
    }
    Ok(taken)
}

/// What a round of the loop works on: the identification data its trials were fitted on and the
/// validation runs they were chosen on.
struct RoundContext<'a> {
    round: usize,
    ident: &'a Run,
    fits: &'a SegmentFits,
    scored_on: &'a [&'a Run],
    settings: &'a OutputSettings,
}

impl RoundContext<'_> {
    /// Whether the admissible fit still makes the round worth taking. The trial
    /// was judged significant on its free fit; the admissible fit is a less flexible model, and is
    /// taken when either
    /// - it keeps within [`ALTERNATING_POLE_SHARE`] of the free fit's validation error (what the
    ///   alternating pole buys is then what a refinement may cost, as on the identification data),
    /// - or it still removes [`MIN_RELATIVE_REDUCTION`] of the current model's validation error,
    ///   the share a significant trial must remove (the round is then worth taking on its own,
    ///   however much better the inadmissible fit would have been).
    ///
    /// With no validation run there is nothing to hold it to.
    fn holds(&self, admissible: &ExtendedModel, trial: &Diagnosis) -> bool {
        if self.scored_on.is_empty() {
            return true;
        }
        validation_rmspe(admissible, self.scored_on, self.settings.initial_state).is_ok_and(|pct| {
            let keeps_the_trial =
                1.0 - trial.rmspe_after_pct / pct.max(f64::MIN_POSITIVE) < ALTERNATING_POLE_SHARE;
            let significant_alone = pct <= (1.0 - MIN_RELATIVE_REDUCTION) * trial.rmspe_before_pct;
            keeps_the_trial || significant_alone
        })
    }
}

/// The significant trial of `report` the round takes, best first, with its model made admissible
/// (see [`without_alternating_poles`]) and what that did, in words. A trial whose fit needs a
/// sample-alternating pole is refused: it no longer counts in `report`, and why is added to
/// `refusals`; the next significant trial is tried. `None` when none is left.
fn admissible_pick(
    report: &mut DiagnosisReport,
    context: &RoundContext,
    refusals: &mut Vec<String>,
) -> Option<(usize, ExtendedModel, Option<String>)> {
    loop {
        let pick = report.entries.iter().position(|d| d.significant)?;
        let trial = &report.entries[pick];
        match without_alternating_poles(trial, context) {
            Admissibility::Fine => return Some((pick, trial.model.clone(), None)),
            Admissibility::Replaced(model, words) => return Some((pick, model, Some(words))),
            Admissibility::Refused(words) => {
                refusals.push(format!(
                    "round {}: {} (validation error from {:.3} % to {:.3} %) is not taken: {words}",
                    context.round + 1,
                    trial.effect,
                    trial.rmspe_before_pct,
                    trial.rmspe_after_pct
                ));
                report.refuse(pick, format!("not taken: {words}"));
            }
        }
    }
}

/// What a round's model becomes when its fit has a sample-alternating pole.
enum Admissibility {
    /// It has none.
    Fine,
    /// The admissible fit replaces it; what was done, in words.
    Replaced(ExtendedModel, String),
    /// No admissible fit holds: why, in words.
    Refused(String),
}

/// `model` without the sample-alternating poles an effect fit may grow (see
/// [`crate::core::effects::admissible`]). The admissible fit must hold on the identification data
/// and on the validation runs ([`RoundContext::holds`]); when it does not, the data are reached only with
/// the alternating pole, and the round that needs it is refused: a controller designer can use the
/// model before the round, and cannot use one with a mode that alternates sign every sample.
fn without_alternating_poles(trial: &Diagnosis, context: &RoundContext) -> Admissibility {
    let list = |poles: &[f64]| poles.iter().map(|p| format!("{p:.3}")).collect::<Vec<_>>().join(", ");
    let needs = |poles: &[f64], why: &str| {
        Admissibility::Refused(format!(
            "its fit needs a sample-alternating pole at {} ({why}), a mode no engine sampled behind a zero-order hold \
             has and that leaves the model no continuous-time form",
            list(poles)
        ))
    };
    let data = FitData::new(context.ident, context.fits, context.settings);
    match data.and_then(|data| admissible(&trial.model, &data)) {
        Ok(None) => Admissibility::Fine,
        Ok(Some(Alternating::Replaced { model, poles })) if context.holds(&model, trial) => {
            Admissibility::Replaced(
                model,
                format!(
                    "the fit's sample-alternating pole at {} gave way to a zero that gives the same phase lead, real \
                 poles kept positive (no engine sampled behind a zero-order hold alternates sign every sample)",
                    list(&poles)
                ),
            )
        }
        Ok(Some(Alternating::Replaced { poles, .. })) => needs(
            &poles,
            &format!(
                "without it the validation error neither stays within {:.0} % of {:.3} % nor falls from {:.3} % by \
                 the {:.0} % a significant change needs",
                100.0 * ALTERNATING_POLE_SHARE,
                trial.rmspe_after_pct,
                trial.rmspe_before_pct,
                100.0 * MIN_RELATIVE_REDUCTION
            ),
        ),
        Ok(Some(Alternating::Kept { poles, more_error: Some(ratio) })) => {
            needs(&poles, &format!("without it the identification error is {ratio:.2}× as large"))
        }
        Ok(Some(Alternating::Kept { poles, more_error: None })) => {
            needs(&poles, "no fit without it could be had")
        }
        Err(e) => Admissibility::Refused(format!(
            "whether its fit has a sample-alternating pole cannot be checked: {e}"
        )),
    }
}

impl EffectSequence {
    fn record(&mut self, step: &str, validation: &[&Run], settings: &OutputSettings) {
        if validation.is_empty() {
            return;
        }
        match validation_rmspe(&self.model, validation, settings.initial_state) {
            Ok(rmspe_pct) => self.history.push(HistoryStep { step: step.to_owned(), rmspe_pct }),
            Err(e) => self.history_gaps.push(format!("no validation error after {step}: {e}")),
        }
    }
}
