//! Errors of the turbojet simulator: bad effect specifications, bad test names, numerical failure.

/// Everything that can go wrong when configuring or running the simulator.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    #[error("simulated fleet: {reason}")]
    BadFleet { reason: String },

    #[error("unknown effect `{id}`; known effects: {}", known.join(", "))]
    UnknownEffect { id: String, known: Vec<String> },

    #[error("effect `{effect}` has no parameter `{param}`; its parameters: {}", known.join(", "))]
    UnknownParameter { effect: String, param: String, known: Vec<String> },

    #[error("effect `{effect}`: parameter `{item}` is not of the form name=value")]
    MalformedParameter { effect: String, item: String },

    #[error("effect `{effect}`: parameter `{param}` given twice")]
    DuplicateParameter { effect: String, param: String },

    #[error("effect `{effect}`: parameter `{param}` = `{value}` is not a number")]
    BadParameterValue { effect: String, param: String, value: String },

    #[error("effect `{effect}`: parameter `{param}` = {value} is outside [{min}, {max}]")]
    ParameterOutOfRange { effect: String, param: String, value: f64, min: f64, max: f64 },

    #[error("effect `{id}` requested twice")]
    DuplicateEffect { id: String },

    #[error("unknown test design `{name}`; known designs: {}", known.join(", "))]
    UnknownTest { name: String, known: Vec<String> },

    #[error("fuel profile is empty or has a segment of non-positive duration (segment {segment})")]
    BadProfile { segment: usize },

    #[error(
        "fuel flow {fuel_gph} gal/h at t = {t_secs} s is outside the engine's range [{min_gph}, {max_gph}]"
    )]
    FuelOutOfRange { t_secs: f64, fuel_gph: f64, min_gph: f64, max_gph: f64 },

    #[error("the simulation produced a non-finite {channel} at t = {t_secs} s")]
    NonFinite { channel: &'static str, t_secs: f64 },

    #[error("no steady state at {fuel_gph} gal/h: {reason}")]
    NoSteadyState { fuel_gph: f64, reason: &'static str },
}
