//! The batch's stage timings and the progress lines on stderr while it works.
//!
//! A stage that runs long (identifying a long log, training a baseline) must not look hung: besides
//! a line when a stage begins, a ticker rewrites the line every second on a terminal with each stage
//! under way, how long it has run and, where the stage reports it, the fraction done; into a log
//! file it adds a line every [`LOG_EVERY_SECS`] while a stage runs.
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// How often the line is rewritten on a terminal.
const TICK: Duration = Duration::from_secs(1);
/// How often a stage still under way is said again in a log (not a terminal): often enough that a
/// reader of a CI log sees the batch is alive, seldom enough not to drown the stage lines.
const LOG_EVERY_SECS: f64 = 15.0;

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
        self.time_with_fraction(name, |_| f())
    }

    /// [`Self::time`] for a stage that reports the fraction it has done (0..=1) to the closure it
    /// is given (which always answers "go on": the batch is stopped by Ctrl+C, not by a button).
    pub fn time_with_fraction<T>(
        &mut self,
        name: &str,
        f: impl FnOnce(&mut dyn FnMut(f64) -> bool) -> T,
    ) -> T {
        self.with_progress(|p| p.begin(name));
        let start = Instant::now();
        let progress = Arc::clone(&self.1);
        let mut report = |fraction: f64| {
            if let Ok(mut p) = progress.lock() {
                p.fraction(name, fraction);
            }
            true
        };
        let out = f(&mut report);
        self.with_progress(|p| p.end(name));
        *self.0.entry(name.to_owned()).or_default() += start.elapsed().as_secs_f64() * 1e3;
        out
    }

    fn with_progress(&self, f: impl FnOnce(&mut Progress)) {
        if let Ok(mut progress) = self.1.lock() {
            f(&mut progress);
        }
    }

    /// Add `other`'s phases to these.
    pub(super) fn absorb(&mut self, other: Timings) {
        for (stage, ms) in other.0 {
            *self.0.entry(stage).or_default() += ms;
        }
    }
}

/// A stage under way.
struct Active {
    name: String,
    since: Instant,
    fraction: Option<f64>,
}

/// Stage lines on stderr while the batch works: one line per stage, or one line rewritten in place
/// on a terminal; nothing with `--quiet`.
pub(super) struct Progress {
    quiet: bool,
    terminal: bool,
    started: Instant,
    active: Vec<Active>,
    /// When the last line was written.
    said: Instant,
}

impl Default for Progress {
    fn default() -> Self {
        Self::new(true)
    }
}

impl Progress {
    pub(super) fn new(quiet: bool) -> Self {
        use std::io::IsTerminal;
        let now = Instant::now();
        Self { quiet, terminal: std::io::stderr().is_terminal(), started: now, active: Vec::new(), said: now }
    }

    fn begin(&mut self, name: &str) {
        self.active.push(Active { name: name.to_owned(), since: Instant::now(), fraction: None });
        if self.terminal {
            self.say(&self.line());
        } else {
            self.say(&stage_words(name));
        }
    }

    fn end(&mut self, name: &str) {
        if let Some(i) = self.active.iter().position(|a| a.name == name) {
            self.active.remove(i);
        }
    }

    fn fraction(&mut self, name: &str, fraction: f64) {
        if let Some(a) = self.active.iter_mut().find(|a| a.name == name) {
            a.fraction = Some(fraction.clamp(0.0, 1.0));
        }
    }

    /// Every [`TICK`]: rewrite the line on a terminal; in a log, say what is under way when nothing
    /// was said for [`LOG_EVERY_SECS`].
    fn tick(&mut self) {
        if self.active.is_empty() {
            return;
        }
        if self.terminal || self.said.elapsed().as_secs_f64() >= LOG_EVERY_SECS {
            let line = if self.terminal { self.line() } else { format!("still {}", self.line()) };
            self.say(&line);
        }
    }

    /// The stages under way: "identifying thrust_n (12 s) · fitting the baselines of PR 40 % (3 s)".
    fn line(&self) -> String {
        let parts: Vec<String> = self
            .active
            .iter()
            .map(|a| {
                let done = a.fraction.map(|f| format!(" {:.0} %", 100.0 * f)).unwrap_or_default();
                format!("{}{done} ({:.0} s)", stage_words(&a.name), a.since.elapsed().as_secs_f64())
            })
            .collect();
        parts.join(" · ")
    }

    fn say(&mut self, what: &str) {
        use std::io::Write;
        if self.quiet {
            return;
        }
        self.said = Instant::now();
        let secs = self.started.elapsed().as_secs_f64();
        let mut err = std::io::stderr();
        let _ = if self.terminal {
            // One screen line, or the next rewrite would leave the wrapped rest behind.
            let width = std::env::var("COLUMNS").ok().and_then(|c| c.parse::<usize>().ok()).unwrap_or(100);
            let what: String = what.chars().take(width.saturating_sub(12).max(20)).collect();
            write!(err, "\r\x1b[2K[{secs:6.1} s] {what}")
        } else {
            writeln!(err, "jetid: [{secs:6.1} s] {what}")
        };
        let _ = err.flush();
    }

    pub(super) fn finish(&mut self) {
        if !self.quiet && self.terminal {
            eprintln!();
        }
    }
}

/// Rewrites the progress line every [`TICK`] on a thread of its own, until dropped.
pub(super) struct Ticker {
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Ticker {
    pub(super) fn start(progress: &Arc<Mutex<Progress>>) -> Self {
        let stop = Arc::new(AtomicBool::new(false));
        let (flag, progress) = (Arc::clone(&stop), Arc::clone(progress));
        let thread = std::thread::spawn(move || {
            let step = Duration::from_millis(100);
            let mut waited = Duration::ZERO;
            while !flag.load(Ordering::Relaxed) {
                std::thread::sleep(step);
                waited += step;
                if waited >= TICK {
                    waited = Duration::ZERO;
                    if let Ok(mut p) = progress.lock() {
                        p.tick();
                    }
                }
            }
        });
        Self { stop, thread: Some(thread) }
    }
}

impl Drop for Ticker {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
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
