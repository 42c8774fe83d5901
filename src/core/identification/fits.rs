//! The first step of the chain: the identification run's segments and one ARX model per segment
//! (with the input dead time estimated from the segments first, when the settings ask for it).
use serde::{Deserialize, Serialize};

use crate::core::identification::arx::{self, ArxModel, ArxOrders, DeadTime, fit_arx};
use crate::core::identification::cluster::SegmentRoots;
use crate::core::identification::error::PipelineError;
use crate::core::identification::segment::{Segment, SegmentSettings, auto_segments, check_segments};
use crate::core::identification::settings::OutputSettings;
use crate::core::numerics::stats::mean;
use crate::core::run::Run;

/// The ARX model of every segment, with the roots the clusters are drawn over.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SegmentFits {
    pub output: String,
    pub dt_secs: f64,
    pub segments: Vec<Segment>,
    pub models: Vec<ArxModel>,
    pub roots: Vec<SegmentRoots>,
    /// Segments that could not be fitted, and fits with rank deficiency.
    pub diagnostics: Vec<String>,
    /// The input dead time, when it was estimated from the segments.
    #[serde(default)]
    pub dead_time: Option<DeadTime>,
}

impl SegmentFits {
    /// The segment models' input delay, samples (1: none beyond the sampling).
    pub fn nk(&self) -> usize {
        self.models.first().map_or(1, |m| m.orders.nk)
    }
}

pub fn output_values<'a>(run: &'a Run, output: &str) -> Result<&'a [f64], PipelineError> {
    run.output(output).map(|c| c.values.as_slice()).ok_or_else(|| PipelineError::MissingOutput {
        run: run.name.clone(),
        output: output.to_owned(),
        available: run.outputs.iter().map(|c| c.name.as_str()).collect::<Vec<_>>().join(", "),
    })
}

/// The signal steps are found on: the run's input, or the channel `steps_from` names (a set-point
/// on closed-loop data, a command when the input sensor drops out).
pub fn step_signal<'a>(run: &'a Run, steps_from: Option<&str>) -> Result<&'a [f64], PipelineError> {
    match steps_from {
        None => Ok(&run.input.values),
        Some(name) => run
            .channel(name)
            .map(|c| c.values.as_slice())
            .ok_or_else(|| PipelineError::NoStepChannel { run: run.name.clone(), channel: name.to_owned() }),
    }
}

/// Segments of the identification run: the user's if given (checked), else detected.
pub fn segments_for(
    run: &Run,
    given: Option<&[Segment]>,
    settings: &SegmentSettings,
) -> Result<Vec<Segment>, PipelineError> {
    let wrap = |source| PipelineError::Segment { run: run.name.clone(), source };
    match given {
        Some(segments) => {
            check_segments(segments, run.len()).map_err(wrap)?;
            Ok(segments.to_vec())
        }
        None => auto_segments(&run.input.values, run.dt_secs, settings).map_err(wrap),
    }
}

/// Fit one ARX model per segment on deviations from the segment's starting steady state.
pub fn fit_segments(
    run: &Run,
    output: &str,
    segments: &[Segment],
    orders: ArxOrders,
) -> Result<SegmentFits, PipelineError> {
    let y = output_values(run, output)?;
    let u = &run.input.values;
    let mut models = Vec::new();
    let mut roots = Vec::new();
    let mut fitted_segments = Vec::new();
    let mut diagnostics = Vec::new();
    for seg in segments {
        let (u0, y0) = (mean(&u[seg.start..seg.step_at]), mean(&y[seg.start..seg.step_at]));
        let du: Vec<f64> = u[seg.start..seg.end].iter().map(|v| v - u0).collect();
        let dy: Vec<f64> = y[seg.start..seg.end].iter().map(|v| v - y0).collect();
        match fit_arx(&du, &dy, orders, run.dt_secs) {
            Ok(model) => {
                if model.rank < orders.n_params() {
                    diagnostics.push(format!(
                        "segment {}: rank {} of {} (condition {:.2e}); minimum-norm solution used",
                        seg.label,
                        model.rank,
                        orders.n_params(),
                        model.cond
                    ));
                }
                roots.push(SegmentRoots {
                    label: seg.label.clone(),
                    poles: model.poles.clone(),
                    zeros: model.zeros.clone(),
                });
                models.push(model);
                fitted_segments.push(seg.clone());
            }
            Err(err) => diagnostics.push(format!("segment {}: {err}", seg.label)),
        }
    }
    if segments.len() < 2 {
        return Err(PipelineError::TooFewSegments { run: run.name.clone(), found: segments.len() });
    }
    if models.len() < 2 {
        return Err(PipelineError::TooFewSegmentFits {
            fitted: models.len(),
            segments: segments.len(),
            diagnostics: diagnostics.join("; "),
        });
    }
    Ok(SegmentFits {
        output: output.to_owned(),
        dt_secs: run.dt_secs,
        segments: fitted_segments,
        models,
        roots,
        diagnostics,
        dead_time: None,
    })
}

/// Longest input dead time searched, s: fuel-line and valve delays of small engines are well under
/// it, and the step segments (tens of seconds) show several times this much response after it.
pub const MAX_DEAD_TIME_SECS: f64 = 2.5;

/// [`fit_segments`] with the output's settings: the input dead time estimated from the segments
/// first when the settings ask for it (see [`arx::estimate_dead_time`]), else `orders.nk`.
pub fn fit_segments_for(
    run: &Run,
    output: &str,
    segments: &[Segment],
    settings: &OutputSettings,
) -> Result<SegmentFits, PipelineError> {
    if !settings.estimate_dead_time {
        return fit_segments(run, output, segments, settings.orders);
    }
    let y = output_values(run, output)?;
    let u = &run.input.values;
    let deviations: Vec<(Vec<f64>, Vec<f64>)> = segments
        .iter()
        .filter(|seg| seg.start < seg.step_at && seg.end <= y.len() && seg.end <= u.len())
        .map(|seg| {
            let (u0, y0) = (mean(&u[seg.start..seg.step_at]), mean(&y[seg.start..seg.step_at]));
            (
                u[seg.start..seg.end].iter().map(|v| v - u0).collect(),
                y[seg.start..seg.end].iter().map(|v| v - y0).collect(),
            )
        })
        .collect();
    let max_nk = ((MAX_DEAD_TIME_SECS / run.dt_secs).round() as usize).clamp(1, 50);
    let dead_time = arx::estimate_dead_time(&deviations, settings.orders.na, max_nk);
    let nk = dead_time.as_ref().map_or(settings.orders.nk, |d| d.nk);
    let mut fits = fit_segments(run, output, segments, ArxOrders { nk, ..settings.orders })?;
    fits.dead_time = dead_time;
    Ok(fits)
}
