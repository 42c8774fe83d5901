//! Clusters of poles and zeros on the z-plane (identification step 2, paper section 3.1).
//!
//! Every identification segment j = 1..J has a high-order ARX model; its poles and zeros are
//! overlaid on the z-plane. A [`Cluster`] is a circle (centre, radius) for one [`RootKind`]. It is
//! *valid* when it holds a root from at least m of the J segment models (the aggregation condition,
//! m = J unless [`ClusterSettings::min_segments`] says otherwise) and it is not excluded: near the
//! origin, near the Nyquist angle, or (poles only) with its centroid on or outside the unit circle.
//!
//! Conventions:
//! - Roots are *folded* into the closed upper half-plane (a root below the real axis is replaced by
//!   its conjugate) before anything is measured, so a circle stands for itself and its mirror image
//!   and a conjugate pair from one segment counts once. Centres are stored in the upper half-plane.
//! - Membership: per segment at most one member, the segment's folded root nearest the centre, if it
//!   lies within the radius. J segments give at most J members.
//! - A cluster is on the real axis when its centre lies within half a radius of it
//!   ([`Cluster::is_real_axis`]); its centroid is then forced real (the mean of the real parts) and
//!   it yields one real root in the reduced model. Any other cluster yields a conjugate pair.
//! - s-plane figures come from s = ln(z) / dt at the centroid.
//!
//! [`propose_clusters`] (in `cluster_proposal`) finds clusters automatically.

use nalgebra::Complex;
use serde::{Deserialize, Serialize};

type Complex64 = Complex<f64>;

/// A cluster counts as on the real axis when |Im c| ≤ this fraction of its radius.
pub const REAL_AXIS_FRACTION: f64 = 0.5;
/// Folded roots of one segment closer than this (relative to 1 + |z|) are one root (conjugate twins).
const TWIN_TOL: f64 = 1e-9;
/// A pole is unstable when its modulus is at least 1 minus this.
const UNIT_CIRCLE_TOL: f64 = 1e-9;

#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum ClusterError {
    #[error("cluster setting `{name}` = {value} is out of range ({expected})")]
    InvalidSetting { name: &'static str, value: f64, expected: &'static str },
    #[error("the aggregation condition needs at least one segment (min_segments = 0)")]
    ZeroMinSegments,
    #[error("sample period {dt_secs} s must be finite and positive")]
    InvalidSamplePeriod { dt_secs: f64 },
    #[error("cluster {cluster}: centre ({re}, {im}) and radius {radius} must be finite, radius ≥ 0")]
    InvalidCluster { cluster: usize, re: f64, im: f64, radius: f64 },
    #[error("cluster proposal needs at least {needed} segment models, got {found}")]
    TooFewSegments { found: usize, needed: usize },
    #[error("aggregation condition asks for {needed} segments but only {segments} were identified")]
    MinSegmentsExceedSegments { needed: usize, segments: usize },
    #[error("cluster {cluster} holds roots from {found} segments, {needed} needed")]
    TooFewMembers { cluster: usize, found: usize, needed: usize },
    #[error("cluster {cluster} is excluded: {status:?}")]
    Excluded { cluster: usize, status: ClusterStatus },
}

/// Poles (roots of A) or zeros (roots of B).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum RootKind {
    Pole,
    Zero,
}

/// The poles and zeros of one segment's high-order model.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
pub struct SegmentRoots {
    pub label: String,
    #[serde(with = "complex_vec_serde")]
    pub poles: Vec<Complex64>,
    #[serde(with = "complex_vec_serde")]
    pub zeros: Vec<Complex64>,
}

impl SegmentRoots {
    pub fn roots(&self, kind: RootKind) -> &[Complex64] {
        match kind {
            RootKind::Pole => &self.poles,
            RootKind::Zero => &self.zeros,
        }
    }
}

