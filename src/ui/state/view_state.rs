//! What the user is looking at and doing, not saved with the session: the tab, the selection,
//! every view's zoom and toggles, dialogs, errors and the status line.
use crate::ui::file_dialog::{PendingPick, PickPurpose};
use crate::ui::mapping_ui::MappingDialog;
use crate::ui::path_prompt::PathPrompt;
use crate::ui::state::Tab;
use crate::ui::state::session::LoadFailure;
use crate::ui::state::setup::History;
use crate::ui::views::StaticMapViewState;
use crate::ui::views::bode::BodeViewState;
use crate::ui::views::compare::CompareViewState;
use crate::ui::views::data::DataViewState;
use crate::ui::views::diagnosis::DiagnosisViewState;
use crate::ui::views::traces::TracesViewState;
use crate::ui::views::zplane::ZPlaneViewState;

/// State that only matters while the app runs: nothing here is saved.
#[derive(Default)]
pub struct ViewState {
    pub tab: Tab,
    pub selected_run: Option<usize>,
    /// The output the model views show (the first output when `None` or not present).
    pub output: Option<String>,
    pub views: ViewStates,
    /// Undo and redo of segment, cluster and settings changes.
    pub history: History,
    /// Model and project file errors, shown until dismissed.
    pub errors: Vec<String>,
    /// Files that could not be read, shown until dismissed.
    pub failures: Vec<LoadFailure>,
    pub mapping: Option<MappingDialog>,
    /// The number of runs restored from the last session, while the notice saying so is shown.
    pub restored_runs: Option<usize>,
    /// The latest message for the status bar.
    pub status: Option<String>,
    /// The duration of the previous frame's UI code, in ms.
    pub frame_ms: Option<f32>,
    /// The whole previous frame as eframe measured it (UI and tessellation), in ms.
    pub cpu_frame_ms: Option<f32>,
    /// A native file dialog is open.
    pub picker: Option<PendingPick>,
    /// A file dialog to open at the end of the frame.
    pub dialog_requested: Option<PickPurpose>,
    /// Whether the system's file dialogs can appear; when not, [`Self::path_prompt`] asks instead.
    pub native_dialogs: bool,
    /// The in-app path field, open.
    pub path_prompt: Option<PathPrompt>,
    pub quit_requested: bool,
}

/// The transient state of every view (zoom, toggles, drags in progress).
#[derive(Default)]
pub struct ViewStates {
    pub data: DataViewState,
    pub zplane: ZPlaneViewState,
    pub bode: BodeViewState,
    pub static_map: StaticMapViewState,
    pub traces: TracesViewState,
    pub compare: CompareViewState,
    pub diagnosis: DiagnosisViewState,
    pub control: crate::ui::views::control::ControlViewState,
    pub history: crate::ui::views::history::HistoryViewState,
}
