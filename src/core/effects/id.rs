//! The blocks a model can hold, as one type: parsed from the command line (clap), from project,
//! session and model files (serde), and from the app's commands ([`std::str::FromStr`]). Their
//! names are written here and nowhere else.
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::EffectError;

/// A block of the model: an effect of METHOD.md's catalog, the scheduled spool time constant (a
/// refinement of the model's own structure that the diagnosis tries as structure), or an output
/// read off the shaft speed's model (a form the spool sharing offers).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum EffectId {
    CalibrationDrift,
    TransportDelay,
    ThermalSoak,
    AmbientCorrection,
    AsymmetricDynamics,
    ScheduledTimeConstant,
    RateLimit,
    SensorDynamics,
    StaticMapOrder,
    ReadOffSpeed,
}

impl EffectId {
    /// Every block, in signal-path order.
    pub const ALL: [Self; 10] = [
        Self::CalibrationDrift,
        Self::TransportDelay,
        Self::ThermalSoak,
        Self::AmbientCorrection,
        Self::AsymmetricDynamics,
        Self::ScheduledTimeConstant,
        Self::RateLimit,
        Self::SensorDynamics,
        Self::StaticMapOrder,
        Self::ReadOffSpeed,
    ];

    /// The physics the diagnosis tries, in the order of METHOD.md's catalog.
    pub const CATALOG: [Self; 8] = [
        Self::TransportDelay,
        Self::ThermalSoak,
        Self::AmbientCorrection,
        Self::AsymmetricDynamics,
        Self::SensorDynamics,
        Self::StaticMapOrder,
        Self::RateLimit,
        Self::CalibrationDrift,
    ];

    /// The id as files and the command line spell it.
    pub fn name(self) -> &'static str {
        match self {
            Self::CalibrationDrift => "calibration_drift",
            Self::TransportDelay => "transport_delay",
            Self::ThermalSoak => "thermal_soak",
            Self::AmbientCorrection => "ambient_correction",
            Self::AsymmetricDynamics => "asymmetric_dynamics",
            Self::ScheduledTimeConstant => "scheduled_time_constant",
            Self::RateLimit => "rate_limit",
            Self::SensorDynamics => "sensor_dynamics",
            Self::StaticMapOrder => "static_map_order",
            Self::ReadOffSpeed => "read_off_speed",
        }
    }

    /// Position in the signal path.
    pub fn rank(self) -> usize {
        Self::ALL.iter().position(|id| *id == self).unwrap_or(Self::ALL.len())
    }

    /// The names of `ids`, for messages.
    pub fn names(ids: &[Self]) -> Vec<String> {
        ids.iter().map(|id| id.name().to_owned()).collect()
    }
}

impl std::fmt::Display for EffectId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for EffectId {
    type Err = EffectError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|id| id.name() == s)
            .ok_or_else(|| EffectError::UnknownEffect { id: s.to_owned(), known: Self::names(&Self::ALL) })
    }
}

impl Serialize for EffectId {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.name())
    }
}

impl<'de> Deserialize<'de> for EffectId {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let name = String::deserialize(deserializer)?;
        name.parse().map_err(serde::de::Error::custom)
    }
}

impl clap::ValueEnum for EffectId {
    fn value_variants<'a>() -> &'a [Self] {
        &Self::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()))
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn names_parse_back_and_serialise_as_names() {
        for id in EffectId::ALL {
            assert_eq!(id.name().parse::<EffectId>(), Ok(id));
            assert_eq!(serde_json::to_string(&id).unwrap(), format!("\"{id}\""));
        }
        let err = serde_json::from_str::<EffectId>("\"warp\"").map(|_| ()).unwrap_err().to_string();
        assert!(err.contains("unknown effect 'warp'") && err.contains("thermal_soak"), "{err}");
    }
}
