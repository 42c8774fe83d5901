//! Reading a run file: CSV table → roles → window → quality repair → time checks → `Run`.
use std::ops::Range;
use std::path::Path;

use super::column_map::{Layout, TimeBase, resolve_layout};
use super::repair::{
    TimeProblem, check_time, fill_gaps, mark_outliers, median_step, merge_repeated_times, resample,
};
use super::{
    DroppedColumn, LoadNotes, LoadOptions, MAX_BAD_FRACTION, MIN_SAMPLES, RunFileError, TIME_TOLERANCE,
    Window,
};
use crate::core::run::{Channel, Run};
use crate::core::running_window::{RunningWindow, running_window};

use super::table::{Cell, Source, Table, read_table};

/// The table plus what is needed to name a cell in an error.
struct Ctx<'a> {
    file: &'a Path,
    table: &'a Table<'a>,
}

impl Ctx<'_> {
    fn name(&self, col: usize) -> String {
        self.table.header.get(col).cloned().unwrap_or_default()
    }

    fn line(&self, row: usize) -> u64 {
        self.table.line(row)
    }

    fn cell(&self, row: usize, col: usize) -> String {
        self.table.text(row, col)
    }

    /// The error for a cell that is not a finite number (`row` 0-based).
    fn cell_error(&self, row: usize, col: usize, missing: bool) -> RunFileError {
        let (file, line, column, cell) =
            (self.file.to_owned(), self.line(row), self.name(col), self.cell(row, col));
        if missing {
            RunFileError::MissingValue { file, line, row: row + 1, column, cell }
        } else {
            RunFileError::NonNumeric { file, line, row: row + 1, column, cell }
        }
    }

    /// Which rows the quality column marks good (all of them without one).
    fn quality(&self, layout: &Layout) -> Result<Vec<bool>, RunFileError> {
        let n = self.table.n_rows();
        let Some(col) = layout.quality else {
            return Ok(vec![true; n]);
        };
        (0..n)
            .map(|row| match self.table.value(row, col) {
                Cell::Number(v) if (v - 1.0).abs() < 1e-9 => Ok(true),
                Cell::Number(v) if v.abs() < 1e-9 => Ok(false),
                _ => Err(RunFileError::BadQualityValue {
                    file: self.file.to_owned(),
                    line: self.line(row),
                    row: row + 1,
                    column: self.name(col),
                    cell: self.cell(row, col),
                }),
            })
            .collect()
    }

    /// Column `col` over `rows`, NaN in bad rows. A bad cell in a good row is an error when
    /// `strict`, otherwise the reason the column is dropped (`Ok(Err(reason))`). The column's cells
    /// are taken out of the table (each column is read once), so no second copy of it is made.
    fn column(
        &self,
        col: usize,
        rows: Range<usize>,
        good: &[bool],
        strict: bool,
    ) -> Result<Result<Vec<f64>, String>, RunFileError> {
        let mut values = self.table.take_column(col);
        values.truncate(rows.end);
        values.drain(..rows.start.min(values.len()));
        for (row, value) in rows.zip(values.iter_mut()) {
            if !good.get(row).copied().unwrap_or(true) {
                *value = f64::NAN;
                continue;
            }
            let bad = match Cell::decode(*value) {
                Cell::Number(_) => continue,
                bad => bad,
            };
            let missing = matches!(bad, Cell::Missing);
            if strict {
                return Err(self.cell_error(row, col, missing));
            }
            let what = if missing { "a missing value" } else { "a non-numeric value" };
            let cell = self.cell(row, col);
            return Ok(Err(format!("line {}: {what} (\"{cell}\")", self.line(row))));
        }
        Ok(Ok(values))
    }

    /// A strict column over `rows` with its bad samples interpolated.
    fn repaired_column(
        &self,
        col: usize,
        rows: Range<usize>,
        good: &[bool],
    ) -> Result<Vec<f64>, RunFileError> {
        let mut values = self.column(col, rows, good, true)?.unwrap_or_default();
        fill_gaps(&mut values);
        Ok(values)
    }

    /// The time of every row of `rows`: the time column (repaired), or the row times the sample time.
    fn time_column(
        &self,
        time: TimeBase,
        rows: Range<usize>,
        good: &[bool],
    ) -> Result<Vec<f64>, RunFileError> {
        match time {
            TimeBase::Column(col) => self.repaired_column(col, rows, good),
            TimeBase::Fixed { dt_secs } => Ok(rows.map(|row| row as f64 * dt_secs).collect()),
        }
    }

    /// The time of a row for selecting a window in seconds; NaN when unreadable.
    fn time_of_row(&self, time: TimeBase, row: usize) -> f64 {
        match time {
            TimeBase::Column(col) => match self.table.value(row, col) {
                Cell::Number(v) => v,
                _ => f64::NAN,
            },
            TimeBase::Fixed { dt_secs } => row as f64 * dt_secs,
        }
    }
}

