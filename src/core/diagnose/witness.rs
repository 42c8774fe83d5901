//! Two witnesses of a trial: the validation runs, and the identification data's segment responses
//! held out by the cross-validation (see `held_out`), combined into one test.
use super::held_out::{HeldOut, Recipe};
use super::{DiagnoseError, MIN_RELATIVE_REDUCTION, SIGNIFICANCE_LEVEL, mean_rmspe, pct_errors};
use crate::core::effects::ExtendedModel;
use crate::core::effects::stats::{
    DmTest, SignedRankTest, diebold_mariano, signed_rank_test, stouffer_combined,
};
use crate::core::identification::initial_state::InitialState;
use crate::core::run::Run;

/// A model's percentage errors on the evidence: each validation run, and each segment response
/// of the identification data held out by the cross-validation when there is one.
#[derive(Clone, Debug)]
pub(super) struct Scores {
    pub(super) validation: Vec<Vec<f64>>,
    held_out: Option<Vec<Vec<f64>>>,
    /// Why there are no held-out errors although there is a cross-validation.
    held_out_note: Option<&'static str>,
    /// The measurement noise over each held-out response, % (see [`HeldOut::noise_pct`]).
    noise_pct: Vec<f64>,
    /// Whether the cross-validation was run on the model (see [`Scores::cross_validate`]).
    tried: bool,
}

