//! Tests of the cluster proposal.
#![allow(clippy::unwrap_used)]
use super::super::cluster::{ClusterStatus, evaluate_cluster};
use super::*;
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;

const DT: f64 = 1.0 / 8.85;
const REAL_POLE: f64 = 0.936;

fn c(re: f64, im: f64) -> Complex64 {
    Complex64::new(re, im)
}

fn pair() -> Complex64 {
    c(0.80, 0.21)
}

fn jitter(rng: &mut ChaCha8Rng, size: f64) -> Complex64 {
    let (r, a) = (size * rng.random::<f64>().sqrt(), rng.random_range(0.0..2.0 * PI));
    c(r * a.cos(), r * a.sin())
}

/// `pairs` conjugate pairs with modulus in `modulus` and any angle, kept 0.05 from the true roots.
fn scattered(rng: &mut ChaCha8Rng, pairs: usize, modulus: std::ops::Range<f64>) -> Vec<Complex64> {
    let mut out = Vec::new();
    while out.len() < 2 * pairs {
        let z = Complex64::from_polar(rng.random_range(modulus.clone()), rng.random_range(0.0..PI));
        if (z - c(REAL_POLE, 0.0)).norm() > 0.05 && (z - pair()).norm() > 0.05 {
            out.extend([z, z.conj()]);
        }
    }
    out
}

/// J segments with the speed model's true poles jittered by `size`, 16 scattered poles and 3
/// scattered zeros each (19 poles / 3 zeros per segment).
fn speed_like(seed: u64, segments: usize, size: f64) -> Vec<SegmentRoots> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..segments)
        .map(|j| {
            let p = pair() + jitter(&mut rng, size);
            let mut poles = vec![c(REAL_POLE + size * rng.random_range(-1.0..1.0), 0.0), p, p.conj()];
            poles.extend(scattered(&mut rng, 8, 0.05..0.98));
            let mut zeros = scattered(&mut rng, 1, 0.05..1.5);
            zeros.push(c(rng.random_range(-1.5..1.5), 0.0));
            SegmentRoots { label: format!("S{j}"), poles, zeros }
        })
        .collect()
}

/// The clusters held by every segment (the relaxed ones are candidates for `core::identification::structure`).
fn full(clusters: &[Cluster]) -> Vec<&Cluster> {
    clusters.iter().filter(|c| c.min_segments.is_none()).collect()
}

#[test]
fn finds_the_true_roots_and_nothing_else() {
    let settings = ClusterSettings::default();
    for seed in 0..12 {
        let roots = speed_like(seed, 7, 0.005);
        let clusters = propose_clusters(&roots, &settings, DT).unwrap();
        let full = full(&clusters);
        let centres: Vec<Complex64> = full.iter().map(|c| c.centre).collect();
        assert_eq!(full.len(), 2, "seed {seed}: {centres:?}");
        assert!(full.iter().all(|c| c.kind == RootKind::Pole));
        assert!((centres[0] - c(REAL_POLE, 0.0)).norm() < 0.01, "seed {seed}: {centres:?}");
        assert!((centres[1] - pair()).norm() < 0.01, "seed {seed}: {centres:?}");
        assert!(full[0].is_real_axis() && !full[1].is_real_axis());
        for cl in &full {
            let e = evaluate_cluster(cl, &roots, &settings, DT).unwrap();
            assert_eq!(e.segments_found, 7);
        }
        // Chance gatherings of the scattered roots may be candidates at a relaxed condition,
        // never below a majority, and each stays valid at the condition it was accepted at.
        for cl in clusters.iter().filter(|c| c.min_segments.is_some()) {
            assert!(cl.min_segments.is_some_and(|m| (4..7).contains(&m)), "{cl:?}");
            assert!(evaluate_cluster(cl, &roots, &settings, DT).unwrap().valid);
        }
    }
}

#[test]
fn noise_ring_and_origin_roots_give_no_clusters_held_by_every_segment() {
    let settings = ClusterSettings::default();
    let mut spurious = 0;
    for seed in 0..20 {
        let mut rng = ChaCha8Rng::seed_from_u64(100 + seed);
        let roots: Vec<SegmentRoots> = (0..7)
            .map(|j| {
                let mut poles = scattered(&mut rng, 8, 0.6..0.9);
                poles.extend(scattered(&mut rng, 1, 0.0..0.12));
                poles.push(c(rng.random_range(-0.1..0.1), 0.0));
                SegmentRoots { label: format!("S{j}"), poles, zeros: vec![] }
            })
            .collect();
        spurious += full(&propose_clusters(&roots, &settings, DT).unwrap()).len();
    }
    assert_eq!(spurious, 0);
}

