//! The identification data as a second witness: a cross-validation over its segments.
//!
//! A validation run can be short (the JetCat's run F is 59 s with four set-point changes) while the
//! identification data hold many more steps. Scored in-sample those steps say nothing about a
//! trial (every extra parameter lowers an in-sample error), but held out they do: each fold is the
//! model refitted without a third of the segments' responses (see [`FitData::folds`]) and then
//! simulated through the responses it never saw. Every response is held out by exactly one fold,
//! so each has one out-of-sample error per model: a second witness beside the validation runs,
//! compared response by response (see `Comparison`). It tests the *structure* (what the trial
//! adds), while its *parameters* are fitted afresh on each fold.
//!
//! Every fold repeats the whole fit on its own two thirds, as the diagnosis does on all the data:
//! the current model refitted on the fold, then the trial's block or refinement added to that and
//! searched from its own starting points ([`Recipe`]). Nothing a fold fits was chosen with its
//! held-out samples in view.
use super::loss::{Errors, measurement_sigma};
use crate::core::effects::{
    EffectId, ExtendedModel, FOLDS, FitData, StructuralChange, apply_effect, refine_structure, refit,
};

/// What a model is, as a fit to repeat on every fold.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Recipe {
    /// The current model, refitted.
    Current,
    /// The current model refitted, with a refinement of its structure.
    Structure(StructuralChange),
    /// The current model refitted, with an effect block added.
    Effect(EffectId),
}

/// The folds of the identification data.
pub(super) struct HeldOut {
    folds: [FitData; FOLDS],
    /// The current model refitted on each fold (`None` where that fails).
    references: Vec<Option<ExtendedModel>>,
    /// The measurement noise σ of the identification run (see `loss`).
    sigma: f64,
}

impl HeldOut {
    /// The folds of `data`, when it has enough segments for them (see [`FitData::folds`]), with
    /// `current` refitted on each.
    pub(super) fn of(data: &FitData, current: &ExtendedModel) -> Option<Self> {
        let folds = data.folds()?;
        let references = std::thread::scope(|scope| {
            let jobs: Vec<_> =
                folds.iter().map(|fold| scope.spawn(move || refit(current, fold).ok())).collect();
            jobs.into_iter().map(|j| j.join().ok().flatten()).collect()
        });
        Some(Self { folds, references, sigma: measurement_sigma(&data.y) })
    }

    /// Segments the cross-validation holds out, over both folds.
    pub(super) fn segments(&self) -> usize {
        self.folds.iter().map(|f| f.held_out.len()).sum()
    }

    /// Errors (see `loss`) of the model `recipe` makes, fitted on each fold, on each segment response
    /// that fold held out, in time order (samples where the measurement is zero are left out, for
    /// every model alike). `None` when a fold cannot be fitted or simulated: the trial is then
    /// judged on the validation runs alone. The folds are fitted on threads of their own.
    ///
    /// A model with a [`calibration_drift`](EffectId::CalibrationDrift) block has none either: the
    /// block takes each run's calibration from the run's own measured holds, so on the
    /// identification run it would read the held-out responses' answer, and a drift between test
    /// days is not something one day's steps can witness.
    pub(super) fn errors(&self, recipe: Recipe) -> Option<Vec<Errors>> {
        let drift = |m: &ExtendedModel| m.effect(EffectId::CalibrationDrift).is_some();
        if recipe == Recipe::Effect(EffectId::CalibrationDrift) || self.references.iter().flatten().any(drift)
        {
            return None;
        }
        let per_fold: Vec<Option<Vec<Response>>> = std::thread::scope(|scope| {
            let jobs: Vec<_> = self
                .folds
                .iter()
                .zip(&self.references)
                .map(|(fold, reference)| {
                    scope.spawn(move || {
                        fold_errors(&fit(recipe, reference.as_ref()?, fold)?, fold, self.sigma)
                    })
                })
                .collect();
            jobs.into_iter().map(|j| j.join().ok().flatten()).collect()
        });
        let mut segments: Vec<Response> = Vec::new();
        for fold in per_fold {
            segments.extend(fold?);
        }
        segments.sort_by_key(|(start, _)| *start);
        Some(segments.into_iter().map(|(_, e)| e).collect())
    }
}

/// A held-out response: its first sample and the errors over it.
type Response = (usize, Errors);

/// The model `recipe` makes on `fold`, from the current model refitted there.
fn fit(recipe: Recipe, reference: &ExtendedModel, fold: &FitData) -> Option<ExtendedModel> {
    match recipe {
        Recipe::Current => Some(reference.clone()),
        Recipe::Structure(change) => refine_structure(reference, change, fold).ok().map(|(m, _)| m),
        Recipe::Effect(id) => apply_effect(reference, id, fold).ok(),
    }
}

/// The responses `fold` held out, with the errors of `fitted` (fitted on it) against the
/// identification run's noise `sigma`.
fn fold_errors(fitted: &ExtendedModel, fold: &FitData, sigma: f64) -> Option<Vec<Response>> {
    let y_hat = fitted.simulate(&fold.run).ok()?;
    let segment = |&(a, b): &(usize, usize)| {
        let errors = Errors::of(&fold.y, &y_hat, a..b, sigma);
        errors.finite().then_some((a, errors))
    };
    fold.held_out.iter().map(segment).collect()
}
