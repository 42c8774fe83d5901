//! Levenberg–Marquardt refinement of a structure's roots and continuous effect parameters
//! together, on the identification error (the poles parametrised so a pair may become two real
//! poles).
use num_complex::Complex64;

use super::memo::LinearMemo;
use super::{Assembled, FitData, Structure, assemble};
use crate::core::effects::EffectBlock;
use crate::core::identification::refine::RootParams;
use crate::core::numerics::lm::{
    Damping, Jacobian, LeastSquares, LmError, LmSettings, Residual, StepSolver, minimise, no_progress,
};
use crate::core::numerics::tf::alternates_sign;

/// Poles must stay inside this radius.
const MAX_POLE_RADIUS: f64 = 0.999;

/// Whether `roots` hold a pole that alternates sign every sample ([`alternates_sign`]): a model
/// that grows one (the refinement lets a pair split into two real poles, see [`PoleParams`]) has
/// local models that zig-zag and no continuous-time equivalent for the controller designer.
pub(in crate::core::effects) fn has_negative_real_pole(roots: &[Complex64]) -> bool {
    roots.iter().any(|p| alternates_sign(*p))
}

/// Smallest real pole of a refinement that keeps real poles positive: a pole this close to the
/// origin decays a thousandfold in one sample, faster than anything the sample rate resolves, and
/// still has a continuous-time equivalent (unlike a pole at the origin itself).
const MIN_REAL_POLE: f64 = 1e-3;

/// Where the refinement may put real poles.
#[derive(Clone, Copy, PartialEq)]
enum RealPoles {
    /// Anywhere inside the unit circle.
    Anywhere,
    /// On the positive real axis only.
    Positive,
}

/// The effect fits' Levenberg–Marquardt: few iterations to a loose tolerance (the screening has
/// already chosen the start; a 10⁻⁵ relative gain is far below what the diagnosis can resolve).
const EFFECT_FIT: LmSettings =
    LmSettings { max_iterations: 15, cost_tol: 1e-5, damping: Damping::marquardt(10) };

/// Move roots and continuous effect parameters together from `start`.
pub(in crate::core::effects) fn refine(start: &Structure, data: &FitData) -> Option<Assembled> {
    refine_with(start, data, &EFFECT_FIT, RealPoles::Anywhere)
}

/// The best fit of `s` with no sample-alternating pole, refined from `s` with its real poles kept
/// on the positive axis. What such a pole does for a fit is a phase lead: a unit-gain pole at `−a`
/// advances the response by `a/(1+a)` of a sample at low frequency (its phase `≈ +ω·a/(1+a)`), as
/// a zero at `c` does by `c/(1−c)`. So the refinement starts from `s` with each such pole made a
/// zero at `c = a/(1+2a)` (the same lead) and the pole itself moved onto the positive axis at
/// [`MIN_REAL_POLE`] (a lag shorter than a sample, so the structure keeps its count of poles and
/// the spool split its shape). Where the structure has no room for a zero (as many zeros as the
/// spool split allows), the pole is only moved onto the positive axis.
pub(in crate::core::effects) fn refine_admissible(s: &Structure, data: &FitData) -> Option<Assembled> {
    let mut lead = s.clone();
    for p in lead.poles.iter_mut().filter(|p| alternates_sign(**p)) {
        let a = (-p.re).min(MAX_POLE_RADIUS);
        lead.zeros.push(Complex64::new(a / (1.0 + 2.0 * a), 0.0));
        *p = Complex64::new(MIN_REAL_POLE, 0.0);
    }
    refine_with(&lead, data, &EFFECT_FIT, RealPoles::Positive)
        .or_else(|| refine_with(s, data, &EFFECT_FIT, RealPoles::Positive))
}