#[test]
fn aggregation_below_all_segments() {
    let mut roots = speed_like(7, 7, 0.005);
    // Segment 3 loses its real pole.
    roots[3].poles.remove(0);
    let all = propose_clusters(&roots, &ClusterSettings::default(), DT).unwrap();
    let full = full(&all);
    assert_eq!(full.len(), 1);
    assert!((full[0].centre - pair()).norm() < 0.01);
    // Relaxing step by step finds the real pole in 6 of the 7 segments and says so.
    let real = all.iter().find(|cl| (cl.centre - c(REAL_POLE, 0.0)).norm() < 0.01).unwrap();
    assert_eq!(real.min_segments, Some(6));
    let six = ClusterSettings { min_segments: Some(6), ..ClusterSettings::default() };
    let some = propose_clusters(&roots, &six, DT).unwrap();
    assert!(some.len() >= 2, "{some:?}");
    assert!(some.iter().any(|cl| (cl.centre - c(REAL_POLE, 0.0)).norm() < 0.01 && cl.min_segments.is_none()));
}

#[test]
fn degenerate_inputs() {
    let s = ClusterSettings::default();
    let empty = propose_clusters(&[], &s, DT);
    assert_eq!(empty, Err(ClusterError::TooFewSegments { found: 0, needed: 2 }));
    let one = speed_like(1, 1, 0.005);
    assert_eq!(propose_clusters(&one, &s, DT), Err(ClusterError::TooFewSegments { found: 1, needed: 2 }));
    let bare: Vec<SegmentRoots> =
        (0..3).map(|j| SegmentRoots { label: format!("{j}"), poles: vec![], zeros: vec![] }).collect();
    assert_eq!(propose_clusters(&bare, &s, DT), Ok(vec![]));
    let eight = ClusterSettings { min_segments: Some(8), ..s.clone() };
    let too_many = propose_clusters(&speed_like(1, 7, 0.005), &eight, DT);
    assert_eq!(too_many, Err(ClusterError::MinSegmentsExceedSegments { needed: 8, segments: 7 }));
    // Identical roots in every segment: radius zero, still a visible circle.
    let same: Vec<SegmentRoots> = (0..4)
        .map(|j| SegmentRoots { label: format!("{j}"), poles: vec![c(0.9, 0.0)], zeros: vec![] })
        .collect();
    let cl = propose_clusters(&same, &s, DT).unwrap();
    assert_eq!(cl.len(), 1);
    assert!(cl[0].radius >= MIN_CIRCLE_RADIUS && (cl[0].centre - c(0.9, 0.0)).norm() < 1e-12);
}

#[test]
fn deterministic() {
    let roots = speed_like(3, 7, 0.01);
    let s = ClusterSettings::default();
    assert_eq!(propose_clusters(&roots, &s, DT), propose_clusters(&roots, &s, DT));
}

fn segments_strategy() -> impl Strategy<Value = (Vec<SegmentRoots>, Option<usize>)> {
    let root = (-1.5..1.5f64, -1.5..1.5f64).prop_map(|(re, im)| c(re, im));
    let shared = prop::collection::vec(root.clone(), 0..3);
    let segment = (prop::collection::vec(root.clone(), 0..8), prop::collection::vec(root, 0..4));
    (shared, prop::collection::vec(segment, 2..7), 0..8usize, 0.0..0.05f64).prop_map(
        |(shared, segs, m, spread)| {
            let j = segs.len();
            let roots = segs
                .into_iter()
                .enumerate()
                .map(|(k, (mut poles, zeros))| {
                    let wobble = c(spread * (k as f64).sin(), spread * (k as f64).cos());
                    poles.extend(shared.iter().map(|z| z + wobble));
                    SegmentRoots { label: format!("{k}"), poles, zeros }
                })
                .collect();
            (roots, (m >= 2 && m <= j).then_some(m))
        },
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]
    #[test]
    fn proposals_are_valid_sorted_and_disjoint((roots, m) in segments_strategy()) {
        let settings = ClusterSettings { min_segments: m, ..ClusterSettings::default() };
        let clusters = propose_clusters(&roots, &settings, DT).unwrap();
        for cl in &clusters {
            let e = evaluate_cluster(cl, &roots, &settings, DT).unwrap();
            prop_assert_eq!(&e.status, &ClusterStatus::Valid);
            prop_assert!(cl.centre.im >= 0.0 && cl.radius > 0.0);
        }
        for (a, b) in clusters.iter().zip(clusters.iter().skip(1)) {
            let key = |c: &Cluster| (c.kind, angle_of(c.centre));
            prop_assert!(key(a).0 < key(b).0 || (key(a).0 == key(b).0 && key(a).1 <= key(b).1));
        }
        for (i, a) in clusters.iter().enumerate() {
            for b in clusters.iter().skip(i + 1).filter(|b| b.kind == a.kind) {
                prop_assert!((a.centre - b.centre).norm() >= a.radius + b.radius);
            }
        }
    }
}