/// Read a run from a CSV file's text; `file` names it in errors and gives the run name.
pub(super) fn parse(
    file: &Path,
    source: Source<'_>,
    opts: &LoadOptions,
) -> Result<(Run, LoadNotes), RunFileError> {
    check_sample_time(file, opts)?;
    let table = read_table(file, source)?;
    let layout = resolve_layout(file, &table.header, opts)?;
    let ctx = Ctx { file, table: &table };
    let good = ctx.quality(&layout)?;
    let (window, kept) = select_rows(&ctx, &layout, opts, &good)?;

    let mut t_secs = ctx.time_column(layout.time, kept.clone(), &good)?;
    let Channels { names, mut values, dropped: dropped_columns } =
        read_channels(&ctx, &layout, kept.clone(), &good)?;
    let invalid_samples = mark_invalid(file, &names, &mut values, &opts.invalid)?;
    let outliers = mark_all_outliers(&names, &mut values, kept.start);
    let axis = uniform_time(&ctx, layout.time, opts.resample, kept.start, &mut t_secs, &mut values)?;
    if t_secs.len() < MIN_SAMPLES {
        return Err(too_few_samples(file, t_secs.len()));
    }

    let mut roles = assign_roles(&ctx, &names, values, opts, layout.outputs.len())?;
    let running_window = matches!(opts.window, Some(Window::Running))
        .then(|| cut_to_running_window(&mut t_secs, &mut roles, axis.dt_secs));
    if t_secs.len() < MIN_SAMPLES {
        return Err(too_few_samples(file, t_secs.len()));
    }
    let name = file.file_stem().map_or_else(|| file.to_string_lossy(), |s| s.to_string_lossy()).into_owned();
    let notes = LoadNotes {
        time_column: match layout.time {
            TimeBase::Column(col) => Some(ctx.name(col)),
            TimeBase::Fixed { .. } => None,
        },
        rows_in_file: table.n_rows(),
        kept_rows: kept.clone(),
        repaired_samples: kept.clone().filter(|&row| !good.get(row).copied().unwrap_or(true)).count(),
        trimmed_bad_start: kept.start - window.start,
        trimmed_bad_end: window.end - kept.end,
        resampled: axis.resampled,
        merged_repeats: axis.merged_repeats,
        invalid_samples,
        dropped_columns,
        running_window,
        separator: table.separator,
        latin1_names: table.latin1_names.clone(),
        outliers,
    };
    let Roles { input, outputs, aux } = roles;
    Ok((Run { name, dt_secs: axis.dt_secs, t_secs, input, outputs, aux }, notes))
}

/// A given sample time must be a positive number.
fn check_sample_time(file: &Path, opts: &LoadOptions) -> Result<(), RunFileError> {
    match opts.sample_time_secs {
        Some(value) if !(value.is_finite() && value > 0.0) => {
            Err(RunFileError::BadSampleTime { file: file.to_owned(), value })
        }
        _ => Ok(()),
    }
}

/// Interpolate every channel's outliers; returns them as (channel, data row, value), `first_row`
/// being the data row of the channels' first sample.
fn mark_all_outliers(
    names: &[String],
    values: &mut [Vec<f64>],
    first_row: usize,
) -> Vec<(String, usize, f64)> {
    let mut outliers = Vec::new();
    for (name, column) in names.iter().zip(values.iter_mut()) {
        for (index, value) in mark_outliers(column) {
            outliers.push((name.clone(), first_row + index, value));
        }
    }
    outliers
}

/// The sample time of a run, and what was done to its time axis to make it uniform.
struct TimeAxis {
    dt_secs: f64,
    resampled: bool,
    merged_repeats: usize,
}

