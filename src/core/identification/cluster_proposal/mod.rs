//! Automatic cluster proposal: a density search under the aggregation condition.
//!
//! Poles and zeros are searched separately, on roots folded into the upper half-plane (conjugate
//! twins merged). With J segments and m = [`ClusterSettings::segments_needed`]:
//!
//! 1. **Grow a candidate from every root still in play.** Start the centre at the root. For each
//!    segment take its root nearest the centre and sort these distances d₍₁₎ ≤ … ≤ d₍J₎. The segments
//!    with the m smallest distances are the members; a further segment whose nearest root is within
//!    `min_isolation` × the current radius (and within `max_radius`) is absorbed too, since it would
//!    otherwise spoil the isolation test below. Re-centre on the members' mean (forced real when it
//!    lies within half a radius of the real axis) and repeat until the member set, hence the centre,
//!    stops changing (at most a fixed number of rounds). The candidate's radius is the largest
//!    member distance: the smallest circle about that centre that satisfies the aggregation condition.
//! 2. **Accept candidates only when they are clusters:** radius ≤ `max_radius`; the nearest root that
//!    is not a member at least `min_isolation` radii away (a consistent mode stands apart; a chance
//!    gathering inside a ring of noise roots does not); the circle does not overlap a cluster accepted
//!    earlier; and [`super::cluster::evaluate_cluster`] calls it valid (not near the origin, not beyond
//!    the Nyquist exclusion angle, a pole inside the unit circle).
//! 3. **Greedy:** accept the acceptable candidate with the smallest radius (most consistent; ties go to
//!    the lower angle, i.e. lower frequency, then the smaller modulus), take its members out of play
//!    and search again, until no candidate is acceptable.
//!
//! The proposed circle keeps the centre and widens the radius by a margin for display, never past
//! half-way to the nearest non-member nor so far that an off-axis centre would count as on the axis.
//! Results are sorted by kind, then angle, then modulus.
//!
//! **Cost.** Growing a candidate looks at every segment's roots, O(R) for R = J · model order roots.
//! Up to [`SEED_SEGMENTS`] segments every root in play seeds a candidate (O(R²) per accepted
//! cluster); a long run's many segments seed from [`SEED_SEGMENTS`] of them spread evenly over the
//! run, and the aggregation condition is relaxed in at most [`MAX_LEVELS`] steps, so that the search
//! grows linearly with the segments (see those constants for why nothing is lost).
//!
//! **Relaxing the aggregation condition step by step.** A mode shared by 7 of 8 segment models is
//! still a mode of the engine (one segment's ARX model may have put that root elsewhere, or the
//! step was too small to excite it); requiring m = J throws it away. So the search runs at m = J
//! first, then at J − 1, J − 2, … on the roots no accepted cluster holds, down to a majority of
//! the segments, m = ⌊J/2⌋ + 1: a root that recurs in only half of the step responses is no more a
//! property of the engine than its absence is. A cluster accepted below the output's own condition
//! records the m it was accepted at ([`Cluster::min_segments`]), so it stays valid when it is
//! evaluated again. Whether a candidate cluster enters the model is decided afterwards, by what it
//! does to the simulation error (`core::identification::reduce`), not here.

use nalgebra::Complex;

use super::cluster::{
    Cluster, ClusterError, ClusterSettings, FoldedRoot, REAL_AXIS_FRACTION, RootKind, SegmentRoots,
    check_inputs, evaluate_folded, folded_roots, nearest_in_segment, nearest_non_member,
};

type Complex64 = Complex<f64>;

