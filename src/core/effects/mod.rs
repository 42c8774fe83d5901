//! The missing-physics catalog of METHOD.md as blocks of the model.
//!
//! The base model is the Wiener model `u → G(z) → v → f(v) → y`. Each effect adds one physical
//! mechanism to it, with its own fitted parameters, and effects compose. Whatever order they are
//! added in, they act in the order of the signal path:
//!
//! ```text
//! u ─ambient: u/(δ√θ)─▶ transport delay z⁻ᵈ ─▶ G(z) (asymmetric: rise/fall time constants;
//!   scheduled: the spool time constant follows the operating point)
//!   ─▶ thermal soak branch ─▶ rate limit ─▶ v ─▶ f(v) (+ static-map kink) ─ambient: ·√θ or ·δ─▶ sensor ─▶ y
//! ```
//!
//! An output read off the shaft speed's model ([`ReadOffSpeed`]) holds the speed's whole path, `y`
//! being the speed, and one more stage at its end: `P(y)`.
//!
//! Every block has a stable serialisable form, [`EffectRecord`] `{ id, params }`, with
//! [`EffectBlock::params`] and [`EffectBlock::from_params`] as the two directions (parameters are
//! checked there). [`ExtendedModel`] is the base model with its effects; the fitting of a block on
//! identification data lives in `fit` and the diagnosis that ranks them in `core::diagnose`.
use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// `block_impl!(Type { field, … }, params: …, physics: …, evidence: fn)`: the [`Block`] of a block
/// whose parameters are its fields, in the order of its parameter specs.
macro_rules! block_impl {
    ($t:ident { $($field:ident),+ }, params: $params:expr, physics: $physics:expr, evidence: $evidence:expr) => {
        impl super::Block for $t {
            const ID: super::EffectId = super::EffectId::$t;
            const PARAMS: &'static [ParamSpec] = $params;
            const PHYSICS: &'static str = $physics;

            fn values(&self) -> Vec<f64> {
                vec![$(self.$field),+]
            }

            fn from_values(values: &[f64]) -> Self {
                let mut values = values.iter().copied();
                Self { $($field: values.next().unwrap_or(0.0)),+ }
            }

            fn evidence(traces: &[ResidualTrace]) -> Evidence {
                $evidence(traces)
            }
        }
    };
}

mod ambient_correction;
mod asymmetric_dynamics;
mod calibration_drift;
mod fit;
mod id;
mod model;
pub(crate) mod power_balance;
mod rate_limit;
mod read_off_speed;
mod scheduled_time_constant;
mod sensor_dynamics;
mod spool;
mod stages;
mod static_map_order;
pub mod stats;
mod structural;
pub(crate) mod thermal_soak;
pub mod transport_delay;
mod wording;

pub use ambient_correction::AmbientCorrection;
pub use asymmetric_dynamics::AsymmetricDynamics;
pub use calibration_drift::{CalibrationDrift, evidence as steady_state_agreement};
pub use fit::{
    ALTERNATING_POLE_SHARE, Alternating, FOLDS, FitData, MIN_HELD_OUT_SEGMENTS, admissible, apply_effect,
    refit, refit_static,
};
pub use id::EffectId;
pub use model::ExtendedModel;
pub use rate_limit::{RateLimit, limits_own_rate};
pub use read_off_speed::ReadOffSpeed;
pub use scheduled_time_constant::ScheduledTimeConstant;
pub use sensor_dynamics::SensorDynamics;
pub use static_map_order::StaticMapOrder;
pub use structural::{StructuralChange, refine_structure};
pub use thermal_soak::{FAN_LAW_EXPONENT, ThermalSoak, exponent_affine_in_power};
pub use transport_delay::TransportDelay;

/// One parameter of an effect block: its name (with unit suffix) and admissible range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamSpec {
    /// Name, with a unit suffix where it has a unit.
    pub name: &'static str,
    /// Smallest admissible value.
    pub min: f64,
    /// Largest admissible value.
    pub max: f64,
    /// The value a record without the parameter reads as: set for a parameter added after model
    /// files were first written, so that such a file predicts as it always did.
    pub absent: Option<f64>,
}

