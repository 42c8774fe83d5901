//! Data computed from the session and recomputed when its revision changes: the plot traces of
//! each run and the identification (see [`model_cache`]), plus the live preview of a cluster drag.
//! Every model is built by the workflow's steps ([`crate::workflow`]), as the batch builds it.
//!
//! The modules import one way: `jobs` and `live_model` (the data) ← `ident_runs`,
//! `empirical_bode`, `model_build`, `diagnosis_model`, `residuals` ← `model_cache` ← this one.
//! `fleet_history` (a fleet for the History view, not from the session) imports only `jobs`.
pub mod diagnosis_model;
pub mod empirical_bode;
pub mod fleet_history;
mod ident_runs;
pub mod jobs;
pub mod live_model;
mod model_build;
pub mod model_cache;
mod proposed;
pub mod residuals;
pub mod uncertainty;
use std::sync::Arc;

use egui_plot::PlotPoint;

use crate::core::identification::cluster::{Cluster, ClusterEval};
use crate::core::run::{Channel, Run};
use crate::ui::derived::live_model::Unavailable;
use crate::ui::derived::model_cache::{IdentCache, LiveModel, OutputCache, Preview};
use crate::ui::state::session::Session;

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

    /// `name [unit]`, or the name alone when the unit is unknown or is the name.
    pub fn axis_label(&self) -> String {
        crate::core::run::name_with_unit(&self.name, &self.unit)
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
    /// The identification; `None` when the session has no identification run.
    pub ident: Option<IdentCache>,
    /// The live path on the clusters being dragged.
    pub preview: Option<Preview>,
}

/// What a model view shows for one output: the committed model or, during a drag, the preview.
pub struct LiveView<'a> {
    pub output: &'a OutputCache,
    pub clusters: &'a [Cluster],
    pub evals: &'a Result<Vec<ClusterEval>, Unavailable>,
    pub live: &'a Result<LiveModel, Unavailable>,
    /// The clusters are being dragged: the model is a preview, centroids not polished.
    pub is_preview: bool,
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
        self.ident = IdentCache::refresh(self.ident.take(), session);
        self.preview = None;
        self.revision = Some(session.revision);
    }

    /// Run the live path on clusters being dragged (`None`: no drag). Returns true when the
    /// preview changed, so the caller can ask for another frame.
    pub fn set_preview(&mut self, request: Option<(&str, &[Cluster])>) -> bool {
        let Some((output, clusters)) = request else {
            return self.preview.take().is_some();
        };
        if self.preview.as_ref().is_some_and(|p| p.output == output && p.clusters == clusters) {
            return false;
        }
        self.preview = self.ident.as_ref().and_then(|ident| {
            let cache = ident.output(output)?;
            let inputs = cache.inputs(&ident.run);
            Some(Preview::compute(&inputs, output, clusters.to_vec(), &cache.preview_settings()))
        });
        true
    }

    /// The output's cache, if the identification has it.
    pub fn output(&self, name: &str) -> Option<&OutputCache> {
        self.ident.as_ref()?.output(name)
    }

    /// The output's model as the views should show it (the drag preview when there is one).
    pub fn live_view(&self, name: &str) -> Option<LiveView<'_>> {
        let output = self.output(name)?;
        Some(match self.preview.as_ref().filter(|p| p.output == name) {
            Some(p) => {
                LiveView { output, clusters: &p.clusters, evals: &p.evals, live: &p.live, is_preview: true }
            }
            None => LiveView {
                output,
                clusters: &output.clusters,
                evals: &output.evals,
                live: &output.live,
                is_preview: false,
            },
        })
    }

    /// The names of the outputs being identified.
    pub fn output_names(&self) -> Vec<&str> {
        self.ident.as_ref().map(|i| i.outputs.iter().map(|o| o.name.as_str()).collect()).unwrap_or_default()
    }

    pub fn revision(&self) -> Option<u64> {
        self.revision
    }
}