/// A circle on the z-plane; the centre is kept in the closed upper half-plane.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
pub struct Cluster {
    pub kind: RootKind,
    #[serde(with = "complex_serde")]
    pub centre: Complex64,
    pub radius: f64,
    /// This cluster's own aggregation condition (segments it must hold a root from), when it was
    /// accepted with fewer than the output's setting asks for (the automatic proposal relaxes the
    /// condition step by step); `None` follows [`ClusterSettings::min_segments`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_segments: Option<usize>,
}

impl Cluster {
    /// The cluster with its centre folded into the upper half-plane.
    pub fn new(kind: RootKind, centre: Complex64, radius: f64) -> Self {
        Self { kind, centre: fold(centre), radius, min_segments: None }
    }

    /// The same circle with its own aggregation condition.
    pub fn with_min_segments(mut self, min_segments: Option<usize>) -> Self {
        self.min_segments = min_segments;
        self
    }

    /// Segments this cluster must hold a root from, out of `segments`, under `settings`: the
    /// output's aggregation condition, or the cluster's own where that is the looser one.
    pub fn segments_needed(&self, settings: &ClusterSettings, segments: usize) -> usize {
        let global = settings.segments_needed(segments);
        self.min_segments.map_or(global, |own| own.min(global)).max(1)
    }

    /// True when the centre lies within [`REAL_AXIS_FRACTION`] of a radius of the real axis.
    pub fn is_real_axis(&self) -> bool {
        self.centre.im.abs() <= REAL_AXIS_FRACTION * self.radius
    }
}

/// Settings of the cluster analysis. Check them with [`ClusterSettings::check`].
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
pub struct ClusterSettings {
    /// Aggregation condition m: segments a valid cluster must hold a root from; `None` = all J.
    pub min_segments: Option<usize>,
    /// Clusters whose centroid angle exceeds this are excluded (sampling distortion), in (0, π].
    pub nyquist_exclusion_rad: f64,
    /// Clusters whose centroid modulus is below this are excluded (ARX noise roots at the origin).
    pub min_modulus: f64,
    /// Proposal only: largest radius a proposed cluster may need to aggregate its segments. Chance
    /// gatherings of ARX noise roots (a ring near |z| ≈ 0.85–0.9) aggregate J = 7 segments at about
    /// 0.07–0.15, so much above the default admits them.
    pub max_radius: f64,
    /// Proposal only: the nearest non-member root must be at least this many radii from the centroid.
    pub min_isolation: f64,
}

impl Default for ClusterSettings {
    fn default() -> Self {
        Self {
            min_segments: None,
            nyquist_exclusion_rad: 0.75 * std::f64::consts::PI,
            min_modulus: 0.1,
            max_radius: 0.08,
            min_isolation: 1.5,
        }
    }
}

impl ClusterSettings {
    pub fn check(&self) -> Result<(), ClusterError> {
        if self.min_segments == Some(0) {
            return Err(ClusterError::ZeroMinSegments);
        }
        let pi = std::f64::consts::PI;
        let checks: [(&'static str, f64, bool, &'static str); 4] = [
            (
                "nyquist_exclusion_rad",
                self.nyquist_exclusion_rad,
                self.nyquist_exclusion_rad > 0.0 && self.nyquist_exclusion_rad <= pi,
                "0 < x ≤ π",
            ),
            ("min_modulus", self.min_modulus, (0.0..1.0).contains(&self.min_modulus), "0 ≤ x < 1"),
            ("max_radius", self.max_radius, self.max_radius > 0.0 && self.max_radius <= 2.0, "0 < x ≤ 2"),
            ("min_isolation", self.min_isolation, (0.0..=100.0).contains(&self.min_isolation), "0 ≤ x ≤ 100"),
        ];
        // NaN fails every range test above.
        match checks.into_iter().find(|(_, _, ok, _)| !ok) {
            Some((name, value, _, expected)) => Err(ClusterError::InvalidSetting { name, value, expected }),
            None => Ok(()),
        }
    }

    /// m for J identified segments.
    pub fn segments_needed(&self, segments: usize) -> usize {
        self.min_segments.unwrap_or(segments)
    }
}

