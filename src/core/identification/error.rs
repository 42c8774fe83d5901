//! What can go wrong identifying one output, for every step of the chain.
use crate::core::identification::cluster::ClusterError;
use crate::core::identification::segment::SegmentError;
use crate::core::identification::static_map::StaticMapError;
use crate::core::identification::wiener::WienerError;
use crate::core::numerics::metrics::MetricsError;

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PipelineError {
    #[error("run '{run}' has no output column '{output}' (outputs: {available})")]
    MissingOutput { run: String, output: String, available: String },
    #[error("segmentation of '{run}': {source}")]
    Segment { run: String, source: SegmentError },
    #[error(
        "steps_from = \"{channel}\": the identification run '{run}' has no such channel (map it with aux={channel})"
    )]
    NoStepChannel { run: String, channel: String },
    #[error("only {fitted} of {segments} segment models could be fitted (need at least 2): {diagnostics}")]
    /// (`diagnostics` says why each of the others could not be.)
    TooFewSegmentFits { fitted: usize, segments: usize, diagnostics: String },
    /// Fewer than two steps: one segment model tells nothing about which roots recur.
    #[error(
        "only {found} step segment(s) in '{run}', at least 2 are needed: record at least two steps of the input, each held until the engine settles"
    )]
    TooFewSegments { run: String, found: usize },
    #[error(transparent)]
    Cluster(#[from] ClusterError),
    #[error(transparent)]
    Wiener(#[from] WienerError),
    #[error("static map: {0}")]
    StaticMap(#[from] StaticMapError),
    #[error("scoring run '{run}': {source}")]
    Metrics { run: String, source: MetricsError },
    #[error("no model can be fitted: {reason}")]
    NoModel { reason: String },
}