/// The sample time: the given one, or the time column's once it is checked uniform. With
/// `resample`, rows repeating the time stamp before them are merged first and a non-uniform axis
/// is resampled onto its median step (`t_secs` and `values` replaced); otherwise a non-uniform or
/// a non-increasing time is an error (`first_row` is the data row of `t_secs[0]`).
fn uniform_time(
    ctx: &Ctx<'_>,
    time: TimeBase,
    resample_time: bool,
    first_row: usize,
    t_secs: &mut Vec<f64>,
    values: &mut [Vec<f64>],
) -> Result<TimeAxis, RunFileError> {
    let col = match time {
        TimeBase::Fixed { dt_secs } => return Ok(TimeAxis { dt_secs, resampled: false, merged_repeats: 0 }),
        TimeBase::Column(col) => col,
    };
    let merged_repeats = if resample_time { merge_repeated_times(t_secs, values).unwrap_or(0) } else { 0 };
    match check_time(t_secs, TIME_TOLERANCE) {
        Ok(dt_secs) => Ok(TimeAxis { dt_secs, resampled: false, merged_repeats }),
        Err(TimeProblem::NonUniform { .. }) if resample_time => {
            let dt_secs = median_step(t_secs);
            *t_secs = resample(t_secs, values, dt_secs);
            Ok(TimeAxis { dt_secs, resampled: true, merged_repeats })
        }
        Err(problem) => Err(time_error(ctx, col, first_row, problem)),
    }
}

/// The run's channels by role.
struct Roles {
    input: Channel,
    outputs: Vec<Channel>,
    aux: Vec<Channel>,
}

/// The channels (`names[i]` holds `values[i]`) with their units from `opts.units`, which must name
/// channels of the run, by role: the input first, then `n_outputs` outputs, then the auxiliary ones.
fn assign_roles(
    ctx: &Ctx<'_>,
    names: &[String],
    values: Vec<Vec<f64>>,
    opts: &LoadOptions,
    n_outputs: usize,
) -> Result<Roles, RunFileError> {
    if let Some(channel) = opts.units.keys().find(|c| !names.contains(c)) {
        return Err(RunFileError::UnknownUnitChannel {
            file: ctx.file.to_owned(),
            channel: channel.clone(),
            present: names.to_vec(),
        });
    }
    let mut channels = names.iter().zip(values).map(|(name, v)| match opts.units.get(name) {
        Some(unit) => Channel { name: name.clone(), unit: unit.clone(), values: v },
        None => Channel::new(name, v),
    });
    // The input is always the first channel; this branch only keeps indexing out of the code.
    let Some(input) = channels.next() else {
        return Err(RunFileError::NoOutput { file: ctx.file.to_owned(), present: ctx.table.header.clone() });
    };
    let outputs: Vec<Channel> = channels.by_ref().take(n_outputs).collect();
    let aux: Vec<Channel> = channels.collect();
    Ok(Roles { input, outputs, aux })
}

/// Cut the run (`t_secs` and every channel) to its running part, found from the input and the
/// outputs; returns that part.
fn cut_to_running_window(t_secs: &mut Vec<f64>, roles: &mut Roles, dt_secs: f64) -> RunningWindow {
    let ys: Vec<&[f64]> = roles.outputs.iter().map(|c| c.values.as_slice()).collect();
    let found = running_window(&roles.input.values, &ys, dt_secs, t_secs.first().copied().unwrap_or(0.0));
    let keep = |v: &mut Vec<f64>| {
        v.truncate(found.end);
        v.drain(..found.start);
    };
    keep(t_secs);
    for c in std::iter::once(&mut roles.input).chain(&mut roles.outputs).chain(&mut roles.aux) {
        keep(&mut c.values);
    }
    found
}

/// Turn every sentinel of `invalid` (channel → values, compared to one part in 10⁹) into a gap and
/// interpolate it; returns how many samples of each channel held one. A sentinel for a channel the
/// run does not have, or a channel with nothing but sentinels, is an error.
fn mark_invalid(
    file: &Path,
    names: &[String],
    values: &mut [Vec<f64>],
    invalid: &std::collections::BTreeMap<String, Vec<f64>>,
) -> Result<Vec<(String, usize)>, RunFileError> {
    let mut counts = Vec::new();
    for (channel, sentinels) in invalid {
        let Some(index) = names.iter().position(|n| n == channel) else {
            return Err(RunFileError::UnknownInvalidChannel {
                file: file.to_owned(),
                channel: channel.clone(),
                present: names.to_vec(),
            });
        };
        let Some(column) = values.get_mut(index) else { continue };
        let is_sentinel = |v: f64| sentinels.iter().any(|s| (v - s).abs() <= 1e-9 * s.abs().max(1.0));
        let mut count = 0;
        for v in column.iter_mut().filter(|v| is_sentinel(**v)) {
            *v = f64::NAN;
            count += 1;
        }
        if count == column.len() && count > 0 {
            let values = sentinels.iter().map(ToString::to_string).collect::<Vec<_>>().join(", ");
            return Err(RunFileError::AllInvalid { file: file.to_owned(), channel: channel.clone(), values });
        }
        fill_gaps(column);
        if count > 0 {
            counts.push((channel.clone(), count));
        }
    }
    Ok(counts)
}