impl ParamSpec {
    const fn real(name: &'static str, min: f64, max: f64) -> Self {
        Self { name, min, max, absent: None }
    }

    /// A parameter that model files written before it existed lack, read as `absent`.
    const fn added_later(name: &'static str, min: f64, max: f64, absent: f64) -> Self {
        Self { name, min, max, absent: Some(absent) }
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
    pub id: EffectId,
    /// Parameters by name (see [`param_specs`]).
    pub params: BTreeMap<String, f64>,
}

/// What every block of the model says about itself: its id, parameters, physics and the evidence
/// for it in a model's residuals. Adding a block: a variant of [`EffectId`] and of [`EffectBlock`],
/// and this trait.
pub trait Block: Sized {
    const ID: EffectId;
    /// Its parameters, with unit suffixes and admissible ranges, in the order of [`Self::values`].
    const PARAMS: &'static [ParamSpec];
    /// What it means physically and what it changes in the model, in one sentence.
    const PHYSICS: &'static str;
    /// Parameter values in the order of [`Self::PARAMS`].
    fn values(&self) -> Vec<f64>;
    /// The block from values in the order of [`Self::PARAMS`], already checked against them.
    fn from_values(values: &[f64]) -> Self;
    /// What the current model's residuals say about this block.
    fn evidence(traces: &[stats::ResidualTrace]) -> Evidence;
}

/// What [`EffectId`] needs of a block type, gathered once per id.
struct BlockInfo {
    params: &'static [ParamSpec],
    physics: &'static str,
    evidence: fn(&[stats::ResidualTrace]) -> Evidence,
}

impl BlockInfo {
    fn of<B: Block>() -> Self {
        Self { params: B::PARAMS, physics: B::PHYSICS, evidence: B::evidence }
    }
}

/// The object-safe part of [`Block`], for a block held in an [`EffectBlock`].
trait BlockValues {
    fn id(&self) -> EffectId;
    fn values(&self) -> Vec<f64>;
}

impl<B: Block> BlockValues for B {
    fn id(&self) -> EffectId {
        B::ID
    }

    fn values(&self) -> Vec<f64> {
        Block::values(self)
    }
}

impl EffectId {
    fn info(self) -> BlockInfo {
        match self {
            Self::CalibrationDrift => BlockInfo::of::<CalibrationDrift>(),
            Self::TransportDelay => BlockInfo::of::<TransportDelay>(),
            Self::ThermalSoak => BlockInfo::of::<ThermalSoak>(),
            Self::AmbientCorrection => BlockInfo::of::<AmbientCorrection>(),
            Self::AsymmetricDynamics => BlockInfo::of::<AsymmetricDynamics>(),
            Self::ScheduledTimeConstant => BlockInfo::of::<ScheduledTimeConstant>(),
            Self::RateLimit => BlockInfo::of::<RateLimit>(),
            Self::SensorDynamics => BlockInfo::of::<SensorDynamics>(),
            Self::StaticMapOrder => BlockInfo::of::<StaticMapOrder>(),
            Self::ReadOffSpeed => BlockInfo::of::<ReadOffSpeed>(),
        }
    }

    /// The parameters the block accepts.
    pub fn param_specs(self) -> &'static [ParamSpec] {
        self.info().params
    }

    /// What the block means physically and what it changes in the model, in one sentence.
    pub fn physics(self) -> &'static str {
        self.info().physics
    }

    /// Whether the block acts before the spool that every output follows: on the fuel (a meter's
    /// calibration, the line's dead time, the ECU's acceleration schedule) or on the spool's own
    /// dynamics (soak, asymmetric or scheduled spool time constants). Its signature is then the
    /// spool's, and it is read where the spool is measured (see `core::diagnose::spool_witness`).
    /// Ambient correction is not among them: it corrects each output by its own exponent.
    pub fn acts_before_spool(self) -> bool {
        matches!(
            self,
            Self::CalibrationDrift
                | Self::TransportDelay
                | Self::ThermalSoak
                | Self::RateLimit
                | Self::AsymmetricDynamics
                | Self::ScheduledTimeConstant
        )
    }

    /// The evidence for the block, computed from the current model's residuals on the given runs
    /// (identification range and validation runs).
    pub fn evidence(self, traces: &[stats::ResidualTrace]) -> Evidence {
        (self.info().evidence)(traces)
    }
}

