//! The operating points' 95 % intervals and the local step responses' bands, from models drawn
//! from the covariance (see the module above for why percentiles).
use super::{DRAWS, percentile_interval};
use crate::core::control::covariance::{CovarianceError, ParameterCovariance};
use crate::core::control::operating_point::{
    LocalPole, OperatingPoint, local_dynamics, operating_points_without_continuous,
};
use crate::core::effects::ExtendedModel;
use crate::core::parallel::on_two_threads;

/// Seed of the draws: a report must come out the same on every run.
const SEED: u64 = 0x6A65_7469_6400;

/// Each of `poles` with the drawn pole that is the same pole: the nearest in z of the same kind
/// (real with a time constant, or a pair), each drawn pole taken once, slowest first. The order by
/// modulus alone would swap two real poles whenever a draw moves one past the other.
fn match_poles<'a>(poles: &[LocalPole], drawn: &'a [LocalPole]) -> Vec<Option<&'a LocalPole>> {
    let mut used = vec![false; drawn.len()];
    poles
        .iter()
        .map(|p| {
            let best = (0..drawn.len())
                .filter(|&k| !used[k] && drawn[k].tau_s.is_some() == p.tau_s.is_some())
                .min_by(|&a, &b| (drawn[a].z - p.z).norm().total_cmp(&(drawn[b].z - p.z).norm()))?;
            used[best] = true;
            Some(&drawn[best])
        })
        .collect()
}

/// Fill the `*_ci95` fields of `points` (computed by [`operating_points`] from `model` over
/// `input_range` and `plateaus`) from the covariance. Returns how many draws gave operating points.
pub fn with_intervals(
    points: &mut [OperatingPoint],
    model: &ExtendedModel,
    covariance: &ParameterCovariance,
    input_range: (f64, f64),
    plateaus: &[(String, f64)],
) -> Result<usize, CovarianceError> {
    let models = covariance.draw_models(model, DRAWS, SEED)?;
    let drawn: Vec<Vec<OperatingPoint>> =
        on_two_threads(&models, |m| operating_points_without_continuous(m, input_range, plateaus).ok())
            .into_iter()
            .flatten()
            .filter(|ps| ps.len() == points.len())
            .collect();
    for (i, point) in points.iter_mut().enumerate() {
        let figure = |pick: &dyn Fn(&OperatingPoint) -> Option<f64>| {
            percentile_interval(drawn.iter().filter_map(|ps| pick(&ps[i])).collect(), DRAWS)
        };
        point.gain_ci95 = figure(&|p| Some(p.gain));
        point.bandwidth_rad_s_ci95 = figure(&|p| p.bandwidth_rad_s);
        point.step.rise_s_ci95 = figure(&|p| p.step.rise_s);
        point.step.settling_s_ci95 = figure(&|p| p.step.settling_s);
        let matched: Vec<Vec<Option<&LocalPole>>> =
            drawn.iter().map(|ps| match_poles(&point.poles, &ps[i].poles)).collect();
        for (j, pole) in point.poles.iter_mut().enumerate() {
            let of = |pick: &dyn Fn(&LocalPole) -> Option<f64>| {
                percentile_interval(matched.iter().filter_map(|m| m[j].and_then(pick)).collect(), DRAWS)
            };
            pole.tau_s_ci95 = pole.tau_s.and_then(|_| of(&|p| p.tau_s));
            if pole.tau_s.is_none() {
                pole.wn_rad_s_ci95 = of(&|p| p.wn_rad_s);
                pole.zeta_ci95 = of(&|p| p.zeta);
            }
        }
    }
    Ok(drawn.len())
}

/// The 2.5 and 97.5 percentiles, sample by sample, of the unit step responses of the drawn
/// models' local dynamics at the steady input `u` (each normalised by its final value, as the
/// operating points' step figures are), over `samples` samples; `None` when too few draws have
/// local dynamics there.
pub fn step_band(draws: &[ExtendedModel], u: f64, samples: usize) -> Option<(Vec<f64>, Vec<f64>)> {
    let responses: Vec<Vec<f64>> = draws
        .iter()
        .filter_map(|m| local_dynamics(m, u).ok())
        .map(|unit| unit.simulate_with_history(&vec![1.0; samples], 0.0, 0.0))
        .collect();
    let mut lo = Vec::with_capacity(samples);
    let mut hi = Vec::with_capacity(samples);
    for k in 0..samples {
        let [a, b] = percentile_interval(responses.iter().map(|r| r[k]).collect(), draws.len())?;
        lo.push(a);
        hi.push(b);
    }
    Some((lo, hi))
}
