//! Run files (CSV) of CONTRACT.md: reading with column mapping, writing atomically.
//!
//! # Reading
//! One header row, comma-separated, `.` decimal point; cells and names are trimmed. Roles come from
//! the canonical names (`time_s`; `fuel_flow_gph`; `shaft_speed_rpm`, `thrust_n`) or from a
//! [`ColumnMap`]. The steps, in order:
//! 1. **Columns.** Duplicate names are an error. A mapped column must exist. When the map names
//!    auxiliary columns only those are kept; otherwise every other named column is kept as an
//!    auxiliary channel *if all its cells (in good samples) are finite numbers*, and is otherwise
//!    left out without an error (listed in [`LoadNotes::dropped_columns`]): extra text columns
//!    such as a date or a comment must not stop a run from loading. Input, output, mapped
//!    auxiliary and time columns are strict: a bad cell is an error naming line, row and column.
//! 2. **Time.** The time column, or `k · sample_time_secs` (0-based row `k`) when the sample time
//!    is given; then a `time_s` column is not read. A mapped time column and a sample time together
//!    are an error.
//! 3. **Window** ([`Window`]): keep rows `START..END` (half-open), in samples or seconds.
//! 4. **Quality** (`LoadOptions::quality`, a 0/1 column where 0 marks a corrupt sample): bad
//!    samples at either end of the window are trimmed (nothing to interpolate from); the others are
//!    replaced in every channel, time included, by linear interpolation between the nearest good
//!    samples — their cells may hold anything, even text. More than 50 % bad samples in the window
//!    is an error. The quality column itself is not kept as a channel.
//! 5. **Time checks.** Time must strictly increase; every step must be within 1 % of the median
//!    step, which becomes `dt_secs`. With `LoadOptions::resample` a non-uniform (but increasing)
//!    time axis is resampled onto `t0 + k · dt` by linear interpolation; a uniform one is left as is.
//! 6. At least [`MIN_SAMPLES`] samples must remain.
//!
//! # Writing
//! [`write_run`] writes `time_s, <input>, <outputs…>, <aux…>` with Rust's shortest round-trip
//! representation of each `f64` (exact on reading back, and short for values such as `0.1`), to a
//! temporary file in the destination directory that is then renamed into place.
use std::ops::Range;
use std::path::Path;

use crate::core::run::Run;

mod column_map;
mod error;
mod read;
mod repair;
mod table;
mod window;
mod write;

pub use column_map::{ColumnMap, ColumnMapError, INPUT_COLUMN, MapSpec, OUTPUT_COLUMNS, Role, TIME_COLUMN};
pub use error::RunFileError;
pub use window::{Window, WindowSpecError};

/// Fewest samples a run may have after windowing and trimming.
pub const MIN_SAMPLES: usize = 10;
/// Largest share of samples the quality column may flag bad.
pub const MAX_BAD_FRACTION: f64 = 0.5;
/// Largest deviation of a time step from the median step, relative to it.
pub const TIME_TOLERANCE: f64 = 0.01;

/// How to read a run file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadOptions {
    pub map: ColumnMap,
    /// Sample time for files without a time column.
    pub sample_time_secs: Option<f64>,
    /// Keep only this part of the file.
    pub window: Option<Window>,
    /// A 0/1 column (e.g. `crc_ok`) where 0 marks a corrupt sample to repair.
    pub quality: Option<String>,
    /// Resample a non-uniform time axis instead of refusing it.
    pub resample: bool,
    /// Per channel, values the logger writes when the channel has no valid reading (a sentinel such
    /// as ±3276.8): they become gaps, interpolated like bad samples.
    pub invalid: std::collections::BTreeMap<String, Vec<f64>>,
    /// Per channel, its unit where the column name does not say it (`PR = "-"`, `power_kW = "kW"`).
    pub units: std::collections::BTreeMap<String, String>,
    /// Read the time and the input only (a fuel schedule to predict from): no output is required,
    /// and other columns are auxiliary channels, left out with the reason when they hold bad values.
    pub input_only: bool,
}

/// A bad option string given to [`LoadOptions::from_cli`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum LoadOptionsError {
    #[error(transparent)]
    Map(#[from] ColumnMapError),
    #[error(transparent)]
    Window(#[from] WindowSpecError),
    #[error("bad --invalid \"{spec}\": expected CHANNEL=VALUE[,VALUE...], e.g. T_inlet_C=-3276.8,3276.8")]
    Invalid { spec: String },
}

impl LoadOptions {
    /// Options from command-line strings: `--map ROLE=COLUMN`…, `--sample-time`, `--window`,
    /// `--quality`, `--resample`. The sample time is checked when a file is read.
    pub fn from_cli<S: AsRef<str>>(
        maps: &[S],
        sample_time_secs: Option<f64>,
        window: Option<&str>,
        quality: Option<&str>,
        resample: bool,
    ) -> Result<Self, LoadOptionsError> {
        Ok(LoadOptions {
            map: ColumnMap::from_specs(maps)?,
            sample_time_secs,
            window: window.map(str::parse).transpose()?,
            quality: quality.map(str::to_owned),
            resample,
            invalid: std::collections::BTreeMap::new(),
            units: std::collections::BTreeMap::new(),
            input_only: false,
        })
    }

    /// `self` with the sentinels of `--invalid CHANNEL=V1,V2` strings added.
    pub fn with_invalid_specs<S: AsRef<str>>(mut self, specs: &[S]) -> Result<Self, LoadOptionsError> {
        for spec in specs {
            let spec = spec.as_ref();
            let bad = || LoadOptionsError::Invalid { spec: spec.to_owned() };
            let (channel, list) = spec.split_once('=').ok_or_else(bad)?;
            let values: Vec<f64> = list
                .split(',')
                .map(|v| v.trim().parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|_| bad())?;
            if channel.trim().is_empty() || values.iter().any(|v| !v.is_finite()) {
                return Err(bad());
            }
            self.invalid.entry(channel.trim().to_owned()).or_default().extend(values);
        }
        Ok(self)
    }
}

/// A column left out of the run, and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DroppedColumn {
    pub name: String,
    pub reason: String,
}

