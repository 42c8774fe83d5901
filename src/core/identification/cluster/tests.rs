//! Tests of cluster evaluation: membership, the aggregation condition, exclusions and statuses.
#![allow(clippy::unwrap_used)]
use super::*;
use std::f64::consts::PI;

const DT: f64 = 1.0 / 8.85;

fn c(re: f64, im: f64) -> Complex64 {
    Complex64::new(re, im)
}

fn segments(poles: &[Vec<Complex64>]) -> Vec<SegmentRoots> {
    let seg = |(j, p): (usize, &Vec<Complex64>)| SegmentRoots {
        label: format!("S{j}"),
        poles: p.clone(),
        zeros: p.clone(),
    };
    poles.iter().enumerate().map(seg).collect()
}

fn eval(cluster: &Cluster, roots: &[SegmentRoots], settings: &ClusterSettings) -> ClusterEval {
    evaluate_cluster(cluster, roots, settings, DT).unwrap()
}

fn four_segments() -> Vec<SegmentRoots> {
    let noise = [c(0.5, 0.0), c(0.2, 0.3), c(0.2, -0.3)];
    let reals = [0.925, 0.93, 0.935, 0.94];
    segments(&reals.map(|r| [vec![c(r, 0.0)], noise.to_vec()].concat()))
}

#[test]
fn aggregation_moving_and_growing() {
    let roots = four_segments();
    let s = ClusterSettings::default();
    let e = eval(&Cluster::new(RootKind::Pole, c(0.93, 0.0), 0.02), &roots, &s);
    assert_eq!(e.status, ClusterStatus::Valid);
    assert_eq!((e.segments_found, e.segments_needed), (4, 4));
    assert!((e.centroid - c(0.9325, 0.0)).norm() < 1e-12);
    assert!((e.time_constant_secs.unwrap() + DT / 0.9325_f64.ln()).abs() < 1e-9);
    let far = eval(&Cluster::new(RootKind::Pole, c(0.98, 0.0), 0.02), &roots, &s);
    assert_eq!(far.status, ClusterStatus::TooFewMembers { found: 0, needed: 4 });
    assert!(!far.valid && far.members.is_empty());
    let mut cluster = Cluster::new(RootKind::Pole, c(0.945, 0.0), 0.012);
    assert_eq!(eval(&cluster, &roots, &s).status, ClusterStatus::TooFewMembers { found: 2, needed: 4 });
    let err = eval(&cluster, &roots, &s).check_valid(3);
    assert_eq!(err, Err(ClusterError::TooFewMembers { cluster: 3, found: 2, needed: 4 }));
    cluster.radius = 0.0175;
    assert_eq!(eval(&cluster, &roots, &s).segments_found, 3);
    cluster.radius = 0.021;
    assert!(eval(&cluster, &roots, &s).valid);
}

#[test]
fn one_member_per_segment_and_m_below_j() {
    let mut roots = four_segments();
    roots[0].poles.push(c(0.926, 0.0));
    roots.push(SegmentRoots { label: "none".into(), poles: vec![c(0.1, 0.1)], zeros: vec![] });
    let cluster = Cluster::new(RootKind::Pole, c(0.93, 0.0), 0.02);
    let e = eval(&cluster, &roots, &ClusterSettings::default());
    assert_eq!(e.status, ClusterStatus::TooFewMembers { found: 4, needed: 5 });
    assert_eq!(e.members.iter().map(|m| m.segment).collect::<Vec<_>>(), vec![0, 1, 2, 3]);
    assert_eq!(e.members[0].root_index, 4, "0.926 is nearer 0.93 than 0.925");
    let m4 = ClusterSettings { min_segments: Some(4), ..ClusterSettings::default() };
    assert!(eval(&cluster, &roots, &m4).valid);
}

#[test]
fn conjugates_fold_and_count_once() {
    // Off-axis: the pair of segment 0, only the lower root of segment 1, only the upper of 2.
    let roots = segments(&[
        vec![c(0.80, 0.21), c(0.80, -0.21)],
        vec![c(0.81, -0.20)],
        vec![c(0.79, 0.22), c(0.3, 0.0)],
    ]);
    let s = ClusterSettings::default();
    let e = eval(&Cluster::new(RootKind::Pole, c(0.80, -0.21), 0.03), &roots, &s);
    assert!(e.valid && e.cluster.centre.im > 0.0 && !e.cluster.is_real_axis());
    assert_eq!(e.members.len(), 3);
    assert_eq!((e.members[0].root_index, e.members[1].root_index), (0, 0));
    assert!(e.members.iter().all(|m| m.root.im > 0.0));
    assert!((e.centroid - c(0.80, 0.21)).norm() < 1e-12);
    assert_eq!(e.reduced_roots(), vec![e.centroid, e.centroid.conj()]);
    // Real axis: a near-real pair counts once and the centroid is real.
    let roots = segments(&[vec![c(0.9, 0.001), c(0.9, -0.001)], vec![c(0.91, 0.0)], vec![c(0.92, 0.0)]]);
    let e = eval(&Cluster::new(RootKind::Pole, c(0.91, 0.0), 0.02), &roots, &s);
    assert!(e.valid && e.cluster.is_real_axis());
    assert_eq!(e.members.len(), 3);
    assert!(e.centroid.im.abs() < 1e-15 && (e.centroid.re - 0.91).abs() < 1e-12);
    assert_eq!(valid_reduced_roots(&[e], RootKind::Pole).len(), 1);
}

