//! The finished model's parameter covariance, as the batch and the app both compute it: from the
//! identification run, with the static map's rows on the steady windows its points were read from.
use crate::core::control::covariance::{self, CovarianceError, ParameterCovariance};
use crate::core::effects::ExtendedModel;
use crate::core::identification::fits::SegmentFits;
use crate::core::identification::reduce::{IdentData, steady_windows};
use crate::core::identification::settings::OutputSettings;
use crate::core::run::Run;

/// The covariance of `model`'s parameters (the identified model with its effects) from the
/// identification run `ident` it was identified on, whose segment fits are `fits`.
pub fn parameter_covariance(
    fits: &SegmentFits,
    model: &ExtendedModel,
    ident: &Run,
    settings: &OutputSettings,
) -> Result<ParameterCovariance, CovarianceError> {
    let windows = IdentData::new(fits, ident, settings).map(|d| steady_windows(&d)).unwrap_or_default();
    covariance::estimate(model, ident, &windows)
}
