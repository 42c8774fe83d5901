//! How one output is identified: the ARX orders, the cluster settings, the static map, the polish
//! and the dead time, read by every step of the chain.
use serde::{Deserialize, Serialize};

use crate::core::run::Quantity;

use crate::core::identification::arx::ArxOrders;
use crate::core::identification::cluster::ClusterSettings;
use crate::core::identification::initial_state::InitialState;

/// Settings for identifying one output.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct OutputSettings {
    pub orders: ArxOrders,
    pub cluster: ClusterSettings,
    /// Static-map order; `None` lets the data choose (leave-one-out on the steady points).
    pub static_order: Option<usize>,
    pub max_static_order: usize,
    /// Length of the settled tail of each segment that gives its steady-state point.
    pub settle_secs: f64,
    /// Polish the cluster centroids by simulation error (see `core::identification::reduce`).
    pub refine: bool,
    /// Where the polish may move a root that came from a cluster.
    pub polish: PolishRegion,
    /// Estimate the input delay of the segment ARX models from the step segments (see
    /// [`estimate_dead_time`](crate::core::identification::arx::estimate_dead_time)); when false, `orders.nk` is used.
    pub estimate_dead_time: bool,
    /// Input dead time of the reduced model built from given clusters, samples (the automatic
    /// proposal chooses its own, see `core::identification::structure`); `None` is none.
    pub dead_time_samples: Option<usize>,
    /// Where scored simulations (validation, chirp, diagnosis) start (see `core::identification::initial_state`).
    pub initial_state: InitialState,
    /// The form a fitted `scheduled_time_constant` takes (see [`SpoolSchedule`]).
    pub spool_schedule: SpoolSchedule,
}

/// The form in which the spool's time constant follows the operating point, when the fits give
/// the model a `scheduled_time_constant` (see `core::effects::ScheduledTimeConstant`).
///
/// Why the default is the exponential. On the engine family the power balance lowers the speed's
/// held-out error on most engines (asymmetric dynamics from 2.7–4.4 to 1.0–1.5 times the
/// effect-free engine's). But on 4 of 20 effect-free engines thrust's own loop then takes a
/// physical effect, which the default never does; with a bleed kink fitted by hand the balance's
/// fit can run to its bound (k = 1) and fall back; and it costs time (the JetCat batch 4.2 s
/// instead of 3.5 s). On the JetCat itself the fit falls back to the exponential form, because the
/// balance does not carry its schedule (the ECU's; `fit::search::balance_carries_the_schedule`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SpoolSchedule {
    /// `τ = τ_ref · exp(…)` of the operating point heading for and the state.
    #[default]
    Exponential,
    /// The spool's power balance `Ṅ ∝ (P(r) − P(N))/N` read through the static map, with the
    /// compressor's load exponent fitted (a spool that shows as a real pole only).
    PowerBalance,
}

/// Where the polish may move a root that came from a cluster.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PolishRegion {
    /// Inside the cluster's circle: the model's roots and the clusters tell one story.
    #[default]
    WithinClusters,
    /// Anywhere inside the unit circle (the cluster only gives the starting point).
    Free,
}

impl Default for OutputSettings {
    fn default() -> Self {
        Self {
            orders: ArxOrders::new(10, 2),
            // Prefer the low-frequency clusters (paper §5.1): above π/2 rad/sample (13.9 rad/s at
            // 8.85 Hz, the top of the chirp band) ARX on noisy data leaves a ring of noise-model
            // roots that recur in every segment but are not engine dynamics.
            cluster: ClusterSettings {
                nyquist_exclusion_rad: std::f64::consts::FRAC_PI_2,
                max_radius: 0.08,
                ..ClusterSettings::default()
            },
            static_order: None,
            max_static_order: 3,
            settle_secs: 6.0,
            refine: true,
            polish: PolishRegion::WithinClusters,
            estimate_dead_time: true,
            dead_time_samples: None,
            initial_state: InitialState::Estimated,
            spool_schedule: SpoolSchedule::Exponential,
        }
    }
}

impl OutputSettings {
    /// The paper's orders for the SR-30 outputs: speed 19 poles / 3 zeros, thrust 21 / 19.
    pub fn for_output(name: &str) -> Self {
        let orders = match Quantity::of(name) {
            Some(Quantity::ShaftSpeed) => ArxOrders::new(19, 3),
            Some(Quantity::Thrust) => ArxOrders::new(21, 19),
            None => ArxOrders::new(10, 2),
        };
        Self { orders, ..Self::default() }
    }
}
