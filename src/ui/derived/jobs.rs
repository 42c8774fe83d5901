//! Long work (baseline training, Monte Carlo, diagnosis) on a worker thread, so the frame stays
//! smooth: a [`Job`] reports its progress, can be cancelled, and hands over its result once.
//!
//! The work gets the core's progress callback (`&mut dyn FnMut(f64) -> bool`): it reports a
//! fraction in 0..=1 and is told to stop (`false`) once the user cancelled.
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, TryRecvError};
use std::time::{Duration, Instant};

/// Why a job has no value.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum JobError {
    /// The user cancelled it (or the job was dropped for a newer one).
    #[error("cancelled")]
    Cancelled,
    /// The work failed, with a message for the user.
    #[error("{0}")]
    Failed(String),
}

impl From<String> for JobError {
    fn from(message: String) -> Self {
        Self::Failed(message)
    }
}

/// What a job's work returns: its value, or why there is none.
pub type JobResult<T> = Result<T, JobError>;

/// Work running on its own thread.
pub struct Job<T> {
    label: String,
    /// The latest progress fraction, as `f64` bits.
    progress: Arc<AtomicU64>,
    cancel: Arc<AtomicBool>,
    result: Receiver<JobResult<T>>,
    started: Instant,
}

impl<T: Send + 'static> Job<T> {
    /// Start `work` on a new thread. `repaint` is called when the progress moves (at most every
    /// 50 ms) and when the work ends, so the UI can draw the change (pass `ctx.request_repaint`).
    pub fn spawn<W, R>(label: impl Into<String>, repaint: R, work: W) -> Self
    where
        W: FnOnce(&mut dyn FnMut(f64) -> bool) -> JobResult<T> + Send + 'static,
        R: Fn() + Send + 'static,
    {
        let progress = Arc::new(AtomicU64::new(0f64.to_bits()));
        let cancel = Arc::new(AtomicBool::new(false));
        let (tx, rx) = mpsc::channel();
        let (worker_progress, worker_cancel) = (Arc::clone(&progress), Arc::clone(&cancel));
        let spawned = std::thread::Builder::new().name("jetid-job".into()).spawn(move || {
            let mut last_repaint = Instant::now();
            let mut report = |fraction: f64| {
                worker_progress.store(fraction.clamp(0.0, 1.0).to_bits(), Ordering::Relaxed);
                if last_repaint.elapsed() >= Duration::from_millis(50) {
                    last_repaint = Instant::now();
                    repaint();
                }
                !worker_cancel.load(Ordering::Relaxed)
            };
            let outcome = work(&mut report);
            let outcome =
                if worker_cancel.load(Ordering::Relaxed) { Err(JobError::Cancelled) } else { outcome };
            // The receiver is gone when the job was dropped; nobody wants the result then.
            let _ = tx.send(outcome);
            repaint();
        });
        let rx = match spawned {
            Ok(_) => rx,
            Err(err) => {
                let (tx, rx) = mpsc::channel();
                let _ = tx.send(Err(JobError::Failed(format!("could not start a worker thread: {err}"))));
                rx
            }
        };
        Self { label: label.into(), progress, cancel, result: rx, started: Instant::now() }
    }
}

impl<T> Job<T> {
    /// What the job does, for the progress indicator.
    pub fn label(&self) -> &str {
        &self.label
    }

    /// The fraction done, 0..=1, as the work last reported it.
    pub fn progress(&self) -> f64 {
        f64::from_bits(self.progress.load(Ordering::Relaxed))
    }

    pub fn elapsed(&self) -> Duration {
        self.started.elapsed()
    }

    /// Ask the work to stop; its result will be [`JobError::Cancelled`].
    pub fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }

    pub fn is_cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }

    /// The result once the work has ended (`None` while it runs). Call it every frame.
    pub fn poll(&self) -> Option<JobResult<T>> {
        match self.result.try_recv() {
            Ok(result) => Some(result),
            Err(TryRecvError::Empty) => None,
            Err(TryRecvError::Disconnected) => Some(Err(stopped())),
        }
    }

    /// Block until the work ends (for tests and screenshots, never in a frame).
    pub fn wait(self) -> JobResult<T> {
        self.result.recv().unwrap_or_else(|_| Err(stopped()))
    }
}

impl<T> Drop for Job<T> {
    /// A job nobody holds any more (its result was for a model nobody shows) stops its work.
    fn drop(&mut self) {
        self.cancel();
    }
}

fn stopped() -> JobError {
    JobError::Failed("the worker thread stopped without a result".into())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn a_job_hands_over_its_result_and_reports_progress() {
        let job = Job::spawn(
            "sum",
            || {},
            |progress| {
                let mut total = 0u64;
                for i in 0..=100u64 {
                    total += i;
                    progress(i as f64 / 100.0);
                }
                Ok(total)
            },
        );
        assert_eq!(job.label(), "sum");
        let progress = Arc::clone(&job.progress);
        assert_eq!(job.wait(), Ok(5050));
        assert!((f64::from_bits(progress.load(Ordering::Relaxed)) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn a_cancelled_job_says_so_even_when_the_work_ignores_the_answer() {
        let (go_tx, go_rx) = mpsc::channel::<()>();
        let job = Job::spawn(
            "wait",
            || {},
            move |progress| {
                go_rx.recv().map_err(|e| JobError::Failed(e.to_string()))?;
                let keep_going = progress(0.5);
                Ok(keep_going)
            },
        );
        job.cancel();
        assert!(job.is_cancelled());
        go_tx.send(()).unwrap();
        assert_eq!(job.wait(), Err(JobError::Cancelled));
    }

    #[test]
    fn poll_is_none_while_the_work_runs() {
        let (go_tx, go_rx) = mpsc::channel::<()>();
        let job =
            Job::spawn("wait", || {}, move |_| go_rx.recv().map_err(|e| JobError::Failed(e.to_string())));
        assert!(job.poll().is_none());
        go_tx.send(()).unwrap();
        assert_eq!(job.wait(), Ok(()));
    }
}