/// What loading did besides reading numbers, for `jetid inspect` and the app's data view.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadNotes {
    /// The column the time axis came from; `None` when it came from the sample time.
    pub time_column: Option<String>,
    /// Data rows in the file.
    pub rows_in_file: usize,
    /// The rows of the file kept (0-based sample indices, half-open), after window and trimming.
    pub kept_rows: Range<usize>,
    /// Samples flagged bad by the quality column and interpolated.
    pub repaired_samples: usize,
    /// Bad samples trimmed at the start and at the end of the window.
    pub trimmed_bad_start: usize,
    pub trimmed_bad_end: usize,
    /// Whether the time axis was resampled onto a uniform grid.
    pub resampled: bool,
    /// Rows merged into the row before them because they repeat its time stamp (with `resample`).
    pub merged_repeats: usize,
    /// Per channel, the samples that held an invalid-value sentinel and were interpolated.
    pub invalid_samples: Vec<(String, usize)>,
    pub dropped_columns: Vec<DroppedColumn>,
    /// With `window = "auto"`: the running part kept, and how it was found.
    pub running_window: Option<crate::core::running_window::RunningWindow>,
    /// The field separator when it was not a comma (`;` or a tab; decimal commas are read too).
    pub separator: Option<char>,
    /// Column names that were not UTF-8 and were read as Latin-1: (the bytes, the name read).
    pub latin1_names: Vec<(String, String)>,
    /// Samples so far from their neighbours that no engine makes them (see `repair::outliers`),
    /// interpolated: (channel, data row of the file, value).
    pub outliers: Vec<(String, usize, f64)>,
}

impl LoadNotes {
    /// What reading the file had to interpret, in words: the separator, names that were not UTF-8,
    /// outliers interpolated.
    pub fn reading_notes(&self) -> Vec<String> {
        let mut notes = Vec::new();
        if let Some(sep) = self.separator {
            let name = if sep == '\t' { "tab".to_owned() } else { format!("'{sep}'") };
            notes.push(format!("fields separated by {name} (decimal commas read as points)"));
        }
        for (bytes, name) in &self.latin1_names {
            notes.push(format!("column name \"{bytes}\" is not UTF-8: read as Latin-1, \"{name}\""));
        }
        for (channel, row, value) in &self.outliers {
            notes.push(format!(
                "data row {row}: {channel} = {value:e} is an outlier (orders of magnitude off its neighbours and its \
                 range): interpolated"
            ));
        }
        notes
    }
}

/// Read a run file. The run is named after the file stem.
pub fn load_run(path: &Path, opts: &LoadOptions) -> Result<Run, RunFileError> {
    load_run_with_notes(path, opts).map(|(run, _)| run)
}

/// Read a run file and report what was repaired, trimmed or left out.
pub fn load_run_with_notes(path: &Path, opts: &LoadOptions) -> Result<(Run, LoadNotes), RunFileError> {
    // Streamed: a long log is parsed cell by cell into numbers, never held as text.
    let meta =
        std::fs::metadata(path).map_err(|io| RunFileError::Unreadable { file: path.to_owned(), io })?;
    if meta.is_dir() {
        return Err(RunFileError::IsFolder { file: path.to_owned() });
    }
    read::parse(path, table::Source::File(path), opts)
}

/// Read a run from CSV bytes in memory; `name` stands for the file in errors and names the run
/// (its stem, as for a file).
pub fn parse_run(name: &str, bytes: &[u8], opts: &LoadOptions) -> Result<Run, RunFileError> {
    parse_run_with_notes(name, bytes, opts).map(|(run, _)| run)
}

/// [`parse_run`] with the [`LoadNotes`].
pub fn parse_run_with_notes(
    name: &str,
    bytes: &[u8],
    opts: &LoadOptions,
) -> Result<(Run, LoadNotes), RunFileError> {
    read::parse(Path::new(name), table::Source::Bytes(bytes), opts)
}

/// Write a run file atomically (temporary file in the same directory, then rename); a missing
/// parent directory is created.
pub fn write_run(path: &Path, run: &Run) -> Result<(), RunFileError> {
    let text = write::csv_text(path, run)?;
    write::write_atomically(path, text.as_bytes())
}

/// Named columns held in memory (a data frame's) as the text of a run file, so that they are read
/// exactly as that file would be ([`parse_run_with_notes`]): the same column roles, load options,
/// repairs and checks. Numbers round-trip exactly; a NaN or infinite value becomes an empty cell,
/// which the reader treats as a file's: refused with its row and column, unless a quality column
/// marks the row for repair or the column is auxiliary (then left out). `name` stands for the file
/// in errors.
pub fn table_to_csv(name: &str, columns: &[(&str, &[f64])]) -> Result<String, RunFileError> {
    write::table_text(Path::new(name), columns)
}

/// The CSV text [`write_run`] would write. Errors name the run instead of a file.
pub fn run_to_csv_string(run: &Run) -> Result<String, RunFileError> {
    write::csv_text(Path::new(&run.name), run)
}
