//! Writing a run file: `time_s, <input>, <outputs…>, <aux…>`, written to a temporary file in the
//! same directory and renamed into place.
use std::fmt::Write as _;
use std::fs;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use super::RunFileError;
use super::column_map::TIME_COLUMN;
use crate::core::run::{Channel, Run};

/// The run as CSV text. Numbers use Rust's shortest representation that reads back to the same
/// `f64` (`{:?}`: `0.1`, `1234.5678`, `1e-7`), so a write → read round trip is exact.
///
/// `file` names the destination in errors: a channel of another length than the time axis, a
/// repeated column name or a non-finite value is refused, since the file could not be read back.
pub(super) fn csv_text(file: &Path, run: &Run) -> Result<String, RunFileError> {
    let time = Channel { name: TIME_COLUMN.to_owned(), unit: "s".to_owned(), values: run.t_secs.clone() };
    let columns: Vec<&Channel> = std::iter::once(&time)
        .chain(std::iter::once(&run.input))
        .chain(&run.outputs)
        .chain(&run.aux)
        .collect();
    for (i, column) in columns.iter().enumerate() {
        if columns.iter().skip(i + 1).any(|other| other.name == column.name) {
            return Err(RunFileError::DuplicateChannel {
                file: file.to_owned(),
                column: column.name.clone(),
            });
        }
        if column.values.len() != run.t_secs.len() {
            return Err(RunFileError::ChannelLength {
                file: file.to_owned(),
                channel: column.name.clone(),
                found: column.values.len(),
                expected: run.t_secs.len(),
            });
        }
        if let Some((sample, &value)) = column.values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(RunFileError::NonFiniteValue {
                file: file.to_owned(),
                channel: column.name.clone(),
                sample,
                value,
            });
        }
    }

    let named: Vec<(&str, &[f64])> = columns.iter().map(|c| (c.name.as_str(), c.values.as_slice())).collect();
    table_text(file, &named)
}

/// Named columns of equal length as CSV text: the header through the csv writer (so that a name
/// holding a comma or quote is quoted), then each row, numbers as `{:?}` (an exact round trip) and
/// a non-finite value as an empty cell, which the reader takes for a missing one.
pub(super) fn table_text(file: &Path, columns: &[(&str, &[f64])]) -> Result<String, RunFileError> {
    let rows = columns.first().map_or(0, |(_, values)| values.len());
    if let Some((name, values)) = columns.iter().find(|(_, values)| values.len() != rows) {
        return Err(RunFileError::ChannelLength {
            file: file.to_owned(),
            channel: (*name).to_owned(),
            found: values.len(),
            expected: rows,
        });
    }
    let mut header = csv::Writer::from_writer(Vec::new());
    let write_error = |err: std::io::Error| RunFileError::Write { file: file.to_owned(), io: err };
    header.write_record(columns.iter().map(|(name, _)| *name)).map_err(|e| write_error(e.into()))?;
    let header = header.into_inner().map_err(|e| write_error(e.into_error()))?;
    let mut text = String::from_utf8_lossy(&header).into_owned();
    text.reserve(rows * columns.len() * 12);
    for k in 0..rows {
        for (i, (_, values)) in columns.iter().enumerate() {
            if i > 0 {
                text.push(',');
            }
            let value = values[k];
            if value.is_finite() {
                // Writing into a String cannot fail.
                let _ = write!(text, "{value:?}");
            }
        }
        text.push('\n');
    }
    Ok(text)
}

/// Write `bytes` to `path` atomically: a temporary file in the same directory (created if
/// missing), flushed to disk, then renamed over `path`. On failure the temporary file is removed.
pub(super) fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), RunFileError> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let fail = |io: std::io::Error| RunFileError::Write { file: path.to_owned(), io };
    let Some(file_name) = path.file_name() else {
        return Err(fail(std::io::Error::new(std::io::ErrorKind::InvalidInput, "the path names no file")));
    };
    let dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir.to_owned(),
        _ => PathBuf::from("."),
    };
    fs::create_dir_all(&dir).map_err(fail)?;
    let (tmp, mut out) = loop {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let name = format!(".{}.{}-{n}.tmp", file_name.to_string_lossy(), std::process::id());
        let tmp = dir.join(name);
        match fs::OpenOptions::new().write(true).create_new(true).open(&tmp) {
            Ok(out) => break (tmp, out),
            Err(err) if err.kind() == std::io::ErrorKind::AlreadyExists && n < u64::MAX => {}
            Err(err) => return Err(fail(err)),
        }
    };
    let written = out.write_all(bytes).and_then(|()| out.sync_all());
    drop(out);
    let result = written.and_then(|()| fs::rename(&tmp, path));
    if let Err(err) = result {
        let _ = fs::remove_file(&tmp);
        return Err(fail(err));
    }
    Ok(())
}
