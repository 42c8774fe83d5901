//! Results as a set (the batch's and the fleet's): a batch writes every file into a staging folder beside its `--out` folder and
//! moves them into place only when every output succeeded. A failed batch leaves the earlier
//! results untouched and adds no file (the staging folder is removed; the `--out` folder is not even
//! created).
//!
//! The files a batch wrote are listed in `jetid-files.txt` in the `--out` folder, so that a later
//! run into the same folder removes what it did not write again (figures of an output no longer
//! modelled, of a run no longer scored) instead of leaving stale results beside the new ones. Only
//! files an earlier jetid listed are ever removed; anything else in the folder is left alone.
//!
//! Ctrl+C (SIGINT, and SIGTERM) is the same as a failure ([`stop_on_interrupt`]): the staging folders
//! are removed and the process exits with status 130, unless the results are being moved into
//! place, which is then finished first (a few renames), so that `--out` holds either the earlier set
//! or the new one, never a mix.
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use anyhow::{Context, Result, bail};

use crate::io::atomic::write_atomic;

/// The manifest's file name inside the output folder.
pub const MANIFEST: &str = "jetid-files.txt";

/// The staging folders in use and whether one is being committed, for the interrupt handler.
struct Live {
    folders: Vec<PathBuf>,
    committing: bool,
}

static LIVE: Mutex<Live> = Mutex::new(Live { folders: Vec::new(), committing: false });

/// Exit status of a process stopped by SIGINT, as shells report it (128 + 2).
const INTERRUPTED: i32 = 130;

/// Whether [`stop_on_interrupt`] may take over SIGINT and SIGTERM: the command line's process may,
/// a host that loaded jetid as a library (the Python package) keeps its own handling.
static OWN_SIGNALS: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(true);

/// Leave SIGINT and SIGTERM to the host process: [`stop_on_interrupt`] does nothing from now on.
/// A staging folder is still removed when its work fails or is dropped uncommitted.
pub fn leave_signals_to_host() {
    OWN_SIGNALS.store(false, std::sync::atomic::Ordering::SeqCst);
}

/// Install the handler that makes Ctrl+C leave nothing half-written (see the module doc). Installing
/// it again is harmless; after [`leave_signals_to_host`] nothing is installed.
pub fn stop_on_interrupt() {
    if !OWN_SIGNALS.load(std::sync::atomic::Ordering::SeqCst) {
        return;
    }
    let _ = ctrlc::set_handler(|| {
        loop {
            let Ok(mut live) = LIVE.lock() else { std::process::exit(INTERRUPTED) };
            if !live.committing {
                for dir in live.folders.drain(..) {
                    let _ = std::fs::remove_dir_all(&dir);
                }
                eprintln!(
                    "\njetid: interrupted: nothing was written (the earlier results, if any, are as they were)"
                );
                std::process::exit(INTERRUPTED);
            }
            drop(live);
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
    });
}

fn with_live(f: impl FnOnce(&mut Live)) {
    if let Ok(mut live) = LIVE.lock() {
        f(&mut live);
    }
}

/// A staging folder for the results bound for `out_dir`; removed when dropped uncommitted.
pub struct Staging {
    dir: PathBuf,
    out_dir: PathBuf,
}

impl Staging {
    /// A new, empty staging folder in the nearest existing folder above `out_dir` (so that its files
    /// can be renamed into place on the same file system).
    pub fn new(out_dir: &Path) -> Result<Self> {
        if out_dir.exists() && !out_dir.is_dir() {
            bail!("--out {} is a file, not a folder", out_dir.display());
        }
        let out_dir = if out_dir.as_os_str().is_empty() { Path::new(".") } else { out_dir };
        let name = out_dir.file_name().map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
        let base = existing_ancestor(out_dir);
        let dir = base.join(format!(".{name}.jetid-staging-{}", std::process::id()));
        if dir.exists() {
            std::fs::remove_dir_all(&dir).with_context(|| format!("clearing {}", dir.display()))?;
        }
        with_live(|live| live.folders.push(dir.clone()));
        std::fs::create_dir(&dir)
            .with_context(|| format!("cannot create a staging folder {}", dir.display()))?;
        Ok(Self { dir, out_dir: out_dir.to_owned() })
    }

    /// Where the results are written until [`Self::commit`].
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// Move the files `written` (names in the staging folder) into the `--out` folder, record them
    /// in its manifest and remove the files the previous manifest listed that are not among them.
    /// Returns the names removed.
    pub fn commit(self, written: &[String]) -> Result<Vec<String>> {
        with_live(|live| live.committing = true);
        let moved = self.move_into_place(written);
        with_live(|live| live.committing = false);
        moved
    }

    fn move_into_place(&self, written: &[String]) -> Result<Vec<String>> {
        std::fs::create_dir_all(&self.out_dir)
            .with_context(|| format!("cannot create output folder {}", self.out_dir.display()))?;
        for name in written {
            let (from, to) = (self.dir.join(name), self.out_dir.join(name));
            move_file(&from, &to)
                .with_context(|| format!("moving the result {} into place", to.display()))?;
        }
        replace_manifest(&self.out_dir, written)
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        // Committed or not, nothing of the staging folder stays behind.
        with_live(|live| live.folders.retain(|d| d != &self.dir));
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// The nearest folder at or above `path` that exists (the current folder at the end).
fn existing_ancestor(path: &Path) -> PathBuf {
    let mut base = path.parent();
    while let Some(dir) = base {
        if dir.as_os_str().is_empty() {
            break;
        }
        if dir.is_dir() {
            return dir.to_owned();
        }
        base = dir.parent();
    }
    PathBuf::from(".")
}

/// Rename `from` to `to`, or copy and remove where they are on different file systems.
fn move_file(from: &Path, to: &Path) -> std::io::Result<()> {
    if std::fs::rename(from, to).is_ok() {
        return Ok(());
    }
    let bytes = std::fs::read(from)?;
    write_atomic(to, &bytes).map_err(std::io::Error::other)?;
    std::fs::remove_file(from)
}

/// Record `written` (file names inside `out_dir`) as this run's files and remove the files the
/// previous manifest listed that are not among them. Returns the names removed.
fn replace_manifest(out_dir: &Path, written: &[String]) -> Result<Vec<String>> {
    let path = out_dir.join(MANIFEST);
    let now: BTreeSet<&str> = written.iter().map(String::as_str).collect();
    let before = std::fs::read_to_string(&path).unwrap_or_default();
    let mut removed = Vec::new();
    for name in before.lines().map(str::trim).filter(|n| !n.is_empty() && !now.contains(n)) {
        // Only a plain file name of this folder, never a path out of it.
        let plain = Path::new(name).file_name().is_some_and(|f| f == name) && name != MANIFEST;
        let stale = out_dir.join(name);
        if plain && stale.is_file() {
            std::fs::remove_file(&stale)
                .with_context(|| format!("removing the stale {}", stale.display()))?;
            removed.push(name.to_owned());
        }
    }
    let mut text = String::new();
    for name in &now {
        text.push_str(name);
        text.push('\n');
    }
    write_atomic(&path, text.as_bytes()).with_context(|| format!("writing {}", path.display()))?;
    Ok(removed)
}
