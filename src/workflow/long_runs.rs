//! A long identification log: the part of it the model's output-error fits work on.
//!
//! Reading a log, finding its steps and scoring a model on it cost a pass over its samples, and
//! jetid does them on every sample of any length. The fits that refine the model by its simulation
//! error do not: every trial structure, cross-validation fold, effect and baseline simulates the
//! run tens of times, so an eight-hour log (1.5 M samples at 50 Hz) would keep them busy for an
//! hour. A log longer than [`FIT_SAMPLES`] is therefore identified on its first whole segments up to
//! that many samples, and the notes say so, with the samples and segments used and how to choose
//! another part (a `window` on the run). One contiguous stretch rather than pieces spread over the
//! log: joined pieces would put a jump in input and output at every join, which a simulated model
//! has to recover from and which would count as model error.
use std::ops::Range;

use crate::core::identification::segment::Segment;
use crate::core::numerics::stats::significant;
use crate::core::run::Run;

/// Most samples the identification run's output-error fits use: 30 000 samples, 56 min at the
/// bundled 8.85 Hz, about 60 step responses of the bundled identification design (seven steps in
/// 3 300 samples). The parameters' standard errors fall as 1/√N, so 60 steps fix them √(60/7) ≈ 3
/// times better than the bundled run, below the error the model's structure leaves; while the fits'
/// cost grows with N (about 1 ms a sample and output on this machine's class, so 30 000 samples keep
/// the batch of a log of any length within two minutes on two cores).
pub const FIT_SAMPLES: usize = 30_000;

/// The part of a long identification run its fits use.
#[derive(Clone, Debug, PartialEq)]
pub struct FitWindow {
    /// Samples of the run, from the first segment's start to the last kept segment's end.
    pub range: Range<usize>,
    pub segments_kept: usize,
    pub segments_total: usize,
}

impl FitWindow {
    /// The window of `run` (whose segments are `segments`, in order) when the segments span more
    /// than `budget` samples: the first whole segments up to `budget` samples (at least two, so
    /// that there is something to cluster). `None` when the run fits the budget.
    pub fn of(segments: &[Segment], budget: usize) -> Option<Self> {
        let (first, last) = (segments.first()?, segments.last()?);
        if last.end.saturating_sub(first.start) <= budget {
            return None;
        }
        let kept = segments.iter().take_while(|s| s.end.saturating_sub(first.start) <= budget).count().max(2);
        let end = segments.get(kept - 1).map_or(last.end, |s| s.end);
        Some(Self { range: first.start..end, segments_kept: kept, segments_total: segments.len() })
    }

    /// The run cut to the window, and the junctions (where joined runs start) inside it.
    pub fn apply(&self, run: &Run, junctions: &[usize]) -> (Run, Vec<usize>) {
        let inside = junctions
            .iter()
            .filter(|&&j| j > self.range.start && j < self.range.end)
            .map(|j| j - self.range.start)
            .collect();
        (run.slice(self.range.clone()), inside)
    }

    /// What was done, for the notes.
    pub fn words(&self, run: &Run) -> String {
        let at = |k: usize| significant(run.t_secs.get(k).copied().unwrap_or(0.0), 6);
        format!(
            "the identification run '{}' is long ({} samples, {} segments): its model is fitted on its first {} \
             segments, samples {}..{} ({} s to {} s, {} samples; at most {FIT_SAMPLES} keep the fits' time bounded); \
             the validation and held-out runs are scored whole. To fit on another part, give the run a window \
             (window = \"from:to\" in the project)",
            run.name,
            run.len(),
            self.segments_total,
            self.segments_kept,
            self.range.start,
            self.range.end,
            at(self.range.start),
            at(self.range.end.saturating_sub(1)),
            self.range.len(),
        )
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn segments(count: usize, length: usize) -> Vec<Segment> {
        (0..count)
            .map(|i| Segment {
                label: format!("S{i}"),
                start: 100 + i * length,
                step_at: 100 + i * length + 10,
                end: 100 + (i + 1) * length,
            })
            .collect()
    }

    #[test]
    fn a_run_within_the_budget_is_fitted_whole() {
        assert_eq!(FitWindow::of(&segments(7, 400), 2_800), None);
    }

    #[test]
    fn a_long_run_keeps_whole_segments_up_to_the_budget() {
        let window = FitWindow::of(&segments(100, 400), 2_900).unwrap();
        assert_eq!(window.segments_kept, 7);
        assert_eq!(window.range, 100..2_900);
        assert_eq!(window.segments_total, 100);
        // A budget below two segments still keeps two.
        assert_eq!(FitWindow::of(&segments(100, 400), 300).unwrap().segments_kept, 2);
    }

    #[test]
    fn the_cut_run_keeps_the_junctions_inside_it() {
        let n = 5_000;
        let run = Run {
            name: "long".into(),
            dt_secs: 0.1,
            t_secs: (0..n).map(|k| k as f64 * 0.1).collect(),
            input: crate::core::run::Channel::new("fuel_flow_gph", (0..n).map(|k| k as f64).collect()),
            outputs: vec![crate::core::run::Channel::new("shaft_speed_rpm", vec![1.0; n])],
            aux: Vec::new(),
        };
        let window = FitWindow::of(&segments(10, 400), 2_000).unwrap();
        let (cut, junctions) = window.apply(&run, &[50, 900, 4_000]);
        assert_eq!(cut.len(), window.range.len());
        assert_eq!(cut.input.values.first().copied(), Some(100.0));
        assert_eq!(junctions, vec![800]);
        assert!(window.words(&run).contains("first 5 segments"));
    }
}
