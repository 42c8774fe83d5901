//! The control-oriented part of an output's report: operating points across the identified range
//! and the steady run's plateau, and the continuous-time equivalent of the linear block.
use crate::core::control::{ContinuousTf, OperatingPoint, d2c_zoh, identified_range, operating_points};
use crate::core::effects::ExtendedModel;
use crate::core::numerics::stats::mean;

use crate::workflow::runs::Runs;

/// Operating points of `model` and the ZOH equivalent of its linear block; what could not be
/// computed goes to `notes`.
pub(super) fn control_report(
    model: &ExtendedModel,
    runs: &Runs,
    notes: &mut Vec<String>,
) -> (Vec<OperatingPoint>, Option<ContinuousTf>) {
    let output = &model.output;
    let u = &runs.ident.input.values;
    let range = identified_range(u);
    let plateaus: Vec<(String, f64)> =
        runs.steady.iter().map(|s| (s.name.clone(), mean(&s.input.values))).collect();
    let points = operating_points(model, range, &plateaus).unwrap_or_else(|e| {
        notes.push(format!("operating points of '{output}': {e}"));
        Vec::new()
    });
    let continuous = d2c_zoh(&model.wiener.linear.tf)
        .map_err(|e| notes.push(format!("continuous-time equivalent of '{output}': {e}")))
        .ok();
    (points, continuous)
}
