//! The models of the paper's comparison, and the paper's own figures for them.
use serde::{Deserialize, Serialize};

/// A model of the comparison. Its report name is how report.json keys it (CONTRACT.md), and maps
/// keyed by it are ordered by that name, as report.json lists them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ModelKind {
    /// The gray-box Wiener model `u → G(z) → f(v)`, with its effects where it has any.
    GrayBox,
    /// The reduced transfer function alone, without the static map: what the nonlinearity buys.
    Linear,
    HammersteinWiener,
    Nnarx,
    /// Reference: the linear ARX(2,2).
    Arx,
    /// Reference: ARX(2,2) on `[u, u², u³]`.
    HammersteinArx,
    /// Reference: the static cubic map `y = p(u)`.
    StaticCubic,
}

/// One row of the paper's Table 1: RMSPE % and SE on the time-domain validation, then on the chirp.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PaperRow {
    pub rmspe_pct: f64,
    pub se: f64,
    pub rmspe_chirp_pct: f64,
    pub se_chirp: f64,
}

use crate::core::run::Quantity;

impl ModelKind {
    /// In the order of the comparison tables: the gray-box model and its linear block, the paper's
    /// baselines, then the simple references.
    pub const ALL: [Self; 7] = [
        Self::GrayBox,
        Self::Linear,
        Self::HammersteinWiener,
        Self::Nnarx,
        Self::Arx,
        Self::HammersteinArx,
        Self::StaticCubic,
    ];

    /// The models of the paper's Monte Carlo study (section 7), and the linear block.
    pub const MONTE_CARLO: [Self; 4] = [Self::GrayBox, Self::Linear, Self::HammersteinWiener, Self::Nnarx];

    /// The simple references (not in the paper): a user sees whether the gray-box beats them.
    pub fn is_reference(self) -> bool {
        matches!(self, Self::Arx | Self::HammersteinArx | Self::StaticCubic)
    }

    /// The key in report.json.
    pub fn report_name(self) -> &'static str {
        match self {
            Self::GrayBox => "gray_box",
            Self::Linear => "linear",
            Self::HammersteinWiener => "hammerstein_wiener",
            Self::Nnarx => "nnarx",
            Self::Arx => "arx",
            Self::HammersteinArx => "hammerstein_arx",
            Self::StaticCubic => "static_cubic",
        }
    }

    pub fn from_report_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.report_name() == name)
    }

    /// The name people read (legends, tables).
    pub fn label(self) -> &'static str {
        match self {
            Self::GrayBox => "gray-box",
            Self::Linear => "linear",
            Self::HammersteinWiener => "Hammerstein–Wiener",
            Self::Nnarx => "NNARX",
            Self::Arx => "ARX(2,2)",
            Self::HammersteinArx => "Hammerstein ARX",
            Self::StaticCubic => "static cubic",
        }
    }

    /// The longer title of report.md's tables.
    pub fn title(self) -> &'static str {
        match self {
            Self::GrayBox => "gray-box (Wiener)",
            Self::Linear => "linear (reduced TF alone)",
            Self::Arx => "reference: linear ARX(2,2)",
            Self::HammersteinArx => "reference: Hammerstein ARX [u, u², u³], na = nb = 2",
            Self::StaticCubic => "reference: static cubic map",
            Self::HammersteinWiener | Self::Nnarx => self.label(),
        }
    }

    /// The paper's Table 1 for this model (section 6; the linear block alone is not in it).
    pub fn paper_table1(self, output: Quantity) -> Option<PaperRow> {
        let row =
            |rmspe_pct, se, rmspe_chirp_pct, se_chirp| PaperRow { rmspe_pct, se, rmspe_chirp_pct, se_chirp };
        Some(match (self, output) {
            (Self::GrayBox, Quantity::ShaftSpeed) => row(1.3429, 26.613, 2.0327, 11.641),
            (Self::HammersteinWiener, Quantity::ShaftSpeed) => row(5.5167, 121.06, 8.5607, 47.835),
            (Self::Nnarx, Quantity::ShaftSpeed) => row(3.1928, 52.280, 3.8578, 27.555),
            (Self::GrayBox, Quantity::Thrust) => row(4.3739, 0.0580, 6.4324, 0.0309),
            (Self::HammersteinWiener, Quantity::Thrust) => row(8.0221, 0.1431, 14.838, 0.0552),
            (Self::Nnarx, Quantity::Thrust) => row(7.4271, 0.1466, 17.136, 0.0489),
            (Self::Linear | Self::Arx | Self::HammersteinArx | Self::StaticCubic, _) => return None,
        })
    }

    /// The paper's Monte Carlo standard deviation (section 7): rpm for shaft speed, N for thrust.
    pub fn paper_monte_carlo_std(self, output: Quantity) -> Option<f64> {
        Some(match (self, output) {
            (Self::GrayBox, Quantity::ShaftSpeed) => 6.035,
            (Self::HammersteinWiener, Quantity::ShaftSpeed) => 14.08,
            (Self::Nnarx, Quantity::ShaftSpeed) => 26.5,
            (Self::GrayBox, Quantity::Thrust) => 0.0136,
            (Self::HammersteinWiener, Quantity::Thrust) => 0.0352,
            (Self::Nnarx, Quantity::Thrust) => 0.1064,
            (Self::Linear | Self::Arx | Self::HammersteinArx | Self::StaticCubic, _) => return None,
        })
    }
}

impl Ord for ModelKind {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.report_name().cmp(other.report_name())
    }
}

impl PartialOrd for ModelKind {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

/// A curve of the chirp comparison: the measured response, or a model's simulation of the chirp
/// input through the same estimator. Keyed in report.json as "measured" or the model's report name,
/// and ordered by that name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Curve {
    Measured,
    Model(ModelKind),
}

impl Curve {
    /// "measured", or the model's report name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Measured => "measured",
            Self::Model(kind) => kind.report_name(),
        }
    }

    /// The name people read: "measured" or the model's label.
    pub fn label(self) -> &'static str {
        match self {
            Self::Measured => "measured",
            Self::Model(kind) => kind.label(),
        }
    }
}

impl Ord for Curve {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.name().cmp(other.name())
    }
}

impl PartialOrd for Curve {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Serialize for Curve {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.name())
    }
}

impl<'de> Deserialize<'de> for Curve {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let name = String::deserialize(deserializer)?;
        match name.as_str() {
            "measured" => Ok(Self::Measured),
            _ => ModelKind::from_report_name(&name)
                .map(Self::Model)
                .ok_or_else(|| serde::de::Error::custom(format!("no model is called '{name}'"))),
        }
    }
}

impl std::fmt::Display for ModelKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.report_name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn report_names_round_trip_and_match_serde() {
        for kind in ModelKind::ALL {
            assert_eq!(ModelKind::from_report_name(kind.report_name()), Some(kind));
            let json = serde_json::to_string(&kind).unwrap_or_default();
            assert_eq!(json, format!("\"{}\"", kind.report_name()));
        }
        assert_eq!(ModelKind::from_report_name("armax"), None);
    }
}
