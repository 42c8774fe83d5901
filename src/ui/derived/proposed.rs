//! The automatic cluster proposal of one output: a structure search (cross-validated across
//! segments) that takes longer than a frame, so it runs on a worker thread while the model views
//! say so.
use std::sync::Arc;

use crate::core::identification::fits::SegmentFits;
use crate::core::identification::settings::OutputSettings;
use crate::core::identification::structure::Proposal;
use crate::core::run::Run;
use crate::ui::derived::jobs::Job;
use crate::workflow::model;

/// The automatic proposal of one output: the structure search's result, or its job while it runs.
pub enum Proposed {
    Running(Job<Arc<Proposal>>),
    Ready(Arc<Proposal>),
    Failed(String),
}

impl Proposed {
    /// Start the structure search for `fits` on a worker thread.
    pub(super) fn start(fits: &Arc<SegmentFits>, run: &Arc<Run>, settings: &OutputSettings) -> Self {
        let (fits, run, settings) = (Arc::clone(fits), Arc::clone(run), settings.clone());
        Self::Running(Job::spawn(
            format!("Proposing clusters for {}", fits.output),
            || {},
            move |_| model::propose(&fits, &run, &settings).map(Arc::new).map_err(|e| e.to_string().into()),
        ))
    }

    pub fn proposal(&self) -> Option<&Proposal> {
        match self {
            Self::Ready(p) => Some(p),
            _ => None,
        }
    }

    pub fn is_running(&self) -> bool {
        matches!(self, Self::Running(_))
    }

    /// The job, while it runs (for its label and elapsed time).
    pub fn job(&self) -> Option<&Job<Arc<Proposal>>> {
        match self {
            Self::Running(job) => Some(job),
            _ => None,
        }
    }

    /// The input dead time the proposal's model carries, samples (`None`: no proposal, or its model
    /// was fitted directly).
    pub fn dead_time_samples(&self) -> Option<usize> {
        self.proposal().filter(|p| p.direct.is_none()).map(|p| p.dead_time.in_model())
    }
}
