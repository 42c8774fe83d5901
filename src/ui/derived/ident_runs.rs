//! Which runs a model is identified on and scored on, from the session: its identification runs
//! joined end to end, their segments, and the validation, held-out and chirp runs on the
//! identification grid, each decided by the workflow's step ([`crate::workflow::runs`]) the batch
//! takes too.
use std::sync::Arc;

use crate::core::identification::segment::Segment;
use crate::core::run::{Run, RunRole};
use crate::ui::derived::live_model::Unavailable;
use crate::ui::state::session::Session;
use crate::workflow::runs::{
    Grid, grid_of, join_identification as join, resample_note, resampled_onto, segments,
};

/// The identification run from the session's identification runs: the one, or all of them joined
/// end to end with the junctions (what the batch does with a project's); when they cannot be joined,
/// the first alone, and the note says why.
pub(super) fn join_identification(sources: &[Arc<Run>]) -> Option<(Arc<Run>, Vec<usize>, Option<String>)> {
    let first = sources.first()?;
    if sources.len() == 1 {
        return Some((Arc::clone(first), Vec::new(), None));
    }
    let names: Vec<&str> = sources.iter().map(|r| r.name.as_str()).collect();
    let runs: Vec<Run> = sources.iter().map(|r| Run::clone(r)).collect();
    Some(match join(&runs) {
        Ok((joined, junctions)) => (
            Arc::new(joined),
            junctions,
            Some(format!(
                "identified on {} joined end to end (no segment crosses a join)",
                names.join(" + ")
            )),
        ),
        Err(e) => (
            Arc::clone(first),
            Vec::new(),
            Some(format!(
                "the identification runs cannot be joined ({e}): identified on {} alone",
                first.name
            )),
        ),
    })
}

/// The user's segments (checked), else steps detected on the input or on the `steps_from` channel,
/// each joined run on its own.
pub(super) fn detect_or_check(
    run: &Run,
    junctions: &[usize],
    given: Option<&[Segment]>,
    steps_from: Option<&str>,
) -> Result<Vec<Segment>, Unavailable> {
    segments(run, junctions, given, steps_from).map_err(|source| match steps_from {
        Some(channel) if given.is_none() => Unavailable::StepsOn { channel: channel.to_owned(), source },
        _ => Unavailable::Pipeline(source),
    })
}

/// A run a model is scored on.
#[derive(Clone)]
pub(super) struct ScoredSource {
    /// Index of the run in the session.
    pub(super) index: usize,
    pub(super) role: RunRole,
    /// The run as scored (on the identification run's grid).
    pub(super) run: Arc<Run>,
    /// The session's run it was made from.
    pub(super) source: Arc<Run>,
}

/// Validation runs, held-out runs, then chirp runs, that have the output and the identification
/// run's sampling. A run resampled from an irregular log onto its own median step (the load
/// option "resample") is put on the identification run's grid, as the batch does; the copy made
/// for `previous` (the last call's runs) is kept while its session run is the same, so a refresh
/// neither resamples again nor takes the unchanged run for a new one.
pub(super) fn scored_runs(
    session: &Session,
    ident: &Run,
    output: &str,
    notes: &mut Vec<String>,
    previous: &[ScoredSource],
) -> Vec<ScoredSource> {
    notes.clear();
    let mut scored = Vec::new();
    for role in RunRole::SCORED {
        for (index, entry) in session.runs.iter().enumerate().filter(|(_, r)| r.role == role) {
            let name = entry.display_name();
            if entry.run.output(output).is_none() {
                notes.push(format!("{} run {name} has no {output} column; not scored", role.label()));
                continue;
            }
            let run = match grid_of(&entry.run, ident.dt_secs, entry.options.resample) {
                Grid::On => Arc::clone(&entry.run),
                Grid::Resample => {
                    let kept = previous.iter().find(|p| {
                        Arc::ptr_eq(&p.source, &entry.run)
                            && (p.run.dt_secs - ident.dt_secs).abs() <= f64::EPSILON * ident.dt_secs
                    });
                    let (run, note) = match kept {
                        Some(kept) => (Arc::clone(&kept.run), resample_note(&entry.run, ident.dt_secs)),
                        None => {
                            let (run, note) = resampled_onto(&entry.run, ident.dt_secs);
                            (Arc::new(run), note)
                        }
                    };
                    notes.push(note);
                    run
                }
                Grid::Off(off_grid) => {
                    notes.push(format!(
                        "{} run {name}: not scored: {off_grid} (the load option \"resample\" puts it on the \
                         identification run's grid)",
                        role.label()
                    ));
                    continue;
                }
            };
            scored.push(ScoredSource { index, role, run, source: Arc::clone(&entry.run) });
        }
    }
    scored
}

/// The identification run, the junctions in it, the note on how it was made, and where it starts in
/// the joined identification runs.
pub(super) type IdentRun = (Arc<Run>, Vec<usize>, Option<String>, usize);

/// The joined identification run cut to the part its model is fitted on when it is long
/// ([`crate::workflow::runs::within_fit_budget`], as the batch cuts it), with where the cut starts; the note says so.
pub(super) fn within_fit_budget(
    joined: (Arc<Run>, Vec<usize>, Option<String>),
    (segments_given, named_steps_from): &(bool, Option<String>),
) -> Option<IdentRun> {
    let (run, junctions, join_note) = joined;
    if *segments_given || run.len() <= crate::workflow::long_runs::FIT_SAMPLES {
        return Some((run, junctions, join_note, 0));
    }
    let (cut, inside, window) = crate::workflow::runs::within_fit_budget(
        Arc::unwrap_or_clone(run),
        junctions,
        named_steps_from.as_deref(),
        false,
    );
    let (start, window_note) = window.map_or((0, None), |(start, note)| (start, Some(note)));
    let note = match (join_note, window_note) {
        (Some(a), Some(b)) => Some(format!("{a}; {b}")),
        (a, b) => a.or(b),
    };
    Some((Arc::new(cut), inside, note, start))
}
