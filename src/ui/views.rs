//! The views of the central area, one tab each.
//!
//! To add a view: add a variant to [`Tab`] and to [`Tab::ALL`], give it a label and a command-line
//! name (`jetid --screenshot OUT.png --view NAME`), put its transient state in a field of
//! [`ViewStates`], and add its `*_ui` call to [`tab_ui`]. The view reads the session and the
//! derived cache, changes only its own view state, and returns commands.
use serde::{Deserialize, Serialize};

use super::app::{ViewState, hint};
use super::bode_ui::{self, BodeViewState};
use super::command::Command;
use super::compare_ui::{self, CompareViewState};
use super::data_ui::{self, DataViewState};
use super::derived::Derived;
use super::diagnosis_ui::{self, DiagnosisViewState};
use super::model_ui;
use super::session::Session;
use super::static_map_ui;
use super::traces_ui::{self, TracesViewState};
use super::zplane_ui::{self, ZPlaneViewState};

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
}

impl Tab {
    /// In the order of the tab bar.
    pub const ALL: [Self; 7] =
        [Self::Data, Self::ZPlane, Self::Bode, Self::StaticMap, Self::Traces, Self::Compare, Self::Diagnosis];

    pub fn label(self) -> &'static str {
        match self {
            Self::Data => "Data",
            Self::ZPlane => "Z-plane",
            Self::Bode => "Bode",
            Self::StaticMap => "Static map",
            Self::Traces => "Traces",
            Self::Compare => "Compare",
            Self::Diagnosis => "Diagnosis",
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

/// The transient state of every view (zoom, toggles, drags in progress).
#[derive(Default)]
pub struct ViewStates {
    pub data: DataViewState,
    pub zplane: ZPlaneViewState,
    pub bode: BodeViewState,
    pub traces: TracesViewState,
    pub compare: CompareViewState,
    pub diagnosis: DiagnosisViewState,
}

/// The output the model views show: the chosen one if it is identified, else the first.
pub fn selected_output(view: &ViewState, cache: &Derived) -> Option<String> {
    let names = cache.output_names();
    let chosen = view.output.as_deref().filter(|name| names.contains(name));
    chosen.or(names.first().copied()).map(ToOwned::to_owned)
}

/// Draw the view of `view.tab`.
pub fn tab_ui(ui: &mut egui::Ui, session: &Session, view: &mut ViewState, cache: &Derived) -> Vec<Command> {
    let tab = view.tab;
    if tab == Tab::Data {
        return data_ui::data_ui(ui, session, view.selected_run, &mut view.views.data, cache);
    }
    let Some(output) = selected_output(view, cache) else {
        hint(ui, "No identification run: give a run the role \"identification\" in the list on the left.");
        return Vec::new();
    };
    let mut commands: Vec<Command> = model_ui::output_bar_ui(ui, cache, &output).into_iter().collect();
    let states = &mut view.views;
    match tab {
        Tab::Data => {}
        Tab::ZPlane => {
            commands.extend(zplane_ui::zplane_ui(ui, &output, &view.history, &mut states.zplane, cache))
        }
        Tab::Bode => bode_ui::bode_ui(ui, &output, &mut states.bode, cache),
        Tab::StaticMap => commands.extend(static_map_ui::static_map_ui(ui, &output, cache)),
        Tab::Traces => traces_ui::traces_ui(ui, &output, &mut states.traces, session, cache),
        Tab::Compare => compare_ui::compare_ui(ui, &output, &mut states.compare, session, cache),
        Tab::Diagnosis => {
            commands.extend(diagnosis_ui::diagnosis_ui(ui, &output, &mut states.diagnosis, session, cache))
        }
    }
    commands
}
