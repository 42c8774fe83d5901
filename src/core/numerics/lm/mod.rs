//! Levenberg–Marquardt: the one damped Gauss–Newton loop of the crate. The reduction's polish, the
//! effect fits, the Hammerstein–Wiener baseline and the NNARX training all run it; they differ only
//! in how a problem is linearised and a damped step solved ([`LmProblem`]) and in their damping
//! schedule ([`Damping`]).
//!
//! Every iteration linearises the problem at θ (a problem with hyper-parameters re-estimates them
//! there), then tries damped steps, raising the damping until one lowers the objective; an accepted
//! step lowers the damping. The loop stops after `max_iterations`, when no damping gives a better
//! point, or when an accepted step lowers the objective by less than `cost_tol` of it. After every
//! iteration `on_iteration(k)` is called: a caller reports progress there and cancels with an error.
use crate::core::numerics::lstsq::LstsqError;

mod least_squares;

pub use least_squares::{Jacobian, LeastSquares, Residual, StepSolver};

/// How the damping moves: it starts at `start`, is scaled by `on_accept` (not below `floor`) after
/// an accepted step and by `on_reject` after a rejected one; an iteration tries at most `max_tries`
/// dampings, none above `ceiling`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Damping {
    pub start: f64,
    pub on_accept: Scale,
    pub floor: f64,
    pub on_reject: Scale,
    pub max_tries: usize,
    pub ceiling: f64,
}

/// A change of the damping: `Times(k)` multiplies by k, `Over(k)` divides by k (kept apart because
/// λ/3 and λ·(1/3) round differently, and a damping path is sensitive to the last bit).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scale {
    Times(f64),
    Over(f64),
}

impl Scale {
    fn apply(self, x: f64) -> f64 {
        match self {
            Self::Times(k) => x * k,
            Self::Over(k) => x / k,
        }
    }
}

impl Damping {
    /// Marquardt's schedule for least squares: λ from 10⁻³, ÷3 on success (not below 10⁻¹²), ×4 on
    /// failure, `max_tries` tries an iteration (4¹² ≈ 1.7·10⁷ covers the scale of any problem here).
    pub const fn marquardt(max_tries: usize) -> Self {
        Self {
            start: 1e-3,
            on_accept: Scale::Over(3.0),
            floor: 1e-12,
            on_reject: Scale::Times(4.0),
            max_tries,
            ceiling: f64::INFINITY,
        }
    }
}

/// Options of [`minimise`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LmSettings {
    pub max_iterations: usize,
    /// Stop when an accepted step lowers the objective by less than this fraction of it.
    pub cost_tol: f64,
    pub damping: Damping,
}

