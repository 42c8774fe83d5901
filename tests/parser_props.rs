//! Project files and model files, mutated at random: reading them never panics, every refusal names
//! the file, and a model file that is accepted can be simulated without a panic (what `predict`
//! does next). The CSV reader has its own properties in `run_files/props.rs`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use jetid::core::effects::ExtendedModel;
use jetid::core::run::{Channel, Run};
use jetid::io::model_file::read_model;
use jetid::io::project::load_project;
use proptest::prelude::*;

/// One edit of a text: the kinds of damage a hand edit, a truncated copy or a bad merge does.
#[derive(Clone, Debug)]
enum Mutation {
    /// Drop `len` bytes at `at` (fractions of the text length).
    Delete { at: f64, len: usize },
    /// Insert a fragment at `at`.
    Insert { at: f64, text: String },
    /// Replace the `nth` number of the text by `value`.
    Number { nth: usize, value: String },
    /// Repeat the line at `at`.
    DuplicateLine { at: f64 },
    /// Cut the text at `at`.
    Truncate { at: f64 },
}

fn fragments() -> impl Strategy<Value = String> {
    prop_oneof![
        prop::sample::select(vec![
            "\"",
            "{",
            "}",
            "[",
            "]",
            ",",
            "=",
            "\n",
            "#",
            "\u{0}",
            "é",
            "\u{feff}",
            "null",
            "true",
            "[[x]]",
            "ident = 3",
            "window = \"9:1\"",
            "-1e400",
            "NaN",
            "\"params\": {}",
            "\"id\": \"warp\"",
            "inf",
        ])
        .prop_map(str::to_owned),
        "[ -~]{0,12}",
    ]
}

fn numbers() -> impl Strategy<Value = String> {
    prop::sample::select(vec![
        "0",
        "-0",
        "1e308",
        "-1e308",
        "1e-320",
        "NaN",
        "inf",
        "-1",
        "18446744073709551616",
        "0.5",
        "\"7\"",
        "[]",
        "2.0e",
        "1e400",
    ])
    .prop_map(str::to_owned)
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (0.0..1.0f64, 1usize..40).prop_map(|(at, len)| Mutation::Delete { at, len }),
        (0.0..1.0f64, fragments()).prop_map(|(at, text)| Mutation::Insert { at, text }),
        (0usize..200, numbers()).prop_map(|(nth, value)| Mutation::Number { nth, value }),
        (0.0..1.0f64).prop_map(|at| Mutation::DuplicateLine { at }),
        (0.0..1.0f64).prop_map(|at| Mutation::Truncate { at }),
    ]
}

/// The byte offset nearest `at·len` that is a character boundary.
fn boundary(text: &str, at: f64) -> usize {
    let mut i = ((text.len() as f64) * at) as usize;
    while i > 0 && !text.is_char_boundary(i) {
        i -= 1;
    }
    i.min(text.len())
}

fn apply(text: &str, m: &Mutation) -> String {
    match m {
        Mutation::Delete { at, len } => {
            let a = boundary(text, *at);
            let mut b = (a + len).min(text.len());
            while !text.is_char_boundary(b) {
                b += 1;
            }
            format!("{}{}", &text[..a], &text[b..])
        }
        Mutation::Insert { at, text: add } => {
            let a = boundary(text, *at);
            format!("{}{add}{}", &text[..a], &text[a..])
        }
        Mutation::Number { nth, value } => {
            let spans = number_spans(text);
            match spans.get(nth % spans.len().max(1)) {
                Some(&(a, b)) => format!("{}{value}{}", &text[..a], &text[b..]),
                None => text.to_owned(),
            }
        }
        Mutation::DuplicateLine { at } => {
            let lines: Vec<&str> = text.lines().collect();
            let i = ((lines.len() as f64) * at) as usize;
            let mut out: Vec<&str> = lines.clone();
            if let Some(line) = lines.get(i) {
                out.insert(i, line);
            }
            out.join("\n")
        }
        Mutation::Truncate { at } => text[..boundary(text, *at)].to_owned(),
    }
}

/// Byte spans of the numbers in a text (digits with sign, point and exponent).
fn number_spans(text: &str) -> Vec<(usize, usize)> {
    let bytes = text.as_bytes();
    let mut spans = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i].is_ascii_digit() {
            let start = if i > 0 && bytes[i - 1] == b'-' { i - 1 } else { i };
            let mut j = i;
            while j < bytes.len()
                && (bytes[j].is_ascii_digit() || matches!(bytes[j], b'.' | b'e' | b'E' | b'-' | b'+'))
            {
                j += 1;
            }
            spans.push((start, j));
            i = j;
        } else {
            i += 1;
        }
    }
    spans
}

