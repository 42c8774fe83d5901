//! The model's numbers a user reads, each with its 95 % interval over drawn models.
use super::{DRAWS, percentile_interval};
use crate::core::control::covariance::{CovarianceError, ParameterCovariance};
use crate::core::effects::ExtendedModel;

/// One number of the model with its 95 % interval (percentiles over models drawn from the
/// covariance); `None` where too few draws have the number.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ParameterInterval {
    pub name: String,
    pub value: f64,
    pub ci95: Option<[f64; 2]>,
}

/// Seed of the draws behind [`parameter_intervals`].
const PARAMETER_SEED: u64 = 0x6A65_7469_6403;

/// The numbers of `model` a user reads, each with its 95 % interval over [`DRAWS`] models drawn
/// from the covariance:
/// - the static map's plain coefficients β0, β1, … of f(v);
/// - each effect's parameters in physical units, as its record names them;
/// - the coefficients of the linear block's zero-order-hold continuous equivalent (descending
///   powers of s, denominator monic), when the block has one.
pub fn parameter_intervals(
    model: &ExtendedModel,
    covariance: &ParameterCovariance,
) -> Result<Vec<ParameterInterval>, CovarianceError> {
    let draws = covariance.draw_models(model, DRAWS, PARAMETER_SEED)?;
    let numbers = |m: &ExtendedModel| -> Vec<(String, f64)> {
        let mut out: Vec<(String, f64)> = m
            .wiener
            .map
            .beta()
            .into_iter()
            .enumerate()
            .map(|(k, b)| (format!("static map β{k}"), b))
            .collect();
        for record in m.records() {
            out.extend(record.params.iter().map(|(name, v)| (format!("{}.{name}", record.id), *v)));
        }
        if let Ok(c) = crate::core::control::d2c::d2c_zoh(&m.wiener.linear.tf) {
            let n = c.num_s.len();
            out.extend(
                c.num_s.iter().enumerate().map(|(k, b)| (format!("G(s) numerator s^{}", n - 1 - k), *b)),
            );
            let d = c.den_s.len();
            out.extend(
                c.den_s
                    .iter()
                    .enumerate()
                    .skip(1)
                    .map(|(k, a)| (format!("G(s) denominator s^{}", d - 1 - k), *a)),
            );
        }
        out
    };
    let drawn: Vec<Vec<(String, f64)>> = draws.iter().map(numbers).collect();
    Ok(numbers(model)
        .into_iter()
        .map(|(name, value)| {
            let values: Vec<f64> =
                drawn.iter().filter_map(|d| d.iter().find(|(n, _)| *n == name).map(|(_, v)| *v)).collect();
            ParameterInterval { ci95: percentile_interval(values, DRAWS), name, value }
        })
        .collect())
}
