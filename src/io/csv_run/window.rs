//! `--window START:END`: the part of a run to keep, in samples (`935:2603`) or seconds (`12.5s:80s`),
//! or `auto`: the running part of a whole-run log (`core::running_window`).
use std::fmt;
use std::ops::Range;
use std::str::FromStr;

/// A half-open selection `[start, end)` of a run; an absent end means "to the end of the file".
///
/// Samples are 0-based data-row indices of the file (the first row under the header is sample 0).
/// Seconds are values of the file's time axis (the time column, or `k · dt` without one); a sample
/// is kept when `start <= t < end`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Window {
    Samples {
        start: Option<usize>,
        end: Option<usize>,
    },
    Seconds {
        start: Option<f64>,
        end: Option<f64>,
    },
    /// `auto`: from the end of the start-up run-up to the fuel cut, found once the channels are read.
    Running,
}

/// A `--window` string that does not parse.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "bad --window \"{spec}\": {reason} (expected START:END in samples, e.g. 935:2603, in seconds, e.g. 12.5s:80s, or auto)"
)]
pub struct WindowSpecError {
    pub spec: String,
    pub reason: String,
}

impl FromStr for Window {
    type Err = WindowSpecError;

    fn from_str(spec: &str) -> Result<Self, Self::Err> {
        let fail = |reason: &str| WindowSpecError { spec: spec.to_owned(), reason: reason.to_owned() };
        if spec.trim().eq_ignore_ascii_case("auto") {
            return Ok(Window::Running);
        }
        let Some((start, end)) = spec.split_once(':') else {
            return Err(fail("no ':' between START and END"));
        };
        let (start, end) = (start.trim(), end.trim());
        if start.is_empty() && end.is_empty() {
            return Err(fail("START and END are both empty"));
        }
        let in_seconds = |s: &str| s.ends_with('s') || s.ends_with('S');
        let seconds = match (start.is_empty(), end.is_empty()) {
            (true, _) => in_seconds(end),
            (_, true) => in_seconds(start),
            _ if in_seconds(start) == in_seconds(end) => in_seconds(start),
            _ => return Err(fail("give both ends in samples or both in seconds")),
        };
        if seconds {
            let parse = |s: &str| -> Result<Option<f64>, WindowSpecError> {
                if s.is_empty() {
                    return Ok(None);
                }
                let number = s.get(..s.len() - 1).unwrap_or_default().trim();
                match number.parse::<f64>() {
                    Ok(v) if v.is_finite() => Ok(Some(v)),
                    _ => Err(fail(&format!("\"{s}\" is not a time in seconds"))),
                }
            };
            let (start, end) = (parse(start)?, parse(end)?);
            if let (Some(a), Some(b)) = (start, end)
                && a >= b
            {
                return Err(fail("the window is empty (START must be before END)"));
            }
            Ok(Window::Seconds { start, end })
        } else {
            let parse = |s: &str| -> Result<Option<usize>, WindowSpecError> {
                if s.is_empty() {
                    return Ok(None);
                }
                s.parse::<usize>().map(Some).map_err(|_| {
                    fail(&format!("\"{s}\" is not a sample index (a whole number; add `s` for seconds)"))
                })
            };
            let (start, end) = (parse(start)?, parse(end)?);
            if let (Some(a), Some(b)) = (start, end)
                && a >= b
            {
                return Err(fail("the window is empty (START must be before END)"));
            }
            Ok(Window::Samples { start, end })
        }
    }
}

impl fmt::Display for Window {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fn side<T: fmt::Display>(v: Option<T>, unit: &str) -> String {
            v.map_or(String::new(), |v| format!("{v}{unit}"))
        }
        match *self {
            Window::Samples { start, end } => write!(f, "{}:{}", side(start, ""), side(end, "")),
            Window::Seconds { start, end } => write!(f, "{}:{}", side(start, "s"), side(end, "s")),
            Window::Running => write!(f, "auto"),
        }
    }
}

impl Window {
    /// The rows `[a, b)` this window keeps out of `n_rows`, given each row's time (NaN when
    /// unknown). `Err` carries the reason the window does not fit the file.
    pub(super) fn select(
        &self,
        n_rows: usize,
        time_of_row: &dyn Fn(usize) -> f64,
    ) -> Result<Range<usize>, String> {
        match *self {
            // The running part is found from the channels, after they are read.
            Window::Running => Ok(0..n_rows),
            Window::Samples { start, end } => {
                let a = start.unwrap_or(0);
                let b = end.unwrap_or(n_rows);
                if b > n_rows || a >= n_rows {
                    return Err(format!("out of range: the file has {n_rows} samples (0..{n_rows})"));
                }
                if a >= b {
                    return Err("the window is empty".to_owned());
                }
                Ok(a..b)
            }
            Window::Seconds { start, end } => {
                let inside =
                    |t: f64| t.is_finite() && start.is_none_or(|a| t >= a) && end.is_none_or(|b| t < b);
                let first = (0..n_rows).find(|&i| inside(time_of_row(i)));
                let last = (0..n_rows).rev().find(|&i| inside(time_of_row(i)));
                match (first, last) {
                    (Some(a), Some(b)) => Ok(a..b + 1),
                    _ => {
                        let known = (0..n_rows).map(time_of_row).filter(|t| t.is_finite());
                        let (lo, hi) = known
                            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), t| (lo.min(t), hi.max(t)));
                        Err(format!(
                            "out of range: no sample has a time in it (the file spans {lo} s to {hi} s)"
                        ))
                    }
                }
            }
        }
    }
}
