//! Cross-validation across segments: a structure is judged by its error on each segment's response
//! when fitted without it ([`cross_validate`]); the model of a structure on all the data
//! ([`fitted`]). How a trial is judged against the current structure from these errors is the
//! parsimony rule (`core::identification::parsimony`).
use crate::core::identification::reduce::{
    IdentData, Polished, RootGroup, assemble_groups, polish, polish_with, rms,
};
use crate::core::identification::refine::Refinement;
use crate::core::parallel::on_two_threads;

/// Starting points kept after screening a grid on the identification error, to be [`fitted`].
pub(super) const REFINED_GUESSES: usize = 2;

/// Iterations of a cross-validation fold's polish, warm-started from the roots polished on all data.
const FOLD_ITERATIONS: usize = 12;

/// Most folds a cross-validation fits. Up to this many segments each is its own fold (leave one
/// segment out, as the method has it); a longer run's segments are dealt into this many folds of
/// neighbouring segments, so that the cost grows with the samples (folds × one fit over the run)
/// rather than with their square (segments × one fit). Sixteen folds leave each fit 15/16 of the
/// data, so a fold's model differs from the model on all data by no more than leave-one-out's does
/// at sixteen segments: the held-out errors stay an honest out-of-sample score, and every segment
/// still gets its own held-out error, which is what the parsimony rule counts.
pub const MAX_FOLDS: usize = 16;

/// The folds of `segments` segments: contiguous runs of neighbouring segments, at most
/// [`MAX_FOLDS`], as equal in count as they can be (one segment each when there are few).
pub fn folds(segments: usize) -> Vec<std::ops::Range<usize>> {
    let count = segments.min(MAX_FOLDS);
    (0..count).map(|k| k * segments / count..(k + 1) * segments / count).collect()
}

/// The held-out error of a set of root groups, segment by segment: the segments are dealt into
/// [`folds`]; for each fold the model is fitted (polished from `groups`, the static map of `order`
/// refitted) on the identification range without that fold's responses, then simulated through
/// them. Mean squared error per segment, in segment order.
pub fn cross_validate(data: &IdentData, groups: &[RootGroup], order: usize) -> Option<Vec<f64>> {
    let segments = &data.fits.segments;
    // The folds are fitted independently of each other: on two threads, gathered in fold order.
    let one = |fold: &std::ops::Range<usize>| -> Option<Vec<f64>> {
        let (first, last) = (segments.get(fold.start)?, segments.get(fold.end.checked_sub(1)?)?);
        let held = data.holding_out(first.step_at, last.end);
        let residual = if data.settings.refine {
            polish_with(&held, groups, order, FOLD_ITERATIONS)?.assembled.residual
        } else {
            assemble_groups(&held, groups, Some(order)).ok()?.residual
        };
        (segments.get(fold.clone())?.iter())
            .map(|seg| Some(rms(residual.get(held.holding_out(seg.step_at, seg.end).held_out?)?).powi(2)))
            .collect()
    };
    let mut errors = Vec::with_capacity(segments.len());
    for fold in on_two_threads(&folds(segments.len()), one) {
        errors.extend(fold?);
    }
    Some(errors)
}

/// A model of a set of root groups, polished (when the settings ask for it) with the static-map
/// order leave-one-out chooses for its starting roots.
pub fn fitted(data: &IdentData, groups: &[RootGroup]) -> Option<Polished> {
    let start = assemble_groups(data, groups, data.settings.static_order).ok()?;
    let order = start.wiener.map.order();
    if !data.settings.refine {
        let refinement = Refinement {
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
