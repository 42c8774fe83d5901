//! The native file dialogs (open runs, import/export a model, open/save a project), run off the UI
//! thread so the app keeps repainting while one is open. The result comes back through a channel
//! that the app polls each frame.
//!
//! Where no native dialog can appear (on Linux: no XDG desktop portal and no `zenity`, as on a bare
//! X server), rfd answers at once as if the user had cancelled. The app then asks for the path
//! in a window of its own ([`crate::ui::path_prompt`]) rather than doing nothing.
use std::future::Future;
use std::path::{Path, PathBuf};
use std::pin::pin;
use std::sync::Arc;
use std::sync::mpsc::{self, Receiver, TryRecvError};
use std::task::{Context, Poll, Wake, Waker};
use std::thread::{self, Thread};
use std::time::{Duration, Instant};

use crate::ui::state::command::FileAction;

/// What the chosen files are for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PickPurpose {
    Runs,
    File(FileAction),
}

/// A file dialog in progress.
pub struct PendingPick {
    pub purpose: PickPurpose,
    /// The chosen files and how long the dialog took to answer.
    rx: Receiver<(Vec<PathBuf>, Duration)>,
}

/// What polling a pending dialog gave.
pub enum PickPoll {
    /// Still open.
    Waiting,
    /// Closed: the chosen files (empty when cancelled).
    Done(Vec<PathBuf>),
    /// Came back empty sooner than anyone can cancel a dialog: no dialog was shown.
    NoDialog,
}

/// A dialog that comes back empty within this time was never on screen: a person needs longer to
/// see a dialog and cancel it, while rfd answers in a few milliseconds when it has no dialog to
/// show.
const NO_DIALOG_WITHIN: Duration = Duration::from_millis(300);

/// Whether a native file dialog can appear. On Linux and the BSDs rfd asks the XDG desktop portal
/// over the D-Bus session bus and falls back to `zenity`: with neither a session bus nor `zenity`
/// it can show nothing. Elsewhere the system always has a dialog.
pub fn native_dialog_available() -> bool {
    if !cfg!(all(unix, not(target_os = "macos"), not(target_os = "android"))) {
        return true;
    }
    session_bus_present() || on_path("zenity")
}

fn session_bus_present() -> bool {
    let set = std::env::var_os("DBUS_SESSION_BUS_ADDRESS").is_some_and(|v| !v.is_empty());
    let socket = std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|dir| Path::new(&dir).join("bus").exists());
    set || socket
}

fn on_path(program: &str) -> bool {
    std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|dir| dir.join(program).is_file()))
}

impl PendingPick {
    /// Open a dialog for run files. `repaint` is called when the dialog closes so the UI wakes up.
    pub fn open_runs(start_dir: Option<PathBuf>, repaint: impl Fn() + Send + 'static) -> Self {
        let mut dialog = rfd::AsyncFileDialog::new()
            .set_title("Open run files")
            .add_filter("Run files (CSV)", &["csv"])
            .add_filter("All files", &["*"]);
        if let Some(dir) = start_dir {
            dialog = dialog.set_directory(dir);
        }
        // Created here (the UI thread, as some platforms require), awaited on a worker thread.
        let future = dialog.pick_files();
        Self::spawn(PickPurpose::Runs, repaint, async move {
            future.await.unwrap_or_default().iter().map(|f| f.path().to_owned()).collect()
        })
    }

    /// Open a dialog to choose a model or project file to read or write.
    pub fn open_file(
        action: FileAction,
        start_dir: Option<PathBuf>,
        repaint: impl Fn() + Send + 'static,
    ) -> Self {
        let (title, filter, extension, default_name) = match action {
            FileAction::ExportModel => ("Export model", "Model (JSON)", "json", "model.json"),
            FileAction::ImportModel => ("Import model", "Model (JSON)", "json", "model.json"),
            FileAction::SaveProject => ("Save project", "Project (TOML)", "toml", "project.toml"),
            FileAction::OpenProject => ("Open project", "Project (TOML)", "toml", "project.toml"),
            FileAction::OpenFleet => {
                ("Open fleet manifest", "Fleet manifest (TOML)", "toml", "manifest.toml")
            }
        };
        let mut dialog = rfd::AsyncFileDialog::new()
            .set_title(title)
            .add_filter(filter, &[extension])
            .add_filter("All files", &["*"]);
        if let Some(dir) = start_dir {
            dialog = dialog.set_directory(dir);
        }
        let purpose = PickPurpose::File(action);
        match action {
            FileAction::ExportModel | FileAction::SaveProject => {
                let future = dialog.set_file_name(default_name).save_file();
                Self::spawn(purpose, repaint, async move {
                    future.await.map(|f| f.path().to_owned()).into_iter().collect()
                })
            }
            FileAction::ImportModel | FileAction::OpenProject | FileAction::OpenFleet => {
                let future = dialog.pick_file();
                Self::spawn(purpose, repaint, async move {
                    future.await.map(|f| f.path().to_owned()).into_iter().collect()
                })
            }
        }
    }

    fn spawn(
        purpose: PickPurpose,
        repaint: impl Fn() + Send + 'static,
        future: impl Future<Output = Vec<PathBuf>> + Send + 'static,
    ) -> Self {
        let (tx, rx) = mpsc::channel();
        let opened = Instant::now();
        thread::spawn(move || {
            let paths = block_on(future);
            // The receiver is gone only if the app closed; nothing to do then.
            let _ = tx.send((paths, opened.elapsed()));
            repaint();
        });
        Self { purpose, rx }
    }

    pub fn poll(&self) -> PickPoll {
        match self.rx.try_recv() {
            Ok((paths, took)) if paths.is_empty() && took < NO_DIALOG_WITHIN => PickPoll::NoDialog,
            Ok((paths, _)) => PickPoll::Done(paths),
            Err(TryRecvError::Empty) => PickPoll::Waiting,
            Err(TryRecvError::Disconnected) => PickPoll::Done(Vec::new()),
        }
    }
}

/// Wakes the blocked worker thread.
struct ThreadWaker(Thread);

impl Wake for ThreadWaker {
    fn wake(self: Arc<Self>) {
        self.0.unpark();
    }
}

/// Drive a future to completion on the current thread (the dialog is the only thing it waits on).
fn block_on<F: Future>(future: F) -> F::Output {
    let mut future = pin!(future);
    let waker = Waker::from(Arc::new(ThreadWaker(thread::current())));
    let mut cx = Context::from_waker(&waker);
    loop {
        if let Poll::Ready(out) = future.as_mut().poll(&mut cx) {
            return out;
        }
        thread::park();
    }
}
