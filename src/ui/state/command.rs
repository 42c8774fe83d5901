//! Everything a view can ask the app to do. Views never change the session themselves: they return
//! commands, and `App::apply` carries them out in one place (and bumps the session revision when
//! the session changed).
use std::path::PathBuf;

use crate::core::diagnose::TrialId;
use crate::core::effects::EffectId;
use crate::core::identification::cluster::Cluster;
use crate::core::identification::segment::Segment;
use crate::core::identification::settings::OutputSettings;
use crate::core::run::RunRole;
use crate::io::csv_run::LoadOptions;
use crate::ui::state::Tab;

#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    // --- Session changes (bump the revision when they succeed) ---
    /// Read a run file and add it to the session. On failure the session is left as it was and the
    /// error is shown.
    LoadRun {
        path: PathBuf,
        role: RunRole,
        options: LoadOptions,
    },
    /// Read session run `index` again with other options (e.g. a new column mapping); on failure
    /// the run stays as it was.
    ReloadRun {
        index: usize,
        options: LoadOptions,
    },
    RemoveRun(usize),
    SetRole(usize, RunRole),

    // --- Setup changes (undoable) ---
    /// The segments of the identification run; `None` detects them from the input again.
    SetSegments(Option<Vec<Segment>>),
    /// The clusters of an output; `None` follows the automatic proposal.
    SetClusters {
        output: String,
        clusters: Option<Vec<Cluster>>,
    },
    SetOutputSettings {
        output: String,
        settings: OutputSettings,
    },
    /// Add what a diagnosis trial adds to an output's model (fitted on the identification data):
    /// an effect of the catalog, or a refinement that is a block (the scheduled time constant).
    ApplyEffect {
        output: String,
        trial: TrialId,
    },
    /// Take an effect out of an output's model (the others are fitted again).
    RemoveEffect {
        output: String,
        effect: EffectId,
    },
    /// The rounds of the missing-physics loop run after the effects added by hand (0: none).
    SetAutoEffects {
        output: String,
        rounds: usize,
    },
    Undo,
    Redo,
    /// Drop the restored session for the one of a first start: the bundled sample runs, else none.
    StartFresh,

    // --- Files (errors are shown, the session is kept) ---
    /// Write the current model of every output as model.json.
    ExportModel(PathBuf),
    /// Take the clusters of every output in a model.json (the model is fitted again on the
    /// session's runs).
    ImportModel(PathBuf),
    /// Write the session as a project file (TOML).
    SaveProject(PathBuf),
    /// Replace the session by a project file's runs and setup.
    OpenProject(PathBuf),
    /// Compute the fleet of a manifest for the History view (the session is not touched; errors
    /// are shown in the view).
    OpenFleet(PathBuf),

    // --- App actions (no session change) ---
    /// Show the native file dialog; chosen files are loaded with a role guessed from their names.
    OpenRunDialog,
    /// Show the native file dialog for a model or project file.
    ChooseFile(FileAction),
    /// Use the path typed in the in-app path field (shown where no native dialog can appear).
    SubmitPath,
    ClosePathPrompt,
    /// Open the column-mapping dialog for session run `index`.
    MapColumnsOfRun(usize),
    /// Open the column-mapping dialog for load failure `index` (a file that is not in the session).
    MapColumnsOfFailure(usize),
    CloseMappingDialog,
    DismissFailure(usize),
    DismissAllFailures,
    /// Hide the notice that the last session was restored.
    DismissRestoreNotice,
    /// Close error message `index` (model and project files).
    DismissError(usize),
    SelectRun(usize),
    /// The output the model views show.
    SelectOutput(String),
    ShowTab(Tab),
    /// Show the Traces view on session run `run`, zoomed to `t0_secs..=t1_secs`.
    FocusTraces {
        run: usize,
        t0_secs: f64,
        t1_secs: f64,
    },
    Quit,
}

/// What a file dialog is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileAction {
    ExportModel,
    ImportModel,
    SaveProject,
    OpenProject,
    OpenFleet,
}

impl FileAction {
    /// The command to run on the chosen file.
    pub fn command(self, path: PathBuf) -> Command {
        match self {
            Self::ExportModel => Command::ExportModel(path),
            Self::ImportModel => Command::ImportModel(path),
            Self::SaveProject => Command::SaveProject(path),
            Self::OpenProject => Command::OpenProject(path),
            Self::OpenFleet => Command::OpenFleet(path),
        }
    }
}

impl Command {
    /// Shorthand for loading a file with default options (canonical column names).
    pub fn load(path: impl Into<PathBuf>, role: RunRole) -> Self {
        Self::LoadRun { path: path.into(), role, options: LoadOptions::default() }
    }
}
