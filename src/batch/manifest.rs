//! The files a batch wrote into its `--out` folder, kept in `jetid-files.txt`, so that a later run
//! into the same folder removes what it did not write again (figures of an output no longer
//! modelled, of a run no longer scored) instead of leaving stale results beside the new ones. Only
//! files an earlier jetid listed are ever removed; anything else in the folder is left alone.
use std::collections::BTreeSet;
use std::path::Path;

use anyhow::{Context, Result};

use crate::io::atomic::write_atomic;

/// The manifest's file name inside the output folder.
pub const MANIFEST: &str = "jetid-files.txt";

/// Record `written` (file names inside `out_dir`) as this run's files and remove the files the
/// previous manifest listed that are not among them. Returns the names removed.
pub fn replace(out_dir: &Path, written: &[String]) -> Result<Vec<String>> {
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
