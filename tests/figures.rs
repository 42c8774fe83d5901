//! Draws every report figure from synthetic data and checks the PNGs decode.
//!
//! Set `JETID_FIGURE_DIR` to also keep a copy of each figure in that folder for a visual check.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};

use jetid::core::identification::cluster::{
    Cluster, ClusterSettings, RootKind, SegmentRoots, evaluate_clusters,
};
use jetid::core::numerics::metrics::percentage_error_box;
use jetid::core::numerics::tf::{DiscreteTf, log_space};
use jetid::io::figures::{
    BodeCurve, EmpiricalBode, FigureError, bode_png, boxplot_png, histogram_png, static_map_png, traces_png,
    zplane_png,
};
use nalgebra::Complex;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

type C64 = Complex<f64>;
const DT_SECS: f64 = 0.02;

/// Checks the file decodes as a PNG of the expected size and is not blank.
fn assert_png(path: &Path, size: (u32, u32)) {
    let img =
        image::open(path).unwrap_or_else(|e| panic!("{} does not decode: {e}", path.display())).to_rgb8();
    assert_eq!(img.dimensions(), size, "{}", path.display());
    let non_white = img.pixels().filter(|p| p.0 != [255, 255, 255]).count();
    assert!(non_white > 2000, "{} looks blank ({non_white} non-white pixels)", path.display());
    let dir = path.parent().unwrap();
    let leftovers: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left behind: {leftovers:?}");
    keep_copy(path);
}

/// Copies the figure to `$JETID_FIGURE_DIR/fig_<name>` when that variable is set.
fn keep_copy(path: &Path) {
    if let Some(keep) = std::env::var_os("JETID_FIGURE_DIR") {
        let name = path.file_name().unwrap().to_string_lossy();
        std::fs::copy(path, PathBuf::from(keep).join(format!("fig_{name}"))).unwrap();
    }
}

fn segment_roots(rng: &mut ChaCha8Rng, segments: usize) -> Vec<SegmentRoots> {
    let mut jitter = |z: C64, s: f64| z + C64::new(rng.random_range(-s..s), rng.random_range(-s..s));
    (0..segments)
        .map(|j| {
            let slow = C64::new(0.965 + 0.01 * (j as f64 / segments as f64 - 0.5), 0.0);
            let pair = jitter(C64::new(0.78, 0.32), 0.02);
            let noise = C64::from_polar(0.86, 1.2 + 0.4 * j as f64);
            let zero = jitter(C64::new(-0.6, 0.0), 0.03);
            let zero_pair = C64::from_polar(0.9, 2.0 + 0.2 * j as f64);
            SegmentRoots {
                label: format!("segment {} ({}–{} s)", j + 1, 20 * j, 20 * (j + 1)),
                poles: vec![slow, pair, pair.conj(), noise, noise.conj(), C64::new(0.04, 0.0)],
                zeros: vec![C64::new(zero.re, 0.0), zero_pair, zero_pair.conj()],
            }
        })
        .collect()
}

#[test]
fn zplane_figure() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let roots = segment_roots(&mut rng, 6);
    let clusters = [
        Cluster::new(RootKind::Pole, C64::new(0.965, 0.0), 0.03),
        Cluster::new(RootKind::Pole, C64::new(0.78, 0.32), 0.05),
        Cluster::new(RootKind::Pole, C64::from_polar(0.86, 1.6), 0.08),
        Cluster::new(RootKind::Zero, C64::new(-0.6, 0.0), 0.06),
    ];
    let evals = evaluate_clusters(&clusters, &roots, &ClusterSettings::default(), DT_SECS).unwrap();
    assert!(evals.iter().any(|e| e.valid) && evals.iter().any(|e| !e.valid));
    let path = dir.path().join("zplane.png");
    zplane_png(&path, "Shaft speed: z-plane of the segment models", &roots, &evals, DT_SECS).unwrap();
    assert_png(&path, (1150, 900));
}

fn lowpass(pole: f64, pair: C64, gain: f64) -> DiscreteTf {
    let poles = [C64::new(pole, 0.0), pair, pair.conj()];
    let dc = (1.0 - pole) * (C64::new(1.0, 0.0) - pair).norm_sqr();
    DiscreteTf::from_zpk(&[C64::new(-0.5, 0.0)], &poles, gain * dc / 1.5, DT_SECS).unwrap()
}

