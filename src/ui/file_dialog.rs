//! The native file dialogs (open runs, import/export a model, open/save a project), run off the UI
//! thread so the app keeps repainting while one is open. The result comes back through a channel
//! that the app polls each frame.
use std::future::Future;
use std::path::PathBuf;
use std::pin::pin;
use std::sync::Arc;
use std::sync::mpsc::{self, Receiver, TryRecvError};
use std::task::{Context, Poll, Wake, Waker};
use std::thread::{self, Thread};

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
    rx: Receiver<Vec<PathBuf>>,
}

/// What polling a pending dialog gave.
pub enum PickPoll {
    /// Still open.
    Waiting,
    /// Closed: the chosen files (empty when cancelled).
    Done(Vec<PathBuf>),
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
            FileAction::ImportModel | FileAction::OpenProject => {
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
        thread::spawn(move || {
            // The receiver is gone only if the app closed; nothing to do then.
            let _ = tx.send(block_on(future));
            repaint();
        });
        Self { purpose, rx }
    }

    pub fn poll(&self) -> PickPoll {
        match self.rx.try_recv() {
            Ok(paths) => PickPoll::Done(paths),
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