/// One member of a cluster: the root of one segment nearest the centre.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
pub struct Member {
    /// Index into the `roots` slice given to the evaluation.
    pub segment: usize,
    /// Index into that segment's `poles` or `zeros`.
    pub root_index: usize,
    /// The root folded into the upper half-plane (where it lies in the circle).
    #[serde(with = "complex_serde")]
    pub root: Complex64,
}

/// Why a cluster is (in)valid. Checked in this order; the first failing reason is reported.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
pub enum ClusterStatus {
    Valid,
    TooFewMembers {
        found: usize,
        needed: usize,
    },
    NearOrigin {
        modulus: f64,
        min_modulus: f64,
    },
    NearNyquist {
        angle_rad: f64,
        limit_rad: f64,
    },
    /// A pole cluster whose centroid is on or outside the unit circle.
    Unstable {
        modulus: f64,
    },
}

/// A cluster with its members and the figures the cluster table and the reduced model need.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
pub struct ClusterEval {
    pub cluster: Cluster,
    /// Sorted by segment.
    pub members: Vec<Member>,
    pub segments_found: usize,
    pub segments_needed: usize,
    /// Mean of the members (real for real-axis clusters); the centre when there are none.
    #[serde(with = "complex_serde")]
    pub centroid: Complex64,
    /// Root-mean-square distance of the members from the centroid.
    pub spread: f64,
    /// Distance from the centroid to the nearest root of the same kind that is not a member.
    pub nearest_non_member: Option<f64>,
    pub valid: bool,
    pub status: ClusterStatus,
    /// |s| with s = ln(centroid) / dt.
    pub natural_freq_rad_s: f64,
    /// −Re(s)/|s|; 0 when s = 0 (z = 1, an integrator).
    pub damping: f64,
    /// −1/Re(s) for a real-axis cluster with its centroid in (0, 1).
    pub time_constant_secs: Option<f64>,
}

impl ClusterEval {
    /// The roots this cluster contributes to the reduced model: the centroid, plus its conjugate
    /// when the cluster is off the real axis.
    pub fn reduced_roots(&self) -> Vec<Complex64> {
        if self.cluster.is_real_axis() {
            vec![Complex64::new(self.centroid.re, 0.0)]
        } else {
            vec![self.centroid, self.centroid.conj()]
        }
    }

    /// `Ok` when valid; otherwise the reason as an error naming the cluster's index.
    pub fn check_valid(&self, cluster: usize) -> Result<(), ClusterError> {
        match &self.status {
            ClusterStatus::Valid => Ok(()),
            ClusterStatus::TooFewMembers { found, needed } => {
                Err(ClusterError::TooFewMembers { cluster, found: *found, needed: *needed })
            }
            status => Err(ClusterError::Excluded { cluster, status: status.clone() }),
        }
    }
}

/// The reduced model's roots of one kind: those of every valid cluster, sorted by angle, then modulus.
pub fn valid_reduced_roots(evals: &[ClusterEval], kind: RootKind) -> Vec<Complex64> {
    let mut roots: Vec<Complex64> = evals
        .iter()
        .filter(|e| e.valid && e.cluster.kind == kind)
        .flat_map(ClusterEval::reduced_roots)
        .collect();
    roots.sort_by(|a, b| a.arg().total_cmp(&b.arg()).then(a.norm().total_cmp(&b.norm())));
    roots
}

/// Evaluates one cluster against the segment models' roots.
pub fn evaluate_cluster(
    cluster: &Cluster,
    roots: &[SegmentRoots],
    settings: &ClusterSettings,
    dt_secs: f64,
) -> Result<ClusterEval, ClusterError> {
    check_inputs(settings, dt_secs)?;
    check_cluster(0, cluster)?;
    let folded = folded_roots(roots, cluster.kind);
    Ok(evaluate_folded(cluster, &folded, cluster.segments_needed(settings, roots.len()), settings, dt_secs))
}

