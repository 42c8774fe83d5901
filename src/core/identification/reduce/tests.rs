//! The root groups' polish parameters, and the polish on a known system.
#![allow(clippy::unwrap_used)]

use super::*;
use crate::core::identification::test_system::TestSystem;

fn region(re: f64, im: f64, radius: f64) -> Option<Region> {
    Some(Region { centre: Complex64::new(re, im), radius })
}

#[test]
fn parameters_round_trip_and_stay_inside_the_circle() {
    let pair = RootGroup {
        kind: RootKind::Pole,
        root: Complex64::new(0.82, 0.21),
        pair: true,
        region: region(0.84, 0.2, 0.05),
        cluster: Some(0),
    };
    let real = RootGroup {
        kind: RootKind::Pole,
        root: Complex64::new(0.93, 0.0),
        pair: false,
        region: region(0.935, 0.004, 0.02),
        cluster: Some(1),
    };
    for g in [&pair, &real, &RootGroup::free_real(RootKind::Zero, -0.3)] {
        let back = g.decode(&g.encode()).unwrap();
        assert!((back.root - g.root).norm() < 1e-12, "{g:?} → {back:?}");
        assert_eq!(g.encode().len(), g.n_params());
    }
    for theta in [[50.0, -80.0], [-3.0, 0.2], [0.0, 0.0]] {
        let z = pair.decode(&theta).unwrap().root;
        assert!((z - Complex64::new(0.84, 0.2)).norm() <= 0.05 + 1e-12);
        let x = real.decode(&theta[..1]).unwrap().root;
        assert!(x.im == 0.0 && (x - Complex64::new(0.935, 0.004)).norm() <= 0.02 + 1e-12);
    }
    assert!(pair.decode(&[50.0, -80.0]).unwrap().at_rim() && !pair.at_rim());
    let touching = RootGroup { region: region(0.9, 0.02, 0.02), ..real.clone() };
    assert_eq!(touching.n_params(), 0);
    assert!((touching.decode(&[]).unwrap().root.re - 0.9).abs() < 1e-15);
}

#[test]
fn the_polish_lowers_the_error_and_keeps_roots_inside_their_circles() {
    let sys = TestSystem::new(&[0.9, 0.7], 0, 0.02, 7);
    let data = IdentData::new(&sys.fits, &sys.run, &sys.settings).unwrap();
    // Circles off the truth: the slow pole's stops just short of 0.9, the fast pole's holds 0.7.
    let circles = [(0.86, 0.02), (0.66, 0.08)];
    let groups = |polish: PolishRegion| -> Vec<RootGroup> {
        circles
            .iter()
            .enumerate()
            .map(|(i, &(centre, radius))| {
                let centre = Complex64::new(centre, 0.0);
                let region = Some(Region { centre, radius });
                RootGroup { kind: RootKind::Pole, root: centre, pair: false, region, cluster: Some(i) }
                    .within(polish)
            })
            .collect()
    };
    let order = sys.settings.static_order.unwrap();
    let within = polish(&data, &groups(PolishRegion::WithinClusters), order).unwrap();
    let r = &within.refinement;
    assert!(r.rms_after < 0.8 * r.rms_before, "{r:?}");
    assert!((within.assembled.rms() - r.rms_after).abs() < 1e-12);
    for (g, (centre, radius)) in within.groups.iter().zip(circles) {
        assert!((g.root - Complex64::new(centre, 0.0)).norm() <= radius + 1e-12, "{g:?}");
    }
    // The data pull the slow pole out of its circle; the circle holds it on the rim.
    assert!(within.groups[0].at_rim(), "{:?}", within.groups[0]);
    // Free, the same start leaves the circle towards the truth and fits better.
    let free = polish(&data, &groups(PolishRegion::Free), order).unwrap();
    assert!(free.groups[0].root.re > 0.88, "{:?}", free.groups[0]);
    assert!(free.refinement.rms_after < r.rms_after, "{:?} vs {r:?}", free.refinement);
}

#[test]
fn s_plane_figures_of_a_real_root() {
    let dt = 0.1;
    let g = RootGroup::free_real(RootKind::Pole, (-dt / 2.0_f64).exp());
    let (omega, zeta, tau) = g.s_plane(dt);
    assert!((tau.unwrap() - 2.0).abs() < 1e-12 && (omega - 0.5).abs() < 1e-12 && (zeta - 1.0).abs() < 1e-12);
}
