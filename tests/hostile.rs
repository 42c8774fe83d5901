//! The hostile-input sweep: about two hundred runs of the binary on files and arguments a user
//! could give by mistake, across `--batch`, `predict`, `inspect`, `export` and `simulate`. Every
//! case ends in one of two ways, and the sweep holds each to it:
//! - exit 0 with a correct result (the file it promises, readable, as long as its input); or
//! - exit 1 with one `error:` message on stderr that names the file (and, where the case says so,
//!   its row and column);
//!
//! and in both no partial file is left (a refused command writes nothing where its output goes) and
//! no input is changed. A panic (exit 101) fails the sweep.
use std::path::{Path, PathBuf};
use std::process::Output;

use crate::common::{jetid, sample};

/// What a case must end in.
enum Expect {
    /// Exit 0, and the check on what was written passes.
    Done(fn(&Path) -> Result<(), String>),
    /// Exit 1 with a message naming `file` and containing every one of `words`.
    Refused { file: &'static str, words: Vec<String> },
}

struct Case {
    name: String,
    args: Vec<String>,
    /// Files the command reads: they must be byte for byte the same afterwards.
    inputs: Vec<PathBuf>,
    /// Where the command writes: a refused command must leave it as it was.
    out: PathBuf,
    expect: Expect,
}

/// A file for the sweep: its name, its contents, and the words its refusal must hold (`None`: it is
/// read and used).
type Named<T> = (&'static str, T, Option<Vec<&'static str>>);

fn refused(file: &'static str, words: &[&str]) -> Expect {
    Expect::Refused { file, words: words.iter().map(|w| (*w).to_owned()).collect() }
}

/// The first `rows` data rows of the bundled validation run, as text lines (header first).
fn base_lines(rows: usize) -> Vec<String> {
    let text = std::fs::read_to_string(sample("sr30/validation.csv")).unwrap();
    text.lines().take(rows + 1).map(str::to_owned).collect()
}

/// Run files a user might hand jetid: each a name, its bytes, and the verdict `predict` and
/// `inspect` must reach (`None`: read as a run; `Some(words)`: refused, naming them).
fn run_files() -> Vec<Named<Vec<u8>>> {
    let lines = base_lines(300);
    let join = |lines: &[String]| (lines.join("\n") + "\n").into_bytes();
    let with = |row: usize, col: usize, cell: &str| {
        let mut l = lines.clone();
        let mut cells: Vec<String> = l[row].split(',').map(str::to_owned).collect();
        cells[col] = cell.to_owned();
        l[row] = cells.join(",");
        join(&l)
    };
    let header = lines[0].clone();
    let semicolon: Vec<String> = lines.iter().map(|l| l.replace(',', ";").replace('.', ",")).collect();
    let mut swapped = lines.clone();
    swapped.swap(10, 11);
    let mut repeated = lines.clone();
    let second: Vec<&str> = lines[5].split(',').collect();
    let mut fifth: Vec<String> = lines[6].split(',').map(str::to_owned).collect();
    fifth[0] = second[0].to_owned();
    repeated[6] = fifth.join(",");
    let mut jitter = lines.clone();
    let mut cells: Vec<String> = jitter[50].split(',').map(str::to_owned).collect();
    cells[0] = format!("{}", cells[0].parse::<f64>().unwrap() + 0.05);
    jitter[50] = cells.join(",");
    let mut ragged = lines.clone();
    ragged[20].push_str(",1.0");
    let mut short = lines.clone();
    short[30] = short[30].rsplit_once(',').unwrap().0.to_owned();
    let quoted: Vec<String> = lines
        .iter()
        .map(|l| l.split(',').map(|c| format!("\"{c}\"")).collect::<Vec<_>>().join(","))
        .collect();
    let crlf = lines.join("\r\n").into_bytes();
    let mut commented = vec!["# logged by a test bench".to_owned()];
    commented.extend(lines.iter().cloned());
    let tab: Vec<String> = lines.iter().map(|l| l.replace(',', "\t")).collect();
    let mut bom = vec![0xef, 0xbb, 0xbf];
    bom.extend(join(&lines));
    let no_time: Vec<String> = lines.iter().map(|l| l.split_once(',').unwrap().1.to_owned()).collect();
    let no_input: Vec<String> = lines
        .iter()
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            [&c[..1], &c[2..]].concat().join(",")
        })
        .collect();
    let duplicate = {
        let mut l = lines.clone();
        l[0] = header.replacen("egt_c", "thrust_n", 1);
        join(&l)
    };
    let outside: Vec<String> = lines
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let mut c: Vec<String> = l.split(',').map(str::to_owned).collect();
            if i > 0 {
                c[1] = format!("{}", 3.0 * c[1].parse::<f64>().unwrap());
            }
            c.join(",")
        })
        .collect();
    vec![
        ("good.csv", join(&lines), None),
        ("outside.csv", join(&outside), None),
        ("crlf.csv", crlf, None),
        ("bom.csv", bom, None),
        ("semicolon.csv", join(&semicolon), None),
        ("tab.csv", join(&tab), None),
        ("quoted.csv", join(&quoted), None),
        ("commented.csv", join(&commented), None),
        ("empty.csv", Vec::new(), Some(vec!["empty file"])),
        ("header_only.csv", (header.clone() + "\n").into_bytes(), Some(vec!["0 samples", "at least 10"])),
        ("few_rows.csv", join(&lines[..6]), Some(vec!["5 samples", "at least 10"])),
        ("nan_input.csv", with(40, 1, "NaN"), Some(vec!["data row 40", "fuel_flow_gph", "missing value"])),
        ("empty_input.csv", with(41, 1, ""), Some(vec!["data row 41", "fuel_flow_gph", "missing value"])),
        ("inf_time.csv", with(42, 0, "inf"), Some(vec!["data row 42", "time_s", "missing value"])),
        (
            "text_input.csv",
            with(43, 1, "abc"),
            Some(vec!["data row 43", "fuel_flow_gph", "\"abc\" is not a number"]),
        ),
        ("text_time.csv", with(44, 0, "12:00"), Some(vec!["data row 44", "time_s", "not a number"])),
        ("ragged_long.csv", join(&ragged), Some(vec!["data row 20", "9 fields", "the header has 8"])),
        ("ragged_short.csv", join(&short), Some(vec!["data row 30", "7 fields", "the header has 8"])),
        ("swapped_time.csv", join(&swapped), Some(vec!["data row 11", "time_s", "does not increase"])),
        ("repeated_time.csv", join(&repeated), Some(vec!["data row 6", "time_s", "does not increase"])),
        (
            "jitter_time.csv",
            join(&jitter),
            Some(vec!["data row 50", "time_s", "differs from the sample time"]),
        ),
        ("no_time.csv", join(&no_time), Some(vec!["no time column", "time_s", "columns present"])),
        ("no_input.csv", join(&no_input), Some(vec!["no input column", "fuel_flow_gph", "columns present"])),
        ("duplicate.csv", duplicate, Some(vec!["thrust_n", "appears twice"])),
        (
            "binary.csv",
            vec![0x00, 0x01, 0x02, 0xff, 0x00, b'a', b',', b'b', b'\n'],
            Some(vec!["not a text CSV"]),
        ),
        (
            "gzip.csv",
            vec![0x1f, 0x8b, 0x08, 0x00, 0x00, 0x00, 0x00, 0x00],
            Some(vec!["not a text CSV", "gzip"]),
        ),
        ("only_commas.csv", b",,,\n,,,\n".to_vec(), Some(vec!["empty file"])),
    ]
}