fn refine_with(
    start: &Structure,
    data: &FitData,
    settings: &LmSettings,
    real: RealPoles,
) -> Option<Assembled> {
    let (pole_params, theta_p) = PoleParams::from_roots(&start.poles);
    let (zero_params, theta_z) = RootParams::from_roots(&start.zeros);
    let mut theta0: Vec<f64> = theta_p.iter().chain(&theta_z).copied().collect();
    let lens: Vec<usize> = start.effects.iter().map(|e| e.free_params().len()).collect();
    theta0.extend(start.effects.iter().flat_map(EffectBlock::free_params));
    let (np, nz) = (theta_p.len(), theta_z.len());
    let unpack = |theta: &[f64]| -> Option<Structure> {
        let mut poles = pole_params.roots(theta.get(..np)?);
        if poles.iter().any(|p| p.norm() >= MAX_POLE_RADIUS) {
            return None;
        }
        if real == RealPoles::Positive {
            lift_onto_positive_axis(&mut poles);
        }
        let zeros = zero_params.roots(theta.get(np..np + nz)?);
        let mut at = np + nz;
        let mut effects = Vec::with_capacity(start.effects.len());
        for (e, len) in start.effects.iter().zip(&lens) {
            effects.push(e.with_free_params(theta.get(at..at + len)?, data.dt_secs)?);
            at += len;
        }
        Some(Structure { poles, zeros, effects, map_order: start.map_order, delay: start.delay })
    };
    let residual = Refinement { unpack: &unpack, memo: LinearMemo::default(), data };
    let mut problem: LeastSquares<_, LmError> =
        LeastSquares::new(residual, Jacobian::default(), StepSolver::QrOnce);
    let fitted = minimise(&mut problem, &theta0, settings, &mut no_progress).ok()?;
    assemble(&unpack(&fitted.theta)?, data)
}

/// The refinement's residual: the identification error of the structure θ unpacks to, with the
/// linear parts of recent structures kept ([`LinearMemo`]) and a Jacobian's columns simulated side
/// by side ([`LinearMemo::assemble_each`]).
struct Refinement<'a, U> {
    unpack: U,
    memo: LinearMemo,
    data: &'a FitData,
}

impl<U: Fn(&[f64]) -> Option<Structure>> Residual for Refinement<'_, U> {
    fn at(&mut self, theta: &[f64]) -> Option<Vec<f64>> {
        let s = (self.unpack)(theta)?;
        self.memo.assemble(&s, self.data).map(|a| a.residual)
    }

    fn at_each(&mut self, thetas: &[Vec<f64>]) -> Vec<Option<Vec<f64>>> {
        let structures: Vec<Option<Structure>> = thetas.iter().map(|theta| (self.unpack)(theta)).collect();
        let structures: Vec<Option<&Structure>> = structures.iter().map(Option::as_ref).collect();
        self.memo.assemble_each(&structures, self.data).into_iter().map(|a| a.map(|a| a.residual)).collect()
    }
}

/// Real poles left of [`MIN_REAL_POLE`] moved onto it. Projecting rather than refusing such a step
/// lets the refinement slide along the boundary of the admissible set: refused steps leave
/// Levenberg–Marquardt's finite-difference Jacobian blind in that direction, and it stops short of
/// the best admissible fit.
fn lift_onto_positive_axis(poles: &mut [Complex64]) {
    for p in poles.iter_mut().filter(|p| p.im.abs() <= 1e-12 && p.re < MIN_REAL_POLE) {
        *p = Complex64::new(MIN_REAL_POLE, 0.0);
    }
}

/// Poles as refinement parameters: a real pole is one parameter, a complex pair the two
/// coefficients `(s, p)` of its quadratic `z² − s·z + p`. Unlike (re, im), these let a pair become
/// two real poles when the data want it: a damped pair found on closed-loop data (an ECU that
/// overshoots its command at every set-point change) may be an overdamped spool once the effect
/// that was missing is in the model.
struct PoleParams {
    /// For each root group: true for a quadratic (pair, or two real poles that were one).
    quadratic: Vec<bool>,
}

impl PoleParams {
    fn from_roots(roots: &[Complex64]) -> (Self, Vec<f64>) {
        let mut quadratic = Vec::new();
        let mut theta = Vec::new();
        for r in roots {
            if r.im.abs() <= 1e-12 {
                quadratic.push(false);
                theta.push(r.re);
            } else if r.im > 0.0 {
                quadratic.push(true);
                theta.extend([2.0 * r.re, r.norm_sqr()]);
            }
        }
        (Self { quadratic }, theta)
    }

    fn roots(&self, theta: &[f64]) -> Vec<Complex64> {
        let mut out = Vec::new();
        let mut values = theta.iter().copied();
        for &quadratic in &self.quadratic {
            let first = values.next().unwrap_or(0.0);
            if !quadratic {
                out.push(Complex64::new(first, 0.0));
                continue;
            }
            let (half, product) = (0.5 * first, values.next().unwrap_or(0.0));
            let disc = half * half - product;
            if disc >= 0.0 {
                out.extend([
                    Complex64::new(half + disc.sqrt(), 0.0),
                    Complex64::new(half - disc.sqrt(), 0.0),
                ]);
            } else {
                out.extend([Complex64::new(half, (-disc).sqrt()), Complex64::new(half, -(-disc).sqrt())]);
            }
        }
        out
    }
}
