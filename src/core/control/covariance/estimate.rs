//! The sandwich estimate of a finished model's parameter covariance (see the module
//! documentation of `core::control::covariance`), step by step: the residual and the Jacobian by
//! central differences, the parameters the run informs, their estimating equations, the sandwich.
use std::ops::Range;

use nalgebra::DMatrix;

use super::map_equations::{MapRows, at_least_stationary, map_rows, window_positions};
use super::{CovarianceError, Layout, ParameterCovariance, layout, with_parameters};
use crate::core::effects::{EffectId, ExtendedModel};
use crate::core::identification::uncertainty::{bandwidth, long_run_variance};
use crate::core::run::{Quantity, Run};

/// The speed's model that `model` is read off, as a model of the run's one shaft speed.
fn spool_of(model: &ExtendedModel, run: &Run) -> Result<ExtendedModel, CovarianceError> {
    let mut speeds = run.outputs.iter().filter(|c| Quantity::of(&c.name) == Some(Quantity::ShaftSpeed));
    let (Some(speed), None) = (speeds.next(), speeds.next()) else {
        return Err(CovarianceError::ReadOff { output: model.output.clone(), run: run.name.clone() });
    };
    let mut spool = model.clone();
    spool.effects.retain(|e| e.id() != EffectId::ReadOffSpeed);
    spool.output = speed.name.clone();
    Ok(spool)
}

/// Relative step of the central differences: large beside a simulation's rounding (~1e-12
/// relative over a run), small beside any parameter's interval.
const STEP: f64 = 1e-6;
/// A Jacobian column whose norm is below this share of the largest carries no information: the
/// output moves by less than a simulation's rounding when that parameter moves.
const NO_INFORMATION: f64 = 1e-9;

/// The covariance of `model`'s parameters from its fit to `run` (see the module documentation):
/// the static map's coefficients by least squares on the means of the `steady_windows` (run
/// indices; the map's own fit), every other parameter by output error over the whole run. With no
/// windows the map is taken as fitted by output error too.
///
/// A model read off the shaft speed's model holds the speed's parameters, fitted on the speed: their
/// covariance is estimated there, on the run's shaft speed (the read-off polynomial, fitted on
/// every sample of the run, is held; its own share of the uncertainty is not estimated).
pub fn estimate(
    model: &ExtendedModel,
    run: &Run,
    steady_windows: &[Range<usize>],
) -> Result<ParameterCovariance, CovarianceError> {
    if model.read_off().is_some() {
        return estimate(&spool_of(model, run)?, run, steady_windows);
    }
    let (layout, names, theta0) = layout(model)?;
    let fit = Residual::of(model, run, theta0.len())?;
    let jac = jacobian(model, run, &layout, &names, &theta0, &fit)?;
    let informed = informed(&jac);
    let held: Vec<String> =
        (0..theta0.len()).filter(|i| !informed.contains(i)).map(|i| names[i].clone()).collect();
    let map_rows = map_rows(&layout, steady_windows, &fit.kept);
    let equations = equations(&jac, &informed, &map_rows);
    let singular = || CovarianceError::Singular {
        output: model.output.clone(),
        names: informed.iter().map(|&i| names[i].clone()).collect(),
    };
    let m = informed.len();
    let slope: DMatrix<f64> =
        DMatrix::from_fn(m, m, |a, b| equations[a].iter().zip(&jac[informed[b]]).map(|(c, j)| c * j).sum());
    let inverse = slope.try_inverse().ok_or_else(singular)?;
    let bandwidth_samples = bandwidth(&fit.e);
    let mut scores = long_run_variance(&equations, &fit.e, bandwidth_samples);
    let map_equations: Vec<usize> = (0..m).filter(|&a| map_rows.range.contains(&informed[a])).collect();
    let windows = window_positions(steady_windows, &fit.kept);
    at_least_stationary(&mut scores, &map_equations, &equations, &fit.e, &windows);
    let sandwich: DMatrix<f64> = &inverse * scores * inverse.transpose();
    if sandwich.iter().any(|v| !v.is_finite()) {
        return Err(singular());
    }
    let n = theta0.len();
    let mut matrix = vec![vec![0.0; n]; n];
    for (a, &i) in informed.iter().enumerate() {
        for (b, &j) in informed.iter().enumerate() {
            matrix[i][j] = 0.5 * (sandwich[(a, b)] + sandwich[(b, a)]);
        }
    }
    let samples = fit.kept.len();
    Ok(ParameterCovariance { names, values: theta0, matrix, held, bandwidth_samples, samples })
}