/// Why a trial's held-out errors were not computed: its validation error does not fall enough for
/// any p-value to make it significant, so the dear refits would change nothing.
pub(super) const NOT_CONSULTED: &str = "not consulted: the validation error does not fall by 10 % of the refitted \
    current model's, which a significant change needs";

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
    ) -> Result<Self, DiagnoseError> {
        Ok(Self {
            validation: pct_errors(model, validation, initial)?,
            held_out: None,
            held_out_note: None,
            noise_pct: Vec::new(),
            tried: false,
        })
    }

    /// Add the held-out errors of the model `recipe` makes (whose validation errors these are), once.
    pub(super) fn cross_validate(&mut self, recipe: Recipe, folds: Option<&HeldOut>) {
        let Some(folds) = folds.filter(|_| !self.tried) else { return };
        self.tried = true;
        self.held_out = folds.errors(recipe);
        self.noise_pct = folds.noise_pct().to_vec();
        self.held_out_note = if self.held_out.is_some() { None } else { Some(NOT_REFITTED) };
    }

    /// Mark the held-out errors as not needed, with the reason.
    pub(super) fn skip_cross_validation(&mut self, folds: Option<&HeldOut>, reason: &'static str) {
        if folds.is_some() && !self.tried {
            self.held_out_note = Some(reason);
        }
    }

    /// Share of this model's validation RMSPE that `after` removes (negative when it adds error).
    fn validation_reduction(&self, after: &Self) -> f64 {
        1.0 - mean_rmspe(&after.validation) / mean_rmspe(&self.validation).max(f64::MIN_POSITIVE)
    }

    /// RMSPE over every held-out sample, %.
    pub(super) fn held_out_rmspe(&self) -> Option<f64> {
        self.held_out.as_ref().map(|segments| {
            let all: Vec<f64> = segments.iter().flatten().copied().collect();
            mean_rmspe(&[all])
        })
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
        let loss = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(pa, pb)| pa.abs() - pb.abs()).collect();
        let d_runs: Vec<Vec<f64>> =
            before.validation.iter().zip(&after.validation).map(|(a, b)| loss(a, b)).collect();
        let validation = diebold_mariano(&d_runs);
        let held_out = match (&before.held_out, &after.held_out, &current.held_out) {
            (Some(a), Some(b), Some(c)) if a.len() == b.len() && c.len() == b.len() => {
                Some(witness(a, b, c, &current.noise_pct))
            }
            _ => None,
        };
        let p_value = match held_out.filter(|h| h.counted) {
            Some(h) => stouffer_combined(&[validation.p_value, h.test.p_value]),
            None => validation.p_value,
        };
        let reduction = before.validation_reduction(after);
        let held_out_note = match held_out {
            Some(_) => None,
            None => after.held_out_note.or(before.held_out_note),
        };
        Self { validation, held_out, held_out_note, p_value, reduction }
    }

    /// Beyond noise and large enough to matter: `p < SIGNIFICANCE_LEVEL` and at least
    /// `MIN_RELATIVE_REDUCTION` of the validation error removed.
    pub fn passes(&self) -> bool {
        self.p_value < SIGNIFICANCE_LEVEL && self.reduction >= MIN_RELATIVE_REDUCTION
    }

    /// What the witnesses say, in words: "validation runs p = 0.0204; held-out identification
    /// responses from 3.190 % to 1.799 %, better on 8 of 10 (p = 0.0068); together p = 0.0007".
    pub fn words(&self) -> String {
        let validation = format!("validation runs p = {}", p_text(self.validation.p_value));
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

/// The held-out witness of `b` against `a` (errors per response), counting the responses on
/// which `b`'s predictions differ from the current model's (`c`) by more than the noise: `c − b`
/// is `100 (ŷ_b − ŷ_c)/y`, so its RMS is the change of prediction, which must exceed the noise
/// `noise_pct` to be seen at all.
fn witness(a: &[Vec<f64>], b: &[Vec<f64>], c: &[Vec<f64>], noise_pct: &[f64]) -> HeldOutWitness {
    let rms = |x: &[f64]| mean_rmspe(&[x]);
    let noise = noise_pct.iter().chain(std::iter::repeat(&0.0));
    let d: Vec<f64> = a
        .iter()
        .zip(b)
        .zip(c)
        .zip(noise)
        .filter(|(((_, y), z), noise)| {
            let change: Vec<f64> = z.iter().zip(y.iter()).map(|(p, q)| p - q).collect();
            rms(&change) > **noise
        })
        .map(|(((x, y), _), _)| rms(x) - rms(y))
        .collect();
    let test = signed_rank_test(&d);
    let all = |s: &[Vec<f64>]| rms(&s.iter().flatten().copied().collect::<Vec<f64>>());
    HeldOutWitness {
        rmspe_before_pct: all(a),
        rmspe_after_pct: all(b),
        responses: a.len(),
        counted: test.n >= MIN_WITNESS_RESPONSES,
        test,
    }
}

/// A p-value to four places, or in scientific notation below 10⁻⁴.
pub fn p_text(p: f64) -> String {
    if p < 1e-4 { format!("{p:.1e}") } else { format!("{p:.4}") }
}

/// The significance rule of the module documentation, against the refitted current model.
pub(super) struct Judge<'a> {
    pub(super) yardstick: &'a Scores,
    pub(super) rmspe_before_pct: f64,
}

/// A trial judged against the refitted current model.
pub(super) struct Verdict {
    pub(super) test: Comparison,
    /// The trial's validation RMSPE, %.
    pub(super) rmspe_after_pct: f64,
    pub(super) significant: bool,
}

impl Judge<'_> {
    /// Cross-validate the trial `model` when that can matter: its validation error falls below the
    /// current model's and by at least [`MIN_RELATIVE_REDUCTION`] of the refitted one's. Otherwise
    /// no held-out evidence can make it significant, and the refits are spared.
    pub(super) fn consult(&self, after: &mut Scores, recipe: Recipe, folds: Option<&HeldOut>) {
        let reduction = self.yardstick.validation_reduction(after);
        if reduction >= MIN_RELATIVE_REDUCTION && mean_rmspe(&after.validation) < self.rmspe_before_pct {
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
        let rmspe_after_pct = mean_rmspe(&after.validation);
        let significant = test.passes() && rmspe_after_pct < self.rmspe_before_pct;
        Verdict { test, rmspe_after_pct, significant }
    }
}
