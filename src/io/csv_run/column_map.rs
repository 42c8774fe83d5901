//! Column roles: `--map ROLE=COLUMN` specs, and the resolution of a file's header into roles.
use std::fmt;
use std::path::Path;
use std::str::FromStr;

use super::{LoadOptions, RunFileError};

/// The canonical time column.
pub const TIME_COLUMN: &str = "time_s";
/// The canonical input column.
pub const INPUT_COLUMN: &str = "fuel_flow_gph";
/// The canonical output columns, in the order they are recognised.
pub const OUTPUT_COLUMNS: [&str; 2] = ["shaft_speed_rpm", "thrust_n"];

/// What a mapped column is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    Time,
    Input,
    Output,
    Aux,
}

impl Role {
    pub fn as_str(self) -> &'static str {
        match self {
            Role::Time => "time",
            Role::Input => "input",
            Role::Output => "output",
            Role::Aux => "aux",
        }
    }
}

impl fmt::Display for Role {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A bad `--map` specification or an inconsistent [`ColumnMap`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ColumnMapError {
    #[error("bad --map \"{spec}\": expected ROLE=COLUMN with ROLE one of time, input, output, aux")]
    BadSyntax { spec: String },
    #[error("bad --map \"{spec}\": unknown role \"{role}\" (roles: time, input, output, aux)")]
    UnknownRole { spec: String, role: String },
    #[error("bad --map: the {role} column is given twice (\"{first}\" and \"{second}\")")]
    RoleTwice { role: Role, first: String, second: String },
    #[error("bad --map: column \"{column}\" is given two roles ({first} and {second})")]
    ColumnInTwoRoles { column: String, first: String, second: String },
}

/// One `ROLE=COLUMN` specification.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MapSpec {
    pub role: Role,
    pub column: String,
}

impl FromStr for MapSpec {
    type Err = ColumnMapError;

    fn from_str(spec: &str) -> Result<Self, Self::Err> {
        let bad_syntax = || ColumnMapError::BadSyntax { spec: spec.to_owned() };
        let Some((role, column)) = spec.split_once('=') else {
            return Err(bad_syntax());
        };
        let (role, column) = (role.trim(), column.trim());
        if role.is_empty() || column.is_empty() {
            return Err(bad_syntax());
        }
        let role = match role.to_ascii_lowercase().as_str() {
            "time" => Role::Time,
            "input" => Role::Input,
            "output" => Role::Output,
            "aux" => Role::Aux,
            _ => return Err(ColumnMapError::UnknownRole { spec: spec.to_owned(), role: role.to_owned() }),
        };
        Ok(MapSpec { role, column: column.to_owned() })
    }
}

/// Which column plays which role, for files whose names are not the canonical ones.
///
/// Empty fields fall back to the canonical names. When `outputs` is not empty only those columns
/// are outputs; when `aux` is not empty only those columns are kept as auxiliary channels.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ColumnMap {
    pub time: Option<String>,
    pub input: Option<String>,
    pub outputs: Vec<String>,
    pub aux: Vec<String>,
}

impl ColumnMap {
    /// A map from `ROLE=COLUMN` strings, as given to `--map`.
    pub fn from_specs<S: AsRef<str>>(specs: &[S]) -> Result<Self, ColumnMapError> {
        let mut map = ColumnMap::default();
        for spec in specs {
            map.add(spec.as_ref().parse()?)?;
        }
        map.check()?;
        Ok(map)
    }

    /// Add one specification; a second time or input column is an error, a repeated output or
    /// auxiliary column is ignored.
    pub fn add(&mut self, spec: MapSpec) -> Result<(), ColumnMapError> {
        let MapSpec { role, column } = spec;
        let single = match role {
            Role::Time => &mut self.time,
            Role::Input => &mut self.input,
            Role::Output | Role::Aux => {
                let list = if role == Role::Output { &mut self.outputs } else { &mut self.aux };
                if !list.contains(&column) {
                    list.push(column);
                }
                return Ok(());
            }
        };
        match single {
            Some(first) if *first != column => {
                Err(ColumnMapError::RoleTwice { role, first: first.clone(), second: column })
            }
            _ => {
                *single = Some(column);
                Ok(())
            }
        }
    }

    pub fn is_empty(&self) -> bool {
        self.time.is_none() && self.input.is_none() && self.outputs.is_empty() && self.aux.is_empty()
    }

    /// Every mapped column with its role, in the order time, input, outputs, aux.
    pub fn entries(&self) -> Vec<(Role, &str)> {
        let mut entries = Vec::new();
        entries.extend(self.time.as_deref().map(|c| (Role::Time, c)));
        entries.extend(self.input.as_deref().map(|c| (Role::Input, c)));
        entries.extend(self.outputs.iter().map(|c| (Role::Output, c.as_str())));
        entries.extend(self.aux.iter().map(|c| (Role::Aux, c.as_str())));
        entries
    }

    /// No column may play two roles (nor be listed twice).
    pub fn check(&self) -> Result<(), ColumnMapError> {
        let entries = self.entries();
        for (i, (role, column)) in entries.iter().enumerate() {
            if let Some((other, _)) = entries.iter().skip(i + 1).find(|(_, c)| c == column) {
                return Err(ColumnMapError::ColumnInTwoRoles {
                    column: (*column).to_owned(),
                    first: role.to_string(),
                    second: other.to_string(),
                });
            }
        }
        Ok(())
    }
}

/// Where the time axis comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum TimeBase {
    Column(usize),
    Fixed { dt_secs: f64 },
}

