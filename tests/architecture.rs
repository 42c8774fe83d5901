//! The dependency rule of ARCHITECTURE.md, read from the sources: the core imports none of the
//! layers above it, the workflow only the core and the files, the batch and the file formats never
//! import the app or the command line, no view imports another view or the app shell, and no two
//! files import each other, directly or round a circle.
use std::collections::{BTreeMap, BTreeSet};
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
    let above = ["crate::io", "crate::batch", "crate::cli", "crate::ui", "crate::sim", "crate::workflow"];
    let found = offenders("core", &above, &[]);
    assert!(found.is_empty(), "{found:#?}");
}

#[test]
fn batch_files_and_simulator_never_import_the_app_or_the_command_line() {
    for dir in ["batch", "io", "sim"] {
        let found = offenders(dir, &["crate::ui", "crate::cli"], &[]);
        assert!(found.is_empty(), "{found:#?}");
    }
    let found = offenders("io", &["crate::workflow", "crate::batch"], &[]);
    assert!(found.is_empty(), "{found:#?}");
}

#[test]
fn the_workflow_imports_only_the_core_and_the_files() {
    let found = offenders("workflow", &["crate::batch", "crate::cli", "crate::ui", "crate::sim"], &[]);
    assert!(found.is_empty(), "{found:#?}");
}

#[test]
fn the_fleet_imports_only_the_core_the_files_and_the_workflow() {
    let found = offenders("fleet", &["crate::batch", "crate::cli", "crate::ui", "crate::sim"], &[]);
    assert!(found.is_empty(), "{found:#?}");
}

/// Every file of `src` as a module path (`core::identification::pipeline`; a `mod.rs` is its
/// folder's module), with the modules its code names (`use` paths and paths in code, through
/// `crate::`, `super::` and `self::`), each resolved to the deepest module that exists.
fn import_graph() -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = BTreeMap::new();
    for (path, text) in sources("") {
        let relative = path.strip_prefix(&root).unwrap().with_extension("");
        let mut module: Vec<String> = relative.iter().map(|s| s.to_string_lossy().into_owned()).collect();
        let folder_module = matches!(module.last().map(String::as_str), Some("mod" | "lib" | "main"));
        if folder_module {
            module.pop();
        }
        files.insert(module, (text, folder_module));
    }
    let resolve = |path: &[String]| -> Option<Vec<String>> {
        (1..=path.len()).rev().map(|n| path[..n].to_vec()).find(|p| files.contains_key(p))
    };
    let mut graph = BTreeMap::new();
    for (module, (text, _)) in &files {
        let mut deps = BTreeSet::new();
        for path in named_paths(code_of(text)) {
            let (head, rest) = path.split_first().unwrap();
            let full: Vec<String> = match head.as_str() {
                "crate" => rest.to_vec(),
                // `super::` is the module's parent, `self::` the module itself.
                "super" => {
                    let mut base = module.clone();
                    let mut rest = rest;
                    base.pop();
                    while let Some(("super", tail)) = rest.split_first().map(|(h, t)| (h.as_str(), t)) {
                        base.pop();
                        rest = tail;
                    }
                    base.into_iter().chain(rest.iter().cloned()).collect()
                }
                _ => module.iter().chain(rest).cloned().collect(),
            };
            if let Some(target) = resolve(&full).filter(|t| t != module && !t.is_empty()) {
                deps.insert(target);
            }
        }
        graph.insert(module.clone(), deps);
    }
    graph
}

/// The code of a file without comments and without its `#[cfg(test)]` module.
fn code_of(text: &str) -> String {
    let code = text.split("#[cfg(test)]").next().unwrap_or("");
    code.lines().map(|line| line.split("//").next().unwrap_or("")).collect::<Vec<_>>().join("\n")
}

