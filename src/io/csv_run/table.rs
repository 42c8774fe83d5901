//! The raw table of a run file: header names, and every cell parsed into a number as it is read
//! (streamed from the file, or from bytes in memory), with what is needed to quote a cell and its
//! line in a message.
use std::path::Path;

use super::RunFileError;

/// The table: trimmed header names, and every cell parsed as it is read (column by column, a
/// number or a code for what it is instead), with each record's byte offset and line number.
///
/// Cells are kept as one `f64` each rather than as text: a 200 MB log then needs about 40 % of
/// its size on top of its bytes instead of three times it. The text of a cell is read again from
/// the file's bytes only for an error message.
pub(super) struct Table<'a> {
    pub(super) header: Vec<String>,
    /// `columns[c][row]`: the number, or [`MISSING`] / [`NOT_NUMBER`] as NaN bit patterns; a
    /// column is moved out when it is read (see [`Table::take_column`]).
    columns: std::cell::RefCell<Vec<Vec<f64>>>,
    /// Byte offset of each record in the file; line numbers are counted from them for messages.
    starts: Vec<u64>,
    source: Source<'a>,
    sep: u8,
    /// The field separator, when it is not a comma (`;` or a tab, found from the header line).
    pub(super) separator: Option<char>,
    /// Header names that were not UTF-8, read as Latin-1: (the bytes as escapes, the name read).
    pub(super) latin1_names: Vec<(String, String)>,
}

/// Where a table's text comes from: bytes in memory, or a file read as a stream (so a large log is
/// never held as text) and read again, at a record's offset, only for a message.
#[derive(Clone, Copy)]
pub(super) enum Source<'a> {
    Bytes(&'a [u8]),
    File(&'a Path),
}

/// Longest stretch read back for one record's text in a message, bytes.
const RECORD_READ_BACK: u64 = 1 << 16;

impl Source<'_> {
    /// Up to `len` bytes from `start` on (fewer at the end of the file; none if unreadable).
    fn read_at(&self, start: u64, len: u64) -> std::borrow::Cow<'_, [u8]> {
        use std::io::{Read, Seek, SeekFrom};
        match self {
            Self::Bytes(bytes) => {
                let a = usize::try_from(start).unwrap_or(usize::MAX).min(bytes.len());
                let b = usize::try_from(start.saturating_add(len)).unwrap_or(usize::MAX).min(bytes.len());
                std::borrow::Cow::Borrowed(&bytes[a..b])
            }
            Self::File(path) => {
                let mut out = Vec::new();
                if let Ok(mut file) = std::fs::File::open(path)
                    && file.seek(SeekFrom::Start(start)).is_ok()
                {
                    let _ = file.take(len).read_to_end(&mut out);
                }
                std::borrow::Cow::Owned(out)
            }
        }
    }

    /// A reader over the whole text.
    fn reader(&self, file: &Path) -> Result<Box<dyn std::io::Read + '_>, RunFileError> {
        Ok(match self {
            Self::Bytes(bytes) => Box::new(*bytes),
            Self::File(path) => Box::new(std::io::BufReader::with_capacity(
                1 << 20,
                std::fs::File::open(path)
                    .map_err(|io| RunFileError::Unreadable { file: file.to_owned(), io })?,
            )),
        })
    }

    /// The 1-based line of the record at byte `start` (messages only: reads the text up to it).
    fn line_at(&self, start: u64) -> u64 {
        // A few bytes past the offset: a record's offset may point at the end of the line before.
        let prefix = self.read_at(0, start.saturating_add(4));
        LineCounter { bytes: &prefix, offset: 0, line: 1 }.line_at(start)
    }
}

/// The text from the first line that is not a `#` comment on (the header line first).
fn first_data_line(bytes: &[u8]) -> &[u8] {
    let mut rest = bytes;
    while rest.first() == Some(&b'#') {
        rest = rest.iter().position(|&b| b == b'\n').map_or(&[][..], |i| &rest[i + 1..]);
    }
    rest
}

/// The field separator of a file: `;` or a tab when the header line has one and no comma (a
/// spreadsheet's export with decimal commas), else a comma.
fn separator(bytes: &[u8]) -> u8 {
    let first_line = bytes.split(|&b| b == b'\n').next().unwrap_or_default();
    if first_line.contains(&b',') {
        b','
    } else if first_line.contains(&b';') {
        b';'
    } else if first_line.contains(&b'\t') {
        b'\t'
    } else {
        b','
    }
}

