//! The native "open file" dialog, run off the UI thread so the app keeps repainting while it is
//! open. The result comes back through a channel that the app polls each frame.
use std::future::Future;
use std::path::PathBuf;
use std::pin::pin;
use std::sync::Arc;
use std::sync::mpsc::{self, Receiver, TryRecvError};
use std::task::{Context, Poll, Wake, Waker};
use std::thread::{self, Thread};

/// A file dialog in progress.
pub struct PendingPick {
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
        let (tx, rx) = mpsc::channel();
        thread::spawn(move || {
            let files = block_on(future).unwrap_or_default();
            let paths = files.iter().map(|f| f.path().to_owned()).collect();
            // The receiver is gone only if the app closed; nothing to do then.
            let _ = tx.send(paths);
            repaint();
        });
        Self { rx }
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
