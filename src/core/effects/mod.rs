//! The missing-physics catalog of METHOD.md as blocks of the model.
//!
//! The base model is the Wiener model `u → G(z) → v → f(v) → y`. Each effect adds one physical
//! mechanism to it, with its own fitted parameters, and effects compose. Whatever order they are
//! added in, they act in the order of the signal path:
//!
//! ```text
//! u ─ambient: u/(δ√θ)─▶ transport delay z⁻ᵈ ─▶ G(z) (asymmetric: rise/fall time constants;
//!   scheduled: the spool time constant follows the operating point)
//!   ─▶ thermal soak branch ─▶ v ─▶ f(v) (+ static-map kink) ─ambient: ·√θ or ·δ─▶ sensor ─▶ y
//! ```
//!
//! Every block has a stable serialisable form, [`EffectRecord`] `{ id, params }`, with
//! [`EffectBlock::params`] and [`EffectBlock::from_params`] as the two directions (parameters are
//! checked there). [`ExtendedModel`] is the base model with its effects; the fitting of a block on
//! identification data lives in `fit` and the diagnosis that ranks them in `core::diagnose`.
use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

mod ambient_correction;
mod asymmetric_dynamics;
mod fit;
mod model;
mod scheduled_time_constant;
mod sensor_dynamics;
mod solver;
mod static_map_order;
pub mod stats;
mod structural;
mod thermal_soak;
pub mod transport_delay;

pub use ambient_correction::AmbientCorrection;
pub use asymmetric_dynamics::AsymmetricDynamics;
pub use fit::{FitData, apply_effect, refit, refit_static};
pub use model::ExtendedModel;
pub use scheduled_time_constant::ScheduledTimeConstant;
pub use sensor_dynamics::SensorDynamics;
pub use static_map_order::StaticMapOrder;
pub use structural::{StructuralChange, refine_structure};
pub use thermal_soak::ThermalSoak;
pub use transport_delay::TransportDelay;

/// Effect ids in the order of METHOD.md's catalog: the physics the diagnosis tries.
pub const EFFECT_IDS: [&str; 6] = [
    TransportDelay::ID,
    ThermalSoak::ID,
    AmbientCorrection::ID,
    AsymmetricDynamics::ID,
    SensorDynamics::ID,
    StaticMapOrder::ID,
];

/// Every block a model can hold, in signal-path order: the catalog's effects and the scheduled
/// time constant, which refines the model's own structure (the diagnosis tries it as structure).
pub const BLOCK_IDS: [&str; 7] = [
    TransportDelay::ID,
    ThermalSoak::ID,
    AmbientCorrection::ID,
    AsymmetricDynamics::ID,
    ScheduledTimeConstant::ID,
    SensorDynamics::ID,
    StaticMapOrder::ID,
];

/// One parameter of an effect block: its name (with unit suffix) and admissible range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamSpec {
    /// Name, with a unit suffix where it has a unit.
    pub name: &'static str,
    /// Smallest admissible value.
    pub min: f64,
    /// Largest admissible value.
    pub max: f64,
}

impl ParamSpec {
    const fn real(name: &'static str, min: f64, max: f64) -> Self {
        Self { name, min, max }
    }
}

/// Errors a user can cause with effects: bad ids or parameters, missing channels, misuse.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EffectError {
    /// The id is not in the catalog.
    #[error("unknown effect '{id}' (known: {})", known.join(", "))]
    UnknownEffect { id: String, known: Vec<String> },
    /// The effect has no such parameter.
    #[error("effect '{effect}' has no parameter '{param}' (its parameters: {})", known.join(", "))]
    UnknownParameter { effect: String, param: String, known: Vec<String> },
    /// A parameter is missing from a record.
    #[error("effect '{effect}' needs the parameter '{param}'")]
    MissingParameter { effect: String, param: String },
    /// A parameter is not finite or outside its range.
    #[error("{effect}.{param} = {value} is outside its range [{min}, {max}]")]
    ParameterOutOfRange { effect: String, param: String, value: f64, min: f64, max: f64 },
    /// A run lacks a channel the effect reads.
    #[error("effect '{effect}' needs the channel '{channel}', which run '{run}' does not have")]
    MissingChannel { effect: String, channel: String, run: String },
    /// A channel is not as long as its run.
    #[error("channel '{channel}' of run '{run}' has {found} samples, the run has {expected}")]
    ChannelLength { channel: String, run: String, found: usize, expected: usize },
    /// A channel holds an unphysical value (absolute temperature or pressure not positive).
    #[error("channel '{channel}' of run '{run}' has the unphysical value {value} at sample {index}")]
    BadChannelValue { channel: String, run: String, index: usize, value: f64 },
    /// Each effect can be in a model once.
    #[error("effect '{effect}' is already in the model")]
    AlreadyApplied { effect: String },
    /// Only an applied effect can be removed.
    #[error("effect '{effect}' is not in the model")]
    NotApplied { effect: String },
    /// The effect makes no sense for this model or output.
    #[error("effect '{effect}' does not apply to this model: {reason}")]
    NotApplicable { effect: String, reason: String },
    /// The linear block's roots cannot be computed or used.
    #[error("the model's linear block is not usable: {reason}")]
    BadBaseModel { reason: String },
    /// No admissible fit on the identification data.
    #[error("fitting the model on run '{run}' failed: {reason}")]
    FitFailed { run: String, reason: String },
}

