//! The control-oriented part of an output's report: operating points across the identified range
//! and the steady run's plateau, and the continuous-time equivalent of the linear block.
use crate::core::control::{
    ContinuousTf, OperatingPoint, ParameterCovariance, bands, d2c_zoh, identified_range, operating_points,
};
use crate::core::effects::ExtendedModel;
use crate::core::numerics::stats::mean;

use crate::workflow::runs::Runs;

/// Where the operating points lie: the identified range of the identification run's input, and
/// each steady run's plateau (its name and mean input).
pub fn range_and_plateaus(runs: &Runs) -> ((f64, f64), Vec<(String, f64)>) {
    let range = identified_range(&runs.ident.input.values);
    let plateaus = runs.steady.iter().map(|s| (s.name.clone(), mean(&s.input.values))).collect();
    (range, plateaus)
}

/// Operating points of `model` across `range` and at the `plateaus`, and the ZOH equivalent of its
/// linear block; what could not be computed goes to `notes`.
pub fn control_report(
    model: &ExtendedModel,
    covariance: Option<&ParameterCovariance>,
    (range, plateaus): ((f64, f64), Vec<(String, f64)>),
    notes: &mut Vec<String>,
) -> (Vec<OperatingPoint>, Option<ContinuousTf>) {
    let output = &model.output;
    let mut points = operating_points(model, range, &plateaus).unwrap_or_else(|e| {
        notes.push(format!("operating points of '{output}': {e}"));
        Vec::new()
    });
    if let Some(covariance) = covariance.filter(|_| !points.is_empty()) {
        match bands::with_intervals(&mut points, model, covariance, range, &plateaus) {
            Ok(drawn) if drawn < bands::DRAWS => notes.push(format!(
                "operating-point intervals of '{output}': {drawn} of {} models drawn from the covariance \
                 gave operating points (the others gave no model: an effect parameter out of its range, or a local model that could not be computed)",
                bands::DRAWS
            )),
            Ok(_) => {}
            Err(e) => notes.push(format!("operating-point intervals of '{output}': {e}")),
        }
    }
    let continuous = d2c_zoh(&model.wiener.linear.tf)
        .map_err(|e| notes.push(format!("continuous-time equivalent of '{output}': {e}")))
        .ok();
    (points, continuous)
}

/// The final model's numbers with their 95 % intervals; what could not be computed goes to `notes`.
pub fn parameter_report(
    model: &ExtendedModel,
    covariance: Option<&ParameterCovariance>,
    notes: &mut Vec<String>,
) -> Vec<bands::ParameterInterval> {
    let Some(covariance) = covariance else { return Vec::new() };
    bands::parameter_intervals(model, covariance).unwrap_or_else(|e| {
        notes.push(format!("parameter intervals of '{}': {e}", model.output));
        Vec::new()
    })
}
