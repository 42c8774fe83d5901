//! The identification data a fit reads ([`FitData`]): the run over the segments' range, its
//! steady windows and segment responses, and the cross-validation's folds over them.
use crate::core::effects::EffectError;
use crate::core::effects::thermal_soak::power_exponent_for;
use crate::core::identification::fits::SegmentFits;
use crate::core::identification::settings::OutputSettings;
use crate::core::run::{Channel, Run};

/// The identification data a model is fitted on: the run over the segments' range, and the
/// steady-state windows inside it.
#[derive(Clone, Debug, PartialEq)]
pub struct FitData {
    /// The output fitted.
    pub output: String,
    /// Sample time, s.
    pub dt_secs: f64,
    /// The identification run cut to the range of the segments.
    pub run: Run,
    /// The output over `run`.
    pub y: Vec<f64>,
    /// Steady-state windows `(start, end)` in `run`.
    pub steady_windows: Vec<(usize, usize)>,
    /// The longest segment's response after its step, s (the slowest dynamics the data can show).
    pub longest_segment_secs: f64,
    /// Highest static-map order the settings allow.
    pub max_static_order: usize,
    /// The form a fitted scheduled time constant takes.
    pub spool_schedule: crate::core::identification::settings::SpoolSchedule,
    /// Each segment's response `(step, end)` in `run`: the stretches a cross-validation holds out.
    pub responses: Vec<(usize, usize)>,
    /// Samples `(start, end)` of `run` left out of the fit (see [`FitData::folds`]): their error is
    /// not in the cost, and the steady windows they touch are not in the static map.
    pub held_out: Vec<(usize, usize)>,
    /// [`FitData::soak_power_exponent`], read from the run the first time it is asked for (and
    /// kept by a cross-validation's folds, which share the run).
    soak_power_exponent: std::sync::OnceLock<f64>,
}

impl FitData {
    /// The data the pipeline fitted `fits` on, for the output of `fits`.
    pub fn new(ident: &Run, fits: &SegmentFits, settings: &OutputSettings) -> Result<Self, EffectError> {
        let failed = |reason: String| EffectError::FitFailed { run: ident.name.clone(), reason };
        let start = fits.segments.first().map_or(0, |s| s.start);
        let end = fits.segments.last().map_or(0, |s| s.end).min(ident.len());
        if end < start + 10 {
            return Err(failed(format!("the segments span only samples {start}..{end}")));
        }
        let run = slice_run(ident, start, end);
        let y = run
            .output(&fits.output)
            .map(|c| c.values.clone())
            .ok_or_else(|| failed(format!("no output column '{}'", fits.output)))?;
        if y.len() != run.len() || run.input.values.len() != run.len() {
            return Err(failed("input, output and time have different lengths".to_owned()));
        }
        let tail = ((settings.settle_secs / ident.dt_secs).round() as usize).max(3);
        let mut steady_windows = Vec::with_capacity(fits.segments.len() + 1);
        if let Some(first) = fits.segments.first() {
            steady_windows.push((0, first.step_at.saturating_sub(start).max(1)));
        }
        for seg in &fits.segments {
            let (a, b) = seg.settled_tail(tail);
            steady_windows.push((a.saturating_sub(start), b.saturating_sub(start).min(y.len())));
        }
        steady_windows.retain(|(a, b)| a < b);
        let responses = fits
            .segments
            .iter()
            .map(|s| (s.step_at.saturating_sub(start), s.end.saturating_sub(start).min(y.len())))
            .filter(|(a, b)| a < b)
            .collect();
        let longest_segment_secs =
            fits.segments.iter().map(|s| s.end.saturating_sub(s.step_at)).max().unwrap_or(0) as f64
                * ident.dt_secs;
        Ok(Self {
            output: fits.output.clone(),
            dt_secs: ident.dt_secs,
            run,
            y,
            steady_windows,
            longest_segment_secs,
            max_static_order: settings.max_static_order,
            spool_schedule: settings.spool_schedule,
            responses,
            held_out: Vec::new(),
            soak_power_exponent: std::sync::OnceLock::new(),
        })
    }

    /// The data with the samples of `ranges` left out of the fit; the steady windows they touch
    /// go too.
    pub fn holding_out(&self, ranges: Vec<(usize, usize)>) -> Self {
        let touches = |&(a, b): &(usize, usize)| ranges.iter().any(|&(s, e)| s < b && a < e);
        let steady_windows = self.steady_windows.iter().copied().filter(|w| !touches(w)).collect();
        Self { steady_windows, held_out: ranges, ..self.clone() }
    }

    /// The power of the output a soak fitted on this data acts on ([`power_exponent_for`]).
    pub fn soak_power_exponent(&self) -> f64 {
        *self.soak_power_exponent.get_or_init(|| power_exponent_for(&self.output, &self.run))
    }

    /// Whether sample `k` of `run` is in the fit.
    pub fn is_fitted(&self, k: usize) -> bool {
        !self.held_out.iter().any(|&(a, b)| a <= k && k < b)
    }

    /// The [`FOLDS`] folds of a cross-validation over the segments: fold `i` holds out the
    /// responses of segments `i`, `i + FOLDS`, `i + 2·FOLDS`, …, so each fold is fitted on two
    /// thirds of the steps, spread over the whole operating range, and judged on the third it never
    /// saw. Interleaving rather than cutting in time keeps every fold's static map an interpolation;
    /// three folds rather than two keep both directions of an up-down staircase in every fold's
    /// fit (two folds would fit one on the rises alone). `None` with fewer than
    /// [`MIN_HELD_OUT_SEGMENTS`] segments per fold.
    pub fn folds(&self) -> Option<[Self; FOLDS]> {
        if self.responses.len() < FOLDS * MIN_HELD_OUT_SEGMENTS {
            return None;
        }
        Some(std::array::from_fn(|fold| {
            let out = self.responses.iter().enumerate().filter(|(i, _)| i % FOLDS == fold).map(|(_, r)| *r);
            self.holding_out(out.collect())
        }))
    }
}

/// Folds of the cross-validation over the segments (see [`FitData::folds`]).
pub const FOLDS: usize = 3;

/// Fewest segments a fold holds out: six segments in all, whose signed-rank test can reach
/// p = 1/64 alone; with fewer the held-out data cannot tell a structure from noise, and every fold's
/// fit keeps at least four segments (five steady points with the baseline) for its static map.
pub const MIN_HELD_OUT_SEGMENTS: usize = 2;

fn slice_run(run: &Run, start: usize, end: usize) -> Run {
    let cut = |c: &Channel| Channel {
        name: c.name.clone(),
        unit: c.unit.clone(),
        values: c.values.get(start..end).map(<[f64]>::to_vec).unwrap_or_default(),
    };
    Run {
        name: run.name.clone(),
        dt_secs: run.dt_secs,
        t_secs: run.t_secs.get(start..end).map(<[f64]>::to_vec).unwrap_or_default(),
        input: cut(&run.input),
        outputs: run.outputs.iter().map(cut).collect(),
        aux: run.aux.iter().map(cut).collect(),
    }
}
