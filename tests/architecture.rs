//! The dependency rule of ARCHITECTURE.md, read from the sources: the core imports none of the
//! layers above it, the batch and the file formats never import the app or the command line, and no
//! view imports another view or the app shell.
use std::path::{Path, PathBuf};

fn sources(dir: &str) -> Vec<(PathBuf, String)> {
    fn walk(dir: &Path, out: &mut Vec<(PathBuf, String)>) {
        let Ok(entries) = std::fs::read_dir(dir) else { return };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let text = std::fs::read_to_string(&path).unwrap_or_default();
                out.push((path, text));
            }
        }
    }
    let mut out = Vec::new();
    walk(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src").join(dir), &mut out);
    assert!(!out.is_empty(), "no sources under src/{dir}");
    out
}

/// Files under `dir` whose code names one of `forbidden` (`crate::ui`, …), with the line.
fn offenders(dir: &str, forbidden: &[&str], allowed_files: &[&str]) -> Vec<String> {
    let mut found = Vec::new();
    for (path, text) in sources(dir) {
        if allowed_files.iter().any(|f| path.ends_with(f)) {
            continue;
        }
        for (n, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            for f in forbidden {
                let hit = code.match_indices(f).any(|(i, _)| {
                    code[i + f.len()..].chars().next().is_none_or(|c| !(c.is_alphanumeric() || c == '_'))
                });
                if hit {
                    found.push(format!("{}:{}: {}", path.display(), n + 1, line.trim()));
                }
            }
        }
    }
    found
}

#[test]
fn the_core_imports_no_layer_above_it() {
    let found =
        offenders("core", &["crate::io", "crate::batch", "crate::cli", "crate::ui", "crate::sim"], &[]);
    assert!(found.is_empty(), "{found:#?}");
}

#[test]
fn batch_files_and_simulator_never_import_the_app_or_the_command_line() {
    for dir in ["batch", "io", "sim"] {
        let found = offenders(dir, &["crate::ui", "crate::cli"], &[]);
        assert!(found.is_empty(), "{found:#?}");
    }
}

#[test]
fn views_import_no_other_view_nor_the_shell() {
    let views = ["bode", "compare", "data", "diagnosis", "static_map", "traces", "zplane"];
    for view in views {
        let others: Vec<String> =
            views.iter().filter(|v| **v != view).map(|v| format!("crate::ui::views::{v}")).collect();
        let mut forbidden: Vec<&str> = others.iter().map(String::as_str).collect();
        forbidden.extend(["crate::ui::app", "crate::ui::panels_ui", "crate::ui::screenshot"]);
        let dir = format!("ui/views/{view}");
        let file = format!("ui/views/{view}.rs");
        let found = if Path::new(env!("CARGO_MANIFEST_DIR")).join("src").join(&dir).is_dir() {
            offenders(&dir, &forbidden, &[])
        } else {
            offenders("ui/views", &forbidden, &[]).into_iter().filter(|o| o.contains(&file)).collect()
        };
        assert!(found.is_empty(), "{view}: {found:#?}");
    }
}

#[test]
fn state_derived_and_widgets_never_import_views_or_the_shell() {
    // The one exception: the view state holds each view's own state type.
    for dir in ["ui/state", "ui/derived", "ui/widgets"] {
        let found = offenders(
            dir,
            &["crate::ui::views", "crate::ui::app", "crate::ui::panels_ui", "crate::ui::screenshot"],
            &["state/view_state.rs"],
        );
        assert!(found.is_empty(), "{found:#?}");
    }
}