/// Re-centring rounds per candidate; the member set usually settles in two or three.
const MAX_ROUNDS: usize = 32;
/// Display margin on a proposed radius.
const RADIUS_MARGIN: f64 = 1.25;
/// Smallest proposed radius, so that a circle around identical roots stays visible and draggable.
const MIN_CIRCLE_RADIUS: f64 = 2e-3;
/// Radii closer than this count as tied in the ranking.
const RADIUS_TIE_TOL: f64 = 1e-9;
/// Segments whose roots seed candidates when a run has more. A cluster the proposal may accept has
/// members in a majority of the segments, and growing from any member converges on the same
/// members (re-centring on their mean); it is missed only if none of these segments holds one. For
/// a mode of the engine, whose absence from a segment's model has nothing to do with the segment's
/// place in the run, that chance is at most 2⁻¹⁶ ≈ 1.5e-5. Up to this many segments every segment
/// seeds, as the method has it.
pub const SEED_SEGMENTS: usize = 16;
/// Most aggregation conditions the relaxation tries, from all J segments down to a majority. At
/// J ≤ 16 that is every condition, one segment at a time; beyond, the steps are J/16 segments wide
/// or less. A finer step means nothing there: the share of segment models that hold a mode is known
/// only to its binomial standard error √(p(1−p)/J), ≥ 0.05 for a share p ≥ 0.55 up to J = 100.
pub const MAX_LEVELS: usize = 8;

/// Proposes clusters of poles and zeros from the segment models' roots.
///
/// Errors when the settings or `dt_secs` are invalid, when there are fewer than two segments, or
/// when the aggregation condition needs fewer than two or more segments than there are.
pub fn propose_clusters(
    roots: &[SegmentRoots],
    settings: &ClusterSettings,
    dt_secs: f64,
) -> Result<Vec<Cluster>, ClusterError> {
    check_inputs(settings, dt_secs)?;
    let segments = roots.len();
    if segments < 2 {
        return Err(ClusterError::TooFewSegments { found: segments, needed: 2 });
    }
    let needed = settings.segments_needed(segments);
    if needed > segments {
        return Err(ClusterError::MinSegmentsExceedSegments { needed, segments });
    }
    if needed < 2 {
        // One root alone is a "cluster" of radius zero: the aggregation condition means nothing.
        return Err(ClusterError::TooFewSegments { found: needed, needed: 2 });
    }
    let floor = relaxed_floor(segments).min(needed);
    let seeds = seed_segments(segments);
    let mut clusters = Vec::new();
    for kind in [RootKind::Pole, RootKind::Zero] {
        let folded = folded_roots(roots, kind);
        let mut in_play = folded.clone();
        for m in relaxation_levels(needed, floor) {
            let own = (m < needed).then_some(m);
            let search = Search { kind, folded: &folded, seeds: &seeds, settings, needed: m, dt_secs };
            let found = search.propose(&mut in_play, &clusters);
            clusters.extend(found.into_iter().map(|c| c.with_min_segments(own)));
        }
    }
    clusters.sort_by(|a, b| {
        a.kind
            .cmp(&b.kind)
            .then(angle_of(a.centre).total_cmp(&angle_of(b.centre)))
            .then(a.centre.norm().total_cmp(&b.centre.norm()))
            .then(a.radius.total_cmp(&b.radius))
    });
    Ok(clusters)
}

/// A grown candidate: centre, members (one per segment) and the radius that holds them.
#[derive(Clone, Debug)]
struct Candidate {
    centre: Complex64,
    radius: f64,
    members: Vec<FoldedRoot>,
}

fn angle_of(z: Complex64) -> f64 {
    z.im.abs().atan2(z.re)
}

/// The smallest aggregation condition the proposal relaxes to: a majority of the J segments (and
/// at least two, so that a cluster is a gathering of roots at all).
pub fn relaxed_floor(segments: usize) -> usize {
    (segments / 2 + 1).max(2)
}

/// The segments whose roots seed candidates: all of them up to [`SEED_SEGMENTS`], else that many
/// spread evenly over the run.
fn seed_segments(segments: usize) -> Vec<bool> {
    let mut seeds = vec![segments <= SEED_SEGMENTS; segments];
    if segments > SEED_SEGMENTS {
        for k in 0..SEED_SEGMENTS {
            if let Some(s) = seeds.get_mut(k * segments / SEED_SEGMENTS) {
                *s = true;
            }
        }
    }
    seeds
}