/// The model's simulation of `run`, the samples where it and the measurement are both finite, and
/// the residual there.
struct Residual {
    sim: Vec<f64>,
    kept: Vec<usize>,
    e: Vec<f64>,
}

impl Residual {
    /// The residual of `model` on `run`, refused when it has too few samples for `params`
    /// parameters.
    fn of(model: &ExtendedModel, run: &Run, params: usize) -> Result<Self, CovarianceError> {
        let output = &model.output;
        let y = &run
            .output(output)
            .ok_or_else(|| CovarianceError::NoOutput { run: run.name.clone(), output: output.clone() })?
            .values;
        let sim = model.simulate(run).map_err(|e| CovarianceError::Simulation {
            output: output.clone(),
            run: run.name.clone(),
            reason: e.to_string(),
        })?;
        let kept: Vec<usize> =
            (0..y.len().min(sim.len())).filter(|&k| y[k].is_finite() && sim[k].is_finite()).collect();
        if kept.len() <= 2 * params.max(1) {
            return Err(CovarianceError::TooFewSamples {
                run: run.name.clone(),
                samples: kept.len(),
                params,
            });
        }
        let e = kept.iter().map(|&k| sim[k] - y[k]).collect();
        Ok(Self { sim, kept, e })
    }
}

/// The output's derivative with respect to each parameter at the kept samples, by central
/// differences (one-sided at a parameter's range bound, where a fit ended on it).
fn jacobian(
    model: &ExtendedModel,
    run: &Run,
    layout: &Layout,
    names: &[String],
    theta0: &[f64],
    fit: &Residual,
) -> Result<Vec<Vec<f64>>, CovarianceError> {
    let simulate =
        |theta: &[f64]| -> Option<Vec<f64>> { with_parameters(model, layout, theta)?.simulate(run).ok() };
    (0..theta0.len())
        .map(|i| {
            let h = STEP * theta0[i].abs().max(1.0);
            let (mut up, mut down) = (theta0.to_vec(), theta0.to_vec());
            up[i] += h;
            down[i] -= h;
            let (su, sd, width) = match (simulate(&up), simulate(&down)) {
                (Some(su), Some(sd)) => (su, sd, 2.0 * h),
                (Some(su), None) => (su, fit.sim.clone(), h),
                (None, Some(sd)) => (fit.sim.clone(), sd, h),
                (None, None) => return Err(CovarianceError::NoModel { name: names[i].clone(), step: h }),
            };
            Ok(fit.kept.iter().map(|&k| (su[k] - sd[k]) / width).collect())
        })
        .collect()
}

/// The parameters the run moves the output with: every Jacobian column above [`NO_INFORMATION`]
/// of the largest.
fn informed(jac: &[Vec<f64>]) -> Vec<usize> {
    let norms: Vec<f64> = jac.iter().map(|c| c.iter().map(|v| v * v).sum::<f64>().sqrt()).collect();
    let largest = norms.iter().copied().fold(0.0, f64::max);
    (0..jac.len()).filter(|&i| norms[i] > NO_INFORMATION * largest && norms[i].is_finite()).collect()
}

/// The estimating equations' columns of the `informed` parameters: the Jacobian itself for
/// output-error parameters, the Jacobian weighted to the steady windows' means for the map's.
fn equations(jac: &[Vec<f64>], informed: &[usize], map_rows: &MapRows) -> Vec<Vec<f64>> {
    informed
        .iter()
        .map(|&i| match (&map_rows.weights, map_rows.range.contains(&i)) {
            (Some(w), true) => jac[i].iter().zip(w).map(|(j, w)| j * w).collect(),
            _ => jac[i].clone(),
        })
        .collect()
}
