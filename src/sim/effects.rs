//! The effect catalog of METHOD.md as switchable physics of the simulated engine.
//!
//! An effect is written `ID` or `ID:name=value,name=value`, e.g. `thermal_soak:gain=0.06,tau_s=40`.
//! Every parameter has a default chosen so the effect is plainly visible in the simulated runs, and a
//! range outside which the physics stops making sense; both are listed by [`Effect::parameters`].
use std::str::FromStr;

use super::error::SimError;
use crate::core::effects::EffectId;

/// One parameter of an effect: its name (with unit suffix), default and admissible range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamSpec {
    pub name: &'static str,
    pub default: f64,
    pub min: f64,
    pub max: f64,
}

const fn spec(name: &'static str, default: f64, min: f64, max: f64) -> ParamSpec {
    ParamSpec { name, default, min, max }
}

/// The effects the simulator can switch on: METHOD.md's catalog, keyed on the model's own ids.
pub const EFFECT_IDS: [EffectId; 8] = [
    EffectId::TransportDelay,
    EffectId::ThermalSoak,
    EffectId::AmbientCorrection,
    EffectId::AsymmetricDynamics,
    EffectId::SensorDynamics,
    EffectId::StaticMapOrder,
    EffectId::RateLimit,
    EffectId::CalibrationDrift,
];

const TRANSPORT_DELAY: &[ParamSpec] = &[spec("delay_s", 0.45, 0.0, 5.0)];
const THERMAL_SOAK: &[ParamSpec] = &[spec("gain", 0.10, 0.0, 0.5), spec("tau_s", 40.0, 1.0, 1000.0)];
const AMBIENT_CORRECTION: &[ParamSpec] = &[
    spec("t_start_c", 18.0, -40.0, 55.0),
    spec("t_end_c", 38.0, -40.0, 55.0),
    spec("p_start_kpa", 101.325, 50.0, 110.0),
    spec("p_end_kpa", 100.8, 50.0, 110.0),
    spec("rh_start_pct", 55.0, 0.0, 100.0),
];
const ASYMMETRIC_DYNAMICS: &[ParamSpec] =
    &[spec("decel_factor", 1.8, 0.2, 5.0), spec("accel_factor", 1.0, 0.2, 5.0)];
const SENSOR_DYNAMICS: &[ParamSpec] = &[
    spec("freq_hz", 1.4, 0.2, 4.0),
    spec("zeta", 0.06, 0.005, 1.0),
    spec("lag_s", 0.3, 0.0, 2.0),
    spec("buffet_n", 1.5, 0.0, 50.0),
];
/// A fuel-meter zero shift of a test day, gal/h: a few percent of an idle flow of ~2 gal/h is what
/// a recalibration or a swapped meter gives; ±2 gal/h is the most a meter would be trusted with.
const CALIBRATION_DRIFT: &[ParamSpec] = &[spec("offset_gph", 0.2, -2.0, 2.0)];
/// The ECU's acceleration and deceleration limits on the (corrected) shaft speed, rpm/s. An
/// SR-30-class spool (τ ≈ 1.7 s) stepped across half its 45–87 krpm range would start at about
/// 20,000/1.7 ≈ 12,000 rpm/s; its fuel system rounds that to 4,000–6,000 rpm/s on the
/// identification design's rises and 2,000–3,000 rpm/s on its (smaller) falls. 4,000 rpm/s up (idle
/// to full in ~10 s, a typical small-engine acceleration schedule) clips the large rises only;
/// 1,500 rpm/s down is the gentler deceleration schedule small-engine ECUs keep for lean blow-out
/// margin when the fuel is cut back, and clips every fall of the designs but the smallest.
const RATE_LIMIT: &[ParamSpec] =
    &[spec("rise_rpm_s", 4_000.0, 100.0, 1.0e6), spec("fall_rpm_s", 1_500.0, 100.0, 1.0e6)];
const STATIC_MAP_ORDER: &[ParamSpec] =
    &[spec("bleed_rpm", 80_000.0, 50_000.0, 95_000.0), spec("gain", 2.0, 0.0, 20.0)];