/// One effect of the catalog with its fitted parameters.
#[derive(Clone, Debug, PartialEq)]
pub enum EffectBlock {
    /// See [`CalibrationDrift`].
    CalibrationDrift(CalibrationDrift),
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
    /// See [`RateLimit`].
    RateLimit(RateLimit),
    /// See [`ReadOffSpeed`].
    ReadOffSpeed(ReadOffSpeed),
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

/// Check named parameters against an effect's specs; returns the values in spec order.
fn checked_values(id: EffectId, params: &BTreeMap<String, f64>) -> Result<Vec<f64>, EffectError> {
    let specs = id.param_specs();
    if let Some(name) = params.keys().find(|name| !specs.iter().any(|s| s.name == name.as_str())) {
        return Err(EffectError::UnknownParameter {
            effect: id.name().to_owned(),
            param: name.clone(),
            known: specs.iter().map(|s| s.name.to_owned()).collect(),
        });
    }
    specs.iter().map(|spec| check_value(id, spec, params.get(spec.name).copied())).collect()
}

fn check_value(id: EffectId, spec: &ParamSpec, value: Option<f64>) -> Result<f64, EffectError> {
    let Some(value) = value.or(spec.absent) else {
        return Err(EffectError::MissingParameter {
            effect: id.name().to_owned(),
            param: spec.name.to_owned(),
        });
    };
    if !value.is_finite() || value < spec.min || value > spec.max {
        return Err(EffectError::ParameterOutOfRange {
            effect: id.name().to_owned(),
            param: spec.name.to_owned(),
            value,
            min: spec.min,
            max: spec.max,
        });
    }
    Ok(value)
}

impl EffectBlock {
    /// The block's id.
    pub fn id(&self) -> EffectId {
        self.as_values().id()
    }

    fn as_values(&self) -> &dyn BlockValues {
        match self {
            Self::CalibrationDrift(b) => b,
            Self::TransportDelay(b) => b,
            Self::ThermalSoak(b) => b,
            Self::AmbientCorrection(b) => b,
            Self::AsymmetricDynamics(b) => b,
            Self::ScheduledTimeConstant(b) => b,
            Self::RateLimit(b) => b,
            Self::SensorDynamics(b) => b,
            Self::StaticMapOrder(b) => b,
            Self::ReadOffSpeed(b) => b,
        }
    }

    /// Whether the block shapes the linear part of a fit's simulation (see `fit::LinearPart`): it
    /// acts on the input or the spool. A rate limit, the stand's dynamics, the map's kink and a read-off
    /// of the speed act after it. A calibration drift and the ambient correction count as shaping it (the drift's
    /// offset and the correction's factors reach the input).
    pub(crate) fn shapes_linear_part(&self) -> bool {
        !matches!(
            self,
            Self::RateLimit(_) | Self::SensorDynamics(_) | Self::StaticMapOrder(_) | Self::ReadOffSpeed(_)
        )
    }

    /// Position in the signal path.
    pub fn rank(&self) -> usize {
        self.id().rank()
    }

    /// Parameter values in the order of [`EffectId::param_specs`].
    fn values(&self) -> Vec<f64> {
        self.as_values().values()
    }

    /// Named parameters (the serialisable form).
    pub fn params(&self) -> BTreeMap<String, f64> {
        let specs = self.id().param_specs();
        specs.iter().zip(self.values()).map(|(s, v)| (s.name.to_owned(), v)).collect()
    }

    /// Build a block from named parameters; every parameter is required and checked.
    pub fn from_params(id: EffectId, params: &BTreeMap<String, f64>) -> Result<Self, EffectError> {
        let v = checked_values(id, params)?;
        Ok(match id {
            EffectId::CalibrationDrift => Self::CalibrationDrift(Block::from_values(&v)),
            EffectId::TransportDelay => Self::TransportDelay(Block::from_values(&v)),
            EffectId::ThermalSoak => Self::ThermalSoak(Block::from_values(&v)),
            EffectId::AmbientCorrection => Self::AmbientCorrection(Block::from_values(&v)),
            EffectId::AsymmetricDynamics => Self::AsymmetricDynamics(Block::from_values(&v)),
            EffectId::ScheduledTimeConstant => Self::ScheduledTimeConstant(Block::from_values(&v)),
            EffectId::RateLimit => Self::RateLimit(Block::from_values(&v)),
            EffectId::SensorDynamics => Self::SensorDynamics(Block::from_values(&v)),
            EffectId::StaticMapOrder => Self::StaticMapOrder(Block::from_values(&v)),
            EffectId::ReadOffSpeed => Self::ReadOffSpeed(Block::from_values(&v)),
        })
    }

