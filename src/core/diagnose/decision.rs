//! The decision over one diagnosis's trials: which count (see [`decide`]), whether the data
//! prefer a physical effect to the structure that explains the same residual, which of two that
//! cannot be told apart goes first, and the report in that order (see the module documentation of
//! `core::diagnose`).
use super::held_out::{HeldOut, Recipe};
use super::witness::Scores;
use super::{
    Bench, Comparison, Diagnosis, DiagnosisKind, DiagnosisReport, MIN_RELATIVE_REDUCTION, RIVAL_LEVEL,
    SIGNIFICANCE_LEVEL, SkippedEffect, p_text,
};

/// The trials so far.
#[derive(Default)]
pub(super) struct Trials {
    /// Each trial with its errors and how it is fitted (for the comparisons between trials).
    pub(super) entries: Vec<(Diagnosis, Scores, Recipe)>,
    pub(super) skipped: Vec<SkippedEffect>,
}

impl Trials {
    /// The report: the trials ranked by validation RMSPE, and what the structure needs in words.
    pub(super) fn into_report(mut self, bench: &Bench<'_>) -> DiagnosisReport {
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
        report.note_structure();
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
    ///   support the refinement lacks. Without a held-out witness of its own where the refinement
    ///   has one, a block with more freedom has not shown it explains more, and the physics is not
    ///   counted.
    /// - Where the held-out responses witness neither (each moves fewer than
    ///   [`MIN_WITNESS_RESPONSES`](super::MIN_WITNESS_RESPONSES) of them by more than the noise:
    ///   a limit or a day's conditions the identification steps do not exercise, or a load cell
    ///   whose noise hides what either changes on one step), they cannot decide, and the validation
    ///   runs, the only data that tell the two apart, do on the terms rule 1 sets against the
    ///   current model, short of its beyond-noise test (the physics has passed that against the
    ///   current model already): the physics keeps its place when the validation runs lean its way
    ///   against the refinement (p < [`RIVAL_LEVEL`]) and it removes at least
    ///   [`MIN_RELATIVE_REDUCTION`] of the refinement's error beyond the noise (of one noise σ
    ///   when that error is smaller, as rule 1 reckons the share), enough to matter.
    ///   Two explanations that differ by less explain the same residual as far as any data here can
    ///   tell, and the physics is then not counted.
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
            let held_out_prefers = match (own_support, rival_support) {
                (Some(own), Some(theirs)) => own <= theirs,
                (Some(_), None) => true,
                (None, Some(_)) => false,
                // The held-out steps witness neither: the validation runs decide.
                (None, None) => against.p_value < RIVAL_LEVEL && against.reduction >= MIN_RELATIVE_REDUCTION,
            };
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
                let verdict = if kept && own_support.is_none() {
                    format!(
                        "{} is counted: the held-out responses witness neither, and on the validation runs it \
                         removes {:.0} % of the refinement's error beyond the noise",
                        d.effect,
                        100.0 * against.reduction
                    )
                } else if kept {
                    format!("{} is counted: the held-out responses prefer it", d.effect)
                } else {
                    format!("{} is not counted: the physics is taken only when the data prefer it", d.effect)
                };
                note = Some(format!(
                    "{} explain the same residual: {}, and the physics does not beat the structure beyond noise \
                     ({}); {support_words}. {verdict}. {}",
                    both_names(d, &rival_entry),
                    both_errors(d, &rival_entry),
                    against.words(),
                    separating_tests(d, &rival_entry)
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
            "{} explain the same residual and cannot be told apart: {}, and the better does not beat the \
             other beyond noise ({}). Taken: {}, because {why}. {}",
            both_names(a, b),
            both_errors(a, b),
            apart.words(),
            if runner_up_first { b.effect } else { a.effect },
            separating_tests(a, b)
        );
        if runner_up_first {
            self.entries.swap(first, second);
        }
        Some(note)
    }
}

/// "transport_delay and extra_pole_pair".
fn both_names(a: &Diagnosis, b: &Diagnosis) -> String {
    format!("{} and {}", a.effect, b.effect)
}

/// "error beyond the noise 2.92 σ against 3.26 σ (RMSPE 0.538 % against 0.579 %)".
fn both_errors(a: &Diagnosis, b: &Diagnosis) -> String {
    format!(
        "error beyond the noise {:.2} σ against {:.2} σ (RMSPE {:.3} % against {:.3} %)",
        a.beyond_noise_after, b.beyond_noise_after, a.rmspe_after_pct, b.rmspe_after_pct
    )
}

/// "A test that would separate them: …; …" (see [`super::TrialId::separating_test`]).
fn separating_tests(a: &Diagnosis, b: &Diagnosis) -> String {
    format!("A test that would separate them: {}; {}", a.effect.separating_test(), b.effect.separating_test())
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
///    responses, and at least [`MIN_RELATIVE_REDUCTION`](super::MIN_RELATIVE_REDUCTION) of the error beyond the noise removed).
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
pub(super) fn decide(beats_current: bool, evidence_supports: bool) -> (bool, Option<String>) {
    match (beats_current, evidence_supports) {
        (true, true) => (true, None),
        (true, false) => {
            (false, Some("not counted: its own evidence does not show the effect's signature".to_owned()))
        }
        (false, _) => (false, None),
    }
}
