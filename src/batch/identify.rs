//! Stage 2 of the batch: the gray-box model of one output.
use crate::core::identification::pipeline::{self, Identified, PipelineError, segments_for, step_signal};
use crate::core::identification::segment::{SegmentSettings, auto_segments_joined};
use crate::io::project::Project;

use super::load::Runs;

/// Identify one output as the project says: the project's segments, else steps detected on the
/// input (or the project's `steps_from` channel) of each joined identification run.
pub fn identify(project: &Project, runs: &Runs, output: &str) -> Result<Identified, PipelineError> {
    let ident = &runs.ident;
    let settings = project.settings_for(output);
    let segments = match project.segments.get(output) {
        Some(given) => segments_for(ident, Some(given), &SegmentSettings::default())?,
        None => {
            let signal = step_signal(ident, project.steps_from.as_deref())?;
            auto_segments_joined(signal, &runs.ident_junctions, ident.dt_secs, &SegmentSettings::default())
                .map_err(|source| PipelineError::Segment { run: ident.name.clone(), source })?
        }
    };
    pipeline::identify_output(
        ident,
        output,
        &settings,
        &segments,
        project.clusters.get(output).map(Vec::as_slice),
    )
}