#[test]
fn bode_figure() {
    let dir = tempfile::tempdir().unwrap();
    let omegas = log_space(0.05, 150.0, 300);
    let mut curves: Vec<BodeCurve> = (0..6)
        .map(|j| {
            let tf = lowpass(
                0.96 + 0.003 * j as f64,
                C64::new(0.78, 0.30 + 0.01 * j as f64),
                1.0 + 0.05 * j as f64,
            );
            BodeCurve {
                name: format!("segment {}", j + 1),
                points: tf.bode_response(&omegas),
                emphasis: false,
                colour: None,
                dashed: false,
            }
        })
        .collect();
    let reduced = lowpass(0.963, C64::new(0.78, 0.32), 1.1);
    curves.push(BodeCurve {
        name: "reduced (gray box)".into(),
        points: reduced.bode_response(&omegas),
        emphasis: true,
        colour: None,
        dashed: false,
    });
    let linear = lowpass(0.95, C64::new(0.7, 0.2), 1.0);
    curves.push(BodeCurve {
        name: "linear baseline".into(),
        points: linear.bode_response(&omegas),
        emphasis: true,
        colour: None,
        dashed: false,
    });
    let emp_omegas = log_space(0.1, 100.0, 40);
    let truth = reduced.bode_response(&emp_omegas);
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let empirical = EmpiricalBode {
        mag_db: truth.iter().map(|p| p.mag_db + rng.random_range(-1.0..1.0)).collect(),
        phase_deg: truth.iter().map(|p| p.phase_deg + rng.random_range(-5.0..5.0)).collect(),
        coherence: emp_omegas.iter().map(|w| 1.0 / (1.0 + (w / 30.0).powi(2))).collect(),
        omega_rad_s: emp_omegas,
    };
    let path = dir.path().join("bode.png");
    bode_png(&path, "Shaft speed: Bode comparison", &curves, Some(&empirical)).unwrap();
    assert_png(&path, (1200, 800));
}

#[test]
fn static_map_figure() {
    let dir = tempfile::tempdir().unwrap();
    let map = |u: f64| 30_000.0 + 9_000.0 * u - 600.0 * u * u;
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let points: Vec<(f64, f64)> = (0..15)
        .map(|i| 0.5 + 0.45 * i as f64)
        .map(|u| (u, map(u) + rng.random_range(-800.0..800.0)))
        .collect();
    let curve: Vec<(f64, f64)> = (0..=100).map(|i| 0.4 + 0.065 * i as f64).map(|u| (u, map(u))).collect();
    let path = dir.path().join("static_map.png");
    static_map_png(&path, "Shaft speed: static map", &points, &curve, "fuel flow (gph)", "shaft speed (rpm)")
        .unwrap();
    assert_png(&path, (1200, 800));
}

#[test]
fn traces_figure() {
    let dir = tempfile::tempdir().unwrap();
    let t_secs: Vec<f64> = (0..3000).map(|k| k as f64 * DT_SECS).collect();
    let level = |t: f64| 40_000.0 + 25_000.0 * (((t / 12.0).floor() as i64 % 3) as f64 / 2.0);
    let lag = |tau: f64| {
        let a = (-DT_SECS / tau).exp();
        let mut y = level(0.0);
        t_secs
            .iter()
            .map(|t| {
                y = a * y + (1.0 - a) * level(*t);
                y
            })
            .collect::<Vec<f64>>()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let measured: Vec<f64> = lag(1.0).iter().map(|y| y + rng.random_range(-300.0..300.0)).collect();
    let models = vec![("gray box".to_string(), lag(1.05)), ("linear".to_string(), lag(1.6))];
    let path = dir.path().join("traces.png");
    traces_png(&path, "Shaft speed: validation run", &t_secs, &measured, &models, "shaft speed (rpm)")
        .unwrap();
    assert_png(&path, (1200, 800));
}

#[test]
fn histogram_figure() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let normal = Normal::new(3.2, 0.4).unwrap();
    let samples: Vec<f64> = (0..500).map(|_| normal.sample(&mut rng)).collect();
    let n = samples.len() as f64;
    let mean = samples.iter().sum::<f64>() / n;
    let std = (samples.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let path = dir.path().join("histogram.png");
    histogram_png(&path, "Monte Carlo: RMSPE", &samples, 30, Some((mean, std)), "RMSPE (%)").unwrap();
    assert_png(&path, (1200, 800));
}

#[test]
fn boxplot_figure() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let y: Vec<f64> = (0..2000).map(|k| 50_000.0 + 10_000.0 * (k as f64 / 200.0).sin()).collect();
    let boxes: Vec<(String, _)> =
        [("gray box", 0.01), ("linear", 0.03), ("Hammerstein–Wiener", 0.02), ("NNARX", 0.015)]
            .into_iter()
            .map(|(name, rel)| {
                let yhat: Vec<f64> = y
                    .iter()
                    .map(|v| {
                        let spike = if rng.random_bool(0.01) { 4.0 } else { 1.0 };
                        v * (1.0 + spike * rng.random_range(-rel..rel))
                    })
                    .collect();
                (name.to_string(), percentage_error_box(&y, &yhat).unwrap())
            })
            .collect();
    let path = dir.path().join("boxplot.png");
    boxplot_png(&path, "Percentage error, validation run", &boxes, "error (%)").unwrap();
    assert_png(&path, (1200, 800));
}

