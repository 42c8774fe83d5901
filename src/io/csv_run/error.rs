//! The errors of reading and writing run files; each names the file and, where it applies, the
//! line, the 1-based data row and the column.
use std::path::PathBuf;

use super::column_map::ColumnMapError;

/// Why a run file could not be read or written.
///
/// `line` is the line of the file (the header is line 1); `row` is the 1-based data row (the first
/// row under the header is row 1, which is sample 0 of a `--window`). Underlying errors are part
/// of the message rather than a `source`, so that printing an error chain names them once.
#[derive(Debug, thiserror::Error)]
pub enum RunFileError {
    #[error("{}: cannot read the file: {io}", file.display())]
    Unreadable { file: PathBuf, io: std::io::Error },

    #[error("{}: empty file: no header row", file.display())]
    Empty { file: PathBuf },

    #[error("{}: is a folder, not a run file; give the CSV file in it", file.display())]
    IsFolder { file: PathBuf },

    #[error("{}: not a text CSV file: it is {what}", file.display())]
    NotText { file: PathBuf, what: &'static str },

    #[error("{}: line {line}: malformed CSV: {message}", file.display())]
    Malformed { file: PathBuf, line: u64, message: String },

    #[error("{}: line 1: column \"{column}\" appears twice (columns {first} and {second})", file.display())]
    DuplicateColumn { file: PathBuf, column: String, first: usize, second: usize },

    #[error("{}: no {role} column \"{column}\"; columns present: {}{}", file.display(), present.join(", "), missing_hint(role))]
    MissingColumn { file: PathBuf, role: String, column: String, present: Vec<String> },

    #[error("{}: bad --map {role}={column}: no column \"{column}\"; columns present: {}", file.display(), present.join(", "))]
    MapColumnNotFound { file: PathBuf, role: String, column: String, present: Vec<String> },

    #[error("{}: {error}", file.display())]
    BadMap { file: PathBuf, error: ColumnMapError },

    #[error("{}: no output column (shaft_speed_rpm or thrust_n); columns present: {}; map one with --map output=COLUMN", file.display(), present.join(", "))]
    NoOutput { file: PathBuf, present: Vec<String> },

    #[error("{}: time is given twice: by column \"{column}\" and by a sample time of {sample_time_secs} s; give one", file.display())]
    TimeGivenTwice { file: PathBuf, column: String, sample_time_secs: f64 },

    #[error("{}: sample time {value} s is not a positive finite number", file.display())]
    BadSampleTime { file: PathBuf, value: f64 },

    #[error("{}: line {line} (data row {row}): {found} fields, the header has {expected}", file.display())]
    WrongFieldCount { file: PathBuf, line: u64, row: usize, expected: usize, found: usize },

    #[error("{}: line {line} (data row {row}), column \"{column}\": \"{cell}\" is not a number", file.display())]
    NonNumeric { file: PathBuf, line: u64, row: usize, column: String, cell: String },

    #[error("{}: line {line} (data row {row}), column \"{column}\": missing value (cell \"{cell}\" is empty, NaN or infinite)", file.display())]
    MissingValue { file: PathBuf, line: u64, row: usize, column: String, cell: String },

    #[error("{}: line {line} (data row {row}), quality column \"{column}\": \"{cell}\" is not 0 or 1", file.display())]
    BadQualityValue { file: PathBuf, line: u64, row: usize, column: String, cell: String },

    #[error("{}: quality column \"{column}\": {bad} of {total} samples are flagged bad (more than {max_pct} %)", file.display())]
    TooManyBadSamples { file: PathBuf, column: String, bad: usize, total: usize, max_pct: f64 },

    #[error("{}: line {line} (data row {row}), column \"{column}\": time {value} s does not increase (previous sample {previous} s); a log with repeated or irregular time stamps is read with resample = true in the project's [load] or --resample", file.display())]
    NonIncreasingTime { file: PathBuf, line: u64, row: usize, column: String, previous: f64, value: f64 },

    #[error("{}: line {line} (data row {row}), column \"{column}\": time step {step} s differs from the sample time {expected} s by more than {tolerance_pct} %; use --resample to resample onto a uniform grid", file.display())]
    NonUniformTime {
        file: PathBuf,
        line: u64,
        row: usize,
        column: String,
        step: f64,
        expected: f64,
        tolerance_pct: f64,
    },

    #[error("{}: {found} samples, at least {needed} are needed", file.display())]
    TooFewSamples { file: PathBuf, found: usize, needed: usize },

    #[error("{}: invalid values are given for channel \"{channel}\", which the run does not have (channels: {})", file.display(), present.join(", "))]
    UnknownInvalidChannel { file: PathBuf, channel: String, present: Vec<String> },

    #[error("{}: a unit is given for channel \"{channel}\", which the run does not have (channels: {})", file.display(), present.join(", "))]
    UnknownUnitChannel { file: PathBuf, channel: String, present: Vec<String> },

    #[error("{}: channel \"{channel}\" holds only its invalid-value sentinels ({values}): it has no reading to use", file.display())]
    AllInvalid { file: PathBuf, channel: String, values: String },

    #[error("{}: bad --window {window}: {reason}", file.display())]
    BadWindow { file: PathBuf, window: String, reason: String },

    #[error("{}: cannot write the run: channel \"{channel}\" has {found} values, the time axis {expected}", file.display())]
    ChannelLength { file: PathBuf, channel: String, found: usize, expected: usize },

    #[error("{}: cannot write the run: column \"{column}\" appears twice", file.display())]
    DuplicateChannel { file: PathBuf, column: String },

    #[error("{}: cannot write the run: channel \"{channel}\", sample {sample}: value {value} is not finite", file.display())]
    NonFiniteValue { file: PathBuf, channel: String, sample: usize, value: f64 },

    #[error("{}: cannot write the file: {io}", file.display())]
    Write { file: PathBuf, io: std::io::Error },
}

fn missing_hint(role: &str) -> &'static str {
    match role {
        "time" => "; give --sample-time SECONDS or --map time=COLUMN",
        "input" => "; map one with --map input=COLUMN",
        _ => "",
    }
}
