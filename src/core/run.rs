//! A measured (or simulated) test-bench run: uniformly sampled input, outputs and auxiliary channels.

use serde::{Deserialize, Serialize};

/// One named signal with its unit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Channel {
    pub name: String,
    pub unit: String,
    pub values: Vec<f64>,
}

impl Channel {
    /// A channel whose unit is guessed from the column-name suffix (`_rpm`, `_n`, `_gph`, …).
    pub fn new(name: &str, values: Vec<f64>) -> Self {
        Self { name: name.to_owned(), unit: unit_from_column_name(name).to_owned(), values }
    }
}

/// A run: the input (fuel flow), one or more outputs and any auxiliary channels, on one time base.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Run {
    pub name: String,
    pub dt_secs: f64,
    pub t_secs: Vec<f64>,
    pub input: Channel,
    pub outputs: Vec<Channel>,
    pub aux: Vec<Channel>,
}

impl Run {
    pub fn len(&self) -> usize {
        self.t_secs.len()
    }

    pub fn is_empty(&self) -> bool {
        self.t_secs.is_empty()
    }

    pub fn output(&self, name: &str) -> Option<&Channel> {
        self.outputs.iter().find(|c| c.name == name)
    }

    pub fn aux(&self, name: &str) -> Option<&Channel> {
        self.aux.iter().find(|c| c.name == name)
    }

    /// Any channel (input, output or auxiliary) by name.
    pub fn channel(&self, name: &str) -> Option<&Channel> {
        std::iter::once(&self.input).chain(&self.outputs).chain(&self.aux).find(|c| c.name == name)
    }
}

/// The unit implied by a canonical column-name suffix; empty when unknown.
pub fn unit_from_column_name(name: &str) -> &'static str {
    let lower = name.to_ascii_lowercase();
    const SUFFIXES: [(&str, &str); 12] = [
        ("_gph", "gal/h"),
        ("_rpm", "rpm"),
        ("_n", "N"),
        ("_c", "°C"),
        ("_k", "K"),
        ("_kpa", "kPa"),
        ("_pct", "%"),
        ("_s", "s"),
        ("_v", "V"),
        ("_a", "A"),
        ("_krpm", "krpm"),
        ("_bar", "bar"),
    ];
    SUFFIXES.iter().find(|(suffix, _)| lower.ends_with(suffix)).map_or("", |(_, unit)| unit)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_follow_suffixes() {
        assert_eq!(unit_from_column_name("shaft_speed_rpm"), "rpm");
        assert_eq!(unit_from_column_name("thrust_n"), "N");
        assert_eq!(unit_from_column_name("fuel_flow_gph"), "gal/h");
        assert_eq!(unit_from_column_name("ambient_pressure_kpa"), "kPa");
        assert_eq!(unit_from_column_name("egt_C"), "°C");
        assert_eq!(unit_from_column_name("mystery"), "");
    }
}