/// A physical effect switched on in the simulated engine, with its parameters.
#[derive(Clone, Debug, PartialEq)]
pub enum Effect {
    /// Fuel line and valve dead time: the fuel system sees the command `delay_s` seconds late.
    TransportDelay { delay_s: f64 },
    /// Casing and rotor soak: a slow state absorbs the share `gain` of every turbine-power change and
    /// gives it back with time constant `tau_s`.
    ThermalSoak { gain: f64, tau_s: f64 },
    /// Inlet conditions drift linearly through the run and the engine runs on corrected quantities.
    AmbientCorrection { t_start_c: f64, t_end_c: f64, p_start_kpa: f64, p_end_kpa: f64, rh_start_pct: f64 },
    /// Spool time constant multiplied by `decel_factor` while slowing down, `accel_factor` while
    /// speeding up.
    AsymmetricDynamics { decel_factor: f64, accel_factor: f64 },
    /// A softer thrust stand: lightly damped resonance at `freq_hz`, a first-order sensor lag `lag_s`,
    /// and broadband combustion buffeting of standard deviation `buffet_n` that excites it.
    SensorDynamics { freq_hz: f64, zeta: f64, lag_s: f64, buffet_n: f64 },
    /// A compressor bleed valve that opens above `bleed_rpm` (corrected) and loads the spool in
    /// proportion to `gain` times the speed above it: a kink in the static map.
    StaticMapOrder { bleed_rpm: f64, gain: f64 },
    /// The fuel meter of this run reads `offset_gph` high: the engine burns the scheduled fuel, the
    /// log's input column is shifted (a calibration that differs between test days; simulate the
    /// runs of one day without it and another day's with it).
    CalibrationDrift { offset_gph: f64 },
    /// The ECU's acceleration schedule: the shaft speed rises by at most `rise_rpm_s` and falls by
    /// at most `fall_rpm_s` (the spool's own rate, clamped).
    RateLimit { rise_rpm_s: f64, fall_rpm_s: f64 },
}

impl Effect {
    /// The catalog id of this effect.
    pub fn id(&self) -> EffectId {
        match self {
            Self::TransportDelay { .. } => EffectId::TransportDelay,
            Self::ThermalSoak { .. } => EffectId::ThermalSoak,
            Self::AmbientCorrection { .. } => EffectId::AmbientCorrection,
            Self::AsymmetricDynamics { .. } => EffectId::AsymmetricDynamics,
            Self::SensorDynamics { .. } => EffectId::SensorDynamics,
            Self::StaticMapOrder { .. } => EffectId::StaticMapOrder,
            Self::CalibrationDrift { .. } => EffectId::CalibrationDrift,
            Self::RateLimit { .. } => EffectId::RateLimit,
        }
    }

    /// The parameters an effect accepts, or `UnknownEffect` for a block the simulator does not
    /// simulate (the scheduled time constant is the engine's own behaviour, always on).
    pub fn parameters(id: EffectId) -> Result<&'static [ParamSpec], SimError> {
        match id {
            EffectId::TransportDelay => Ok(TRANSPORT_DELAY),
            EffectId::ThermalSoak => Ok(THERMAL_SOAK),
            EffectId::AmbientCorrection => Ok(AMBIENT_CORRECTION),
            EffectId::AsymmetricDynamics => Ok(ASYMMETRIC_DYNAMICS),
            EffectId::SensorDynamics => Ok(SENSOR_DYNAMICS),
            EffectId::StaticMapOrder => Ok(STATIC_MAP_ORDER),
            EffectId::CalibrationDrift => Ok(CALIBRATION_DRIFT),
            EffectId::RateLimit => Ok(RATE_LIMIT),
            // Not simulated: the scheduled time constant is the engine's own behaviour (always on).
            EffectId::ScheduledTimeConstant | EffectId::ReadOffSpeed => Err(unknown_effect(id.name())),
        }
    }

    /// The effect with its default parameters.
    pub fn with_defaults(id: EffectId) -> Result<Self, SimError> {
        let specs = Self::parameters(id)?;
        let values: Vec<f64> = specs.iter().map(|p| p.default).collect();
        Ok(Self::from_values(id, &values))
    }

    /// Build from parameter values listed in the order of [`Effect::parameters`]; values are checked.
    fn from_values(id: EffectId, v: &[f64]) -> Self {
        let at = |i: usize| v.get(i).copied().unwrap_or(0.0);
        match id {
            EffectId::TransportDelay => Self::TransportDelay { delay_s: at(0) },
            EffectId::ThermalSoak => Self::ThermalSoak { gain: at(0), tau_s: at(1) },
            EffectId::AmbientCorrection => Self::AmbientCorrection {
                t_start_c: at(0),
                t_end_c: at(1),
                p_start_kpa: at(2),
                p_end_kpa: at(3),
                rh_start_pct: at(4),
            },
            EffectId::AsymmetricDynamics => {
                Self::AsymmetricDynamics { decel_factor: at(0), accel_factor: at(1) }
            }
            EffectId::SensorDynamics => {
                Self::SensorDynamics { freq_hz: at(0), zeta: at(1), lag_s: at(2), buffet_n: at(3) }
            }
            EffectId::CalibrationDrift => Self::CalibrationDrift { offset_gph: at(0) },
            EffectId::RateLimit => Self::RateLimit { rise_rpm_s: at(0), fall_rpm_s: at(1) },
            EffectId::StaticMapOrder | EffectId::ScheduledTimeConstant | EffectId::ReadOffSpeed => {
                Self::StaticMapOrder { bleed_rpm: at(0), gain: at(1) }
            }
        }
    }
}

