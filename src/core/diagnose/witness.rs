//! Two witnesses of a trial: the validation runs, and the identification data's segment responses
//! held out by the cross-validation (see `held_out`), combined into one test.
use super::held_out::{HeldOut, Recipe};
use super::loss::{Errors, mean_beyond_noise, mean_pct_rms, measurement_sigma, rms};
use super::{DiagnoseError, MIN_RELATIVE_REDUCTION, SIGNIFICANCE_LEVEL, measured};
use crate::core::effects::ExtendedModel;
use crate::core::effects::stats::{
    DmTest, SignedRankTest, diebold_mariano, signed_rank_test, stouffer_combined,
};
use crate::core::identification::initial_state::InitialState;
use crate::core::identification::segment::{SegmentSettings, auto_segments};
use crate::core::run::Run;

/// A model's errors on the evidence (see `loss`): each validation run, and each segment response
/// of the identification data held out by the cross-validation when there is one.
#[derive(Clone, Debug)]
pub(super) struct Scores {
    pub(super) validation: Vec<Errors>,
    /// The validation runs' step responses, each run's in turn (see [`ValidationResponses`]).
    responses: Vec<Errors>,
    held_out: Option<Vec<Errors>>,
    /// Why there are no held-out errors although there is a cross-validation.
    held_out_note: Option<&'static str>,
    /// Whether the cross-validation was run on the model (see [`Scores::cross_validate`]).
    tried: bool,
}

/// Why a trial's held-out errors were not computed: its validation error does not fall enough for
/// any p-value to make it significant, so the dear refits would change nothing.
pub(super) const NOT_CONSULTED: &str = "not consulted: the validation error beyond the noise does not fall by 10 % \
    of the refitted current model's, which a significant change needs";

/// Why a model has no held-out errors although the data have a cross-validation.
const NOT_REFITTED: &str = "not available: the model could not be refitted on every fold (or it \
    carries a calibration drift, which reads each run's own holds)";

impl Scores {
    /// The model's errors on the validation runs; the held-out errors come later, when they can
    /// matter (see [`Scores::cross_validate`]).
    pub(super) fn of(
        model: &ExtendedModel,
        validation: &[&Run],
        initial: InitialState,
        responses: &ValidationResponses,
    ) -> Result<Self, DiagnoseError> {
        let mut whole = Vec::with_capacity(validation.len());
        let mut parts = Vec::new();
        for (i, run) in validation.iter().enumerate() {
            let y = measured(run, &model.output)?;
            let y_hat = model
                .simulate_scored(run, initial)
                .map_err(|source| DiagnoseError::CurrentModel { run: run.name.clone(), source })?;
            let sigma = measurement_sigma(y);
            whole.push(Errors::of(y, &y_hat, 0..y.len(), sigma));
            let ranges = responses.0.get(i).map_or(&[][..], Vec::as_slice);
            parts.extend(ranges.iter().map(|&(a, b)| Errors::of(y, &y_hat, a..b, sigma)));
        }
        Ok(Self { validation: whole, responses: parts, held_out: None, held_out_note: None, tried: false })
    }

    /// The validation error the decision compares: each run's error beyond its measurement noise,
    /// in units of the noise, averaged over the runs (see `loss`).
    pub(super) fn beyond_noise(&self) -> f64 {
        mean_beyond_noise(&self.validation)
    }

    /// The validation RMSPE, averaged over the runs, % (the reported metric).
    pub(super) fn rmspe(&self) -> f64 {
        mean_pct_rms(&self.validation)
    }

    /// Add the held-out errors of the model `recipe` makes (whose validation errors these are), once.
    pub(super) fn cross_validate(&mut self, recipe: Recipe, folds: Option<&HeldOut>) {
        let Some(folds) = folds.filter(|_| !self.tried) else { return };
        self.tried = true;
        self.held_out = folds.errors(recipe);
        self.held_out_note = if self.held_out.is_some() { None } else { Some(NOT_REFITTED) };
    }

    /// Mark the held-out errors as not needed, with the reason.
    pub(super) fn skip_cross_validation(&mut self, folds: Option<&HeldOut>, reason: &'static str) {
        if folds.is_some() && !self.tried {
            self.held_out_note = Some(reason);
        }
    }