/// Every `crate::a::b`, `super::a` and `self::a` path in `code`, braces of `use` lists expanded
/// one level (`use super::{a, b::c}` names `super::a` and `super::b::c`).
fn named_paths(code: String) -> Vec<Vec<String>> {
    let mut paths = Vec::new();
    let bytes = code.as_bytes();
    let mut i = 0;
    while i < bytes.len() {
        if !code.is_char_boundary(i) {
            i += 1;
            continue;
        }
        let at_word =
            i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_' || bytes[i - 1] == b':');
        let head = ["crate::", "super::", "self::"].into_iter().find(|h| code[i..].starts_with(h));
        let Some(head) = head.filter(|_| at_word) else {
            i += 1;
            continue;
        };
        let mut end = i + head.len();
        while end < bytes.len()
            && (bytes[end].is_ascii_alphanumeric() || bytes[end] == b'_' || bytes[end] == b':')
        {
            end += 1;
        }
        let path: Vec<String> =
            code[i..end].split("::").filter(|s| !s.is_empty()).map(str::to_owned).collect();
        if code[end..].starts_with('{') {
            let close = code[end..].find('}').map_or(code.len(), |c| end + c);
            for item in code[end + 1..close].split(',') {
                let item = item.trim().split(" as ").next().unwrap_or("").trim();
                let item: Vec<String> =
                    item.split("::").filter(|s| !s.is_empty() && *s != "{").map(str::to_owned).collect();
                if !item.is_empty() {
                    paths.push(path.iter().cloned().chain(item).collect());
                }
            }
        }
        paths.push(path);
        i = end;
    }
    paths
}

/// The import circles of `graph`: strongly connected groups of two or more modules (Tarjan). A
/// folder module and its own files are left out of it: the folder declares and re-exports them.
fn circles(graph: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>) -> Vec<Vec<String>> {
    let parent_child = |a: &Vec<String>, b: &Vec<String>| {
        (a.len() + 1 == b.len() && b.starts_with(a)) || (b.len() + 1 == a.len() && a.starts_with(b))
    };
    let edges: BTreeMap<&Vec<String>, Vec<&Vec<String>>> =
        graph.iter().map(|(a, deps)| (a, deps.iter().filter(|b| !parent_child(a, b)).collect())).collect();
    let mut index = BTreeMap::new();
    let mut low = BTreeMap::new();
    let mut stack: Vec<&Vec<String>> = Vec::new();
    let mut found = Vec::new();
    fn visit<'a>(
        v: &'a Vec<String>,
        edges: &BTreeMap<&'a Vec<String>, Vec<&'a Vec<String>>>,
        index: &mut BTreeMap<&'a Vec<String>, usize>,
        low: &mut BTreeMap<&'a Vec<String>, usize>,
        stack: &mut Vec<&'a Vec<String>>,
        found: &mut Vec<Vec<String>>,
    ) {
        let n = index.len();
        index.insert(v, n);
        low.insert(v, n);
        stack.push(v);
        for &w in edges.get(v).into_iter().flatten() {
            if !index.contains_key(w) {
                visit(w, edges, index, low, stack, found);
                let lw = low[w];
                low.entry(v).and_modify(|l| *l = (*l).min(lw));
            } else if stack.contains(&w) {
                let iw = index[w];
                low.entry(v).and_modify(|l| *l = (*l).min(iw));
            }
        }
        if low[v] == index[v] {
            let mut group = Vec::new();
            while let Some(w) = stack.pop() {
                group.push(w.join("::"));
                if w == v {
                    break;
                }
            }
            if group.len() > 1 {
                group.sort();
                found.push(group);
            }
        }
    }
    for v in edges.keys() {
        if !index.contains_key(v) {
            visit(v, &edges, &mut index, &mut low, &mut stack, &mut found);
        }
    }
    found
}

#[test]
fn no_two_files_import_each_other_directly_or_round_a_circle() {
    let found = circles(&import_graph());
    assert!(found.is_empty(), "import circles (each a group of files that import one another): {found:#?}");
}

#[test]
fn the_circle_check_finds_a_circle() {
    // The check itself: a made-up graph a → b → c → a (and d on its own, and a folder with its file)
    // is one circle.
    let m = |s: &str| s.split("::").map(str::to_owned).collect::<Vec<_>>();
    let graph: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = [
        (m("x::a"), [m("x::b")].into()),
        (m("x::b"), [m("x::c")].into()),
        (m("x::c"), [m("x::a"), m("x::d")].into()),
        (m("x::d"), BTreeSet::new()),
        (m("x"), [m("x::d")].into()),
        (m("x::e"), [m("x")].into()),
    ]
    .into();
    assert_eq!(circles(&graph), vec![vec!["x::a".to_owned(), "x::b".to_owned(), "x::c".to_owned()]]);
    let paths = named_paths("use super::{a, b::c as d};\nlet x = crate::core::run::Run::new();".to_owned());
    assert!(paths.contains(&m("super::a")) && paths.contains(&m("super::b::c")), "{paths:?}");
    assert!(paths.contains(&m("crate::core::run::Run::new")), "{paths:?}");
}

#[test]
fn views_import_no_other_view_nor_the_shell() {
    let views =
        ["bode", "compare", "control", "data", "diagnosis", "history", "static_map", "traces", "zplane"];
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