/// The stable, serialisable form of an effect block: its catalog id and named parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EffectRecord {
    /// Catalog id.
    pub id: String,
    /// Parameters by name (see [`param_specs`]).
    pub params: BTreeMap<String, f64>,
}

/// One effect of the catalog with its fitted parameters.
#[derive(Clone, Debug, PartialEq)]
pub enum EffectBlock {
    /// See [`TransportDelay`].
    TransportDelay(TransportDelay),
    /// See [`ThermalSoak`].
    ThermalSoak(ThermalSoak),
    /// See [`AmbientCorrection`].
    AmbientCorrection(AmbientCorrection),
    /// See [`AsymmetricDynamics`].
    AsymmetricDynamics(AsymmetricDynamics),
    /// See [`SensorDynamics`].
    SensorDynamics(SensorDynamics),
    /// See [`StaticMapOrder`].
    StaticMapOrder(StaticMapOrder),
    /// See [`ScheduledTimeConstant`].
    ScheduledTimeConstant(ScheduledTimeConstant),
}

/// The known block ids as owned strings (for error messages).
fn known_ids() -> Vec<String> {
    BLOCK_IDS.iter().map(|s| (*s).to_owned()).collect()
}

/// Check that `id` names a block (an effect of the catalog or the scheduled time constant).
pub fn check_id(id: &str) -> Result<&'static str, EffectError> {
    BLOCK_IDS
        .iter()
        .find(|known| **known == id)
        .copied()
        .ok_or_else(|| EffectError::UnknownEffect { id: id.to_owned(), known: known_ids() })
}

/// The parameters an effect id accepts.
pub fn param_specs(id: &str) -> Result<&'static [ParamSpec], EffectError> {
    Ok(match check_id(id)? {
        TransportDelay::ID => TransportDelay::PARAMS,
        ThermalSoak::ID => ThermalSoak::PARAMS,
        AmbientCorrection::ID => AmbientCorrection::PARAMS,
        AsymmetricDynamics::ID => AsymmetricDynamics::PARAMS,
        SensorDynamics::ID => SensorDynamics::PARAMS,
        ScheduledTimeConstant::ID => ScheduledTimeConstant::PARAMS,
        _ => StaticMapOrder::PARAMS,
    })
}

/// What an effect means physically and what it changes in the model, in one sentence.
pub fn physics(id: &str) -> Result<&'static str, EffectError> {
    Ok(match check_id(id)? {
        TransportDelay::ID => "fuel line and valve dead time: the input reaches the engine d samples late",
        ThermalSoak::ID => {
            "casing and rotor absorb heat after a power change: a share g of every change arrives \
             with a slow time constant τ"
        }
        AmbientCorrection::ID => {
            "the engine scales with inlet conditions: it runs on corrected fuel u/(δ√θ) and gives \
             corrected speed N/√θ or thrust F/δ"
        }
        AsymmetricDynamics::ID => {
            "acceleration and deceleration differ: the spool time constant is scaled while slowing down"
        }
        SensorDynamics::ID => "load cell or stand resonance and sensor lag: a second-order sensor block",
        ScheduledTimeConstant::ID => {
            "the spool time constant changes with the operating point (slower at low speed): the \
             slowest pole is scheduled on the operating point"
        }
        _ => "the static map is too simple: a kink (bleed valve, limiter) is added to f(v)",
    })
}

/// What the current model's residuals say about an effect: one sentence, and whether it shows the
/// effect's signature at all. The thresholds are the evidence sentences' own words: where the
/// sentence says there is little or nothing ("little slow creep", "no sharp resonance", "rise and
/// fall look alike", "within noise", "responses start with the model's"), the evidence does not
/// support the effect.
#[derive(Clone, Debug, PartialEq)]
pub struct Evidence {
    pub sentence: String,
    pub supports: bool,
}

