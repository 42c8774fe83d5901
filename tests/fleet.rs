//! `jetid fleet` and `jetid simulate-fleet` end to end: a small simulated fleet whose injected faults
//! must be flagged and whose healthy runs must not (the truth is read here only to score the
//! command's table, never given to it), the table's columns in CSV and parquet, the manifest's errors,
//! and the JetCat's real runs (where `../shared/realdata` is present).
#![allow(clippy::unwrap_used, clippy::expect_used)]
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use jetid::fleet::manifest::{load_manifest, parse_manifest};

fn jetid(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_jetid")).args(args).output().unwrap()
}

/// A simulated fleet (4 engines × 8 short runs, one run in seven faulty on average) and the fleet
/// command's results on it, made once for every test here (under the target's temporary folder).
fn simulated() -> (&'static Path, &'static Path) {
    static FLEET: OnceLock<(PathBuf, PathBuf)> = OnceLock::new();
    let (data, out) = FLEET.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fleet-simulated");
        let _ = std::fs::remove_dir_all(&dir);
        let (data, out) = (dir.join("fleet"), dir.join("results"));
        let o = jetid(&[
            "simulate-fleet",
            "--engines",
            "4",
            "--runs",
            "8",
            "--seed",
            "3",
            "--run-secs",
            "120",
            "--fault-rate",
            "0.15",
            "--out",
            data.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let o =
            jetid(&["fleet", data.join("manifest.toml").to_str().unwrap(), "--out", out.to_str().unwrap()]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        (data, out)
    });
    (data, out)
}

fn read_csv(path: &Path) -> Vec<BTreeMap<String, String>> {
    let mut reader = csv::Reader::from_path(path).unwrap();
    let header: Vec<String> = reader.headers().unwrap().iter().map(str::to_owned).collect();
    reader
        .records()
        .map(|r| header.iter().cloned().zip(r.unwrap().iter().map(str::to_owned)).collect())
        .collect()
}

#[test]
fn simulated_faults_are_flagged_and_healthy_runs_are_not() {
    let (data, out) = simulated();
    let truth = read_csv(&data.join("truth.csv"));
    let rows = read_csv(&out.join("fleet.csv"));
    let flagged = |engine: &str, run: &str| {
        rows.iter().any(|r| r["engine"] == engine && r["run"] == run && !r["flag"].is_empty())
    };
    let faults: Vec<_> = truth.iter().filter(|t| t["fault"] != "none").collect();
    assert!(faults.len() >= 3, "the fleet should hold faults to find: {faults:?}");
    for t in &truth {
        let (engine, run, fault) = (&t["engine"], &t["run"], &t["fault"]);
        assert_eq!(flagged(engine, run), fault != "none", "{engine}/{run} ({fault})");
    }
    // A starved run says why, in words.
    for t in faults.iter().filter(|t| t["fault"] == "fuel_starvation") {
        let row = rows.iter().find(|r| r["engine"] == t["engine"] && r["run"] == t["run"]).unwrap();
        assert!(row["flag"].contains("fuel supply"), "{}", row["flag"]);
    }
    // The fitted input gain follows the meter's injected drift on the healthy runs.
    let (mut fitted, mut injected) = (Vec::new(), Vec::new());
    for t in truth.iter().filter(|t| t["fault"] == "none") {
        let row = rows.iter().find(|r| r["engine"] == t["engine"] && r["run"] == t["run"]).unwrap();
        fitted.push(row["input_gain"].parse::<f64>().unwrap());
        injected.push(t["input_gain"].parse::<f64>().unwrap());
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (mf, mi) = (mean(&fitted), mean(&injected));
    let cov: f64 = fitted.iter().zip(&injected).map(|(f, i)| (f - mf) * (i - mi)).sum();
    let var = |v: &[f64], m: f64| v.iter().map(|x| (x - m) * (x - m)).sum::<f64>();
    let correlation = cov / (var(&fitted, mf) * var(&injected, mi)).sqrt();
    let rms = (fitted.iter().zip(&injected).map(|(f, i)| (f - i) * (f - i)).sum::<f64>()
        / fitted.len() as f64)
        .sqrt();
    assert!(correlation > 0.9 && rms < 0.005, "correlation {correlation:.3}, RMS error {rms:.4}");
}

#[test]
fn fleet_table_has_its_columns_in_csv_and_parquet() {
    use parquet::file::reader::{FileReader, SerializedFileReader};
    use parquet::record::RowAccessor;
    let (_, out) = simulated();
    let mut expected = vec!["engine", "run", "date", "output", "rmse", "rmspe_pct"]
        .into_iter()
        .map(String::from)
        .collect::<Vec<_>>();
    for delta in ["input_gain", "input_offset", "tau_scale", "map_shift", "map_shift_pct"] {
        expected.extend([delta.to_owned(), format!("{delta}_ci95_low"), format!("{delta}_ci95_high")]);
    }
    expected.extend(["diagnosed", "effects", "flag"].map(String::from));
    let mut reader = csv::Reader::from_path(out.join("fleet.csv")).unwrap();
    let header: Vec<String> = reader.headers().unwrap().iter().map(str::to_owned).collect();
    assert_eq!(header, expected);
    let rows = reader.records().count();
    assert_eq!(rows, 4 * 8 * 2, "one row per run and output");
    let parquet = SerializedFileReader::new(std::fs::File::open(out.join("fleet.parquet")).unwrap()).unwrap();
    let meta = parquet.metadata().file_metadata();
    let names: Vec<String> = meta.schema_descr().columns().iter().map(|c| c.name().to_owned()).collect();
    assert_eq!(names, expected);
    assert_eq!(meta.num_rows(), rows as i64);
    let first = parquet.get_row_iter(None).unwrap().next().unwrap().unwrap();
    assert_eq!(first.get_string(0).unwrap(), "e001");
    // Each interval holds its estimate; the report and one trend figure per engine are there.
    for row in read_csv(&out.join("fleet.csv")) {
        let (v, lo, hi) = (&row["input_gain"], &row["input_gain_ci95_low"], &row["input_gain_ci95_high"]);
        let (v, lo, hi) = (v.parse::<f64>().unwrap(), lo.parse::<f64>().unwrap(), hi.parse::<f64>().unwrap());
        assert!(lo < v && v < hi, "{row:?}");
    }
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    for e in 1..=4 {
        let figure = format!("trend_{e:02}_e{e:03}.png");
        assert!(out.join(&figure).is_file() && report.contains(&figure), "{figure}");
    }
}

/// The micro gas turbine's T07 runs of 2023-04-05, against the reference identified on 2023-02-10:
/// both flagged, each with the direction of the change against the reference, the same for both;
/// the reference day's own runs are not flagged.
#[test]
#[cfg_attr(not(jetid_realdata), ignore = "needs ../shared/realdata")]
fn the_t07_april_runs_are_flagged_with_the_direction_of_the_change() {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR")).join("sample_runs/fleet/mgt.toml");
    let dir = tempfile::tempdir().unwrap();
    let o = jetid(&["fleet", manifest.to_str().unwrap(), "--out", dir.path().to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = read_csv(&dir.path().join("fleet.csv"));
    let t07: Vec<_> = rows.iter().filter(|r| r["engine"] == "T07").collect();
    let direction = |flag: &str| {
        ["more fuel", "less fuel"]
            .into_iter()
            .find(|d| flag.contains("against the reference") && flag.contains(d))
    };
    let april: Vec<_> =
        t07.iter().filter(|r| r["date"] == "2023-04-05").map(|r| direction(&r["flag"])).collect();
    assert!(!april.is_empty() && april.iter().all(Option::is_some), "{t07:?}");
    assert!(april.windows(2).all(|w| w[0] == w[1]), "{april:?}");
    assert!(t07.iter().filter(|r| r["date"] == "2023-02-10").all(|r| r["flag"].is_empty()), "{t07:?}");
}

/// fleet.parquet reads back with pyarrow (what Dask, Spark, Polars and DuckDB read it with): the
/// same columns as fleet.csv, the same rows, the same numbers.
#[test]
fn the_fleet_table_reads_back_with_pyarrow() {
    if !crate::common::have_pyarrow() {
        return;
    }
    let (_, out) = simulated();
    let script = "import sys, json, pyarrow.parquet as pq\n\
                  t = pq.read_table(sys.argv[1])\n\
                  print(json.dumps({'columns': t.column_names, 'rows': t.num_rows, \
                  'rmse': t.column('rmse').to_pylist(), 'flag': t.column('flag').to_pylist()}))";
    let o = crate::common::python3()
        .args(["-c", script, out.join("fleet.parquet").to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let read: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let csv = read_csv(&out.join("fleet.csv"));
    let mut reader = csv::Reader::from_path(out.join("fleet.csv")).unwrap();
    let header: Vec<String> = reader.headers().unwrap().iter().map(str::to_owned).collect();
    let columns: Vec<String> = serde_json::from_value(read["columns"].clone()).unwrap();
    assert_eq!(columns, header);
    assert_eq!(read["rows"].as_u64(), Some(csv.len() as u64));
    for (i, row) in csv.iter().enumerate() {
        let rmse = read["rmse"][i].as_f64().unwrap();
        let written: f64 = row["rmse"].parse().unwrap();
        assert!((rmse - written).abs() <= 1e-9 * written.abs().max(1.0), "row {i}: {rmse} against {written}");
        assert_eq!(read["flag"][i].as_str().unwrap_or(""), row["flag"], "row {i}");
    }
}

/// A manifest's error, in full.
fn manifest_error(text: &str, dir: &Path) -> String {
    let path = dir.join("fleet.toml");
    std::fs::write(&path, text).unwrap();
    format!("{:#}", load_manifest(&path).unwrap_err())
}

#[test]
fn manifest_errors_name_the_file_and_the_entry() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("model.json"), "{}").unwrap();
    std::fs::write(dir.path().join("a.csv"), "time_s,fuel_flow_gph,shaft_speed_rpm\n").unwrap();
    let engine = |rest: &str| format!("[[engine]]\nname = \"E1\"\nreference = \"model.json\"\n{rest}");
    // (manifest, what the error must quote, whether it names the engine: a key the format does not
    // know is refused by the parser, which quotes the line instead).
    let cases = [
        (engine("runs = [{ path = \"missing.csv\" }]"), "missing.csv", true),
        (engine("runs = [{ path = \"a.csv\", date = \"2023-02-30\" }]"), "2023-02-30", true),
        (engine("runs = [{ path = \"a.csv\", dat = \"2023-02-01\" }]"), "dat", false),
        (engine(""), "no runs", true),
        ("[[engine]]\nname = \"E1\"\nruns = [{ path = \"a.csv\" }]".to_owned(), "no reference", true),
        (engine("runs = [{ path = \"a.csv\" }]").replace("model.json", "gone.json"), "gone.json", true),
        ("name = \"empty\"".to_owned(), "names no engine", false),
    ];
    for (text, needle, names_engine) in cases {
        let message = manifest_error(&text, dir.path());
        assert!(message.contains("fleet.toml") && message.contains(needle), "{needle}: {message}");
        assert!(!names_engine || message.contains("'E1'"), "{message}");
    }
    // Runs sort by date; a run's name defaults to its file's stem.
    std::fs::write(dir.path().join("b.csv"), "").unwrap();
    let runs = "runs = [{ path = \"b.csv\", date = \"2023-03-01\" }, { path = \"a.csv\", date = \"2023-01-01\", name = \"A\" }]";
    let manifest = parse_manifest(&engine(runs), dir.path(), "fleet.toml").unwrap();
    let names: Vec<&str> = manifest.engines[0].runs.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(names, ["A", "b"]);
}

#[test]
fn a_failed_fleet_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::write(dir.path().join("model.json"), "not json").unwrap();
    std::fs::write(dir.path().join("a.csv"), "").unwrap();
    let manifest = dir.path().join("fleet.toml");
    std::fs::write(
        &manifest,
        "[[engine]]\nname = \"E1\"\nreference = \"model.json\"\nruns = [{ path = \"a.csv\" }]\n",
    )
    .unwrap();
    let o = jetid(&["fleet", manifest.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("E1") && stderr.contains("model.json"), "{stderr}");
    assert!(!out.exists());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 3, "no staging folder left behind");
}

#[test]
#[cfg_attr(not(jetid_realdata), ignore = "needs ../shared/realdata")]
fn jetcat_runs_c_and_e_are_flagged_for_their_fuel_supply() {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR")).join("sample_runs/fleet/jetcat.toml");
    let dir = tempfile::tempdir().unwrap();
    let o = jetid(&["fleet", manifest.to_str().unwrap(), "--out", dir.path().to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = read_csv(&dir.path().join("fleet.csv"));
    for row in &rows {
        let starved = ["C", "E"].contains(&row["run"].as_str());
        assert_eq!(row["flag"].contains("fuel supply"), starved, "{row:?}");
        assert_eq!(!row["flag"].is_empty(), starved, "{row:?}");
    }
}

#[test]
fn a_run_on_another_input_or_a_bad_fleet_size_is_refused() {
    let (data, _) = simulated();
    let dir = tempfile::tempdir().unwrap();
    // The same run with its input under another name, mapped as the input: not the reference's.
    let text =
        std::fs::read_to_string(data.join("e001_r01.csv")).unwrap().replacen("fuel_flow_gph", "pump_V", 1);
    std::fs::write(dir.path().join("renamed.csv"), text).unwrap();
    let reference = data.join("e001_reference.json");
    let manifest = dir.path().join("fleet.toml");
    std::fs::write(
        &manifest,
        format!(
            "[[engine]]\nname = \"E1\"\nreference = \"{}\"\nruns = [{{ path = \"renamed.csv\", name = \"R\" }}]\n\
             [engine.load]\nmap = [\"input=pump_V\"]\n",
            reference.display()
        ),
    )
    .unwrap();
    let out = dir.path().join("out");
    let o = jetid(&["fleet", manifest.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("'E1'") && stderr.contains("'R'") && stderr.contains("pump_V"), "{stderr}");
    assert!(!out.exists());
    for (args, needle) in [
        (vec!["--engines", "0"], "at least one engine"),
        (vec!["--run-secs", "30"], "at least"),
        (vec!["--fault-rate", "1.5"], "not a probability"),
    ] {
        let out = dir.path().join("sim");
        let mut all = vec!["simulate-fleet", "--out", out.to_str().unwrap()];
        all.extend(args);
        let o = jetid(&all);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.code() == Some(1) && stderr.contains(needle), "{stderr}");
        assert!(!out.exists());
    }
}

/// The diagnosis `jetid fleet` runs on a screened run, on engines of the family it has never seen:
/// each engine commissioned on the identification design (its reference), then a run of the
/// validation design (steps of several sizes, the experiment that tells a rate limit from a slow
/// spool) with the spool's acceleration and deceleration limited (the simulator's rate limit at its
/// defaults), and the same run without it. The test only reads what the diagnosis found.
#[test]
fn a_run_diagnosis_finds_a_rate_limit_and_nothing_on_the_healthy_run() {
    use jetid::core::effects::EffectId;
    use jetid::fleet::diagnosis::diagnose_samples;
    use jetid::fleet::reference::{Reference, identify_run};
    use jetid::sim::effects::Effect;
    use jetid::sim::{EngineFamily, SimConfig, TestKind, simulate};
    let mut found = Vec::new();
    for seed in [21_u64, 22, 23] {
        let drawn = EngineFamily::small_turbojets().draw(seed);
        let commissioning =
            simulate(&SimConfig::for_test("commissioning", TestKind::Ident, seed).unwrap().on_engine(&drawn))
                .unwrap()
                .measured;
        let reference =
            Reference::of_model_file(&identify_run(&commissioning).unwrap(), "test".into()).unwrap();
        let run = |effects: Vec<Effect>| {
            let cfg = SimConfig::for_test("run", TestKind::Validation, seed + 100).unwrap();
            simulate(&cfg.on_engine(&drawn).with_effects(effects)).unwrap().measured
        };
        let plain = run(Vec::new());
        // Cut after its first steps, a run has too few to split: said, and nothing found.
        let short = diagnose_samples(&plain, plain.len() / 20, &reference);
        assert!(short.diagnosed.is_empty() && short.findings.is_empty(), "{short:?}");
        assert!(
            short.notes.iter().any(|n| n.contains("not diagnosed: fewer than 2 steps")),
            "{:?}",
            short.notes
        );
        let healthy = diagnose_samples(&plain, usize::MAX, &reference);
        assert_eq!(healthy.diagnosed.len(), 2, "engine {seed}: both outputs diagnosed: {:?}", healthy.notes);
        assert!(healthy.findings.is_empty(), "engine {seed}, healthy run: {:?}", healthy.findings);
        let limited = run(vec![Effect::with_defaults(EffectId::RateLimit).unwrap()]);
        let diagnosis = diagnose_samples(&limited, usize::MAX, &reference);
        assert!(
            diagnosis.findings.iter().all(|f| f.effect == EffectId::RateLimit),
            "engine {seed}: {:?}",
            diagnosis.findings
        );
        found.push(diagnosis.findings.iter().any(|f| f.output.contains("speed")));
    }
    assert!(found.iter().filter(|f| **f).count() >= 2, "{found:?}");
}