    /// Share of this model's validation error beyond the noise that `after` removes (negative
    /// when it adds error).
    ///
    /// The share is taken of the error beyond the noise, or of the noise itself (1 in these units)
    /// when the error beyond it is smaller: near the noise floor the excess is a small difference of
    /// two estimates, and a change worth a tenth of it would be a change nobody can see in a trace,
    /// well below what the sensor itself resolves.
    fn validation_reduction(&self, after: &Self) -> f64 {
        (self.beyond_noise() - after.beyond_noise()) / self.beyond_noise().max(1.0)
    }

    /// RMSPE over every held-out sample, %.
    pub(super) fn held_out_rmspe(&self) -> Option<f64> {
        self.held_out.as_ref().map(|responses| rms(&all_of(responses, |e| &e.pct)))
    }
}

/// The held-out responses as a witness: which of them can tell the two models apart, and what they
/// say.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeldOutWitness {
    /// Held-out RMSPE of the first and of the second model over every held-out response, %.
    pub rmspe_before_pct: f64,
    pub rmspe_after_pct: f64,
    /// Responses held out in all.
    pub responses: usize,
    /// Signed-rank test over the responses that exercise what the second model adds: those on
    /// which its predictions differ from the current model's by more than the measurement noise
    /// (RMSPE first − second, one value per response).
    pub test: SignedRankTest,
    /// Whether it took part in the p-value: at least [`MIN_WITNESS_RESPONSES`] responses exercise
    /// the second model's addition.
    pub counted: bool,
}

/// Fewest held-out responses that must tell two models apart for them to witness: six, whose
/// signed-rank test can reach p = 1/64 alone. With fewer the identification data do not exercise
/// what the trial adds (a rate limit the identification steps never reach, a drift between test
/// days, conditions the identification day did not have), and counting them would only dilute the
/// validation runs' verdict with a witness that saw nothing.
pub const MIN_WITNESS_RESPONSES: usize = 6;

/// Two models compared on the evidence (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Comparison {
    /// Diebold–Mariano test on the validation runs.
    pub validation: DmTest,
    /// The validation runs' step responses as a witness (see [`ValidationResponses`] and
    /// [`validation_p_value`]).
    pub responses: Option<HeldOutWitness>,
    /// The held-out identification responses, when both models were cross-validated.
    pub held_out: Option<HeldOutWitness>,
    /// Why there is no held-out witness although the data have a cross-validation.
    pub held_out_note: Option<&'static str>,
    /// One-sided p-value of "the second model is no better": Stouffer's combination of the two
    /// tests, equally weighted (see [`stouffer_combined`]), when the held-out responses witness;
    /// otherwise the validation test's alone.
    pub p_value: f64,
    /// Share of the first model's validation RMSPE the second removes.
    pub reduction: f64,
}

impl Comparison {
    /// `after` against `before`; `current` is the refitted current model both extend (or is
    /// `before` itself): the held-out responses that exercise `after`'s addition are those where
    /// `after` moves away from it. A physical effect held against a structural refinement is so
    /// judged on the responses the effect changes, not on those only the refinement changes: that
    /// the identification steps never reach a rate limit says nothing about the limit.
    pub(super) fn of(before: &Scores, after: &Scores, current: &Scores) -> Self {
        let loss = |a: &Errors, b: &Errors| {
            a.noise.iter().zip(&b.noise).map(|(za, zb)| za.abs() - zb.abs()).collect()
        };
        let d_runs: Vec<Vec<f64>> =
            before.validation.iter().zip(&after.validation).map(|(a, b)| loss(a, b)).collect();
        let validation = diebold_mariano(&d_runs);
        let responses = (!after.responses.is_empty()
            && before.responses.len() == after.responses.len()
            && current.responses.len() == after.responses.len())
        .then(|| witness(&before.responses, &after.responses, &current.responses));
        let validation_p = validation_p_value(&validation, responses.as_ref());
        let held_out = match (&before.held_out, &after.held_out, &current.held_out) {
            (Some(a), Some(b), Some(c)) if a.len() == b.len() && c.len() == b.len() => Some(witness(a, b, c)),
            _ => None,
        };
        let p_value = match held_out.filter(|h| h.counted) {
            Some(h) => stouffer_combined(&[validation_p, h.test.p_value]),
            None => validation_p,
        };
        let reduction = before.validation_reduction(after);
        let held_out_note = match held_out {
            Some(_) => None,
            None => after.held_out_note.or(before.held_out_note),
        };
        Self { validation, responses, held_out, held_out_note, p_value, reduction }
    }

