//! `report.json` and `report.md` of `jetid --batch` (CONTRACT.md).
use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};

use crate::core::compare::{Curve, ModelKind};
use crate::core::diagnose::HistoryStep;
use crate::core::effects::EffectId;
use crate::core::numerics::metrics::Metrics;
use crate::io::atomic::write_atomic;

mod ident;
pub mod markdown;
pub mod preparation;
pub use ident::{CandidateSummary, ClusterSummary, IdentSummary, RootSummary, SegmentSummary};

pub const REPORT_FORMAT_VERSION: u32 = 1;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DiagnosisEntry {
    /// Effect id of the catalog, or the id of a structural refinement.
    pub effect: String,
    /// "physics" (an effect of the catalog) or "structure" (a refinement of the model itself).
    #[serde(default = "physics_kind")]
    pub kind: String,
    pub significant: bool,
    pub rmspe_before_pct: f64,
    pub rmspe_after_pct: f64,
    /// The validation error after the change beyond the measurement noise, in units of the noise
    /// (what the decision and the ranking compare; see `core::diagnose`).
    #[serde(default)]
    pub beyond_noise_after: Option<f64>,
    pub evidence: String,
    /// One-sided p-value of "the effect does not reduce the error": the validation runs' (the
    /// Diebold–Mariano test, or where enough of their step responses are changed the better of it
    /// and the responses' signed-rank test, doubled), combined with the held-out identification
    /// responses when they witness.
    #[serde(default)]
    pub p_value: Option<f64>,
    /// Error of the extension on the identification responses held out by the cross-validation, %.
    #[serde(default)]
    pub held_out_rmspe_pct: Option<f64>,
    /// What the witnesses say, in words (validation runs, held-out identification responses).
    #[serde(default)]
    pub significance: String,
}

fn band_applies() -> bool {
    true
}

fn physics_kind() -> String {
    "physics".to_owned()
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OutputReport {
    pub unit: String,
    /// model → run name → metrics.
    pub models: BTreeMap<ModelKind, BTreeMap<String, Metrics>>,
    pub identified: IdentSummary,
    pub diagnosis: Vec<DiagnosisEntry>,
    pub effects_applied: Vec<EffectId>,
    pub error_history: Vec<HistoryStep>,
    /// model → run → box-plot statistics of the percentage error 100·(y − ŷ)/y.
    #[serde(default)]
    pub error_boxes: BTreeMap<ModelKind, BTreeMap<String, crate::core::numerics::metrics::BoxStats>>,
    /// −3 dB cut-off on the chirp run (rad/s): "measured" and each model's, from the same estimator.
    #[serde(default)]
    pub cutoff_rad_s: BTreeMap<Curve, Option<f64>>,
    /// Where the final model fails on each scored run.
    #[serde(default)]
    pub residuals: Vec<ResidualReport>,
    /// Where every model's simulation of a scored run starts ("estimated" or "steady"), and what
    /// that means.
    #[serde(default)]
    pub initial_state: String,
    #[serde(default)]
    pub initial_state_meaning: String,
    /// Whether the scored runs agree on the steady state (the calibration-drift evidence, in
    /// words: "runs disagree on the steady state by X %: …" or "… agree …").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steady_states: Option<String>,
    /// Every model that fails on a run (fit below 50 %), in words, with why.
    #[serde(default)]
    pub failing: Vec<String>,
    /// model → run → why it fails there (only failing models).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub failure_reasons: BTreeMap<ModelKind, BTreeMap<String, String>>,
    /// Operating points across the identified range and at the steady run's plateau, each with
    /// its local linear model.
    #[serde(default)]
    pub operating_points: Vec<crate::core::control::OperatingPoint>,
    /// The final model's numbers (static map, effects, continuous-time block) with their 95 %
    /// intervals from its parameter covariance.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub parameter_intervals: Vec<crate::core::control::bands::ParameterInterval>,
    /// Zero-order-hold continuous equivalent of the final model's linear block (input to v).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub continuous: Option<crate::core::control::ContinuousTf>,
    /// How much the channel the steps were detected on moves the plain model, when the steps came
    /// from a channel other than the input.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub preparation: Option<preparation::SegmentationChoice>,
    /// The shaft speed's spool blocks offered to this output's model, and what came of each.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub shared_spool: Vec<crate::core::diagnose::SharedBlock>,
}

/// The residual analysis of one output's final model on one run, as the report keeps it (the
/// per-sample traces are in the figure).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ResidualReport {
    pub run: String,
    /// A few plain sentences on what the residual shows.
    pub summary: String,
    /// Measurement-noise σ the band is drawn with, output unit.
    pub noise_sigma: f64,
    /// Where σ comes from: the steady run's noise fit, or estimated from the run itself.
    pub noise_sigma_source: String,
    /// Share of samples outside the ±2σ band, % (about 4.6 % for a model as good as the sensor).
    pub outside_band_pct: f64,
    /// Whether the band is this residual's noise: false when σ, estimated from the run, is not (the
    /// residual's spectrum near Nyquist lies far above white noise of that σ, or its RMS is more
    /// than a hundred times σ); the share outside then says nothing about the model (see the
    /// summary and `core::residuals::BandFit`).
    #[serde(default = "band_applies")]
    pub noise_band_applies: bool,
    pub regimes: Vec<crate::core::residuals::RegimeRow>,
    /// Residual autocorrelation lags beyond the 99 % bound, s.
    pub acf_lags_beyond_99_secs: Vec<f64>,
    /// Largest residual–input cross-correlation: lag (s, positive: input leads) and value, and
    /// whether it lies beyond the 99 % bound.
    pub input_xcorr_peak: Option<(f64, f64, bool)>,
    /// Frequency of the residual spectrum's largest peak, Hz, and its prominence over the median.
    pub spectrum_peak_hz: f64,
    pub spectrum_peak_prominence: f64,
    /// Recorded channels the model does not use, by correlation with the residual.
    pub channels: Vec<crate::core::residuals::ChannelCorrelation>,
    pub worst_stretches: Vec<crate::core::residuals::Stretch>,
    /// The picture of this analysis, when it was written.
    pub figure: Option<String>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Report {
    pub format_version: u32,
    pub project: String,
    pub input: String,
    /// The input's unit ("" when unknown): the operating points' u* and dy/du are in it.
    #[serde(default)]
    pub input_unit: String,
    pub runs: BTreeMap<String, String>,
    pub outputs: BTreeMap<String, OutputReport>,
    pub noise_fit: Option<serde_json::Value>,
    pub monte_carlo: Option<serde_json::Value>,
    pub timings_ms: BTreeMap<String, f64>,
    pub figures: Vec<String>,
    pub diagnostics: Vec<String>,
}

pub fn write_report_json(path: &Path, report: &Report) -> Result<()> {
    let text = serde_json::to_string_pretty(report).context("serialising the report")?;
    write_atomic(path, text.as_bytes())
}
