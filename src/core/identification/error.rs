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
    TooFewSegmentFits { fitted: usize, segments: usize, diagnostics: String },
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
