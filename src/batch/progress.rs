//! The batch's stage timings and the progress lines on stderr while it works.
use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// Stopwatch that records named phases in milliseconds; the progress lines are shared by the
/// outputs' threads.
#[derive(Default)]
pub struct Timings(pub BTreeMap<String, f64>, pub(super) Arc<Mutex<Progress>>);

impl Timings {
    /// Timings that report to the same progress lines as `self`.
    pub(super) fn sibling(&self) -> Self {
        Self(BTreeMap::new(), Arc::clone(&self.1))
    }

    pub fn time<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        if let Ok(mut progress) = self.1.lock() {
            progress.stage(name);
        }
        let start = Instant::now();
        let out = f();
        *self.0.entry(name.to_owned()).or_default() += start.elapsed().as_secs_f64() * 1e3;
        out
    }

    /// Add `other`'s phases to these.
    pub(super) fn absorb(&mut self, other: Timings) {
        for (stage, ms) in other.0 {
            *self.0.entry(stage).or_default() += ms;
        }
    }
}

/// Stage lines on stderr while the batch works: one line per stage, or one line rewritten in place
/// on a terminal; nothing with `--quiet`.
#[derive(Default)]
pub(super) struct Progress {
    quiet: bool,
    started: Option<Instant>,
    last: String,
}

impl Progress {
    pub(super) fn new(quiet: bool) -> Self {
        Self { quiet, started: Some(Instant::now()), last: String::new() }
    }

    fn stage(&mut self, name: &str) {
        use std::io::{IsTerminal, Write};
        if self.quiet || self.last == name {
            return;
        }
        name.clone_into(&mut self.last);
        let secs = self.started.get_or_insert_with(Instant::now).elapsed().as_secs_f64();
        let what = stage_words(name);
        let mut err = std::io::stderr();
        let _ = if err.is_terminal() {
            write!(err, "\r\x1b[2K[{secs:6.1} s] {what}")
        } else {
            writeln!(err, "jetid: [{secs:6.1} s] {what}")
        };
        let _ = err.flush();
    }

    pub(super) fn finish(&mut self) {
        use std::io::IsTerminal;
        if !self.quiet && std::io::stderr().is_terminal() {
            eprintln!();
        }
    }
}

/// A stage's timing key in words: "baselines_PR" → "fitting the baselines of PR".
fn stage_words(name: &str) -> String {
    const STAGES: [(&str, &str); 10] = [
        ("identify_", "identifying "),
        ("effects_", "adding the effects to "),
        ("baselines_", "fitting the baselines of "),
        ("diagnosis_", "diagnosing "),
        ("load_runs", "loading the runs"),
        ("validate", "scoring every model on the runs"),
        ("frequency", "comparing frequency responses on the chirp run"),
        ("monte_carlo", "the Monte Carlo study"),
        ("residuals", "analysing the residuals"),
        ("figures", "drawing the figures"),
    ];
    STAGES
        .iter()
        .find_map(|(key, words)| name.strip_prefix(key).map(|rest| format!("{words}{rest}")))
        .unwrap_or_else(|| name.replace('_', " "))
}
