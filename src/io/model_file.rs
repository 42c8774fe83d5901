//! `model.json`: everything needed to simulate each output's model again (CONTRACT.md).
use std::path::Path;

use anyhow::{Context, Result, bail};
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use crate::core::identification::cluster::Cluster;
use crate::core::identification::refine::Refinement;
use crate::core::identification::wiener::WienerModel;
use crate::io::atomic::write_atomic;

pub const MODEL_FORMAT_VERSION: u32 = 1;

pub const CONVENTION: &str = "Wiener model u -> G(z) -> v -> f(v) -> y. linear.tf.num_zinv[k] and \
den_zinv[k] multiply z^-k, den_zinv[0] = 1; v = G(z) u + linear.offset, simulated from the steady \
state of the first input sample. f(v) = sum_i static_map.coeffs_scaled[i] * x^i with x = (v - v_center)/v_scale \
= sum_i static_map_beta[i] * v^i on the identified range |x| <= 1; with static_map.beyond = \"end_slope\" the map \
continues beyond it along its tangent at x = +-1 (a missing beyond reads as \"polynomial\": the polynomial everywhere).";

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SignalInfo {
    pub name: String,
    pub unit: String,
}

/// An effect applied to a model, with its fitted parameters (see METHOD.md's catalog).
pub use crate::core::effects::EffectRecord;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OutputModel {
    pub name: String,
    pub unit: String,
    /// The model the file simulates.
    pub wiener: WienerModel,
    /// Plain coefficients β0, β1, … of f(v), for reading (the scaled form above is what is simulated).
    pub static_map_beta: Vec<f64>,
    pub poles: Vec<Complex64>,
    pub zeros: Vec<Complex64>,
    pub clusters: Vec<Cluster>,
    #[serde(default)]
    pub refinement: Option<Refinement>,
    #[serde(default)]
    pub effects: Vec<EffectRecord>,
    /// The covariance of the model's parameters (roots, static map, effects) from its fit to the
    /// identification run (`core::control::covariance`); absent in older files and where the run
    /// does not fix the parameters.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub covariance: Option<crate::core::control::ParameterCovariance>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModelFile {
    pub format_version: u32,
    pub convention: String,
    pub dt_secs: f64,
    pub input: SignalInfo,
    /// The lowest and highest input of the identification run: outside it the model
    /// extrapolates (`jetid predict` says so; absent in older files).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub input_range: Option<[f64; 2]>,
    pub outputs: Vec<OutputModel>,
}

impl ModelFile {
    pub fn new(dt_secs: f64, input: SignalInfo) -> Self {
        Self {
            format_version: MODEL_FORMAT_VERSION,
            convention: CONVENTION.to_owned(),
            dt_secs,
            input,
            input_range: None,
            outputs: Vec::new(),
        }
    }
}

/// What a saved model's output was built from: its clusters and the input dead time the linear
/// block carries (part of the structure the clusters were chosen with).
#[derive(Clone, Debug, PartialEq)]
pub struct SavedStructure {
    pub clusters: Vec<Cluster>,
    pub dead_time_samples: usize,
}

/// The clusters and dead time of every output of a saved model that has clusters, checked against
/// the sample time they will be used with: a z-plane position means a different frequency at
/// another sample time.
pub fn structures_from_model(
    path: &Path,
    dt_secs: f64,
) -> Result<std::collections::BTreeMap<String, SavedStructure>> {
    let model = read_model(path)?;
    if ((model.dt_secs - dt_secs) / dt_secs).abs() > 0.02 {
        bail!(
            "{} was identified at a sample time of {} s, but the identification run is sampled every {} s; its clusters do not apply",
            path.display(),
            crate::core::numerics::stats::significant(model.dt_secs, 5),
            crate::core::numerics::stats::significant(dt_secs, 5)
        );
    }
    Ok(model
        .outputs
        .into_iter()
        .filter(|o| !o.clusters.is_empty())
        .map(|o| {
            let dead_time_samples = o.wiener.linear.tf.input_delay();
            (o.name, SavedStructure { clusters: o.clusters, dead_time_samples })
        })
        .collect())
}

pub fn write_model(path: &Path, model: &ModelFile) -> Result<()> {
    let text = serde_json::to_string_pretty(model).context("serialising the model")?;
    write_atomic(path, text.as_bytes())
}

pub fn read_model(path: &Path) -> Result<ModelFile> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read model file {}", path.display()))?;
    parse_model(&text, path)
}

/// A model file from its JSON text, checked as [`read_model`] checks a file; `path` names it in
/// errors.
pub fn parse_model(text: &str, path: &Path) -> Result<ModelFile> {
    let model: ModelFile = serde_json::from_str(text)
        .with_context(|| format!("{} is not a jetid model file", path.display()))?;
    if model.format_version != MODEL_FORMAT_VERSION {
        bail!(
            "{} has format_version {}, this jetid reads version {MODEL_FORMAT_VERSION}",
            path.display(),
            model.format_version
        );
    }
    if !(model.dt_secs.is_finite() && model.dt_secs > 0.0) {
        bail!("{}: dt_secs must be positive, got {}", path.display(), model.dt_secs);
    }
    for out in &model.outputs {
        // Re-check what the constructor checks, so a hand-edited file cannot panic the simulation.
        crate::core::numerics::tf::DiscreteTf::new(
            out.wiener.linear.tf.num_zinv.clone(),
            out.wiener.linear.tf.den_zinv.clone(),
            out.wiener.linear.tf.dt_secs,
        )
        .with_context(|| format!("{}: output '{}'", path.display(), out.name))?;
        if out.wiener.map.coeffs_scaled.is_empty() || !out.wiener.map.v_scale.is_normal() {
            bail!("{}: output '{}' has an empty static map or a zero v_scale", path.display(), out.name);
        }
    }
    Ok(model)
}
