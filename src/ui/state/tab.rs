//! The tabs of the central area: one per view, in the order of the tab bar.
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Tab {
    #[default]
    Data,
    ZPlane,
    Bode,
    StaticMap,
    Traces,
    Compare,
    Diagnosis,
    Control,
    History,
}

impl Tab {
    /// In the order of the tab bar.
    pub const ALL: [Self; 9] = [
        Self::Data,
        Self::ZPlane,
        Self::Bode,
        Self::StaticMap,
        Self::Traces,
        Self::Compare,
        Self::Diagnosis,
        Self::Control,
        Self::History,
    ];

    pub fn label(self) -> &'static str {
        match self {
            Self::Data => "Data",
            Self::ZPlane => "Z-plane",
            Self::Bode => "Bode",
            Self::StaticMap => "Static map",
            Self::Traces => "Traces",
            Self::Compare => "Compare",
            Self::Diagnosis => "Diagnosis",
            Self::Control => "Control",
            Self::History => "History",
        }
    }

    /// The name used on the command line (`--view`).
    pub fn cli_name(self) -> &'static str {
        match self {
            Self::Data => "data",
            Self::ZPlane => "zplane",
            Self::Bode => "bode",
            Self::StaticMap => "static",
            Self::Traces => "traces",
            Self::Compare => "compare",
            Self::Diagnosis => "diagnosis",
            Self::Control => "control",
            Self::History => "history",
        }
    }

    pub fn from_cli_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|t| t.cli_name().eq_ignore_ascii_case(name))
    }

    /// `data, zplane, …` for error messages.
    pub fn cli_names() -> String {
        Self::ALL.map(Self::cli_name).join(", ")
    }
}