/// The simulator's error for an effect it does not know, listing the ones it does.
fn unknown_effect(id: &str) -> SimError {
    SimError::UnknownEffect { id: id.to_owned(), known: EffectId::names(&EFFECT_IDS) }
}

impl FromStr for Effect {
    type Err = SimError;

    /// Parse `ID` or `ID:name=value,...`; unnamed parameters keep their defaults.
    fn from_str(text: &str) -> Result<Self, SimError> {
        let (id, params) = match text.split_once(':') {
            Some((id, params)) => (id.trim(), params.trim()),
            None => (text.trim(), ""),
        };
        let effect: EffectId = id.parse().map_err(|_| unknown_effect(id))?;
        let specs = Self::parameters(effect)?;
        let mut values: Vec<f64> = specs.iter().map(|p| p.default).collect();
        let mut seen = vec![false; specs.len()];
        for item in params.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let Some((name, value_text)) = item.split_once('=') else {
                return Err(SimError::MalformedParameter { effect: id.to_owned(), item: item.to_owned() });
            };
            let (name, value_text) = (name.trim(), value_text.trim());
            let Some(index) = specs.iter().position(|p| p.name == name) else {
                return Err(SimError::UnknownParameter {
                    effect: id.to_owned(),
                    param: name.to_owned(),
                    known: specs.iter().map(|p| p.name.to_owned()).collect(),
                });
            };
            let (Some(slot), Some(seen_slot), Some(p)) =
                (values.get_mut(index), seen.get_mut(index), specs.get(index))
            else {
                continue;
            };
            if *seen_slot {
                return Err(SimError::DuplicateParameter { effect: id.to_owned(), param: name.to_owned() });
            }
            *seen_slot = true;
            let value: f64 = value_text.parse().map_err(|_| SimError::BadParameterValue {
                effect: id.to_owned(),
                param: name.to_owned(),
                value: value_text.to_owned(),
            })?;
            if !value.is_finite() || value < p.min || value > p.max {
                return Err(SimError::ParameterOutOfRange {
                    effect: id.to_owned(),
                    param: name.to_owned(),
                    value,
                    min: p.min,
                    max: p.max,
                });
            }
            *slot = value;
        }
        Ok(Self::from_values(effect, &values))
    }
}

/// The effects of one run gathered into the switches the engine model reads, with neutral values
/// for the effects that are off.
#[derive(Clone, Debug, PartialEq)]
pub struct ActiveEffects {
    pub delay_s: f64,
    /// `(gain, tau_s)` of the thermal soak.
    pub soak: Option<(f64, f64)>,
    pub ambient: Option<AmbientDrift>,
    pub decel_factor: f64,
    pub accel_factor: f64,
    /// Stand resonance and sensor lag replacing the base load cell's.
    pub stand: Option<StandOverride>,
    /// `(bleed_rpm, gain)` of the bleed valve.
    pub bleed: Option<(f64, f64)>,
    /// What the fuel meter adds to the flow it logs, gal/h.
    pub meter_offset_gph: f64,
    /// `(rise_rpm_s, fall_rpm_s)`: the ECU's limits on the speed's rate of change.
    pub rate_limit: Option<(f64, f64)>,
}

/// Linear drift of the inlet conditions through a run, and the humidity at its start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AmbientDrift {
    pub t_start_c: f64,
    pub t_end_c: f64,
    pub p_start_kpa: f64,
    pub p_end_kpa: f64,
    pub rh_start_pct: f64,
}

/// The `sensor_dynamics` stand.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StandOverride {
    pub freq_hz: f64,
    pub zeta: f64,
    pub lag_s: f64,
    pub buffet_n: f64,
}

