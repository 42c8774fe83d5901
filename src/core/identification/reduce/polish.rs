//! The polish: Levenberg–Marquardt moves the roots by simulation error on the identification
//! range, each cluster's root inside its circle (see the parent module's documentation).
use super::{Assembled, IdentData, RootGroup, assemble_each, assemble_groups, roots_of};
use crate::core::identification::cluster::RootKind;
use crate::core::identification::refine::Refinement;
use crate::core::numerics::lm::{
    Damping, Jacobian, LeastSquares, LmError, LmSettings, Residual, StepSolver, minimise, no_progress,
};

/// Relative cost decrease below which the polish stops.
const POLISH_COST_TOL: f64 = 1e-7;
/// Iterations of the polish; it usually converges in 5–15.
const POLISH_ITERATIONS: usize = 30;
/// Roots must stay inside this modulus while polishing (a stable, not quite integrating block).
const MAX_POLE_MODULUS: f64 = 0.999;

/// RMS of the residual over the samples that take part in the fit.
fn fitted_rms(data: &IdentData, residual: &[f64]) -> f64 {
    let kept: Vec<f64> =
        residual.iter().enumerate().filter(|(k, _)| data.fits_sample(*k)).map(|(_, r)| *r).collect();
    super::rms(&kept)
}

/// The groups moved to a parameter vector; `None` where a pole leaves [`MAX_POLE_MODULUS`].
fn decode_all(groups: &[RootGroup], theta: &[f64]) -> Option<Vec<RootGroup>> {
    let mut at = 0;
    let mut out = Vec::with_capacity(groups.len());
    for g in groups {
        let n = g.n_params();
        let moved = g.decode(theta.get(at..at + n)?)?;
        if moved.kind == RootKind::Pole && moved.root.norm() >= MAX_POLE_MODULUS {
            return None;
        }
        out.push(moved);
        at += n;
    }
    Some(out)
}

/// A polished model: the roots where the polish left them, and what it did.
#[derive(Clone, Debug)]
pub struct Polished {
    pub groups: Vec<RootGroup>,
    pub assembled: Assembled,
    pub refinement: Refinement,
}

/// Polish the roots by simulation error on the identification range, each cluster's root inside its
/// circle, free roots anywhere inside the unit circle; the static map keeps `static_order`. `None`
/// when the starting roots give no model. The result is never worse than the start.
pub fn polish(data: &IdentData, groups: &[RootGroup], static_order: usize) -> Option<Polished> {
    polish_with(data, groups, static_order, POLISH_ITERATIONS)
}

/// [`polish`] with at most `max_iterations` Levenberg–Marquardt steps.
pub fn polish_with(
    data: &IdentData,
    groups: &[RootGroup],
    static_order: usize,
    max_iterations: usize,
) -> Option<Polished> {
    let start = assemble_groups(data, groups, Some(static_order)).ok()?;
    let theta0: Vec<f64> = groups.iter().flat_map(RootGroup::encode).collect();
    let residual = PolishResidual { data, groups, static_order };
    let settings = LmSettings { max_iterations, cost_tol: POLISH_COST_TOL, damping: Damping::marquardt(12) };
    let mut problem: LeastSquares<_, LmError> =
        LeastSquares::new(residual, Jacobian::default(), StepSolver::Svd);
    let fitted = minimise(&mut problem, &theta0, &settings, &mut no_progress).ok();
    let moved = fitted.as_ref().and_then(|f| decode_all(groups, &f.theta));
    let after = moved.as_ref().and_then(|m| assemble_groups(data, m, Some(static_order)).ok());
    let before_rms = fitted_rms(data, &start.residual);
    let refinement = |after_rms: f64, iterations: usize| Refinement {
        poles_before: roots_of(groups, RootKind::Pole),
        zeros_before: roots_of(groups, RootKind::Zero),
        rms_before: before_rms,
        rms_after: after_rms,
        iterations,
    };
    match (moved, after, fitted) {
        (Some(moved), Some(after), Some(fit)) if fitted_rms(data, &after.residual) < before_rms => {
            Some(Polished {
                refinement: refinement(fitted_rms(data, &after.residual), fit.iterations),
                groups: moved,
                assembled: after,
            })
        }
        (_, _, fit) => Some(Polished {
            refinement: refinement(before_rms, fit.map_or(0, |f| f.iterations)),
            groups: groups.to_vec(),
            assembled: start,
        }),
    }
}

/// The polish's residual: the model of the roots θ moves the groups to, on the samples that take
/// part in the fit; a Jacobian's columns assembled side by side ([`assemble_each`]).
struct PolishResidual<'a, 'd> {
    data: &'a IdentData<'d>,
    groups: &'a [RootGroup],
    static_order: usize,
}

impl Residual for PolishResidual<'_, '_> {
    fn at(&mut self, theta: &[f64]) -> Option<Vec<f64>> {
        self.at_each(&[theta.to_vec()]).pop().flatten()
    }

    fn at_each(&mut self, thetas: &[Vec<f64>]) -> Vec<Option<Vec<f64>>> {
        let moved: Vec<Option<Vec<RootGroup>>> = thetas.iter().map(|t| decode_all(self.groups, t)).collect();
        let roots: Vec<(Vec<_>, Vec<_>)> = moved
            .iter()
            .flatten()
            .map(|m| (roots_of(m, RootKind::Pole), roots_of(m, RootKind::Zero)))
            .collect();
        let refs: Vec<(&[_], &[_])> = roots.iter().map(|(p, z)| (p.as_slice(), z.as_slice())).collect();
        let mut assembled = assemble_each(self.data, &refs, Some(self.static_order)).into_iter();
        let data = self.data;
        moved
            .iter()
            .map(|m| {
                let full = m.as_ref().and_then(|_| assembled.next())?.ok()?.residual;
                Some(match &data.held_out {
                    None => full,
                    Some(_) => full
                        .into_iter()
                        .enumerate()
                        .filter(|(k, _)| data.fits_sample(*k))
                        .map(|(_, r)| r)
                        .collect(),
                })
            })
            .collect()
    }
}