/// Evaluates clusters; the result is in the order of `clusters`.
pub fn evaluate_clusters(
    clusters: &[Cluster],
    roots: &[SegmentRoots],
    settings: &ClusterSettings,
    dt_secs: f64,
) -> Result<Vec<ClusterEval>, ClusterError> {
    check_inputs(settings, dt_secs)?;
    for (i, c) in clusters.iter().enumerate() {
        check_cluster(i, c)?;
    }
    let poles = folded_roots(roots, RootKind::Pole);
    let zeros = folded_roots(roots, RootKind::Zero);
    Ok(clusters
        .iter()
        .map(|c| {
            let folded = match c.kind {
                RootKind::Pole => &poles,
                RootKind::Zero => &zeros,
            };
            evaluate_folded(c, folded, c.segments_needed(settings, roots.len()), settings, dt_secs)
        })
        .collect())
}

pub(crate) fn check_inputs(settings: &ClusterSettings, dt_secs: f64) -> Result<(), ClusterError> {
    settings.check()?;
    if !(dt_secs.is_finite() && dt_secs > 0.0) {
        return Err(ClusterError::InvalidSamplePeriod { dt_secs });
    }
    Ok(())
}

fn check_cluster(index: usize, c: &Cluster) -> Result<(), ClusterError> {
    let ok = c.centre.re.is_finite() && c.centre.im.is_finite() && c.radius.is_finite() && c.radius >= 0.0;
    if ok {
        Ok(())
    } else {
        Err(ClusterError::InvalidCluster {
            cluster: index,
            re: c.centre.re,
            im: c.centre.im,
            radius: c.radius,
        })
    }
}

/// A root folded into the closed upper half-plane, with where it came from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct FoldedRoot {
    pub segment: usize,
    pub root_index: usize,
    pub z: Complex64,
}

pub(crate) fn fold(z: Complex64) -> Complex64 {
    if z.im < 0.0 { z.conj() } else { z }
}

/// Per segment, its finite roots of `kind` folded into the upper half-plane, conjugate twins merged
/// (the upper one kept).
pub(crate) fn folded_roots(roots: &[SegmentRoots], kind: RootKind) -> Vec<Vec<FoldedRoot>> {
    roots
        .iter()
        .enumerate()
        .map(|(segment, seg)| {
            let mut kept: Vec<FoldedRoot> = Vec::new();
            for (root_index, &z) in seg.roots(kind).iter().enumerate() {
                if !(z.re.is_finite() && z.im.is_finite()) {
                    continue;
                }
                let folded = FoldedRoot { segment, root_index, z: fold(z) };
                let twin =
                    kept.iter_mut().find(|k| (k.z - folded.z).norm() <= TWIN_TOL * (1.0 + folded.z.norm()));
                match twin {
                    None => kept.push(folded),
                    Some(k) => {
                        let kept_is_lower = seg.roots(kind).get(k.root_index).is_some_and(|r| r.im < 0.0);
                        if kept_is_lower && z.im >= 0.0 {
                            k.root_index = root_index;
                        }
                    }
                }
            }
            kept
        })
        .collect()
}

/// The root of one segment nearest `centre` (ties: the earlier root) and its distance.
pub(crate) fn nearest_in_segment(points: &[FoldedRoot], centre: Complex64) -> Option<(f64, FoldedRoot)> {
    points.iter().map(|p| ((p.z - centre).norm(), *p)).min_by(|a, b| a.0.total_cmp(&b.0))
}

/// Distance from `point` to the nearest root that is not one of `members`.
pub(crate) fn nearest_non_member(
    folded: &[Vec<FoldedRoot>],
    members: &[FoldedRoot],
    point: Complex64,
) -> Option<f64> {
    folded
        .iter()
        .flatten()
        .filter(|p| !members.iter().any(|m| m.segment == p.segment && m.root_index == p.root_index))
        .map(|p| (p.z - point).norm())
        .min_by(f64::total_cmp)
}