impl Evidence {
    /// Evidence that says nothing for the effect.
    fn none(sentence: &str) -> Self {
        Self { sentence: sentence.to_owned(), supports: false }
    }
}

/// The evidence for effect `id`, computed from the current model's residuals on the given runs
/// (identification range and validation runs).
pub fn evidence(id: &str, traces: &[stats::ResidualTrace]) -> Result<Evidence, EffectError> {
    Ok(match check_id(id)? {
        TransportDelay::ID => transport_delay::evidence(traces),
        ThermalSoak::ID => thermal_soak::evidence(traces),
        AmbientCorrection::ID => ambient_correction::evidence(traces),
        AsymmetricDynamics::ID => asymmetric_dynamics::evidence(traces),
        SensorDynamics::ID => sensor_dynamics::evidence(traces),
        ScheduledTimeConstant::ID => asymmetric_dynamics::level_evidence(traces),
        _ => static_map_order::evidence(traces),
    })
}

/// Check named parameters against an effect's specs; returns the values in spec order.
fn checked_values(id: &str, params: &BTreeMap<String, f64>) -> Result<Vec<f64>, EffectError> {
    let specs = param_specs(id)?;
    if let Some(name) = params.keys().find(|name| !specs.iter().any(|s| s.name == name.as_str())) {
        return Err(EffectError::UnknownParameter {
            effect: id.to_owned(),
            param: name.clone(),
            known: specs.iter().map(|s| s.name.to_owned()).collect(),
        });
    }
    specs.iter().map(|spec| check_value(id, spec, params.get(spec.name).copied())).collect()
}

fn check_value(id: &str, spec: &ParamSpec, value: Option<f64>) -> Result<f64, EffectError> {
    let Some(value) = value else {
        return Err(EffectError::MissingParameter { effect: id.to_owned(), param: spec.name.to_owned() });
    };
    if !value.is_finite() || value < spec.min || value > spec.max {
        return Err(EffectError::ParameterOutOfRange {
            effect: id.to_owned(),
            param: spec.name.to_owned(),
            value,
            min: spec.min,
            max: spec.max,
        });
    }
    Ok(value)
}

/// The value at `index` of a checked list (specs and values have equal lengths by construction).
fn value_at(values: &[f64], index: usize) -> f64 {
    values.get(index).copied().unwrap_or(0.0)
}