/// A hand-made model of the bundled runs' input: one pole, a linear map, `effects` as JSON.
fn model_text(pole: f64, coeffs: &str, dt: &str, input: &str, effects: &str) -> String {
    format!(
        r#"{{"format_version": 1, "convention": "", "dt_secs": {dt},
            "input": {{"name": "{input}", "unit": "gal/h"}}, "input_range": [2.0, 7.4],
            "outputs": [{{"name": "shaft_speed_rpm", "unit": "rpm",
              "wiener": {{"linear": {{"tf": {{"num_zinv": [0.0, {gain}], "den_zinv": [1.0, {minus_pole}],
                                             "dt_secs": {dt}}}, "offset": 0.0}},
                          "map": {{"v_center": 0.0, "v_scale": 1.0, "coeffs_scaled": {coeffs}}}}},
              "static_map_beta": [30000.0, 1.0], "poles": [[{pole}, 0.0]], "zeros": [], "clusters": [],
              "effects": {effects}}}]}}"#,
        gain = 8000.0 * (1.0 - pole),
        minus_pole = -pole,
    )
}

/// Model files a user might hand `predict` and `export`: each a name, its text, and the words a
/// refusal must hold (`None`: a model to use).
fn model_files() -> Vec<Named<String>> {
    let dt = "0.112994350282";
    let good = model_text(0.9, "[30000.0, 1.0]", dt, "fuel_flow_gph", "[]");
    vec![
        ("model_good.json", good.clone(), None),
        (
            "model_unstable.json",
            model_text(1.02, "[30000.0, 1.0]", dt, "fuel_flow_gph", "[]"),
            Some(vec!["unit circle"]),
        ),
        (
            "model_integrator.json",
            model_text(1.0, "[30000.0, 1.0]", dt, "fuel_flow_gph", "[]"),
            Some(vec!["unit circle"]),
        ),
        ("model_not_json.json", "this is not json".to_owned(), Some(vec!["not a jetid model file"])),
        ("model_empty.json", String::new(), Some(vec!["not a jetid model file"])),
        ("model_truncated.json", good[..good.len() / 2].to_owned(), Some(vec!["not a jetid model file"])),
        (
            "model_version.json",
            good.replace("\"format_version\": 1", "\"format_version\": 7"),
            Some(vec!["format_version 7"]),
        ),
        (
            "model_dt.json",
            model_text(0.9, "[30000.0, 1.0]", "-0.1", "fuel_flow_gph", "[]"),
            Some(vec!["dt_secs must be positive"]),
        ),
        (
            "model_no_map.json",
            model_text(0.9, "[]", dt, "fuel_flow_gph", "[]"),
            Some(vec!["empty static map"]),
        ),
        (
            "model_other_input.json",
            model_text(0.9, "[30000.0, 1.0]", dt, "pump_V", "[]"),
            Some(vec!["pump_V", "fuel_flow_gph"]),
        ),
        (
            "model_unknown_effect.json",
            model_text(0.9, "[30000.0, 1.0]", dt, "fuel_flow_gph", r#"[{"id": "warp_drive", "params": []}]"#),
            Some(vec!["warp_drive"]),
        ),
        (
            "model_huge.json",
            model_text(0.9, "[30000.0, 1e300, 1e300]", dt, "fuel_flow_gph", "[]"),
            Some(vec!["shaft_speed_rpm", "coeffs_scaled"]),
        ),
        (
            "model_dt_other.json",
            model_text(0.9, "[30000.0, 1.0]", "0.5", "fuel_flow_gph", "[]"),
            Some(vec!["sampled every", "0.5"]),
        ),
    ]
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

fn s(path: &Path) -> String {
    path.to_str().expect("utf-8 path").to_owned()
}

/// A prediction of `rows` rows: time and the modelled output, every value finite.
fn prediction_rows(out: &Path, rows: usize) -> Result<(), String> {
    let text = std::fs::read_to_string(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let lines: Vec<&str> = text.lines().collect();
    if !lines.first().is_some_and(|h| h.starts_with("time_s") && h.contains("shaft_speed_rpm")) {
        return Err(format!("header {:?}", lines.first()));
    }
    if lines.len() != rows + 1 {
        return Err(format!("{} rows, expected {rows}", lines.len() - 1));
    }
    let finite =
        lines[1..].iter().all(|l| l.split(',').all(|c| c.trim().parse::<f64>().is_ok_and(f64::is_finite)));
    if finite { Ok(()) } else { Err("a value is not a finite number".into()) }
}

fn printed_nothing_wrong(_: &Path) -> Result<(), String> {
    Ok(())
}

fn model_written(out: &Path) -> Result<(), String> {
    let text = std::fs::read_to_string(out.join("model.json")).map_err(|e| e.to_string())?;
    serde_json::from_str::<serde_json::Value>(&text).map(|_| ()).map_err(|e| e.to_string())
}

fn program_written(out: &Path) -> Result<(), String> {
    let text = std::fs::read_to_string(out).map_err(|e| e.to_string())?;
    if text.contains("shaft_speed_rpm") { Ok(()) } else { Err("the program does not hold the output".into()) }
}

fn run_written(out: &Path) -> Result<(), String> {
    let text = std::fs::read_to_string(out).map_err(|e| e.to_string())?;
    (text.lines().count() > 10).then_some(()).ok_or_else(|| "too few rows".to_owned())
}

/// Every case of the sweep, its files written into `dir`.
fn cases(dir: &Path) -> Vec<Case> {
    let mut cases = Vec::new();
    let files: Vec<Named<PathBuf>> = run_files()
        .into_iter()
        .map(|(name, bytes, verdict)| (name, write(dir, name, &bytes), verdict))
        .collect();
    let models: Vec<Named<PathBuf>> = model_files()
        .into_iter()
        .map(|(name, text, verdict)| (name, write(dir, name, text.as_bytes()), verdict))
        .collect();
    let good_model = models[0].1.clone();
    let folder = dir.join("a_folder.csv");
    std::fs::create_dir_all(&folder).unwrap();
    let missing = dir.join("missing.csv");
    run_file_cases(dir, &files, &good_model, &mut cases);
    let odd = [("a_folder.csv", folder, vec!["a folder"]), ("missing.csv", missing, vec!["cannot read"])];
    for (name, path, words) in odd {
        cases.extend(odd_path_cases(dir, name, &path, &good_model, &words));
    }
    model_cases(dir, &models, &files[0].1, &mut cases);
    option_cases(dir, &files[0].1, &good_model, &mut cases);
    cases
}

/// Every run file through `inspect`, `predict` and `--batch` (as the validation run: refused files
/// stop the batch before any model is fitted; the good one would take the whole pipeline, so only
/// the bad ones run there).
fn run_file_cases(
    dir: &Path,
    files: &[(&str, PathBuf, Option<Vec<&str>>)],
    model: &Path,
    cases: &mut Vec<Case>,
) {
    let ident = sample("sr30/ident.csv");
    for (name, path, verdict) in files {
        let file: &'static str = Box::leak(name.to_string().into_boxed_str());
        let expect = |done: Expect| match verdict {
            None => done,
            Some(words) => refused(file, words),
        };
        cases.push(Case {
            name: format!("inspect {name}"),
            args: vec!["inspect".into(), s(path)],
            inputs: vec![path.clone()],
            out: dir.join("nothing"),
            expect: expect(Expect::Done(printed_nothing_wrong)),
        });
        let out = dir.join(format!("pred_{name}"));
        cases.push(Case {
            name: format!("predict {name}"),
            args: ["predict", "--model", &s(model), "--input", &s(path), "--out", &s(&out)]
                .map(String::from)
                .to_vec(),
            inputs: vec![path.clone(), model.to_owned()],
            out,
            expect: expect(Expect::Done(|p: &Path| prediction_rows(p, 300))),
        });
        if verdict.is_some() {
            let out = dir.join(format!("batch_{name}"));
            cases.push(Case {
                name: format!("batch --validate {name}"),
                args: [
                    "--batch",
                    "--ident",
                    &s(&ident),
                    "--validate",
                    &s(path),
                    "--out",
                    &s(&out),
                    "--quiet",
                ]
                .map(String::from)
                .to_vec(),
                inputs: vec![path.clone(), ident.clone()],
                out,
                expect: expect(Expect::Done(model_written)),
            });
            let out = dir.join(format!("batch_ident_{name}"));
            cases.push(Case {
                name: format!("batch --ident {name}"),
                args: ["--batch", "--ident", &s(path), "--out", &s(&out), "--quiet"]
                    .map(String::from)
                    .to_vec(),
                inputs: vec![path.clone()],
                out,
                expect: expect(Expect::Done(model_written)),
            });
        }
    }
}

/// A folder or a missing file where a run file goes, in every command that reads one.
fn odd_path_cases(dir: &Path, name: &'static str, path: &Path, model: &Path, words: &[&str]) -> Vec<Case> {
    let out = dir.join(format!("odd_{}", name.replace('.', "_")));
    let commands: [Vec<String>; 3] = [
        vec!["inspect".into(), s(path)],
        ["predict", "--model", &s(model), "--input", &s(path), "--out", &s(&out)].map(String::from).to_vec(),
        ["--batch", "--ident", &s(path), "--out", &s(&out), "--quiet"].map(String::from).to_vec(),
    ];
    commands
        .into_iter()
        .map(|args| Case {
            name: format!("{} {name}", args[0]),
            args,
            inputs: vec![model.to_owned()],
            out: out.clone(),
            expect: refused(name, words),
        })
        .collect()
}

/// Every model file through `predict` and through `export` in each language.
fn model_cases(dir: &Path, models: &[Named<PathBuf>], run: &Path, cases: &mut Vec<Case>) {
    for (name, path, verdict) in models {
        let file: &'static str = Box::leak(name.to_string().into_boxed_str());
        let out = dir.join(format!("pred_{name}.csv"));
        let predict_verdict = match (verdict, *name) {
            // Predicting is refused; exporting it is fine where the model itself is (another input,
            // another sample time and huge numbers are the run's or the simulation's business).
            (None, _) => Expect::Done(|p: &Path| prediction_rows(p, 300)),
            (Some(words), _) => refused(file, words),
        };
        cases.push(Case {
            name: format!("predict --model {name}"),
            args: ["predict", "--model", &s(path), "--input", &s(run), "--out", &s(&out)]
                .map(String::from)
                .to_vec(),
            inputs: vec![path.clone(), run.to_owned()],
            out,
            expect: predict_verdict,
        });
        let exportable = matches!(
            *name,
            "model_good.json" | "model_other_input.json" | "model_huge.json" | "model_dt_other.json"
        );
        for (format, ext) in [("python", "py"), ("c", "c"), ("matlab", "m")] {
            let out = dir.join(format!("export_{}_{format}.{ext}", name.replace('.', "_")));
            cases.push(Case {
                name: format!("export --format {format} {name}"),
                args: ["export", "--model", &s(path), "--format", format, "--out", &s(&out)]
                    .map(String::from)
                    .to_vec(),
                inputs: vec![path.clone()],
                out,
                expect: match verdict {
                    Some(words) if !exportable => refused(file, words),
                    _ => Expect::Done(program_written),
                },
            });
        }
    }
}

/// Options and arguments a user can get wrong.
fn option_cases(dir: &Path, run: &Path, model: &Path, cases: &mut Vec<Case>) {
    let case = |name: &str, args: &[&str], inputs: &[&Path], out: &Path, expect: Expect| Case {
        name: name.to_owned(),
        args: args.iter().map(|a| (*a).to_owned()).collect(),
        inputs: inputs.iter().map(|p| p.to_path_buf()).collect(),
        out: out.to_owned(),
        expect,
    };
    let out = dir.join("opt_out.csv");
    let (r, m, o) = (s(run), s(model), s(&out));
    let project = write(dir, "bad_project.toml", b"ident = 5\n");
    let order = write(
        dir,
        "order_project.toml",
        format!("ident = '{r}'\n[output.shaft_speed_rpm]\nstatic_order = 50\n").as_bytes(),
    );
    let unknown_key = write(dir, "key_project.toml", b"idnet = 'x.csv'\n");
    let schedule = write(
        dir,
        "schedule_project.toml",
        format!("ident = '{r}'\n[output.shaft_speed_rpm]\nspool_schedule = 'cubic'\n").as_bytes(),
    );
    let not_toml = write(dir, "not_toml.toml", b"[[[\n");
    let truth = dir.join("sim.csv");
    let sim = s(&truth);
    let p = s(&project);
    cases.extend([
        case(
            "predict --out = --input",
            &["predict", "--model", &m, "--input", &r, "--out", &r],
            &[run, model],
            run,
            refused("good.csv", &["--out", "--input"]),
        ),
        case(
            "predict --out = --model",
            &["predict", "--model", &m, "--input", &r, "--out", &m],
            &[run, model],
            model,
            refused("model_good.json", &["--out", "--model"]),
        ),
        case(
            "export --out = --model",
            &["export", "--model", &m, "--format", "python", "--out", &m],
            &[model],
            model,
            refused("model_good.json", &["--out", "--model"]),
        ),
        case(
            "predict --sample-time -1",
            &["predict", "--model", &m, "--input", &r, "--out", &o, "--sample-time", "-1"],
            &[run, model],
            &out,
            refused("", &["positive"]),
        ),
        case(
            "predict --sample-time 0",
            &["predict", "--model", &m, "--input", &r, "--out", &o, "--sample-time", "0"],
            &[run, model],
            &out,
            refused("", &["positive"]),
        ),
        case(
            "predict --window 5:2",
            &["predict", "--model", &m, "--input", &r, "--out", &o, "--window", "5:2"],
            &[run, model],
            &out,
            refused("", &["window"]),
        ),
        case(
            "predict --window 0:5000",
            &["predict", "--model", &m, "--input", &r, "--out", &o, "--window", "0:5000"],
            &[run, model],
            &out,
            refused("good.csv", &["window"]),
        ),
        case(
            "predict --window 0:100",
            &["predict", "--model", &m, "--input", &r, "--out", &o, "--window", "0:100"],
            &[run, model],
            &out,
            Expect::Done(|p: &Path| prediction_rows(p, 100)),
        ),
        case(
            "predict --map input=nope",
            &["predict", "--model", &m, "--input", &r, "--out", &o, "--map", "input=nope"],
            &[run, model],
            &out,
            refused("good.csv", &["nope", "columns present"]),
        ),
        case(
            "predict --map nonsense",
            &["predict", "--model", &m, "--input", &r, "--out", &o, "--map", "nonsense"],
            &[run, model],
            &out,
            refused("", &["ROLE=COLUMN"]),
        ),
        case(
            "predict --quality nope",
            &["predict", "--model", &m, "--input", &r, "--out", &o, "--quality", "nope"],
            &[run, model],
            &out,
            refused("good.csv", &["nope"]),
        ),
        case(
            "predict --invalid nonsense",
            &["predict", "--model", &m, "--input", &r, "--out", &o, "--invalid", "x"],
            &[run, model],
            &out,
            refused("", &["CHANNEL=VALUE"]),
        ),
        case(
            "predict --project not toml",
            &["predict", "--model", &m, "--input", &r, "--out", &o, "--project", &s(&not_toml)],
            &[run, model],
            &out,
            refused("not_toml.toml", &[]),
        ),
        case(
            "predict --strict outside range",
            &[
                "predict",
                "--model",
                &m,
                "--input",
                &s(&run.with_file_name("outside.csv")),
                "--out",
                &o,
                "--strict",
            ],
            &[model],
            &out,
            refused("outside.csv", &["outside the identified range", "--strict"]),
        ),
        case(
            "batch ident = 5",
            &["--batch", &p, "--out", &s(&dir.join("b1"))],
            &[&project],
            &dir.join("b1"),
            refused("bad_project.toml", &["ident is a run"]),
        ),
        case(
            "batch static_order = 50",
            &["--batch", &s(&order), "--out", &s(&dir.join("b2"))],
            &[&order],
            &dir.join("b2"),
            refused("order_project.toml", &["static_order = 50", "out of range"]),
        ),
        case(
            "batch spool_schedule = cubic",
            &["--batch", &s(&schedule), "--out", &s(&dir.join("b6"))],
            &[&schedule],
            &dir.join("b6"),
            refused("schedule_project.toml", &["cubic", "power_balance", "exponential"]),
        ),
        case(
            "batch unknown key",
            &["--batch", &s(&unknown_key), "--out", &s(&dir.join("b3"))],
            &[&unknown_key],
            &dir.join("b3"),
            refused("key_project.toml", &["idnet"]),
        ),
        case(
            "batch not toml",
            &["--batch", &s(&not_toml), "--out", &s(&dir.join("b4"))],
            &[&not_toml],
            &dir.join("b4"),
            refused("not_toml.toml", &[]),
        ),
        case(
            "batch missing project",
            &["--batch", &s(&dir.join("none.toml")), "--out", &s(&dir.join("b5"))],
            &[],
            &dir.join("b5"),
            refused("none.toml", &["cannot read"]),
        ),
        case(
            "batch --out is a file",
            &["--batch", "--ident", &r, "--out", &r],
            &[run],
            run,
            refused("good.csv", &["is a file"]),
        ),
        case(
            "batch --auto-effects x",
            &["--batch", "--auto-effects", "x", "--out", &s(&dir.join("b6"))],
            &[],
            &dir.join("b6"),
            refused("", &["invalid value"]),
        ),
        case(
            "batch --add-effect warp",
            &["--batch", "--add-effect", "warp_drive", "--out", &s(&dir.join("b7"))],
            &[],
            &dir.join("b7"),
            refused("", &["warp_drive"]),
        ),
        case(
            "batch --output nope",
            &["--batch", "--ident", &r, "--output", "nope", "--out", &s(&dir.join("b8"))],
            &[run],
            &dir.join("b8"),
            refused("good", &["nope"]),
        ),
        case(
            "batch one step",
            &[
                "--batch",
                "--ident",
                &s(&write(dir, "one_step.csv", &one_step())),
                "--out",
                &s(&dir.join("b9")),
            ],
            &[],
            &dir.join("b9"),
            refused("one_step", &["at least two steps"]),
        ),
        case(
            "batch constant input",
            &[
                "--batch",
                "--ident",
                &s(&write(dir, "constant.csv", &constant())),
                "--out",
                &s(&dir.join("b10")),
            ],
            &[],
            &dir.join("b10"),
            refused("constant", &["never changes"]),
        ),
        case(
            "options without --batch",
            &["--ident", &r, "--out", &s(&dir.join("b11"))],
            &[run],
            &dir.join("b11"),
            refused("", &["--batch"]),
        ),
        case(
            "simulate --truth-out = --out",
            &["simulate", "--test", "steady", "--out", &sim, "--truth-out", &sim],
            &[],
            &truth,
            refused("sim.csv", &["--truth-out", "--out"]),
        ),
        case(
            "simulate bad effect",
            &["simulate", "--test", "steady", "--effect", "warp_drive", "--out", &sim],
            &[],
            &truth,
            refused("", &["warp_drive"]),
        ),
        case(
            "simulate bad effect parameter",
            &["simulate", "--test", "steady", "--effect", "thermal_soak:gain=abc", "--out", &sim],
            &[],
            &truth,
            refused("", &["thermal_soak"]),
        ),
        case(
            "simulate bad test",
            &["simulate", "--test", "sprint", "--out", &sim],
            &[],
            &truth,
            refused("", &["sprint"]),
        ),
        case(
            "simulate into a file as folder",
            &["simulate", "--test", "steady", "--out", &s(&run.join("x.csv"))],
            &[run],
            &run.join("x.csv"),
            refused("x.csv", &[]),
        ),
        case(
            "simulate steady",
            &["simulate", "--test", "steady", "--seed", "3", "--out", &sim],
            &[],
            &truth,
            Expect::Done(run_written),
        ),
        case(
            "simulate on a family engine",
            &["simulate", "--test", "steady", "--engine", "4", "--out", &s(&dir.join("sim_engine.csv"))],
            &[],
            &dir.join("sim_engine.csv"),
            Expect::Done(run_written),
        ),
        case(
            "inspect --window auto",
            &["inspect", &r, "--window", "auto"],
            &[run],
            &dir.join("nothing"),
            Expect::Done(printed_nothing_wrong),
        ),
        case(
            "inspect --sample-time with a time column",
            &["inspect", &r, "--sample-time", "0.2"],
            &[run],
            &dir.join("nothing"),
            Expect::Done(printed_nothing_wrong),
        ),
        case(
            "inspect --map time=... --sample-time",
            &["inspect", &r, "--map", "time=time_s", "--sample-time", "0.2"],
            &[run],
            &dir.join("nothing"),
            refused("good.csv", &["time is given twice"]),
        ),
        case(
            "export bad format",
            &["export", "--model", &m, "--format", "fortran", "--out", &s(&dir.join("x.f"))],
            &[model],
            &dir.join("x.f"),
            refused("", &["fortran"]),
        ),
    ]);
}

/// A run with one step of the input: too few segments to identify from.
fn one_step() -> Vec<u8> {
    let mut text = String::from("time_s,fuel_flow_gph,shaft_speed_rpm\n");
    for k in 0..600 {
        let u = if k < 300 { 3.0 } else { 5.0 };
        let y =
            if k < 300 { 50_000.0 } else { 50_000.0 + 20_000.0 * (1.0 - (-((k - 300) as f64) / 20.0).exp()) };
        text.push_str(&format!("{},{u},{y}\n", k as f64 * 0.1));
    }
    text.into_bytes()
}

/// A run whose input never changes.
fn constant() -> Vec<u8> {
    let mut text = String::from("time_s,fuel_flow_gph,shaft_speed_rpm\n");
    for k in 0..600 {
        text.push_str(&format!("{},4.0,{}\n", k as f64 * 0.1, 60_000.0 + (k % 7) as f64));
    }
    text.into_bytes()
}

/// The bytes of every file `paths` names (`None` for a missing one or a folder).
fn snapshot(paths: &[PathBuf]) -> Vec<Option<Vec<u8>>> {
    paths.iter().map(|p| std::fs::read(p).ok()).collect()
}

/// Why `case`'s run `o` breaks the sweep's rules, if it does.
fn judge(case: &Case, o: &Output, before_out: &Option<Vec<u8>>, out_existed: bool) -> Option<String> {
    let stderr = String::from_utf8_lossy(&o.stderr);
    match (&case.expect, o.status.code()) {
        (Expect::Done(check), Some(0)) => {
            check(&case.out).err().map(|why| format!("done, but {why}: {stderr}"))
        }
        (Expect::Refused { file, words }, Some(1)) => {
            let message = stderr.lines().find(|l| l.starts_with("error:")).unwrap_or_default();
            let missing: Vec<&String> = words.iter().filter(|w| !stderr.contains(w.as_str())).collect();
            let unchanged = if out_existed {
                std::fs::read(&case.out).ok() == *before_out || case.out.is_dir()
            } else {
                !case.out.exists()
            };
            if message.is_empty() || !stderr.contains(file) || !missing.is_empty() {
                Some(format!("refused without naming {file:?} or {missing:?}: {stderr}"))
            } else if !unchanged {
                Some(format!("refused, but {} was written", case.out.display()))
            } else {
                None
            }
        }
        (_, code) => Some(format!("exit {code:?}: {stderr}")),
    }
}

#[test]
fn every_hostile_input_ends_in_a_correct_result_or_a_clear_refusal_and_changes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let cases = cases(dir.path());
    let mut failures = Vec::new();
    let (mut done, mut refusals) = (0, 0);
    for case in &cases {
        let inputs_before = snapshot(&case.inputs);
        let (out_existed, before_out) = (case.out.exists(), std::fs::read(&case.out).ok());
        let args: Vec<&str> = case.args.iter().map(String::as_str).collect();
        let o = jetid(&args);
        match judge(case, &o, &before_out, out_existed) {
            Some(why) => failures.push(format!("{}: {why}", case.name)),
            None if o.status.success() => done += 1,
            None => refusals += 1,
        }
        if snapshot(&case.inputs) != inputs_before {
            failures.push(format!("{}: an input file changed", case.name));
        }
        let leftovers: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().into_owned()))
            .filter(|n| n.contains(".tmp-") || n.contains("jetid-staging"))
            .collect();
        if !leftovers.is_empty() {
            failures.push(format!("{}: left {leftovers:?}", case.name));
        }
    }
    eprintln!("hostile sweep: {} cases, {done} done, {refusals} refused", cases.len());
    assert!(cases.len() >= 150, "the sweep has {} cases", cases.len());
    assert!(
        failures.is_empty(),
        "{} of {} cases broke the rules:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}
