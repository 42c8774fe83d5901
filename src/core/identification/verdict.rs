//! What became of each candidate cluster of the automatic proposal: kept or dropped and why, with
//! the numbers as data; the words are made only where they are shown (the `Display` of
//! [`Verdict`]).
use std::fmt;

use serde::{Deserialize, Serialize};

use crate::core::identification::cluster::{Cluster, ClusterEval};
use crate::core::identification::parsimony::Gain;
use crate::core::identification::words::fmt_error;

/// Why a candidate cluster is in the model or not.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Verdict {
    /// The selection never came to it (no pole candidate gave a model of its own).
    NotTried,
    /// The cluster is not valid (too few segments hold a root in it, or it is not isolated).
    NotValid,
    /// A pole candidate whose model alone cannot be fitted (its gain cannot be).
    NoModelAlone,
    /// Kept as the first pole: of the pole candidates it alone fits the identification run best.
    KeptFirst {
        /// Identification RMS error of the model of this root alone, output units.
        rms: f64,
    },
    /// A zero not tried: the model has no pole to spare beside it.
    ZeroWithoutPole { poles: usize, zeros: usize },
    /// No model can be fitted with it beside the kept roots.
    NoModelBeside,
    /// Judged on its fit to all the identification data alone, which it improves too little to be
    /// worth trying on held-out segments.
    DroppedInSample {
        /// Identification RMS errors without and with it, output units.
        rms_without: f64,
        rms_with: f64,
        /// Share of the model error above noise it removes (negative: it adds some).
        reduction: f64,
    },
    /// Cross-validated beside the kept roots and not kept: it fails the parsimony rule, or another
    /// trial lowered the held-out error more.
    DroppedHeldOut { gain: Gain },
    /// Kept: the trial that lowered the held-out error most, and it passes the parsimony rule.
    Kept { gain: Gain },
    /// Replaced by a dead time that predicts the held-out segments as well with fewer parameters.
    DroppedForDeadTime {
        /// The dead time, samples.
        samples: usize,
        /// Held-out errors with the root and with the dead time instead, output units.
        held_out_without: f64,
        held_out_with: f64,
    },
    /// Taken out again once the dead time was kept: the model with the dead time does not need it.
    DroppedStoodIn {
        /// The root against the model with the dead time and without it.
        gain: Gain,
    },
}

impl Verdict {
    /// Whether the root is in the model.
    pub fn kept(&self) -> bool {
        matches!(self, Self::KeptFirst { .. } | Self::Kept { .. })
    }
}

/// The sentence the report and the app show.
impl fmt::Display for Verdict {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NotTried => write!(f, "not tried"),
            Self::NotValid => write!(f, "not valid, so not tried"),
            Self::NoModelAlone => write!(f, "gives no model on its own (its gain cannot be fitted)"),
            Self::KeptFirst { rms } => write!(
                f,
                "kept: of the pole candidates it alone fits the identification run best (RMS error {})",
                fmt_error(*rms)
            ),
            Self::ZeroWithoutPole { poles, zeros } => write!(
                f,
                "not tried: the model has {poles} poles and {zeros} zeros, and a zero needs a pole beside it"
            ),
            Self::NoModelBeside => write!(f, "gives no model beside the kept roots"),
            Self::DroppedInSample { rms_without, rms_with, reduction } => write!(
                f,
                "dropped: beside the kept roots it {} the identification error from {} to {} ({:+.0} %), \
                 too little of the error above noise to try it on held-out segments",
                if *reduction > 0.0 { "lowers" } else { "raises" },
                fmt_error(*rms_without),
                fmt_error(*rms_with),
                -100.0 * reduction
            ),
            Self::DroppedHeldOut { gain } => write!(f, "dropped: beside the kept roots, {gain}"),
            Self::Kept { gain } => write!(f, "kept: {gain}"),
            Self::DroppedForDeadTime { samples, held_out_without, held_out_with } => write!(
                f,
                "dropped: a dead time of {samples} samples predicts the held-out segments as well with fewer \
                 parameters (held-out error from {} to {}); the root only stood in for it",
                fmt_error(*held_out_without),
                fmt_error(*held_out_with)
            ),
            Self::DroppedStoodIn { gain } => write!(
                f,
                "dropped once the dead time was kept: it only stood in for it; with the dead time, {gain}"
            ),
        }
    }
}

/// What became of one candidate cluster, with its numbers.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CandidateVerdict {
    pub cluster: Cluster,
    /// Segments whose models have a root in the circle, and how many segments there are.
    pub segments_found: usize,
    pub segments_total: usize,
    /// Natural frequency (rad/s) and damping of the centroid.
    pub natural_freq_rad_s: f64,
    pub damping: f64,
    /// Identification RMS error (output units) of the model without and with this root, when tried.
    pub rms_without: Option<f64>,
    pub rms_with: Option<f64>,
    /// Standard errors by which the root lowered the held-out error, when it was kept by
    /// cross-validation (kept even if the root was later taken out for the dead time).
    pub standard_errors: Option<f64>,
    /// Why it was kept or dropped.
    pub verdict: Verdict,
}

impl CandidateVerdict {
    /// A candidate before the selection: not tried.
    pub fn untried(e: &ClusterEval, segments_total: usize) -> Self {
        Self {
            cluster: e.cluster.clone(),
            segments_found: e.segments_found,
            segments_total,
            natural_freq_rad_s: e.natural_freq_rad_s,
            damping: e.damping,
            rms_without: None,
            rms_with: None,
            standard_errors: None,
            verdict: Verdict::NotTried,
        }
    }

    /// Whether the root is in the model.
    pub fn kept(&self) -> bool {
        self.verdict.kept()
    }
}
