//! Everything a view can ask the app to do. Views never change the session themselves: they return
//! commands, and `App::apply` carries them out in one place (and bumps the session revision when
//! the session changed).
use std::path::PathBuf;

use super::session::Role;
use super::views::Tab;
use crate::io::csv_run::LoadOptions;

#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    // --- Session changes (bump the revision when they succeed) ---
    /// Read a run file and add it to the session. On failure the session is left as it was and the
    /// error is shown.
    LoadRun {
        path: PathBuf,
        role: Role,
        options: LoadOptions,
    },
    /// Read session run `index` again with other options (e.g. a new column mapping); on failure
    /// the run stays as it was.
    ReloadRun {
        index: usize,
        options: LoadOptions,
    },
    RemoveRun(usize),
    SetRole(usize, Role),

    // --- App actions (no session change) ---
    /// Show the native file dialog; chosen files are loaded with a role guessed from their names.
    OpenRunDialog,
    /// Open the column-mapping dialog for session run `index`.
    MapColumnsOfRun(usize),
    /// Open the column-mapping dialog for load failure `index` (a file that is not in the session).
    MapColumnsOfFailure(usize),
    CloseMappingDialog,
    DismissFailure(usize),
    DismissAllFailures,
    SelectRun(usize),
    ShowTab(Tab),
    Quit,
}

impl Command {
    /// Shorthand for loading a file with default options (canonical column names).
    pub fn load(path: impl Into<PathBuf>, role: Role) -> Self {
        Self::LoadRun { path: path.into(), role, options: LoadOptions::default() }
    }
}
