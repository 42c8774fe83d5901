//! A small known discrete Wiener system for the chain's step tests: a staircase input of four steps,
//! a unit-gain linear block of given poles (and input dead time), a quadratic static map and a
//! little seeded Gaussian output noise; the run, its segments and the segment ARX fits.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use num_complex::Complex64;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

use crate::core::identification::arx::ArxOrders;
use crate::core::identification::cluster::{self, Cluster, ClusterEval, RootKind};
use crate::core::identification::fits::{SegmentFits, fit_segments_for};
use crate::core::identification::segment::Segment;
use crate::core::identification::settings::OutputSettings;
use crate::core::identification::wiener::unit_gain_tf;
use crate::core::run::{Channel, Run};

pub(crate) const DT_SECS: f64 = 0.1;
/// Input levels, each held for [`HOLD`] samples.
pub(crate) const LEVELS: [f64; 5] = [1.0, 2.0, 1.4, 2.6, 1.7];
const HOLD: usize = 100;
/// Samples of each segment before its step.
const BEFORE_STEP: usize = 30;
pub(crate) const OUTPUT: &str = "y";

/// The static map of the system.
pub(crate) fn static_map(v: f64) -> f64 {
    2.0 + 3.0 * v + 0.5 * v * v
}

/// A known Wiener system and its segment ARX fits.
pub(crate) struct TestSystem {
    pub(crate) run: Run,
    pub(crate) settings: OutputSettings,
    pub(crate) fits: SegmentFits,
}

impl TestSystem {
    /// The system with real `poles` behind `delay` samples of input dead time, measured with
    /// Gaussian noise of standard deviation `noise_sd` (seeded by `seed`).
    pub(crate) fn new(poles: &[f64], delay: usize, noise_sd: f64, seed: u64) -> Self {
        let poles: Vec<Complex64> = poles.iter().map(|p| Complex64::new(*p, 0.0)).collect();
        Self::with_poles(&poles, delay, noise_sd, seed)
    }

    /// [`TestSystem::new`] with any poles (a pair given as both conjugates).
    pub(crate) fn with_poles(poles: &[Complex64], delay: usize, noise_sd: f64, seed: u64) -> Self {
        let tf = unit_gain_tf(poles, &[], DT_SECS).unwrap().with_input_delay(delay);
        let u: Vec<f64> = LEVELS.iter().flat_map(|level| [*level; HOLD]).collect();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let noise = Normal::new(0.0, noise_sd).unwrap();
        let y: Vec<f64> =
            tf.simulate_from_steady(&u).iter().map(|v| static_map(*v) + noise.sample(&mut rng)).collect();
        let run = Run {
            name: "test".to_owned(),
            dt_secs: DT_SECS,
            t_secs: (0..u.len()).map(|k| k as f64 * DT_SECS).collect(),
            input: Channel::new("u", u),
            outputs: vec![Channel::new(OUTPUT, y)],
            aux: Vec::new(),
        };
        let settings = OutputSettings {
            orders: ArxOrders::new(4, 2),
            static_order: Some(2),
            settle_secs: 3.0,
            ..OutputSettings::default()
        };
        let fits = fit_segments_for(&run, OUTPUT, &segments(), &settings).unwrap();
        Self { run, settings, fits }
    }

    /// The candidate of a circle around `centre` as the segment models' roots make it.
    pub(crate) fn candidate(&self, kind: RootKind, centre: Complex64, radius: f64) -> ClusterEval {
        let circle = Cluster::new(kind, centre, radius);
        cluster::evaluate_cluster(&circle, &self.fits.roots, &self.settings.cluster, DT_SECS).unwrap()
    }
}

/// One segment per step: [`BEFORE_STEP`] samples before it, the rest of the level after it.
fn segments() -> Vec<Segment> {
    (1..LEVELS.len())
        .map(|k| Segment {
            label: format!("step {k}"),
            start: k * HOLD - BEFORE_STEP,
            step_at: k * HOLD,
            end: (k + 1) * HOLD - BEFORE_STEP,
        })
        .collect()
}
