//! The views of the central area, one tab each.
//!
//! To add a view: add a variant to [`Tab`] and to [`Tab::ALL`], give it a label and a command-line
//! name (`jetid --screenshot OUT.png --view NAME`), put its transient state in a field of
//! [`ViewStates`], and add its `*_ui` call to [`tab_ui`]. The view reads the session and the
//! derived cache, changes only its own view state, and returns commands.
use serde::{Deserialize, Serialize};

use super::command::Command;
use super::data_ui::{self, DataViewState};
use super::derived::Derived;
use super::session::Session;

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Tab {
    #[default]
    Data,
}

impl Tab {
    /// In the order of the tab bar.
    pub const ALL: [Self; 1] = [Self::Data];

    pub fn label(self) -> &'static str {
        match self {
            Self::Data => "Data",
        }
    }

    /// The name used on the command line (`--view`).
    pub fn cli_name(self) -> &'static str {
        match self {
            Self::Data => "data",
        }
    }

    pub fn from_cli_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|t| t.cli_name().eq_ignore_ascii_case(name))
    }

    /// `data, bode, …` for error messages.
    pub fn cli_names() -> String {
        Self::ALL.map(Self::cli_name).join(", ")
    }
}

/// The transient state of every view (zoom, toggles, drags in progress).
#[derive(Default)]
pub struct ViewStates {
    pub data: DataViewState,
}

/// Draw the view of `tab`.
pub fn tab_ui(
    ui: &mut egui::Ui,
    tab: Tab,
    session: &Session,
    selected_run: Option<usize>,
    states: &mut ViewStates,
    cache: &Derived,
) -> Vec<Command> {
    match tab {
        Tab::Data => data_ui::data_ui(ui, session, selected_run, &mut states.data, cache),
    }
}
