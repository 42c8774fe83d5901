//! What the diagnosis of a fleet run found (see `fleet::diagnosis`): the types a run's score
//! carries, read by the flags and the table.
use serde::{Deserialize, Serialize};

use crate::core::control::bands::ParameterInterval;
use crate::core::effects::EffectId;

/// An effect the diagnosis finds significant on a run, for one output.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Finding {
    pub output: String,
    pub effect: EffectId,
    /// The test's one-sided p-value.
    pub p_value: f64,
    /// The second part's error beyond the noise (in units of the noise) of the reference refitted on
    /// the first part, and of the reference with the effect.
    pub beyond_noise_before: f64,
    pub beyond_noise_after: f64,
    /// The evidence sentence read from the reference's residuals.
    pub evidence: String,
    /// The effect's parameters with their 95 % intervals (empty when the covariance cannot be
    /// estimated; the note says why).
    pub params: Vec<ParameterInterval>,
    /// The other effects the diagnosis finds significant on this output, each with its error beyond
    /// the noise: they explain less of the same residual (ranked below `effect`).
    #[serde(default)]
    pub also: Vec<(EffectId, f64)>,
}

/// What the diagnosis of one run found, and what it could not do.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RunDiagnosis {
    /// The outputs the diagnosis ran on.
    pub diagnosed: Vec<String>,
    pub findings: Vec<Finding>,
    pub notes: Vec<String>,
}