    /// Beyond noise and large enough to matter: `p < SIGNIFICANCE_LEVEL` and at least
    /// `MIN_RELATIVE_REDUCTION` of the validation error removed.
    pub fn passes(&self) -> bool {
        self.p_value < SIGNIFICANCE_LEVEL && self.reduction >= MIN_RELATIVE_REDUCTION
    }

    /// What the witnesses say, in words: "validation runs p = 0.0204; held-out identification
    /// responses from 3.190 % to 1.799 %, better on 8 of 10 (p = 0.0068); together p = 0.0007".
    pub fn words(&self) -> String {
        let validation = match self.responses.filter(decides) {
            Some(r) => format!(
                "validation runs p = {} (samples p = {}; responses from {:.3} % to {:.3} %, better on {} of {}, \
                 p = {})",
                p_text(validation_p_value(&self.validation, Some(&r))),
                p_text(self.validation.p_value),
                r.rmspe_before_pct,
                r.rmspe_after_pct,
                r.test.wins,
                r.test.n,
                p_text(r.test.p_value)
            ),
            None => format!("validation runs p = {}", p_text(self.validation.p_value)),
        };
        match self.held_out {
            Some(h) if h.counted => format!(
                "{validation}; held-out identification responses from {:.3} % to {:.3} %, better on {} of {} \
                 (p = {}); together p = {}",
                h.rmspe_before_pct,
                h.rmspe_after_pct,
                h.test.wins,
                h.test.n,
                p_text(h.test.p_value),
                p_text(self.p_value)
            ),
            Some(h) => format!(
                "{validation}; the held-out identification responses do not witness: the addition moves \
                 only {} of {} by more than the measurement noise",
                h.test.n, h.responses
            ),
            None => match self.held_out_note {
                Some(note) => format!("{validation}; held-out identification responses {note}"),
                None => validation,
            },
        }
    }
}

/// Fewest validation responses a change must move by more than the noise for their signed-rank
/// test to take part (see [`validation_p_value`]): eight, whose test reaches p = 1/256 when every
/// one is better, and twice that, 0.0078, is still below [`SIGNIFICANCE_LEVEL`]: the validation
/// runs must be able to make a change significant on their own (the held-out witness is often
/// silent). Seven would top out at 2/128 = 0.016.
pub const MIN_VALIDATION_RESPONSES: usize = 8;

/// Whether the validation responses take part (see [`MIN_VALIDATION_RESPONSES`]).
fn decides(responses: &HeldOutWitness) -> bool {
    responses.test.n >= MIN_VALIDATION_RESPONSES
}

/// The validation runs' one-sided p-value from their two views: sample by sample (the
/// Diebold–Mariano test, powerful for a change spread over the run, a scheduled time constant that
/// helps a little everywhere) and response by response (the signed-rank test over the step
/// responses, powerful for a change concentrated in transients, a rate limit). Where the responses
/// take part, the smaller p-value doubled (Bonferroni's bound for the better of two tests, valid
/// however the two depend on each other, as two readings of the same runs do); otherwise the
/// Diebold–Mariano test's alone.
fn validation_p_value(samples: &DmTest, responses: Option<&HeldOutWitness>) -> f64 {
    match responses.filter(|r| decides(r)) {
        Some(r) => (2.0 * samples.p_value.min(r.test.p_value)).min(1.0),
        None => samples.p_value,
    }
}

/// The validation runs cut into their step responses: for each run, the samples `(step, end)` of
/// each response its input's steps make (the automatic step detection, as on an identification
/// run); none for a run without steps (a chirp).
///
/// A model's error on a run of steps comes in transients: a step's response is wrong for as long
/// as the dynamics last and then settles. Read sample by sample, the Diebold–Mariano test must
/// estimate how long the loss differences stay correlated; on a test design whose steps repeat (a
/// staircase up and down) they correlate with themselves a period later, its bandwidth reaches its
/// cap, and it keeps the power of a handful of samples however consistently one model is better (a
/// rate limit that removes nine tenths of the error on each of thirty steps: p = 0.02). The step
/// responses are the unit the held-out identification responses already use: each response's
/// error is nearly independent of the next's, and the same witness asks how consistently the
/// second model is better on the responses it changes by more than the noise. When at least
/// [`MIN_VALIDATION_RESPONSES`] are so changed it takes part beside the Diebold–Mariano test (see
/// [`validation_p_value`]); otherwise (a chirp, a short log, a change too small to see on single
/// steps) the Diebold–Mariano test decides alone.
#[derive(Clone, Debug, Default)]
pub struct ValidationResponses(pub Vec<Vec<(usize, usize)>>);

