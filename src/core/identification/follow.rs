//! Roots go where the data put them. The automatic proposal draws each cluster's circle before the
//! reduced model is fitted, around where the segment ARX models put a root; the polish then keeps
//! the model's root inside it (`core::identification::reduce`). When the polish stops on the rim,
//! the circle, not the data, decided where the root is: a model held there can predict the responses
//! much worse than the same structure fitted freely. So the circle follows the root: it grows towards
//! it (keeping the whole of the old circle, so every segment root it held it still holds) and the
//! roots are polished again from where they stopped, until no root is on a rim or the circle has
//! followed [`MAX_FOLLOWS`] times. Each follow is judged again, as a candidate is, on the segment
//! responses a cross-validation holds out: a root the identification data pull further but the
//! held-out responses do not is the polish fitting the noise of a few segments, and the circle
//! stops where the held-out error is lowest (the number of parameters does not change). The proposal keeps the grown circles, so the model, the z-plane
//! and the cluster table still tell one story, and it says which circles followed and how far.
//!
//! Circles an engineer drew or dragged are the engineer's statement and are never moved: only the
//! automatic proposal's circles follow.
use std::fmt;

use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use crate::core::identification::cluster::{ClusterEval, RootKind, natural_freq_and_damping};
use crate::core::identification::cross_validation::{cross_validate, fitted};
use crate::core::identification::parsimony::pooled;
use crate::core::identification::reduce::{IdentData, Polished, Region, RootGroup};
use crate::core::identification::words::{fmt_error, root_words};

/// How many times a circle may follow its root. Each time it grows by [`GROWTH`] towards the root,
/// so after four its radius is 5.1 times the segment models' and it reaches 9.1 of their radii beyond
/// their centre: a root the data pull further than that is no longer the root those segment models
/// saw, and the proposal says the data still pull it (the engineer decides, or frees the polish).
pub const MAX_FOLLOWS: usize = 4;

/// Radius of the grown circle over the old one. The grown circle is tangent to the old one on the far
/// side from the root and so contains it whole (its centre moves by `(GROWTH − 1)·r` towards the
/// root): the members stay members. One and a half lets the root move half a radius beyond the old
/// rim per follow, a step the polish takes in a few iterations.
const GROWTH: f64 = 1.5;

/// A circle of the automatic proposal that followed its root out of the segment models' circle.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CircleFollow {
    /// Index of the candidate cluster (in the proposal's verdicts).
    pub candidate: usize,
    pub kind: RootKind,
    pub pair: bool,
    /// The circle the segment models gave and the one the model ends in.
    pub from: Region,
    pub to: Region,
    /// The model's root at the end (upper half-plane for a pair).
    pub root: Complex64,
    /// Of the root at the end.
    pub natural_freq_rad_s: f64,
    pub damping: f64,
    /// The root is still on the rim at the end: the data pull it further still.
    pub still_pulled: bool,
    /// Held-out error (cross-validation across segments, RMS over the segments' responses, output
    /// units) inside the segment models' circles and after the follows.
    pub held_out: (f64, f64),
    /// The next follow the held-out segments refused (held-out error before and with it), when one was.
    pub refused: Option<(f64, f64)>,
    /// Identification RMS error inside the first circles and after the follows, output units.
    pub rms_before: f64,
    pub rms_after: f64,
}

impl CircleFollow {
    /// What happened, as the report and the app head the sentence.
    pub fn heading(&self) -> &'static str {
        if self.from == self.to { "root on the rim" } else { "circle followed its root" }
    }
}

/// The sentence the report and the app show.
impl fmt::Display for CircleFollow {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let kind = if self.kind == RootKind::Pole { "pole" } else { "zero" };
        let root = if self.pair {
            format!("{:.4} ± {:.4}j", self.root.re, self.root.im.abs())
        } else {
            format!("{:.4}", self.root.re)
        };
        if self.from == self.to {
            let (before, with) = self.refused.unwrap_or(self.held_out);
            return write!(
                f,
                "{kind} {}: the polish stopped on the rim of the segment models' circle at {root}; the circle \
                 stays, because following the root raises the held-out error from {} to {}",
                root_words(self.root, self.pair, self.natural_freq_rad_s, self.damping),
                fmt_error(before),
                fmt_error(with)
            );
        }
        write!(
            f,
            "{kind} {}: the polish stopped on the rim of the segment models' circle, so the circle followed \
             the root (radius {:.4} to {:.4}); the root settled at {root}, identification error {} to {}, \
             held-out error {} to {}",
            root_words(self.root, self.pair, self.natural_freq_rad_s, self.damping),
            self.from.radius,
            self.to.radius,
            fmt_error(self.rms_before),
            fmt_error(self.rms_after),
            fmt_error(self.held_out.0),
            fmt_error(self.held_out.1),
        )?;
        match (self.refused, self.still_pulled) {
            (Some((before, with)), _) => write!(
                f,
                "; it stops there, on the rim, because following further raises the held-out error from {} to {}",
                fmt_error(before),
                fmt_error(with)
            ),
            (None, true) => write!(
                f,
                "; after {MAX_FOLLOWS} follows the data still pull it further from where the segment models put it"
            ),
            (None, false) => Ok(()),
        }
    }
}

