//! Paths a command reads and writes: an output that is one of the command's inputs would destroy
//! it, so every command refuses one before it reads anything.
use std::path::{Path, PathBuf};

/// The file `path` names, with links followed, whether or not it exists yet (its folder must).
fn resolved(path: &Path) -> Option<PathBuf> {
    std::fs::canonicalize(path).ok().or_else(|| {
        let parent = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
        Some(std::fs::canonicalize(parent).ok()?.join(path.file_name()?))
    })
}

/// Whether `a` and `b` name the same file (links followed; `b` need not exist yet).
pub fn same_file(a: &Path, b: &Path) -> bool {
    matches!((resolved(a), resolved(b)), (Some(x), Some(y)) if x == y)
}

/// Why writing `out` (given as `out_flag`) is refused: it is the file of one of `inputs`, each
/// `(flag, path)`; the message says which and what would be lost.
pub fn overwrites_input(out_flag: &str, out: &Path, inputs: &[(&str, &Path)]) -> Option<String> {
    inputs.iter().find(|(_, input)| same_file(input, out)).map(|(flag, input)| {
        format!(
            "{out_flag} {} is the {flag} file {}: writing it would destroy what the command reads; write elsewhere",
            out.display(),
            input.display()
        )
    })
}
