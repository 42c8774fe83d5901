//! Nothing silent at the edges: what `predict` and the batch say about runs that lie outside what
//! the model knows, runs used twice or named alike, few segments, and sample times of any size.
use std::path::{Path, PathBuf};

use crate::common::{jetid, sample};

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn s(path: &Path) -> &str {
    path.to_str().expect("utf-8 path")
}

/// A one-pole model of the bundled runs' input, identified (says its file) on 2.0–7.4 gal/h.
fn model(dir: &Path) -> PathBuf {
    let path = dir.join("model.json");
    let text = r#"{"format_version": 1, "convention": "", "dt_secs": 0.112994350282,
 "input": {"name": "fuel_flow_gph", "unit": "gal/h"}, "input_range": [2.0, 7.4],
 "outputs": [{"name": "shaft_speed_rpm", "unit": "rpm",
   "wiener": {"linear": {"tf": {"num_zinv": [0.0, 800.0], "den_zinv": [1.0, -0.9], "dt_secs": 0.112994350282}, "offset": 0.0},
              "map": {"v_center": 0.0, "v_scale": 1.0, "coeffs_scaled": [30000.0, 1.0]}},
   "static_map_beta": [30000.0, 1.0], "poles": [[0.9, 0.0]], "zeros": [], "clusters": [], "effects": []}]}"#;
    std::fs::write(&path, text).unwrap();
    path
}

/// The bundled validation run with its input passed through `f`.
fn run_with_input(dir: &Path, name: &str, f: impl Fn(f64) -> f64) -> PathBuf {
    let text = std::fs::read_to_string(sample("sr30/validation.csv")).unwrap();
    let mut lines = text.lines();
    let mut out = vec![lines.next().unwrap().to_owned()];
    for line in lines {
        let mut cells: Vec<String> = line.split(',').map(str::to_owned).collect();
        cells[1] = format!("{}", f(cells[1].parse::<f64>().unwrap()));
        out.push(cells.join(","));
    }
    let path = dir.join(name);
    std::fs::write(&path, out.join("\n") + "\n").unwrap();
    path
}