/// A model file with an effect applied, written once by the batch on the bundled runs.
fn model_text() -> &'static str {
    static TEXT: OnceLock<String> = OnceLock::new();
    TEXT.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let status = std::process::Command::new(env!("CARGO_BIN_EXE_jetid"))
            .args(["--batch", "--quiet", "--add-effect", "thermal_soak", "--out"])
            .arg(dir.path())
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .status()
            .unwrap();
        assert!(status.success(), "the batch writes a model file");
        std::fs::read_to_string(dir.path().join("model.json")).unwrap()
    })
}

fn project_texts() -> Vec<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("sample_runs");
    ["sr30", "hot_day", "soak", "jetcat_p300", "t07"]
        .iter()
        .map(|d| std::fs::read_to_string(root.join(d).join("project.toml")).unwrap())
        .collect()
}

/// A file name no message would contain by accident.
fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// The messages of an error and its causes, as the command line prints them.
fn message(e: &anyhow::Error) -> String {
    e.chain().map(ToString::to_string).collect::<Vec<_>>().join(": ")
}

/// What `predict` does with a model it has read: every output simulated from a short schedule.
fn simulate_all(path: &Path) {
    let Ok(model) = read_model(path) else { return };
    let n = 60;
    let run = Run {
        name: "schedule".into(),
        dt_secs: model.dt_secs,
        t_secs: (0..n).map(|k| k as f64 * model.dt_secs).collect(),
        input: Channel::new(&model.input.name, (0..n).map(|k| if k < 20 { 3.0 } else { 5.0 }).collect()),
        outputs: vec![],
        aux: vec![],
    };
    for out in &model.outputs {
        if let Ok(extended) = ExtendedModel::from_records(&out.name, out.wiener.clone(), &out.effects) {
            let _ = extended.simulate(&run);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn mutated_project_files_are_read_or_refused_with_their_name(
        which in 0usize..5,
        edits in prop::collection::vec(mutation(), 1..4),
    ) {
        let texts = project_texts();
        let text = edits.iter().fold(texts[which % texts.len()].clone(), |t, m| apply(&t, m));
        let dir = tempfile::tempdir().unwrap();
        let path = write(dir.path(), "bench_project_q7.toml", &text);
        if let Err(e) = load_project(&path) {
            let msg = message(&e);
            prop_assert!(msg.contains("bench_project_q7.toml"), "{msg}");
        }
    }

    #[test]
    fn mutated_model_files_are_read_or_refused_with_their_name_and_never_panic_the_simulation(
        edits in prop::collection::vec(mutation(), 1..4),
    ) {
        let text = edits.iter().fold(model_text().to_owned(), |t, m| apply(&t, m));
        let dir = tempfile::tempdir().unwrap();
        let path = write(dir.path(), "bench_model_q7.json", &text);
        match read_model(&path) {
            Err(e) => {
                let msg = message(&e);
                prop_assert!(msg.contains("bench_model_q7.json"), "{msg}");
            }
            Ok(_) => simulate_all(&path),
        }
    }

    #[test]
    fn arbitrary_bytes_are_refused_with_the_file_name(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bench_any_q7.json");
        std::fs::write(&path, &bytes).unwrap();
        if let Err(e) = read_model(&path) {
            prop_assert!(message(&e).contains("bench_any_q7.json"), "{}", message(&e));
        }
        let toml_path = dir.path().join("bench_any_q7.toml");
        std::fs::write(&toml_path, &bytes).unwrap();
        if let Err(e) = load_project(&toml_path) {
            prop_assert!(message(&e).contains("bench_any_q7.toml"), "{}", message(&e));
        }
    }
}

#[test]
fn the_unmutated_files_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "model.json", model_text());
    let model = read_model(&path).unwrap();
    assert!(model.outputs.iter().any(|o| !o.effects.is_empty()), "the model carries an effect");
    for (i, text) in project_texts().iter().enumerate() {
        // Written beside the samples' own folder layout is not needed: reading does not open runs.
        let path = write(dir.path(), &format!("p{i}.toml"), text);
        load_project(&path).unwrap();
    }
}