impl ActiveEffects {
    /// No effect: the base engine.
    pub fn none() -> Self {
        Self {
            delay_s: 0.0,
            soak: None,
            ambient: None,
            decel_factor: 1.0,
            accel_factor: 1.0,
            stand: None,
            bleed: None,
            meter_offset_gph: 0.0,
            rate_limit: None,
        }
    }

    /// Gather a list of effects; each id may appear once.
    pub fn from_effects(effects: &[Effect]) -> Result<Self, SimError> {
        let mut active = Self::none();
        for (i, effect) in effects.iter().enumerate() {
            if effects.iter().take(i).any(|e| e.id() == effect.id()) {
                return Err(SimError::DuplicateEffect { id: effect.id().name().to_owned() });
            }
            match *effect {
                Effect::TransportDelay { delay_s } => active.delay_s = delay_s,
                Effect::ThermalSoak { gain, tau_s } => active.soak = Some((gain, tau_s)),
                Effect::AmbientCorrection { t_start_c, t_end_c, p_start_kpa, p_end_kpa, rh_start_pct } => {
                    active.ambient =
                        Some(AmbientDrift { t_start_c, t_end_c, p_start_kpa, p_end_kpa, rh_start_pct });
                }
                Effect::AsymmetricDynamics { decel_factor, accel_factor } => {
                    active.decel_factor = decel_factor;
                    active.accel_factor = accel_factor;
                }
                Effect::SensorDynamics { freq_hz, zeta, lag_s, buffet_n } => {
                    active.stand = Some(StandOverride { freq_hz, zeta, lag_s, buffet_n });
                }
                Effect::StaticMapOrder { bleed_rpm, gain } => active.bleed = Some((bleed_rpm, gain)),
                Effect::CalibrationDrift { offset_gph } => active.meter_offset_gph = offset_gph,
                Effect::RateLimit { rise_rpm_s, fall_rpm_s } => {
                    active.rate_limit = Some((rise_rpm_s, fall_rpm_s))
                }
            }
        }
        Ok(active)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn parses_defaults_and_overrides() {
        let e: Effect = "thermal_soak:gain=0.06,tau_s=40".parse().unwrap();
        assert_eq!(e, Effect::ThermalSoak { gain: 0.06, tau_s: 40.0 });
        let e: Effect = "transport_delay".parse().unwrap();
        assert_eq!(e, Effect::with_defaults(EffectId::TransportDelay).unwrap());
        let e: Effect = " sensor_dynamics : freq_hz = 2 ".parse().unwrap();
        let Effect::SensorDynamics { freq_hz, zeta, .. } = e else { panic!("wrong effect {e:?}") };
        assert!((freq_hz - 2.0).abs() < 1e-12 && (zeta - 0.06).abs() < 1e-12);
    }

    #[test]
    fn every_catalog_id_has_defaults_within_range() {
        for id in EFFECT_IDS {
            let effect = Effect::with_defaults(id).unwrap();
            assert_eq!(effect.id(), id);
            for p in Effect::parameters(id).unwrap() {
                assert!(p.min <= p.default && p.default <= p.max, "{id}.{}", p.name);
            }
        }
    }

    #[test]
    fn bad_specifications_are_errors_with_data() {
        assert!(matches!("warp_drive".parse::<Effect>(), Err(SimError::UnknownEffect { id, known })
            if id == "warp_drive" && known.len() == EFFECT_IDS.len()));
        assert!(matches!("thermal_soak:tau=3".parse::<Effect>(),
            Err(SimError::UnknownParameter { param, .. }) if param == "tau"));
        assert!(matches!("thermal_soak:gain".parse::<Effect>(), Err(SimError::MalformedParameter { .. })));
        assert!(matches!("thermal_soak:gain=abc".parse::<Effect>(), Err(SimError::BadParameterValue { .. })));
        assert!(matches!("thermal_soak:gain=0.9".parse::<Effect>(),
            Err(SimError::ParameterOutOfRange { max, .. }) if (max - 0.5).abs() < 1e-12));
        assert!(matches!(
            "thermal_soak:gain=0.1,gain=0.2".parse::<Effect>(),
            Err(SimError::DuplicateParameter { .. })
        ));
        assert!(matches!(
            "transport_delay:delay_s=NaN".parse::<Effect>(),
            Err(SimError::ParameterOutOfRange { .. })
        ));
        let twice = [
            Effect::with_defaults(EffectId::ThermalSoak).unwrap(),
            Effect::with_defaults(EffectId::ThermalSoak).unwrap(),
        ];
        assert!(matches!(ActiveEffects::from_effects(&twice), Err(SimError::DuplicateEffect { .. })));
    }
}