    /// The serialisable record.
    pub fn record(&self) -> EffectRecord {
        EffectRecord { id: self.id(), params: self.params() }
    }

    /// Build from a record (checked).
    pub fn from_record(record: &EffectRecord) -> Result<Self, EffectError> {
        Self::from_params(record.id, &record.params)
    }

    /// Channels (besides the input and the output) the block reads from every run.
    pub fn required_channels(&self) -> &'static [&'static str] {
        match self {
            Self::AmbientCorrection(_) => AmbientCorrection::CHANNELS,
            _ => &[],
        }
    }

    /// Parameters the fit moves continuously, in an unconstrained form.
    pub(crate) fn free_params(&self) -> Vec<f64> {
        match self {
            Self::TransportDelay(b) => b.free_params(),
            Self::ThermalSoak(b) => b.free_params(),
            Self::AsymmetricDynamics(b) => b.free_params(),
            Self::SensorDynamics(b) => b.free_params(),
            Self::StaticMapOrder(b) => b.free_params(),
            Self::ScheduledTimeConstant(b) => b.free_params(),
            Self::RateLimit(b) => b.free_params(),
            Self::AmbientCorrection(_) | Self::CalibrationDrift(_) | Self::ReadOffSpeed(_) => Vec::new(),
        }
    }

    /// The block with new free parameters, or `None` where they leave the admissible range.
    pub(crate) fn with_free_params(&self, theta: &[f64], dt_secs: f64) -> Option<Self> {
        Some(match self {
            Self::TransportDelay(b) => Self::TransportDelay(b.with_free_params(theta)?),
            Self::ThermalSoak(b) => Self::ThermalSoak(b.with_free_params(theta)?),
            Self::AsymmetricDynamics(b) => Self::AsymmetricDynamics(b.with_free_params(theta)?),
            Self::SensorDynamics(b) => Self::SensorDynamics(b.with_free_params(theta, dt_secs)?),
            Self::StaticMapOrder(b) => Self::StaticMapOrder(b.with_free_params(theta)?),
            Self::ScheduledTimeConstant(b) => Self::ScheduledTimeConstant(b.with_free_params(theta)?),
            Self::RateLimit(b) => Self::RateLimit(b.with_free_params(theta)?),
            Self::AmbientCorrection(_) | Self::CalibrationDrift(_) | Self::ReadOffSpeed(_) => self.clone(),
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
            EffectBlock::ThermalSoak(ThermalSoak { gain: 0.1, tau_s: 40.0, power_exponent: 0.6 }),
            EffectBlock::AmbientCorrection(AmbientCorrection {
                output_theta_exp: 0.5,
                output_delta_exp: 0.0,
            }),
            EffectBlock::AsymmetricDynamics(AsymmetricDynamics { decel_factor: 1.8 }),
            EffectBlock::SensorDynamics(SensorDynamics { freq_hz: 1.4, zeta: 0.06, lag_s: 0.3 }),
            EffectBlock::StaticMapOrder(StaticMapOrder { knot_v: 80_000.0, slope_change: -0.5 }),
            EffectBlock::RateLimit(RateLimit { rise_per_s: 6000.0, fall_per_s: 9000.0 }),
            EffectBlock::CalibrationDrift(CalibrationDrift { hold_s: 4.0 }),
        ];
        for (block, id) in blocks.iter().zip(EffectId::CATALOG) {
            assert_eq!(block.id(), id);
            let record = block.record();
            let json = serde_json::to_string(&record).unwrap();
            let back: EffectRecord = serde_json::from_str(&json).unwrap();
            assert_eq!(&EffectBlock::from_record(&back).unwrap(), block);
            assert!(id.physics().len() > 20);
        }
    }
}