#[test]
fn predict_says_which_share_of_the_input_lies_outside_the_identified_range() {
    let dir = tempfile::tempdir().unwrap();
    let model = model(dir.path());
    let inside = run_with_input(dir.path(), "inside.csv", |u| u.clamp(2.0, 7.4));
    let o = jetid(&[
        "predict",
        "--model",
        s(&model),
        "--input",
        s(&inside),
        "--out",
        s(&dir.path().join("a.csv")),
    ]);
    assert!(o.status.success() && !stderr(&o).contains("outside"), "{}", stderr(&o));

    // Every sample at three times the fuel flow: 15 gal/h and more, far above what was identified.
    let high = run_with_input(dir.path(), "high.csv", |u| 3.0 * u);
    let out = dir.path().join("b.csv");
    let o = jetid(&["predict", "--model", s(&model), "--input", s(&high), "--out", s(&out)]);
    let err = stderr(&o);
    assert!(o.status.success() && out.exists(), "{err}");
    assert!(
        err.contains("high.csv") && err.contains("% of the input") && err.contains("samples) lies"),
        "{err}"
    );
    assert!(err.contains("outside the identified range 2.000 to 7.400 gal/h"), "{err}");
    assert!(err.contains("extrapolates"), "{err}");

    // A fuel flow that goes negative on a model identified on positive values: named.
    let negative = run_with_input(dir.path(), "negative.csv", |u| u - 5.0);
    let o = jetid(&[
        "predict",
        "--model",
        s(&model),
        "--input",
        s(&negative),
        "--out",
        s(&dir.path().join("c.csv")),
    ]);
    assert!(stderr(&o).contains("changes sign"), "{}", stderr(&o));

    // --strict refuses it, naming the range, and writes nothing.
    let strict = dir.path().join("d.csv");
    let o = jetid(&["predict", "--model", s(&model), "--input", s(&high), "--out", s(&strict), "--strict"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--strict") && stderr(&o).contains("2.000 to 7.400"), "{}", stderr(&o));
    assert!(!strict.exists());
}

#[test]
fn the_batch_notes_scored_runs_outside_the_range_and_a_validation_run_that_is_the_identification_run() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let ident = sample("sr30/ident.csv");
    let high = run_with_input(dir.path(), "validation.csv", |u| u * 1.5);
    let args = ["--batch", "--ident", s(&ident), "--validate", s(&ident), "--held-out", s(&high)];
    let o = jetid(&[&args[..], &["--output", "shaft_speed_rpm", "--out", s(&out), "--quiet"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let notes = report["diagnostics"].to_string();
    assert!(notes.contains("is also the identification run"), "{notes}");
    assert!(notes.contains("run 'validation'") && notes.contains("outside the identified range"), "{notes}");
    let model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("model.json")).unwrap()).unwrap();
    let range = model["input_range"].as_array().expect("model.json holds the identified input range");
    assert!(range[0].as_f64().unwrap() < range[1].as_f64().unwrap(), "{range:?}");
}

#[test]
fn runs_of_the_same_file_name_from_two_folders_are_told_apart() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("dayA"), dir.path().join("dayB"));
    std::fs::create_dir_all(&a).unwrap();
    std::fs::create_dir_all(&b).unwrap();
    std::fs::copy(sample("sr30/validation.csv"), a.join("run.csv")).unwrap();
    std::fs::copy(sample("sr30/chirp.csv"), b.join("run.csv")).unwrap();
    let out = dir.path().join("out");
    let ident = sample("sr30/ident.csv");
    let (run_a, run_b) = (a.join("run.csv"), b.join("run.csv"));
    let args = ["--batch", "--ident", s(&ident), "--validate", s(&run_a), "--validate", s(&run_b)];
    let o = jetid(&[&args[..], &["--output", "shaft_speed_rpm", "--out", s(&out), "--quiet"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let scored = report["outputs"]["shaft_speed_rpm"]["models"]["gray_box"].as_object().unwrap();
    assert!(scored.contains_key("dayA-run") && scored.contains_key("dayB-run"), "{:?}", scored.keys());
    assert!(report["diagnostics"].to_string().contains("another run has the same file name"));
}

#[test]
fn a_run_with_few_steps_gives_a_model_and_a_warning() {
    // The bundled identification run cut after its third step: three segments.
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(sample("sr30/ident.csv")).unwrap();
    let cut: Vec<&str> = text.lines().take(1500).collect();
    let ident = dir.path().join("short.csv");
    std::fs::write(&ident, cut.join("\n") + "\n").unwrap();
    let out = dir.path().join("out");
    let args = ["--batch", "--ident", s(&ident), "--output", "shaft_speed_rpm", "--out", s(&out), "--quiet"];
    let o = jetid(&args);
    if o.status.success() {
        let report = std::fs::read_to_string(out.join("report.json")).unwrap();
        let segments: serde_json::Value = serde_json::from_str(&report).unwrap();
        let n =
            segments["outputs"]["shaft_speed_rpm"]["identified"]["segments"].as_array().map_or(0, Vec::len);
        let warned = report.contains("so few make a weak model");
        assert_eq!(warned, n < 4, "{n} segments, warned: {warned}");
        assert!(n < 4, "the cut run has {n} segments: the test needs fewer than four");
    } else {
        let err = stderr(&o);
        assert!(err.contains("at least two steps") || err.contains("at least 2"), "{err}");
    }
}

#[test]
fn tiny_sample_times_read_in_significant_digits() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::from("time_s,fuel_flow_gph,shaft_speed_rpm\n");
    for k in 0..50 {
        text.push_str(&format!("{:e},{},{}\n", k as f64 * 1e-7, 3.0 + (k / 10) as f64, 60_000.0 + k as f64));
    }
    let run = dir.path().join("fast.csv");
    std::fs::write(&run, text).unwrap();
    let o = jetid(&["inspect", s(&run)]);
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(said.contains("1.00000e-7 s"), "{said}");
    assert!(!said.contains("0.00000"), "{said}");
}