/// The aggregation conditions tried, strictest first: every one from `needed` down to `floor`
/// when there are at most [`MAX_LEVELS`], else [`MAX_LEVELS`] of them evenly spaced, both ends kept.
fn relaxation_levels(needed: usize, floor: usize) -> Vec<usize> {
    let span = needed.saturating_sub(floor);
    if span < MAX_LEVELS {
        return (floor..=needed).rev().collect();
    }
    let mut levels: Vec<usize> = (0..MAX_LEVELS).map(|k| needed - k * span / (MAX_LEVELS - 1)).collect();
    levels.dedup();
    levels
}

/// One search for clusters of one kind at one aggregation condition.
struct Search<'a> {
    kind: RootKind,
    folded: &'a [Vec<FoldedRoot>],
    /// Which segments' roots seed candidates ([`seed_segments`]).
    seeds: &'a [bool],
    settings: &'a ClusterSettings,
    needed: usize,
    dt_secs: f64,
}

impl Search<'_> {
    /// Clusters grown over the roots still `in_play` (their members are taken out of play), disjoint
    /// from the clusters in `earlier`.
    fn propose(&self, in_play: &mut [Vec<FoldedRoot>], earlier: &[Cluster]) -> Vec<Cluster> {
        let mut accepted: Vec<Cluster> = earlier.iter().filter(|c| c.kind == self.kind).cloned().collect();
        let before = accepted.len();
        while let Some((candidate, cluster)) = self.best(in_play, &accepted) {
            let taken: std::collections::HashSet<(usize, usize)> =
                candidate.members.iter().map(|m| (m.segment, m.root_index)).collect();
            for seg in in_play.iter_mut() {
                seg.retain(|p| !taken.contains(&(p.segment, p.root_index)));
            }
            accepted.push(cluster);
        }
        accepted.split_off(before)
    }

    /// The acceptable candidate that ranks first, grown from every seed root still in play.
    fn best(&self, in_play: &[Vec<FoldedRoot>], accepted: &[Cluster]) -> Option<(Candidate, Cluster)> {
        let mut best: Option<(Candidate, Cluster)> = None;
        let seeds = in_play.iter().flatten().filter(|p| self.seeds.get(p.segment).copied().unwrap_or(true));
        for seed in seeds {
            let Some(candidate) = grow(seed.z, in_play, self.needed, self.settings) else {
                continue;
            };
            if best.as_ref().is_some_and(|(b, _)| !ranks_before(&candidate, b)) {
                continue;
            }
            let accepted_as = accept(
                self.kind,
                &candidate,
                self.folded,
                accepted,
                self.needed,
                self.settings,
                self.dt_secs,
            );
            if let Some(cluster) = accepted_as {
                best = Some((candidate, cluster));
            }
        }
        best
    }
}

/// Strictly better: smaller radius, then lower angle, then smaller modulus.
fn ranks_before(a: &Candidate, b: &Candidate) -> bool {
    if (a.radius - b.radius).abs() > RADIUS_TIE_TOL {
        return a.radius < b.radius;
    }
    let key = |c: &Candidate| (angle_of(c.centre), c.centre.norm());
    let (ka, kb) = (key(a), key(b));
    ka.0.total_cmp(&kb.0).then(ka.1.total_cmp(&kb.1)).is_lt()
}

/// Step 1 of the module doc: grow a candidate from `seed` over the roots still in play.
fn grow(
    seed: Complex64,
    in_play: &[Vec<FoldedRoot>],
    needed: usize,
    settings: &ClusterSettings,
) -> Option<Candidate> {
    let mut centre = seed;
    let mut last = None;
    for _ in 0..MAX_ROUNDS {
        let members = select_members(centre, in_play, needed, settings)?;
        let radius = members.iter().map(|p| (p.z - centre).norm()).fold(0.0, f64::max);
        let next = recentre(&members)?;
        let settled = (next - centre).norm() <= f64::EPSILON * (1.0 + centre.norm());
        last = Some(Candidate { centre, radius, members });
        if settled {
            break;
        }
        centre = next;
    }
    last
}