impl EffectBlock {
    /// The catalog id.
    pub fn id(&self) -> &'static str {
        match self {
            Self::TransportDelay(_) => TransportDelay::ID,
            Self::ThermalSoak(_) => ThermalSoak::ID,
            Self::AmbientCorrection(_) => AmbientCorrection::ID,
            Self::AsymmetricDynamics(_) => AsymmetricDynamics::ID,
            Self::SensorDynamics(_) => SensorDynamics::ID,
            Self::StaticMapOrder(_) => StaticMapOrder::ID,
            Self::ScheduledTimeConstant(_) => ScheduledTimeConstant::ID,
        }
    }

    /// Position in the signal path.
    pub fn rank(&self) -> usize {
        BLOCK_IDS.iter().position(|id| *id == self.id()).unwrap_or(BLOCK_IDS.len())
    }

    /// Parameter values in the order of [`param_specs`].
    fn values(&self) -> Vec<f64> {
        match self {
            Self::TransportDelay(b) => vec![b.delay_samples],
            Self::ThermalSoak(b) => vec![b.gain, b.tau_s],
            Self::AmbientCorrection(b) => vec![b.output_theta_exp, b.output_delta_exp],
            Self::AsymmetricDynamics(b) => vec![b.decel_factor],
            Self::SensorDynamics(b) => vec![b.freq_hz, b.zeta, b.lag_s],
            Self::StaticMapOrder(b) => vec![b.knot_v, b.slope_change],
            Self::ScheduledTimeConstant(b) => vec![b.log_ratio, b.state_log_ratio, b.ref_input, b.input_span],
        }
    }

    /// Named parameters (the serialisable form).
    pub fn params(&self) -> BTreeMap<String, f64> {
        let specs = param_specs(self.id()).unwrap_or(&[]);
        specs.iter().zip(self.values()).map(|(s, v)| (s.name.to_owned(), v)).collect()
    }

    /// Build a block from named parameters; every parameter is required and checked.
    pub fn from_params(id: &str, params: &BTreeMap<String, f64>) -> Result<Self, EffectError> {
        let v = checked_values(id, params)?;
        let at = |i| value_at(&v, i);
        Ok(match check_id(id)? {
            TransportDelay::ID => Self::TransportDelay(TransportDelay { delay_samples: at(0) }),
            ThermalSoak::ID => Self::ThermalSoak(ThermalSoak { gain: at(0), tau_s: at(1) }),
            AmbientCorrection::ID => Self::AmbientCorrection(AmbientCorrection {
                output_theta_exp: at(0),
                output_delta_exp: at(1),
            }),
            AsymmetricDynamics::ID => Self::AsymmetricDynamics(AsymmetricDynamics { decel_factor: at(0) }),
            SensorDynamics::ID => {
                Self::SensorDynamics(SensorDynamics { freq_hz: at(0), zeta: at(1), lag_s: at(2) })
            }
            ScheduledTimeConstant::ID => Self::ScheduledTimeConstant(ScheduledTimeConstant {
                log_ratio: at(0),
                state_log_ratio: at(1),
                ref_input: at(2),
                input_span: at(3),
            }),
            _ => Self::StaticMapOrder(StaticMapOrder { knot_v: at(0), slope_change: at(1) }),
        })
    }

    /// The serialisable record.
    pub fn record(&self) -> EffectRecord {
        EffectRecord { id: self.id().to_owned(), params: self.params() }
    }

    /// Build from a record (checked).
    pub fn from_record(record: &EffectRecord) -> Result<Self, EffectError> {
        Self::from_params(&record.id, &record.params)
    }

    /// Channels (besides the input and the output) the block reads from every run.
    pub fn required_channels(&self) -> &'static [&'static str] {
        match self {
            Self::AmbientCorrection(_) => AmbientCorrection::CHANNELS,
            _ => &[],
        }
    }

    /// Parameters the fit moves continuously, in an unconstrained form.
    fn free_params(&self) -> Vec<f64> {
        match self {
            Self::TransportDelay(b) => b.free_params(),
            Self::ThermalSoak(b) => b.free_params(),
            Self::AsymmetricDynamics(b) => b.free_params(),
            Self::SensorDynamics(b) => b.free_params(),
            Self::StaticMapOrder(b) => b.free_params(),
            Self::ScheduledTimeConstant(b) => b.free_params(),
            Self::AmbientCorrection(_) => Vec::new(),
        }
    }

    /// The block with new free parameters, or `None` where they leave the admissible range.
    fn with_free_params(&self, theta: &[f64], dt_secs: f64) -> Option<Self> {
        Some(match self {
            Self::TransportDelay(b) => Self::TransportDelay(b.with_free_params(theta)?),
            Self::ThermalSoak(b) => Self::ThermalSoak(b.with_free_params(theta)?),
            Self::AsymmetricDynamics(b) => Self::AsymmetricDynamics(b.with_free_params(theta)?),
            Self::SensorDynamics(b) => Self::SensorDynamics(b.with_free_params(theta, dt_secs)?),
            Self::StaticMapOrder(b) => Self::StaticMapOrder(b.with_free_params(theta)?),
            Self::ScheduledTimeConstant(b) => Self::ScheduledTimeConstant(b.with_free_params(theta)?),
            Self::AmbientCorrection(_) => self.clone(),
        })
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn every_effect_round_trips_through_its_record() {
        let blocks = [
            EffectBlock::TransportDelay(TransportDelay { delay_samples: 4.0 }),
            EffectBlock::ThermalSoak(ThermalSoak { gain: 0.1, tau_s: 40.0 }),
            EffectBlock::AmbientCorrection(AmbientCorrection {
                output_theta_exp: 0.5,
                output_delta_exp: 0.0,
            }),
            EffectBlock::AsymmetricDynamics(AsymmetricDynamics { decel_factor: 1.8 }),
            EffectBlock::SensorDynamics(SensorDynamics { freq_hz: 1.4, zeta: 0.06, lag_s: 0.3 }),
            EffectBlock::StaticMapOrder(StaticMapOrder { knot_v: 80_000.0, slope_change: -0.5 }),
        ];
        for (block, id) in blocks.iter().zip(EFFECT_IDS) {
            assert_eq!(block.id(), id);
            let record = block.record();
            let json = serde_json::to_string(&record).unwrap();
            let back: EffectRecord = serde_json::from_str(&json).unwrap();
            assert_eq!(&EffectBlock::from_record(&back).unwrap(), block);
            assert!(physics(id).unwrap().len() > 20);
        }
    }
}