/// The mean of folded roots; real when it lies within half of its radius of the real axis.
pub(crate) fn centroid_of(points: &[FoldedRoot], real_axis: bool) -> Option<Complex64> {
    if points.is_empty() {
        return None;
    }
    let n = points.len() as f64;
    let mean = points.iter().fold(Complex64::new(0.0, 0.0), |acc, p| acc + p.z) / n;
    Some(if real_axis { Complex64::new(mean.re, 0.0) } else { mean })
}

pub(crate) fn evaluate_folded(
    cluster: &Cluster,
    folded: &[Vec<FoldedRoot>],
    needed: usize,
    settings: &ClusterSettings,
    dt_secs: f64,
) -> ClusterEval {
    let cluster =
        Cluster::new(cluster.kind, cluster.centre, cluster.radius).with_min_segments(cluster.min_segments);
    let real_axis = cluster.is_real_axis();
    let chosen: Vec<FoldedRoot> = folded
        .iter()
        .filter_map(|seg| nearest_in_segment(seg, cluster.centre))
        .filter(|(d, _)| *d <= cluster.radius)
        .map(|(_, p)| p)
        .collect();
    let fallback = if real_axis { Complex64::new(cluster.centre.re, 0.0) } else { cluster.centre };
    let centroid = centroid_of(&chosen, real_axis).unwrap_or(fallback);
    let spread = if chosen.is_empty() {
        0.0
    } else {
        (chosen.iter().map(|p| (p.z - centroid).norm_sqr()).sum::<f64>() / chosen.len() as f64).sqrt()
    };
    let nearest_non_member = nearest_non_member(folded, &chosen, centroid);
    let status = status_of(&cluster, centroid, chosen.len(), needed, settings);
    let (natural_freq_rad_s, damping) = natural_freq_and_damping(centroid, dt_secs);
    let time_constant_secs = (real_axis && centroid.re > 0.0 && centroid.re < 1.0)
        .then(|| -dt_secs / centroid.re.ln())
        .filter(|t| t.is_finite());
    ClusterEval {
        segments_found: chosen.len(),
        members: chosen
            .iter()
            .map(|p| Member { segment: p.segment, root_index: p.root_index, root: p.z })
            .collect(),
        cluster,
        segments_needed: needed,
        centroid,
        spread,
        nearest_non_member,
        valid: status == ClusterStatus::Valid,
        status,
        natural_freq_rad_s,
        damping,
        time_constant_secs,
    }
}

fn status_of(
    cluster: &Cluster,
    centroid: Complex64,
    found: usize,
    needed: usize,
    settings: &ClusterSettings,
) -> ClusterStatus {
    let modulus = centroid.norm();
    let angle_rad = centroid.im.abs().atan2(centroid.re);
    if found < needed {
        ClusterStatus::TooFewMembers { found, needed }
    } else if modulus < settings.min_modulus {
        ClusterStatus::NearOrigin { modulus, min_modulus: settings.min_modulus }
    } else if angle_rad > settings.nyquist_exclusion_rad {
        ClusterStatus::NearNyquist { angle_rad, limit_rad: settings.nyquist_exclusion_rad }
    } else if cluster.kind == RootKind::Pole && modulus >= 1.0 - UNIT_CIRCLE_TOL {
        ClusterStatus::Unstable { modulus }
    } else {
        ClusterStatus::Valid
    }
}

/// (|s|, −Re(s)/|s|) for s = ln(z)/dt; z = 0 is treated as the smallest positive modulus.
pub fn natural_freq_and_damping(z: Complex64, dt_secs: f64) -> (f64, f64) {
    let ln_modulus = z.norm().max(f64::MIN_POSITIVE).ln();
    let s = Complex64::new(ln_modulus, z.im.atan2(z.re)) / dt_secs;
    let omega = s.norm();
    let damping = if omega > 0.0 { -s.re / omega } else { 0.0 };
    (omega, damping)
}

mod complex_serde;
mod complex_vec_serde;

#[cfg(test)]
mod tests;
