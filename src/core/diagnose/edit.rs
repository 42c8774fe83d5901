//! Effects added or removed by hand (the app's Apply and Remove, the batch's `--add-effect`).
use super::DiagnoseError;
use crate::core::effects::{EffectId, ExtendedModel, FitData, apply_effect, refit};
use crate::core::identification::fits::SegmentFits;
use crate::core::identification::settings::OutputSettings;
use crate::core::run::Run;

/// An effect added to a model or taken out of it by hand.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Edit {
    Add(EffectId),
    Remove(EffectId),
}

/// `current` with `edit` made, refitted on the identification data of `fits` (`ident` the run it
/// was fitted on, with `settings`).
pub fn edit(
    current: &ExtendedModel,
    edit: Edit,
    ident: &Run,
    fits: &SegmentFits,
    settings: &OutputSettings,
) -> Result<ExtendedModel, DiagnoseError> {
    let data = FitData::new(ident, fits, settings)?;
    match edit {
        Edit::Add(id) => add(current, id, &data),
        // What remains is refitted.
        Edit::Remove(id) => Ok(refit(&current.without_effect(id)?, &data)?),
    }
}

/// Add the effect `id` to `current` and refit on the identification data.
fn add(current: &ExtendedModel, id: EffectId, data: &FitData) -> Result<ExtendedModel, DiagnoseError> {
    let from_current = apply_effect(current, id, data)?;
    // The diagnosis tries each effect from the current model refitted on the identification data;
    // adding it keeps whichever of the two fits the identification data better, so an effect added
    // by hand is never worse there than the one the diagnosis ranked.
    let from_refit = refit(current, data).and_then(|r| apply_effect(&r, id, data));
    Ok(match from_refit {
        Ok(other) if ident_cost(&other, data) < ident_cost(&from_current, data) => other,
        _ => from_current,
    })
}

/// Sum of squared simulation errors on the identification data (infinite when it cannot be simulated).
fn ident_cost(model: &ExtendedModel, data: &FitData) -> f64 {
    model
        .simulate(&data.run)
        .map_or(f64::INFINITY, |y_hat| y_hat.iter().zip(&data.y).map(|(a, b)| (a - b).powi(2)).sum::<f64>())
}