/// A cell that is empty, NaN or infinite, as stored in a [`Table`] column.
const MISSING: u64 = 0x7ff8_0000_0000_0001;
/// A cell that is not a number, as stored in a [`Table`] column.
const NOT_NUMBER: u64 = 0x7ff8_0000_0000_0002;

impl Cell {
    /// The cell as one `f64`: finite numbers as themselves, the rest as NaN codes.
    fn encode(self) -> f64 {
        match self {
            Self::Number(v) => v,
            Self::Missing => f64::from_bits(MISSING),
            Self::NotNumber => f64::from_bits(NOT_NUMBER),
        }
    }

    pub(super) fn decode(v: f64) -> Self {
        match v.to_bits() {
            _ if !v.is_nan() => Self::Number(v),
            NOT_NUMBER => Self::NotNumber,
            _ => Self::Missing,
        }
    }
}

/// A cell read as a number.
pub(super) enum Cell {
    Number(f64),
    /// Empty, NaN or infinite.
    Missing,
    NotNumber,
}

fn parse_cell(bytes: &[u8]) -> Cell {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return Cell::NotNumber;
    };
    if text.is_empty() {
        return Cell::Missing;
    }
    // A decimal comma (only possible in a file not separated by commas, or in a quoted cell).
    let parsed = text
        .parse::<f64>()
        .or_else(|e| if text.contains(',') { text.replace(',', ".").parse() } else { Err(e) });
    match parsed {
        Ok(v) if v.is_finite() => Cell::Number(v),
        Ok(_) => Cell::Missing,
        Err(_) => Cell::NotNumber,
    }
}

/// A cell as text for a message, cut to a readable length.
fn shown(bytes: &[u8]) -> String {
    const MAX_CHARS: usize = 40;
    let text = String::from_utf8_lossy(bytes);
    if text.chars().count() > MAX_CHARS {
        format!("{}…", text.chars().take(MAX_CHARS).collect::<String>())
    } else {
        text.into_owned()
    }
}

/// Line numbers from byte offsets. The csv crate's own line count lags behind CRLF line endings
/// and blank lines, and a record's byte offset may point at the end of the previous line.
struct LineCounter<'a> {
    bytes: &'a [u8],
    offset: usize,
    line: u64,
}

impl LineCounter<'_> {
    /// The 1-based line of the record starting at `byte`; records must come in file order.
    fn line_at(&mut self, byte: u64) -> u64 {
        let mut start = usize::try_from(byte).unwrap_or(usize::MAX).min(self.bytes.len());
        while matches!(self.bytes.get(start), Some(b'\r' | b'\n')) {
            start += 1;
        }
        if let Some(skipped) = self.bytes.get(self.offset..start) {
            self.line += skipped.iter().filter(|&&b| b == b'\n').count() as u64;
            self.offset = start;
        }
        self.line
    }
}

/// What a file that is not text is, from its first bytes: gzip-compressed, or binary (a NUL byte,
/// which no text encoding a logger writes has).
fn not_text(start: &[u8]) -> Option<&'static str> {
    if start.starts_with(&[0x1f, 0x8b]) {
        Some("gzip-compressed: decompress it first (gunzip)")
    } else if start.starts_with(b"PK\x03\x04") {
        Some("a zip archive (a spreadsheet's .xlsx, say): export the sheet as CSV")
    } else if start.contains(&0) {
        Some("binary (it holds NUL bytes)")
    } else {
        None
    }
}

/// The csv reader every read of a run file uses: no header handling, ragged rows reported by the
/// caller, cells trimmed, lines starting with `#` skipped as comments (loggers write their settings
/// there).
fn csv_reader<R: std::io::Read>(sep: u8, reader: R) -> csv::Reader<R> {
    csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .delimiter(sep)
        .from_reader(reader)
}