impl ValidationResponses {
    /// The step responses of each of `runs`.
    pub fn of(runs: &[&Run]) -> Self {
        let settings = SegmentSettings::default();
        Self(
            runs.iter()
                .map(|run| {
                    auto_segments(&run.input.values, run.dt_secs, &settings)
                        .map(|segments| {
                            segments
                                .iter()
                                .map(|s| (s.step_at, s.end.min(run.len())))
                                .filter(|(a, b)| a < b)
                                .collect()
                        })
                        .unwrap_or_default()
                })
                .collect(),
        )
    }
}

/// The held-out witness of `b` against `a` (errors per response), counting the responses on
/// which `b`'s predictions differ from the current model's (`c`) by more than the measurement
/// noise: `c − b` is `(ŷ_b − ŷ_c)/σ`, so its RMS is the change of prediction in units of the noise,
/// which must exceed 1 to be seen at all. Each response's difference is its RMS error over the
/// noise, first model minus second.
fn witness(a: &[Errors], b: &[Errors], c: &[Errors]) -> HeldOutWitness {
    let d: Vec<f64> = a
        .iter()
        .zip(b)
        .zip(c)
        .filter(|((_, b), c)| {
            let change: Vec<f64> = c.noise.iter().zip(&b.noise).map(|(zc, zb)| zc - zb).collect();
            rms(&change) > 1.0
        })
        .map(|((a, b), _)| rms(&a.noise) - rms(&b.noise))
        .collect();
    let test = signed_rank_test(&d);
    HeldOutWitness {
        rmspe_before_pct: rms(&all_of(a, |e| &e.pct)),
        rmspe_after_pct: rms(&all_of(b, |e| &e.pct)),
        responses: a.len(),
        counted: test.n >= MIN_WITNESS_RESPONSES,
        test,
    }
}

/// One list of every response's errors, in the units `pick` takes.
fn all_of(responses: &[Errors], pick: impl Fn(&Errors) -> &Vec<f64>) -> Vec<f64> {
    responses.iter().flat_map(|e| pick(e).iter().copied()).collect()
}

/// A p-value to four places, or in scientific notation below 10⁻⁴.
pub fn p_text(p: f64) -> String {
    if p < 1e-4 { format!("{p:.1e}") } else { format!("{p:.4}") }
}

/// The significance rule of the module documentation, against the refitted current model.
pub(super) struct Judge<'a> {
    pub(super) yardstick: &'a Scores,
    /// The current model (not refitted) on the validation runs.
    pub(super) current: &'a Scores,
}

/// A trial judged against the refitted current model.
pub(super) struct Verdict {
    pub(super) test: Comparison,
    /// The trial's validation RMSPE, %.
    pub(super) rmspe_after_pct: f64,
    /// The trial's validation error over the noise (see `loss`).
    pub(super) beyond_noise_after: f64,
    pub(super) significant: bool,
}

impl Judge<'_> {
    /// Cross-validate the trial `model` when that can matter: its validation error falls below the
    /// current model's and by at least [`MIN_RELATIVE_REDUCTION`] of the refitted one's. Otherwise
    /// no held-out evidence can make it significant, and the refits are spared.
    pub(super) fn consult(&self, after: &mut Scores, recipe: Recipe, folds: Option<&HeldOut>) {
        let reduction = self.yardstick.validation_reduction(after);
        if reduction >= MIN_RELATIVE_REDUCTION && after.beyond_noise() < self.current.beyond_noise() {
            after.cross_validate(recipe, folds);
        } else {
            after.skip_cross_validation(folds, NOT_CONSULTED);
        }
    }

    /// The comparison over the validation runs and the held-out identification data, the trial's
    /// validation RMSPE, and whether it is significant: the comparison passes and the validation
    /// runs' own error falls below the current model's.
    pub(super) fn verdict(&self, after: &Scores) -> Verdict {
        let test = Comparison::of(self.yardstick, after, self.yardstick);
        let beyond_noise_after = after.beyond_noise();
        let significant = test.passes() && beyond_noise_after < self.current.beyond_noise();
        Verdict { test, rmspe_after_pct: after.rmspe(), beyond_noise_after, significant }
    }
}