#[test]
fn exclusions_nyquist_origin_unstable() {
    let s = ClusterSettings::default();
    let at = |z: Complex64| segments(&[vec![z], vec![z]]);
    let angle = |a: f64| c(0.7 * a.cos(), 0.7 * a.sin());
    let status = |z: Complex64, kind| eval(&Cluster::new(kind, z, 0.01), &at(z), &s).status;
    assert_eq!(status(angle(0.7 * PI), RootKind::Pole), ClusterStatus::Valid);
    assert!(matches!(status(angle(0.8 * PI), RootKind::Pole), ClusterStatus::NearNyquist { .. }));
    assert!(matches!(status(c(-0.8, 0.0), RootKind::Zero), ClusterStatus::NearNyquist { .. }));
    assert!(matches!(status(c(0.05, 0.0), RootKind::Pole), ClusterStatus::NearOrigin { .. }));
    assert!(matches!(status(c(1.02, 0.0), RootKind::Pole), ClusterStatus::Unstable { .. }));
    assert!(matches!(status(c(1.0, 0.0), RootKind::Pole), ClusterStatus::Unstable { .. }));
    assert_eq!(status(c(1.02, 0.0), RootKind::Zero), ClusterStatus::Valid);
    let looser = ClusterSettings { nyquist_exclusion_rad: PI, ..s.clone() };
    let z = c(-0.8, 0.0);
    assert!(eval(&Cluster::new(RootKind::Pole, z, 0.01), &at(z), &looser).valid);
}

#[test]
fn s_plane_figures_are_recovered() {
    let (omega, zeta) = (3.0, 0.4);
    let s = c(-zeta * omega, omega * (1.0 - zeta * zeta).sqrt());
    let z = (s * DT).exp();
    let e = eval(&Cluster::new(RootKind::Pole, z, 0.01), &segments(&[vec![z], vec![z]]), &Default::default());
    assert!((e.natural_freq_rad_s - omega).abs() < 1e-9 && (e.damping - zeta).abs() < 1e-9);
    assert_eq!(e.time_constant_secs, None);
    assert_eq!(natural_freq_and_damping(c(1.0, 0.0), DT), (0.0, 0.0));
    assert!(natural_freq_and_damping(c(0.0, 0.0), DT).0.is_finite());
}

#[test]
fn bad_inputs_are_errors() {
    let roots = four_segments();
    let cl = Cluster::new(RootKind::Pole, c(0.93, 0.0), 0.02);
    let s = ClusterSettings::default();
    assert!(matches!(evaluate_cluster(&cl, &roots, &s, 0.0), Err(ClusterError::InvalidSamplePeriod { .. })));
    let zero = ClusterSettings { min_segments: Some(0), ..s.clone() };
    assert_eq!(zero.check(), Err(ClusterError::ZeroMinSegments));
    let nan = ClusterSettings { max_radius: f64::NAN, ..s.clone() };
    assert!(matches!(nan.check(), Err(ClusterError::InvalidSetting { name: "max_radius", .. })));
    let bad = Cluster { radius: -1.0, ..cl.clone() };
    let err = evaluate_clusters(&[cl, bad], &roots, &s, DT);
    assert!(matches!(err, Err(ClusterError::InvalidCluster { cluster: 1, .. })));
}

#[test]
fn serde_round_trip() {
    let roots = four_segments();
    let cl = Cluster::new(RootKind::Pole, c(0.93, 0.0), 0.02);
    let evals = evaluate_clusters(&[cl], &roots, &ClusterSettings::default(), DT).unwrap();
    let json = serde_json::to_string(&(&evals, &roots)).unwrap();
    let back: (Vec<ClusterEval>, Vec<SegmentRoots>) = serde_json::from_str(&json).unwrap();
    assert_eq!(back, (evals, roots));
}