pub(super) fn read_table<'a>(file: &Path, source: Source<'a>) -> Result<Table<'a>, RunFileError> {
    let start = source.read_at(0, RECORD_READ_BACK);
    if let Some(what) = not_text(&start) {
        return Err(RunFileError::NotText { file: file.to_owned(), what });
    }
    let sep = separator(first_data_line(&start));
    let mut reader = csv_reader(sep, source.reader(file)?);
    let malformed = |err: csv::Error| RunFileError::Malformed {
        file: file.to_owned(),
        line: err.position().map_or(0, csv::Position::line),
        message: err.to_string(),
    };
    let mut records = reader.byte_records();
    let header_record = match records.next() {
        None => return Err(RunFileError::Empty { file: file.to_owned() }),
        Some(record) => record.map_err(malformed)?,
    };
    let mut latin1_names = Vec::new();
    let header: Vec<String> = header_record
        .iter()
        .enumerate()
        .map(|(i, bytes)| {
            let name = match std::str::from_utf8(bytes) {
                Ok(text) => text.to_owned(),
                // Not UTF-8: a logger writing Latin-1 (Windows-1252) names; each byte is its code point.
                Err(_) => {
                    let read: String = bytes.iter().map(|&b| char::from(b)).collect();
                    latin1_names.push((bytes.escape_ascii().to_string(), read.trim().to_owned()));
                    read
                }
            };
            let name = if i == 0 { name.trim_start_matches('\u{feff}') } else { &name };
            name.trim().to_owned()
        })
        .collect();
    if header.iter().all(String::is_empty) {
        return Err(RunFileError::Empty { file: file.to_owned() });
    }
    for (i, name) in header.iter().enumerate().filter(|(_, name)| !name.is_empty()) {
        if let Some(j) = header.iter().skip(i + 1).position(|other| other == name) {
            return Err(RunFileError::DuplicateColumn {
                file: file.to_owned(),
                column: name.clone(),
                first: i + 1,
                second: i + j + 2,
            });
        }
    }
    let mut columns: Vec<Vec<f64>> = vec![Vec::new(); header.len()];
    let mut starts = Vec::new();
    let mut record = csv::ByteRecord::new();
    loop {
        match reader.read_byte_record(&mut record) {
            Ok(true) => {}
            Ok(false) => break,
            Err(err) => return Err(malformed(err)),
        }
        let start = record.position().map_or(0, csv::Position::byte);
        if record.len() != header.len() {
            return Err(RunFileError::WrongFieldCount {
                file: file.to_owned(),
                line: source.line_at(start),
                row: starts.len() + 1,
                expected: header.len(),
                found: record.len(),
            });
        }
        for (column, cell) in columns.iter_mut().zip(record.iter()) {
            column.push(parse_cell(cell).encode());
        }
        starts.push(start);
    }
    let separator = (sep != b',').then_some(char::from(sep));
    let columns = std::cell::RefCell::new(columns);
    Ok(Table { header, columns, starts, source, sep, separator, latin1_names })
}

impl Table<'_> {
    pub(super) fn n_rows(&self) -> usize {
        self.starts.len()
    }

    /// The parsed cell (of a column not yet taken).
    pub(super) fn value(&self, row: usize, col: usize) -> Cell {
        let columns = self.columns.borrow();
        Cell::decode(columns.get(col).and_then(|c| c.get(row)).copied().unwrap_or(f64::from_bits(MISSING)))
    }

    /// Column `col`'s cells, moved out of the table: every later read of it sees missing cells.
    pub(super) fn take_column(&self, col: usize) -> Vec<f64> {
        self.columns.borrow_mut().get_mut(col).map(std::mem::take).unwrap_or_default()
    }

    /// The 1-based line of a record, counted from the start of the file (for messages only).
    pub(super) fn line(&self, row: usize) -> u64 {
        self.starts.get(row).map_or(0, |&start| self.source.line_at(start))
    }

    /// The text of a cell, read again from the file (for messages).
    pub(super) fn text(&self, row: usize, col: usize) -> String {
        let Some(&start) = self.starts.get(row) else { return String::new() };
        let record_bytes = self.source.read_at(start, RECORD_READ_BACK);
        let mut reader = csv_reader(self.sep, &record_bytes[..]);
        let mut record = csv::ByteRecord::new();
        match reader.read_byte_record(&mut record) {
            Ok(true) => shown(record.get(col).unwrap_or_default()),
            _ => String::new(),
        }
    }
}
