//! Cross-validation across segments: a structure is judged by its error on each segment's response
//! when fitted without it ([`cross_validate`]); the model of a structure on all the data
//! ([`fitted`]). How a trial is judged against the current structure from these errors is the
//! parsimony rule (`core::identification::parsimony`).
use crate::core::identification::reduce::{
    IdentData, Polished, RootGroup, assemble_groups, polish, polish_with, rms,
};
use crate::core::identification::refine::Refinement;

/// Starting points kept after screening a grid on the identification error, to be [`fitted`].
pub(super) const REFINED_GUESSES: usize = 2;

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
                polish_with(&fold, groups, order, FOLD_ITERATIONS)?.assembled.residual
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
