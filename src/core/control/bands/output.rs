//! The 95 % band of a model's noiseless output on a run (delta method, see the module above).
use super::Z95;
use crate::core::control::covariance::{CovarianceError, ParameterCovariance, model_at};
use crate::core::effects::ExtendedModel;
use crate::core::run::Run;

/// The half-width of the 95 % band of `model`'s noiseless output on `run`, sample by sample, from
/// the covariance (delta method, see the module documentation).
pub fn output_half_widths(
    model: &ExtendedModel,
    covariance: &ParameterCovariance,
    run: &Run,
) -> Result<Vec<f64>, CovarianceError> {
    let theta0 = &covariance.values;
    let n = theta0.len();
    let simulate = |theta: &[f64], name: &str, step: f64| -> Result<Vec<f64>, CovarianceError> {
        let no_model = || CovarianceError::NoModel { name: name.to_owned(), step };
        model_at(model, theta).ok_or_else(no_model)?.simulate(run).map_err(|_| no_model())
    };
    let centre = simulate(theta0, "the fitted values", 0.0)?;
    let sd = covariance.std_devs();
    let mut gradients: Vec<Vec<f64>> = Vec::with_capacity(n);
    for i in 0..n {
        if sd[i] == 0.0 {
            gradients.push(vec![0.0; run.len()]);
            continue;
        }
        // A tenth of the parameter's own standard deviation: inside the region the band describes,
        // and far above rounding.
        let h = 0.1 * sd[i];
        let (mut up, mut down) = (theta0.clone(), theta0.clone());
        up[i] += h;
        down[i] -= h;
        let name = &covariance.names[i];
        // One-sided at a parameter's range bound (a fit that ended on it).
        let (a, b, width) = match (simulate(&up, name, h), simulate(&down, name, h)) {
            (Ok(a), Ok(b)) => (a, b, 2.0 * h),
            (Ok(a), Err(_)) => (a, centre.clone(), h),
            (Err(_), Ok(b)) => (centre.clone(), b, h),
            (Err(e), Err(_)) => return Err(e),
        };
        gradients.push(a.iter().zip(&b).map(|(a, b)| (a - b) / width).collect());
    }
    let len = gradients.first().map_or(run.len(), Vec::len);
    Ok((0..len)
        .map(|k| {
            let mut var = 0.0;
            for i in 0..n {
                for j in 0..n {
                    var += gradients[i][k] * covariance.matrix[i][j] * gradients[j][k];
                }
            }
            Z95 * var.max(0.0).sqrt()
        })
        .collect())
}