#[test]
fn empty_data_gives_a_chart_with_a_note() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name);
    zplane_png(&p("z.png"), "empty", &[], &[], DT_SECS).unwrap();
    bode_png(&p("b.png"), "empty", &[], None).unwrap();
    static_map_png(&p("s.png"), "empty", &[], &[], "u", "y").unwrap();
    traces_png(&p("t.png"), "empty", &[], &[], &[], "y").unwrap();
    traces_png(&p("t1.png"), "measured only", &[0.0, 1.0, 2.0], &[1.0, 3.0, 2.0], &[], "y").unwrap();
    histogram_png(&p("h.png"), "empty", &[f64::NAN], 10, None, "x").unwrap();
    histogram_png(&p("h1.png"), "one value", &[2.0, 2.0], 10, Some((2.0, 0.0)), "x").unwrap();
    boxplot_png(&p("x.png"), "empty", &[], "y").unwrap();
    static_map_png(&p("s1.png"), "huge", &[(f64::MAX, -f64::MAX), (-f64::MAX, 1.0)], &[], "u", "y").unwrap();
    for name in ["z.png", "b.png", "s.png", "s1.png", "t.png", "t1.png", "h.png", "h1.png", "x.png"] {
        let img = image::open(p(name)).unwrap();
        assert!(img.width() >= 1000, "{name}");
        keep_copy(&p(name));
    }
}

#[test]
fn inconsistent_data_is_an_error_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.png");
    let models = vec![("m".to_string(), vec![1.0, 2.0])];
    let err = traces_png(&path, "t", &[0.0, 1.0, 2.0], &[1.0, 2.0, 3.0], &models, "y").unwrap_err();
    assert!(matches!(err, FigureError::LengthMismatch { found: 2, expected: 3, .. }), "{err}");
    assert!(err.to_string().contains("bad.png"), "{err}");
    let err = histogram_png(&path, "h", &[1.0], 0, None, "x").unwrap_err();
    assert!(matches!(err, FigureError::InvalidParameter { name: "bins", .. }), "{err}");
    let err = zplane_png(&path, "z", &[], &[], 0.0).unwrap_err();
    assert!(matches!(err, FigureError::InvalidParameter { name: "dt_secs", .. }), "{err}");
    let emp = EmpiricalBode {
        omega_rad_s: vec![1.0, 2.0],
        mag_db: vec![0.0],
        phase_deg: vec![0.0; 2],
        coherence: vec![1.0; 2],
    };
    assert!(matches!(bode_png(&path, "b", &[], Some(&emp)), Err(FigureError::LengthMismatch { .. })));
    assert!(!path.exists(), "no file is written on error");
}

#[test]
fn unwritable_path_is_an_io_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("missing-folder").join("fig.png");
    let err = static_map_png(&path, "s", &[(1.0, 2.0)], &[], "u", "y").unwrap_err();
    assert!(matches!(err, FigureError::Io { .. }), "{err}");
    assert!(err.to_string().contains("fig.png"), "{err}");
}