/// Where the loop ended.
#[derive(Clone, Debug, PartialEq)]
pub struct LmOutcome {
    pub theta: Vec<f64>,
    /// The objective at `theta`.
    pub cost: f64,
    /// The objective at the start.
    pub initial_cost: f64,
    pub iterations: usize,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LmError {
    #[error("the objective cannot be evaluated at the starting point")]
    BadStart,
    #[error(transparent)]
    Lstsq(#[from] LstsqError),
}

/// A problem [`minimise`] can solve.
pub trait LmProblem {
    /// What a damped step needs of the problem at θ (a Jacobian, a factorisation).
    type Linearisation;
    type Error: From<LmError>;

    /// The objective at θ, `None` where θ is not admissible (e.g. an unstable pole).
    fn objective(&mut self, theta: &[f64]) -> Option<f64>;

    /// Linearise at θ, whose objective is `objective`; returns the linearisation and the objective
    /// the next step must beat (different from `objective` when hyper-parameters were re-estimated).
    fn linearise(&mut self, theta: &[f64], objective: f64)
    -> Result<(Self::Linearisation, f64), Self::Error>;

    /// The candidate of the step damped by `damping`, `None` when it cannot be computed.
    fn step(
        &mut self,
        lin: &mut Self::Linearisation,
        theta: &[f64],
        damping: f64,
    ) -> Result<Option<Vec<f64>>, Self::Error>;
}

/// Minimise `problem` from `theta0` (see the module documentation).
pub fn minimise<P: LmProblem>(
    problem: &mut P,
    theta0: &[f64],
    settings: &LmSettings,
    on_iteration: &mut dyn FnMut(usize) -> Result<(), P::Error>,
) -> Result<LmOutcome, P::Error> {
    let damping = settings.damping;
    let mut theta = theta0.to_vec();
    let Some(initial_cost) = problem.objective(&theta) else { return Err(LmError::BadStart.into()) };
    let mut cost = initial_cost;
    let mut lambda = damping.start;
    let mut iterations = 0;
    while iterations < settings.max_iterations && !theta.is_empty() {
        iterations += 1;
        let (mut lin, objective) = problem.linearise(&theta, cost)?;
        cost = objective;
        let mut accepted = None;
        let mut tries = 0;
        while tries < damping.max_tries && lambda <= damping.ceiling {
            tries += 1;
            let candidate = problem.step(&mut lin, &theta, lambda)?;
            let better = candidate.and_then(|c| {
                problem.objective(&c).filter(|new| new.is_finite() && *new < cost).map(|new| (c, new))
            });
            if let Some(found) = better {
                lambda = damping.on_accept.apply(lambda).max(damping.floor);
                accepted = Some(found);
                break;
            }
            lambda = damping.on_reject.apply(lambda);
        }
        on_iteration(iterations)?;
        let Some((candidate, new_cost)) = accepted else { break };
        let converged = cost - new_cost < settings.cost_tol * cost;
        (theta, cost) = (candidate, new_cost);
        if converged {
            break;
        }
    }
    Ok(LmOutcome { theta, cost, initial_cost, iterations })
}

/// Continue without reporting.
pub fn no_progress<E>(_: usize) -> Result<(), E> {
    Ok(())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn exponential() -> impl FnMut(&[f64]) -> Option<Vec<f64>> {
        let t: Vec<f64> = (0..50).map(|k| k as f64 * 0.1).collect();
        let y: Vec<f64> = t.iter().map(|t| 2.0 * (-0.7 * t).exp()).collect();
        move |th: &[f64]| Some(t.iter().zip(&y).map(|(t, y)| th[0] * (th[1] * t).exp() - y).collect())
    }

    fn settings() -> LmSettings {
        LmSettings { max_iterations: 100, cost_tol: 1e-12, damping: Damping::marquardt(16) }
    }

    #[test]
    fn fits_an_exponential_with_either_step_solver() {
        for solver in [StepSolver::Svd, StepSolver::QrOnce] {
            let mut problem: LeastSquares<_, LmError> =
                LeastSquares::new(exponential(), Jacobian::default(), solver);
            let res = minimise(&mut problem, &[1.0, -0.2], &settings(), &mut no_progress).unwrap();
            assert!(
                (res.theta[0] - 2.0).abs() < 1e-5 && (res.theta[1] + 0.7).abs() < 1e-5,
                "{:?}",
                res.theta
            );
            assert!(res.cost < 1e-10 && res.cost < res.initial_cost);
        }
    }

    #[test]
    fn can_be_stopped_after_an_iteration() {
        #[derive(Debug, PartialEq)]
        enum Stop {
            Cancelled,
            Lm,
        }
        impl From<LmError> for Stop {
            fn from(_: LmError) -> Self {
                Stop::Lm
            }
        }
        let mut problem: LeastSquares<_, Stop> =
            LeastSquares::new(exponential(), Jacobian::default(), StepSolver::Svd);
        let mut calls = 0;
        let stopped = minimise(&mut problem, &[1.0, -0.2], &settings(), &mut |_| {
            calls += 1;
            Err(Stop::Cancelled)
        });
        assert_eq!(stopped, Err(Stop::Cancelled));
        assert_eq!(calls, 1);
    }

    #[test]
    fn inadmissible_start_is_an_error() {
        let mut problem: LeastSquares<_, LmError> =
            LeastSquares::new(|_: &[f64]| None, Jacobian::default(), StepSolver::Svd);
        assert_eq!(minimise(&mut problem, &[1.0], &settings(), &mut no_progress), Err(LmError::BadStart));
    }
}
