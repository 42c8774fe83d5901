//! Cross-validation across segments: a structure is judged by its error on each segment's response
//! when fitted without it ([`cross_validate`]), and a trial against the current structure by the
//! share of the held-out model error above the noise it removes ([`Gain`]).
use crate::core::identification::reduce::{IdentData, Polished, RootGroup, assemble_groups, polish, rms};
use crate::core::identification::structure::{MIN_RELATIVE_REDUCTION, MIN_STANDARD_ERRORS};

/// A trial structure against the current one, over the held-out segments of a cross-validation.
pub(super) struct Gain {
    /// Share of the held-out model error (above the noise) the trial removes.
    pub(super) reduction: f64,
    /// Held-out errors without and with the trial (output units, pooled over the segments).
    pub(super) without: f64,
    pub(super) with: f64,
    /// Segments whose held-out error the trial lowers, and how many segments there are.
    pub(super) wins: usize,
    pub(super) folds: usize,
    /// Mean per-segment relative improvement over its standard error.
    pub(super) standard_errors: f64,
}

impl Gain {
    /// From the per-segment held-out mean squared errors of the two structures; `noise` is the
    /// measurement noise, which no structure can remove.
    pub(super) fn of(without: &[f64], with: &[f64], noise: Noise) -> Self {
        let d: Vec<f64> = without.iter().zip(with).map(|(a, b)| (a - b) / a.max(f64::MIN_POSITIVE)).collect();
        let n = d.len().max(1) as f64;
        let mean = d.iter().sum::<f64>() / n;
        let sd = (d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt();
        let pooled = |x: &[f64]| x.iter().sum::<f64>() / x.len().max(1) as f64;
        let (without, with) = (pooled(without), pooled(with));
        Self {
            reduction: model_error_reduction(without, with, noise),
            without: without.sqrt(),
            with: with.sqrt(),
            wins: d.iter().filter(|x| **x > 0.0).count(),
            folds: d.len(),
            standard_errors: mean / (sd / n.sqrt()).max(f64::MIN_POSITIVE),
        }
    }

    pub(super) fn passes(&self) -> bool {
        self.reduction >= MIN_RELATIVE_REDUCTION && self.standard_errors >= MIN_STANDARD_ERRORS
    }

    pub(super) fn words(&self) -> String {
        format!(
            "held-out error from {} to {} (model error above noise {:+.0} %), lower on {} of {} segments \
             ({:.1} standard errors); a root must remove {:.0} % of the model error and more than {} \
             standard error",
            fmt_error(self.without),
            fmt_error(self.with),
            -100.0 * self.reduction,
            self.wins,
            self.folds,
            self.standard_errors,
            100.0 * MIN_RELATIVE_REDUCTION,
            MIN_STANDARD_ERRORS
        )
    }
}

pub(super) fn fmt_error(x: f64) -> String {
    if x.abs() >= 100.0 { format!("{x:.0}") } else { format!("{x:.3}") }
}

/// The measurement noise's variance σ² as read from the data, and how uncertain that reading is.
#[derive(Clone, Copy, Debug)]
pub(super) struct Noise {
    pub(super) var: f64,
    /// Two standard errors of `var`: σ is read by a median (of absolute first differences), whose
    /// asymptotic efficiency for Gaussian noise is about 37 %, so SE(σ̂) ≈ 1.16 σ/√N and
    /// SE(σ̂²) ≈ 2.33 σ²/√N over N samples.
    pub(super) uncertainty: f64,
}

impl Noise {
    pub(super) fn of(data: &IdentData) -> Self {
        let var = data.noise_sigma().powi(2);
        Self { var, uncertainty: 2.0 * 2.33 * var / (data.y.len().max(1) as f64).sqrt() }
    }
}

/// Share of the model error — the held-out mean squared error above the measurement noise's
/// variance — that a trial removes, as a share of RMS: 1 − √((with − σ²)/(without − σ²)). Zero when
/// the model error is within the noise reading's own uncertainty: the model is at the noise level
/// and nothing is left that a root could remove.
pub(super) fn model_error_reduction(without_mse: f64, with_mse: f64, noise: Noise) -> f64 {
    let excess = without_mse - noise.var;
    if excess <= noise.uncertainty {
        return 0.0;
    }
    let left = (with_mse - noise.var).max(0.0);
    1.0 - (left / excess).sqrt()
}

/// Iterations of a cross-validation fold's polish, warm-started from the roots polished on all data.
const FOLD_ITERATIONS: usize = 12;

/// The held-out error of a set of root groups, segment by segment: for each segment the model is
/// fitted (polished from `groups`, the static map of `order` refitted) on the identification range
/// without that segment's response, then simulated through it. Mean squared error per segment.
pub fn cross_validate(data: &IdentData, groups: &[RootGroup], order: usize) -> Option<Vec<f64>> {
    data.fits
        .segments
        .iter()
        .map(|seg| {
            let fold = data.holding_out(seg.step_at, seg.end);
            let residual = if data.settings.refine {
                crate::core::identification::reduce::polish_with(&fold, groups, order, FOLD_ITERATIONS)?
                    .assembled
                    .residual
            } else {
                assemble_groups(&fold, groups, Some(order)).ok()?.residual
            };
            let out = fold.held_out.clone()?;
            let held: Vec<f64> = residual.get(out)?.to_vec();
            Some(rms(&held).powi(2))
        })
        .collect()
}

/// A model of a set of root groups, polished (when the settings ask for it) with the static-map
/// order leave-one-out chooses for its starting roots.
pub fn fitted(data: &IdentData, groups: &[RootGroup]) -> Option<Polished> {
    let start = assemble_groups(data, groups, data.settings.static_order).ok()?;
    let order = start.wiener.map.order();
    if !data.settings.refine {
        let refinement = crate::core::identification::refine::Refinement {
            poles_before: Vec::new(),
            zeros_before: Vec::new(),
            rms_before: start.rms(),
            rms_after: start.rms(),
            iterations: 0,
        };
        return Some(Polished { groups: groups.to_vec(), assembled: start, refinement });
    }
    polish(data, groups, order)
}
