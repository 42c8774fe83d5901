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

/// Assign each header column a role following `opts` (map, sample time, quality column).
pub(super) fn resolve_layout(
    file: &Path,
    header: &[String],
    opts: &LoadOptions,
) -> Result<Layout, RunFileError> {
    let map = &opts.map;
    map.check().map_err(|error| RunFileError::BadMap { file: file.to_owned(), error })?;
    let find = |name: &str| header.iter().position(|h| h == name);
    let mapped = |role: Role, name: &str| {
        find(name).ok_or_else(|| RunFileError::MapColumnNotFound {
            file: file.to_owned(),
            role: role.to_string(),
            column: name.to_owned(),
            present: present(header),
        })
    };
    let missing = |role: &str, name: &str| RunFileError::MissingColumn {
        file: file.to_owned(),
        role: role.to_owned(),
        column: name.to_owned(),
        present: present(header),
    };

    let mut ignored = Vec::new();
    let time = match (&map.time, opts.sample_time_secs) {
        (Some(column), Some(dt_secs)) => {
            return Err(RunFileError::TimeGivenTwice {
                file: file.to_owned(),
                column: column.clone(),
                sample_time_secs: dt_secs,
            });
        }
        (Some(column), None) => TimeBase::Column(mapped(Role::Time, column)?),
        (None, Some(dt_secs)) => {
            let mapped_elsewhere = map.entries().iter().any(|(_, c)| *c == TIME_COLUMN);
            ignored.extend(find(TIME_COLUMN).filter(|_| !mapped_elsewhere));
            TimeBase::Fixed { dt_secs }
        }
        (None, None) => TimeBase::Column(find(TIME_COLUMN).ok_or_else(|| missing("time", TIME_COLUMN))?),
    };
    let input = match &map.input {
        Some(column) => mapped(Role::Input, column)?,
        None => find(INPUT_COLUMN).ok_or_else(|| missing("input", INPUT_COLUMN))?,
    };
    let outputs = if opts.input_only {
        Vec::new()
    } else if map.outputs.is_empty() {
        let found: Vec<usize> = OUTPUT_COLUMNS.iter().filter_map(|name| find(name)).collect();
        if found.is_empty() {
            return Err(RunFileError::NoOutput { file: file.to_owned(), present: present(header) });
        }
        found
    } else {
        map.outputs.iter().map(|c| mapped(Role::Output, c)).collect::<Result<_, _>>()?
    };
    let aux = map.aux.iter().map(|c| mapped(Role::Aux, c)).collect::<Result<Vec<_>, _>>()?;
    let quality = match &opts.quality {
        Some(column) => {
            if let Some((role, _)) = map.entries().into_iter().find(|(_, c)| c == column) {
                let error = ColumnMapError::ColumnInTwoRoles {
                    column: column.clone(),
                    first: role.to_string(),
                    second: "quality".to_owned(),
                };
                return Err(RunFileError::BadMap { file: file.to_owned(), error });
            }
            Some(find(column).ok_or_else(|| missing("quality", column))?)
        }
        None => None,
    };

    let mut used: Vec<usize> = vec![input];
    used.extend(&outputs);
    used.extend(&aux);
    used.extend(quality);
    used.extend(&ignored);
    if let TimeBase::Column(c) = time {
        used.push(c);
    }
    let extras = if map.aux.is_empty() {
        (0..header.len())
            .filter(|i| !used.contains(i) && header.get(*i).is_some_and(|h| !h.is_empty()))
            .collect()
    } else {
        Vec::new()
    };
    Ok(Layout { time, input, outputs, aux, extras, quality, ignored })
}

fn present(header: &[String]) -> Vec<String> {
    header.iter().filter(|h| !h.is_empty()).cloned().collect()
}
