//! The chirp run's measured frequency response, drawn on the Bode view: the Welch estimate the
//! batch's comparison uses ([`crate::workflow::products::chirp_points`]). Recomputed only when the
//! chirp run (or the identification run it is checked against) changes, never while clusters are
//! dragged.
use std::sync::Arc;

use crate::core::run::{Run, RunRole};
use crate::ui::state::session::Session;
use crate::workflow::products::{EmpiricalPoint, chirp_points};
use crate::workflow::runs::{Grid, grid_of};

/// The chirp's measured response of one output, and the runs it was computed from.
#[derive(Default)]
pub struct EmpiricalBode {
    /// The chirp and identification runs the points were computed from (compared by pointer).
    source: Option<(Arc<Run>, Arc<Run>)>,
    /// ω [rad/s], |G| [dB], ∠G [deg], coherence; empty when there is no chirp run or the estimate
    /// fails.
    pub points: Vec<EmpiricalPoint>,
}

impl EmpiricalBode {
    /// Bring the points up to date with the session's first chirp run that has `output` and the
    /// identification run's sampling.
    pub fn refresh(&mut self, session: &Session, ident: &Arc<Run>, output: &str) {
        let chirp = session
            .runs
            .iter()
            .filter(|r| r.role == RunRole::Chirp)
            .map(|r| &r.run)
            .find(|run| run.output(output).is_some() && grid_of(run, ident.dt_secs, false) == Grid::On);
        let Some(chirp) = chirp else {
            *self = Self::default();
            return;
        };
        let unchanged =
            self.source.as_ref().is_some_and(|(c, i)| Arc::ptr_eq(c, chirp) && Arc::ptr_eq(i, ident));
        if !unchanged {
            self.points = chirp_points(chirp, output);
            self.source = Some((Arc::clone(chirp), Arc::clone(ident)));
        }
    }
}
