//! Data computed from the session and recomputed when its revision changes: for now the plot
//! traces of each run. Later views add their caches (models, Bode curves, …) here.
use std::sync::Arc;

use egui_plot::PlotPoint;

use super::session::Session;
use crate::core::run::{Channel, Run};

/// Which part of a run a channel is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChannelKind {
    Input,
    /// Output number `n` of the run.
    Output(usize),
    /// Auxiliary channel number `n` of the run.
    Aux(usize),
}

/// One channel ready to plot against time.
#[derive(Clone, Debug)]
pub struct Trace {
    pub name: String,
    pub unit: String,
    pub kind: ChannelKind,
    pub points: Vec<PlotPoint>,
}

impl Trace {
    fn new(t_secs: &[f64], channel: &Channel, kind: ChannelKind) -> Self {
        let points = t_secs.iter().zip(&channel.values).map(|(&t, &v)| PlotPoint::new(t, v)).collect();
        Self { name: channel.name.clone(), unit: channel.unit.clone(), kind, points }
    }

    /// `name [unit]`, or the name alone when the unit is unknown.
    pub fn axis_label(&self) -> String {
        if self.unit.is_empty() { self.name.clone() } else { format!("{} [{}]", self.name, self.unit) }
    }
}

/// The traces of one run: input first, then outputs, then auxiliary channels.
#[derive(Clone, Debug)]
pub struct RunTraces {
    /// The run these traces were made from (compared by pointer to skip unchanged runs).
    source: Arc<Run>,
    pub traces: Vec<Trace>,
}

impl RunTraces {
    fn new(run: &Arc<Run>) -> Self {
        let t = &run.t_secs;
        let mut traces = vec![Trace::new(t, &run.input, ChannelKind::Input)];
        traces.extend(run.outputs.iter().enumerate().map(|(i, c)| Trace::new(t, c, ChannelKind::Output(i))));
        traces.extend(run.aux.iter().enumerate().map(|(i, c)| Trace::new(t, c, ChannelKind::Aux(i))));
        Self { source: Arc::clone(run), traces }
    }

    pub fn input(&self) -> impl Iterator<Item = &Trace> {
        self.traces.iter().filter(|t| t.kind == ChannelKind::Input)
    }

    pub fn outputs(&self) -> impl Iterator<Item = &Trace> {
        self.traces.iter().filter(|t| matches!(t.kind, ChannelKind::Output(_)))
    }

    pub fn aux(&self) -> impl Iterator<Item = &Trace> {
        self.traces.iter().filter(|t| matches!(t.kind, ChannelKind::Aux(_)))
    }
}

/// Everything derived from the session, tagged with the revision it was computed for.
#[derive(Default)]
pub struct Derived {
    revision: Option<u64>,
    /// One entry per session run, same order.
    pub runs: Vec<RunTraces>,
}

impl Derived {
    /// Bring the cache up to date with the session; cheap when nothing changed.
    pub fn refresh(&mut self, session: &Session) {
        if self.revision == Some(session.revision) && self.runs.len() == session.runs.len() {
            return;
        }
        let mut old = std::mem::take(&mut self.runs);
        self.runs = session
            .runs
            .iter()
            .map(|entry| match old.iter().position(|t| Arc::ptr_eq(&t.source, &entry.run)) {
                Some(i) => old.swap_remove(i),
                None => RunTraces::new(&entry.run),
            })
            .collect();
        self.revision = Some(session.revision);
    }

    pub fn revision(&self) -> Option<u64> {
        self.revision
    }
}