/// The circle grown towards `root` (see [`GROWTH`]); a real root's circle stays on the real axis.
fn grown(region: Region, root: Complex64, pair: bool) -> Region {
    let away = if pair { root - region.centre } else { Complex64::new(root.re - region.centre.re, 0.0) };
    let direction = if away.norm() > 0.0 { away / away.norm() } else { Complex64::new(0.0, 0.0) };
    Region {
        centre: region.centre + direction * ((GROWTH - 1.0) * region.radius),
        radius: GROWTH * region.radius,
    }
}

/// The follows of the kept candidates `kept` (indices into `evals`) on `data` (with the proposal's
/// dead time): empty when no root of the polished model stops on a rim, or the model cannot be fitted.
pub(super) fn follow_roots(data: &IdentData, evals: &[ClusterEval], kept: &[usize]) -> Vec<CircleFollow> {
    let groups: Vec<RootGroup> = kept
        .iter()
        .filter_map(|&i| evals.get(i).map(|e| RootGroup::of_cluster(i, e).within(data.settings.polish)))
        .collect();
    let Some(first) = fitted(data, &groups) else { return Vec::new() };
    if !first.groups.iter().any(RootGroup::at_rim) {
        return Vec::new();
    }
    let held_out =
        |p: &Polished| cross_validate(data, &p.groups, p.assembled.wiener.map.order()).map(|cv| pooled(&cv));
    let Some(first_held_out) = held_out(&first) else { return Vec::new() };
    let (rms_before, mut current, mut current_held_out) = (first.assembled.rms(), first, first_held_out);
    let mut first_regions: Vec<Option<Region>> = vec![None; current.groups.len()];
    let mut stopped_by_held_out = None;
    for _ in 0..MAX_FOLLOWS {
        if !current.groups.iter().any(RootGroup::at_rim) {
            break;
        }
        let mut next = current.groups.clone();
        let mut regions = first_regions.clone();
        for (g, first) in next.iter_mut().zip(regions.iter_mut()) {
            if let (true, Some(region)) = (g.at_rim(), g.region) {
                first.get_or_insert(region);
                g.region = Some(grown(region, g.root, g.pair));
            }
        }
        let Some(p) = fitted(data, &next) else { break };
        let Some(next_held_out) = held_out(&p) else { break };
        if next_held_out > current_held_out {
            stopped_by_held_out = Some((current_held_out, next_held_out));
            break;
        }
        (current, current_held_out, first_regions) = (p, next_held_out, regions);
    }
    let dt_secs = data.fits.dt_secs;
    current
        .groups
        .iter()
        .zip(&first_regions)
        .filter_map(|(g, from)| {
            // A root on the rim whose first follow was refused is reported with its circle unchanged.
            let refused_at_once = from.is_none() && stopped_by_held_out.is_some() && g.at_rim();
            let to = g.region?;
            let from = if refused_at_once { to } else { (*from)? };
            let candidate = g.cluster?;
            let (natural_freq_rad_s, damping) = natural_freq_and_damping(g.root, dt_secs);
            Some(CircleFollow {
                candidate,
                kind: g.kind,
                pair: g.pair,
                from,
                to,
                root: g.root,
                natural_freq_rad_s,
                damping,
                still_pulled: g.at_rim(),
                held_out: (first_held_out.sqrt(), current_held_out.sqrt()),
                refused: stopped_by_held_out.map(|(a, b)| (a.sqrt(), b.sqrt())),
                rms_before,
                rms_after: current.assembled.rms(),
            })
        })
        .collect()
}