/// The nearest root of the m closest segments, plus any further segment close enough to spoil
/// the isolation test. Sorted by segment.
fn select_members(
    centre: Complex64,
    in_play: &[Vec<FoldedRoot>],
    needed: usize,
    settings: &ClusterSettings,
) -> Option<Vec<FoldedRoot>> {
    let mut nearest: Vec<(f64, FoldedRoot)> =
        in_play.iter().filter_map(|seg| nearest_in_segment(seg, centre)).collect();
    if nearest.len() < needed {
        return None;
    }
    nearest.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.segment.cmp(&b.1.segment)));
    let mut count = needed;
    while let (Some(&(radius, _)), Some(&(next, _))) = (nearest.get(count - 1), nearest.get(count)) {
        if next <= settings.max_radius && next < settings.min_isolation * radius {
            count += 1;
        } else {
            break;
        }
    }
    nearest.truncate(count);
    let mut members: Vec<FoldedRoot> = nearest.into_iter().map(|(_, p)| p).collect();
    members.sort_by_key(|p| p.segment);
    Some(members)
}

/// The members' mean, put on the real axis when within half its radius of it.
fn recentre(members: &[FoldedRoot]) -> Option<Complex64> {
    let n = members.len() as f64;
    if members.is_empty() {
        return None;
    }
    let mean = members.iter().fold(Complex64::new(0.0, 0.0), |acc, p| acc + p.z) / n;
    let radius = members.iter().map(|p| (p.z - mean).norm()).fold(0.0, f64::max);
    Some(if mean.im.abs() <= REAL_AXIS_FRACTION * radius { Complex64::new(mean.re, 0.0) } else { mean })
}

/// Step 2 of the module doc: the proposed circle when `candidate` is an acceptable cluster.
fn accept(
    kind: RootKind,
    candidate: &Candidate,
    folded: &[Vec<FoldedRoot>],
    accepted: &[Cluster],
    needed: usize,
    settings: &ClusterSettings,
    dt_secs: f64,
) -> Option<Cluster> {
    if candidate.radius > settings.max_radius {
        return None;
    }
    let gap = nearest_non_member(folded, &candidate.members, candidate.centre);
    if gap.is_some_and(|g| g < settings.min_isolation * candidate.radius) {
        return None;
    }
    let cluster = Cluster::new(kind, candidate.centre, display_radius(candidate, gap));
    let overlaps = accepted.iter().any(|a| (a.centre - cluster.centre).norm() < a.radius + cluster.radius);
    if overlaps {
        return None;
    }
    let eval = evaluate_folded(&cluster, folded, needed, settings, dt_secs);
    eval.valid.then_some(cluster)
}

/// The member radius widened by [`RADIUS_MARGIN`] (at least [`MIN_CIRCLE_RADIUS`]), but no further than
/// half-way to the nearest non-member, and keeping an off-axis centre off the axis.
fn display_radius(candidate: &Candidate, gap: Option<f64>) -> f64 {
    let r = candidate.radius;
    let mut radius = (r * RADIUS_MARGIN).max(MIN_CIRCLE_RADIUS);
    if let Some(g) = gap {
        radius = radius.min(0.5 * (r + g));
    }
    let im = candidate.centre.im.abs();
    if im > 0.0 && im <= REAL_AXIS_FRACTION * radius {
        // Off-axis at radius r (the re-centring decided so): stay below the real-axis threshold.
        radius = radius.min(0.5 * (r + im / REAL_AXIS_FRACTION));
    }
    // Members lie within r; keep them inside despite rounding.
    radius.max(r * (1.0 + 4.0 * f64::EPSILON) + f64::MIN_POSITIVE)
}

#[cfg(test)]
mod tests;