/// Column indices for every role of one file.
#[derive(Clone, Debug)]
pub(super) struct Layout {
    pub time: TimeBase,
    pub input: usize,
    pub outputs: Vec<usize>,
    /// Mapped auxiliary columns: every cell must be numeric.
    pub aux: Vec<usize>,
    /// Unmapped other columns: kept only if numeric throughout.
    pub extras: Vec<usize>,
    pub quality: Option<usize>,
    /// Named columns deliberately not read (a `time_s` overridden by the sample time).
    pub ignored: Vec<usize>,
}

impl Layout {
    /// Every column a role reads, and the ones deliberately not read.
    fn used(&self) -> Vec<usize> {
        let mut used: Vec<usize> = vec![self.input];
        used.extend(&self.outputs);
        used.extend(&self.aux);
        used.extend(self.quality);
        used.extend(&self.ignored);
        if let TimeBase::Column(c) = self.time {
            used.push(c);
        }
        used
    }
}

/// Assign each header column a role following `opts` (map, sample time, quality column).
pub(super) fn resolve_layout(
    file: &Path,
    header: &[String],
    opts: &LoadOptions,
) -> Result<Layout, RunFileError> {
    let map = &opts.map;
    map.check().map_err(|error| RunFileError::BadMap { file: file.to_owned(), error })?;
    let h = Header { file, names: header };
    let (time, ignored) = time_base(&h, opts)?;
    let input = match &map.input {
        Some(column) => h.mapped(Role::Input, column)?,
        None => h.required("input", INPUT_COLUMN)?,
    };
    let outputs = output_columns(&h, opts)?;
    let aux = map.aux.iter().map(|c| h.mapped(Role::Aux, c)).collect::<Result<Vec<_>, _>>()?;
    let quality = quality_column(&h, opts)?;
    let mut layout = Layout { time, input, outputs, aux, extras: Vec::new(), quality, ignored };
    if map.aux.is_empty() {
        let used = layout.used();
        layout.extras = (0..header.len())
            .filter(|i| !used.contains(i) && header.get(*i).is_some_and(|h| !h.is_empty()))
            .collect();
    }
    Ok(layout)
}

/// A file's header, to find its columns and to name them in errors.
struct Header<'a> {
    file: &'a Path,
    names: &'a [String],
}

impl Header<'_> {
    fn find(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|h| h == name)
    }

    /// The column the map gives `role`: an error when the file has none of that name.
    fn mapped(&self, role: Role, name: &str) -> Result<usize, RunFileError> {
        self.find(name).ok_or_else(|| RunFileError::MapColumnNotFound {
            file: self.file.to_owned(),
            role: role.to_string(),
            column: name.to_owned(),
            present: present(self.names),
        })
    }

    /// A column `role` needs under its default (or given) name: an error when it is missing.
    fn required(&self, role: &str, name: &str) -> Result<usize, RunFileError> {
        self.find(name).ok_or_else(|| RunFileError::MissingColumn {
            file: self.file.to_owned(),
            role: role.to_owned(),
            column: name.to_owned(),
            present: present(self.names),
        })
    }
}

/// Where the time comes from, and the time column left unread when the sample time is given (unless
/// the map gives it another role).
fn time_base(h: &Header<'_>, opts: &LoadOptions) -> Result<(TimeBase, Vec<usize>), RunFileError> {
    let map = &opts.map;
    match (&map.time, opts.sample_time_secs) {
        (Some(column), Some(dt_secs)) => Err(RunFileError::TimeGivenTwice {
            file: h.file.to_owned(),
            column: column.clone(),
            sample_time_secs: dt_secs,
        }),
        (Some(column), None) => Ok((TimeBase::Column(h.mapped(Role::Time, column)?), Vec::new())),
        (None, Some(dt_secs)) => {
            let mapped_elsewhere = map.entries().iter().any(|(_, c)| *c == TIME_COLUMN);
            let ignored = h.find(TIME_COLUMN).filter(|_| !mapped_elsewhere).into_iter().collect();
            Ok((TimeBase::Fixed { dt_secs }, ignored))
        }
        (None, None) => Ok((TimeBase::Column(h.required("time", TIME_COLUMN)?), Vec::new())),
    }
}

/// The output columns: none when only the input is read, the mapped ones, or else the canonical
/// ones the file has (at least one).
fn output_columns(h: &Header<'_>, opts: &LoadOptions) -> Result<Vec<usize>, RunFileError> {
    if opts.input_only {
        return Ok(Vec::new());
    }
    if !opts.map.outputs.is_empty() {
        return opts.map.outputs.iter().map(|c| h.mapped(Role::Output, c)).collect();
    }
    let found: Vec<usize> = OUTPUT_COLUMNS.iter().filter_map(|name| h.find(name)).collect();
    if found.is_empty() {
        return Err(RunFileError::NoOutput { file: h.file.to_owned(), present: present(h.names) });
    }
    Ok(found)
}

/// The quality column, when one is named; it may not also play a mapped role.
fn quality_column(h: &Header<'_>, opts: &LoadOptions) -> Result<Option<usize>, RunFileError> {
    let Some(column) = &opts.quality else { return Ok(None) };
    if let Some((role, _)) = opts.map.entries().into_iter().find(|(_, c)| c == column) {
        let error = ColumnMapError::ColumnInTwoRoles {
            column: column.clone(),
            first: role.to_string(),
            second: "quality".to_owned(),
        };
        return Err(RunFileError::BadMap { file: h.file.to_owned(), error });
    }
    h.required("quality", column).map(Some)
}

fn present(header: &[String]) -> Vec<String> {
    header.iter().filter(|h| !h.is_empty()).cloned().collect()
}