fn too_few_samples(file: &Path, found: usize) -> RunFileError {
    RunFileError::TooFewSamples { file: file.to_owned(), found, needed: MIN_SAMPLES }
}

/// The rows of the window, and the rows kept of it once bad samples at either end are trimmed.
fn select_rows(
    ctx: &Ctx<'_>,
    layout: &Layout,
    opts: &LoadOptions,
    good: &[bool],
) -> Result<(Range<usize>, Range<usize>), RunFileError> {
    let n_rows = ctx.table.n_rows();
    if n_rows < MIN_SAMPLES {
        return Err(too_few_samples(ctx.file, n_rows));
    }
    let window = match &opts.window {
        None => 0..n_rows,
        Some(window) => {
            window.select(n_rows, &|row| ctx.time_of_row(layout.time, row)).map_err(|reason| {
                RunFileError::BadWindow { file: ctx.file.to_owned(), window: window.to_string(), reason }
            })?
        }
    };
    let is_good = |row: &usize| good.get(*row).copied().unwrap_or(false);
    let bad = window.len() - window.clone().filter(is_good).count();
    if let Some(col) = layout.quality
        && bad as f64 > MAX_BAD_FRACTION * window.len() as f64
    {
        return Err(RunFileError::TooManyBadSamples {
            file: ctx.file.to_owned(),
            column: ctx.name(col),
            bad,
            total: window.len(),
            max_pct: 100.0 * MAX_BAD_FRACTION,
        });
    }
    // Bad samples at either end have no good neighbour to interpolate from: trim them.
    let first = window.clone().find(is_good).unwrap_or(window.start);
    let end = window.clone().rev().find(is_good).map_or(first, |last| last + 1);
    if end - first < MIN_SAMPLES {
        return Err(too_few_samples(ctx.file, end - first));
    }
    Ok((window, first..end))
}

/// The input, outputs and auxiliary channels, in that order: `names[i]` holds `values[i]`.
struct Channels {
    names: Vec<String>,
    values: Vec<Vec<f64>>,
    /// Unmapped columns left out because they are not numeric throughout.
    dropped: Vec<DroppedColumn>,
}

/// Read and repair every channel over the kept rows.
fn read_channels(
    ctx: &Ctx<'_>,
    layout: &Layout,
    kept: Range<usize>,
    good: &[bool],
) -> Result<Channels, RunFileError> {
    let mut names = Vec::new();
    let mut values = Vec::new();
    for &col in std::iter::once(&layout.input).chain(&layout.outputs).chain(&layout.aux) {
        names.push(ctx.name(col));
        values.push(ctx.repaired_column(col, kept.clone(), good)?);
    }
    let mut dropped = Vec::new();
    for &col in &layout.extras {
        match ctx.column(col, kept.clone(), good, false)? {
            Ok(mut column) => {
                fill_gaps(&mut column);
                names.push(ctx.name(col));
                values.push(column);
            }
            Err(reason) => dropped.push(DroppedColumn { name: ctx.name(col), reason }),
        }
    }
    for &col in &layout.ignored {
        let reason = "the sample time is given, so the time column is not read".to_owned();
        dropped.push(DroppedColumn { name: ctx.name(col), reason });
    }
    Ok(Channels { names, values, dropped })
}

fn time_error(ctx: &Ctx<'_>, col: usize, first_row: usize, problem: TimeProblem) -> RunFileError {
    let row = first_row + problem.index();
    let (file, line, column) = (ctx.file.to_owned(), ctx.line(row), ctx.name(col));
    match problem {
        TimeProblem::NonIncreasing { previous, value, .. } => {
            RunFileError::NonIncreasingTime { file, line, row: row + 1, column, previous, value }
        }
        TimeProblem::NonUniform { step, expected, .. } => {
            let tolerance_pct = 100.0 * TIME_TOLERANCE;
            RunFileError::NonUniformTime { file, line, row: row + 1, column, step, expected, tolerance_pct }
        }
    }
}
