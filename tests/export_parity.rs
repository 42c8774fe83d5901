//! The exported programs read run files as `jetid predict` does: one set of good and bad run files,
//! each given to `jetid predict`, the exported Python program and the exported C program. For every
//! file the three accept it or refuse it together; a refused file gets the same message (the text
//! after jetid's `error: `), an accepted one the same prediction (to 1e-6 relative).
//!
//! Without python3 (numpy, python-control) or cc a program is left out with a message, unless
//! `JETID_REQUIRE_EXPORT_TOOLS=1` (CI), where a missing tool fails the test.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::common::{have_cc, have_python, jetid_in, python3};

/// The sample time of the runs and of the models.
const DT: f64 = 0.1;
/// Samples in the run every case starts from.
const N: usize = 60;

/// Two outputs from `fuel_flow_gph`, thrust corrected for inlet conditions (so that the auxiliary
/// channels matter).
const MODEL: &str = r#"{"format_version": 1, "convention": "", "dt_secs": 0.1,
  "input": {"name": "fuel_flow_gph", "unit": "gph"},
  "outputs": [
    {"name": "shaft_speed_rpm", "unit": "rpm",
     "wiener": {"linear": {"tf": {"num_zinv": [0.0, 800.0], "den_zinv": [1.0, -0.9], "dt_secs": 0.1}, "offset": 0.0},
                "map": {"v_center": 0.0, "v_scale": 1.0, "coeffs_scaled": [30000.0, 1.0]}},
     "static_map_beta": [30000.0, 1.0], "poles": [[0.9, 0.0]], "zeros": [], "clusters": [], "effects": []},
    {"name": "thrust_n", "unit": "N",
     "wiener": {"linear": {"tf": {"num_zinv": [0.0, 2.0], "den_zinv": [1.0, -0.8], "dt_secs": 0.1}, "offset": 0.0},
                "map": {"v_center": 0.0, "v_scale": 1.0, "coeffs_scaled": [5.0, 1.0, 0.1]}},
     "static_map_beta": [5.0, 1.0, 0.1], "poles": [[0.8, 0.0]], "zeros": [], "clusters": [],
     "effects": [{"id": "ambient_correction", "params": {"output_theta_exp": 0.5, "output_delta_exp": 1.0}}]}]}"#;

/// One output from `pump_V`: a raw log's input, read with `--map input=pump_V`.
const PUMP_MODEL: &str = r#"{"format_version": 1, "convention": "", "dt_secs": 0.1,
  "input": {"name": "pump_V", "unit": "V"},
  "outputs": [
    {"name": "shaft_speed_rpm", "unit": "rpm",
     "wiener": {"linear": {"tf": {"num_zinv": [0.0, 800.0], "den_zinv": [1.0, -0.9], "dt_secs": 0.1}, "offset": 0.0},
                "map": {"v_center": 0.0, "v_scale": 1.0, "coeffs_scaled": [30000.0, 1.0]}},
     "static_map_beta": [30000.0, 1.0], "poles": [[0.9, 0.0]], "zeros": [], "clusters": [], "effects": []}]}"#;

/// A run file's cells as text, to be changed and written out.
#[derive(Clone)]
struct Cells {
    header: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Cells {
    /// The run every case starts from: canonical columns, N samples DT apart.
    fn base() -> Self {
        let header = [
            "time_s",
            "fuel_flow_gph",
            "shaft_speed_rpm",
            "thrust_n",
            "ambient_temp_c",
            "ambient_pressure_kpa",
        ];
        let rows = (0..N)
            .map(|k| {
                let x = k as f64;
                vec![
                    format!("{:.1}", x * DT),
                    format!("{:.6}", 2.0 + 1.5 * (x / 7.0).sin()),
                    format!("{}", 45000 + 100 * k),
                    format!("{:.2}", 20.0 + 0.5 * x),
                    format!("{:.3}", 15.0 + 0.01 * x),
                    "101.3".to_owned(),
                ]
            })
            .collect();
        Self { header: header.map(str::to_owned).to_vec(), rows }
    }

    fn col(&self, name: &str) -> usize {
        self.header.iter().position(|h| h == name).unwrap_or_else(|| panic!("no column {name}"))
    }

    /// The cell of `row` (0-based data row) in column `name` set to `text`.
    fn set(mut self, row: usize, name: &str, text: &str) -> Self {
        let c = self.col(name);
        self.rows[row][c] = text.to_owned();
        self
    }

    fn rename(mut self, from: &str, to: &str) -> Self {
        let c = self.col(from);
        self.header[c] = to.to_owned();
        self
    }

    fn drop_column(mut self, name: &str) -> Self {
        let c = self.col(name);
        self.header.remove(c);
        self.rows.iter_mut().for_each(|row| {
            row.remove(c);
        });
        self
    }

    /// A column `name` whose cell in row k is `cell(k)`.
    fn with_column(mut self, name: &str, cell: impl Fn(usize) -> String) -> Self {
        self.header.push(name.to_owned());
        self.rows.iter_mut().enumerate().for_each(|(k, row)| row.push(cell(k)));
        self
    }

    /// Every time stamp from `row` on moved by `secs`.
    fn shift_time(mut self, row: usize, secs: f64) -> Self {
        let c = self.col("time_s");
        for r in &mut self.rows[row..] {
            r[c] = format!("{}", r[c].parse::<f64>().unwrap() + secs);
        }
        self
    }

    fn truncate(mut self, n: usize) -> Self {
        self.rows.truncate(n);
        self
    }

    /// The lines of the file: the header, then one per row.
    fn lines(&self, sep: &str) -> Vec<String> {
        std::iter::once(&self.header).chain(&self.rows).map(|cells| cells.join(sep)).collect()
    }

    fn csv(&self) -> Vec<u8> {
        self.text(",", "\n").into_bytes()
    }

    fn text(&self, sep: &str, eol: &str) -> String {
        self.lines(sep).iter().map(|line| format!("{line}{eol}")).collect()
    }

    /// A spreadsheet's export: fields separated by `sep`, decimal commas.
    fn decimal_commas(&self, sep: &str) -> Vec<u8> {
        let mut lines = self.lines(sep);
        lines.iter_mut().skip(1).for_each(|line| *line = line.replace('.', ","));
        lines.iter().map(|line| format!("{line}\n")).collect::<String>().into_bytes()
    }
}

/// Which model a case runs.
#[derive(Clone, Copy, PartialEq)]
enum Model {
    Main,
    Pump,
}

/// One run file and the options it is read with, and what jetid does with it: accept it, or refuse
/// it with a message holding the given text.
struct Case {
    name: &'static str,
    model: Model,
    /// The file's bytes; `None`: no such file.
    file: Option<Vec<u8>>,
    args: Vec<&'static str>,
    refused: Option<&'static str>,
}

fn accepted(name: &'static str, file: Vec<u8>, args: &[&'static str]) -> Case {
    Case { name, model: Model::Main, file: Some(file), args: args.to_vec(), refused: None }
}

fn refused(name: &'static str, file: Vec<u8>, args: &[&'static str], message: &'static str) -> Case {
    Case { name, model: Model::Main, file: Some(file), args: args.to_vec(), refused: Some(message) }
}

/// `text` with a line inserted before data row `row` (0-based; the header is line 0).
fn insert_line(text: &str, row: usize, line: &str) -> Vec<u8> {
    let mut lines: Vec<&str> = text.lines().collect();
    lines.insert(row + 1, line);
    lines.iter().map(|l| format!("{l}\n")).collect::<String>().into_bytes()
}

fn good_cases() -> Vec<Case> {
    let base = Cells::base();
    let plain = base.text(",", "\n");
    let quoted = {
        let mut cells = base
            .clone()
            .with_column("note", |k| if k == 3 { "\"ramp, then \"\"hold\"\"\"".into() } else { "ok".into() });
        let c = cells.col("fuel_flow_gph");
        cells.header.iter_mut().for_each(|h| *h = format!("\"{h}\""));
        cells.rows.iter_mut().for_each(|row| row[c] = format!("\"{}\"", row[c]));
        cells.csv()
    };
    // A logger writing Latin-1 names: "T_\xb0C" (T_°C).
    let latin1 = {
        let text = base.clone().with_column("T_\u{b0}C", |_| "15.0".into()).text(",", "\n");
        [
            b"time_s,fuel_flow_gph,shaft_speed_rpm,thrust_n,ambient_temp_c,ambient_pressure_kpa,T_\xb0C"
                .as_slice(),
            &text.as_bytes()[text.find('\n').unwrap()..],
        ]
        .concat()
    };
    let repeated = {
        let mut cells = base.clone().shift_time(30, 0.03);
        let again = cells.rows[10].clone();
        cells.rows.insert(11, again);
        cells.csv()
    };
    let quality = base
        .clone()
        .with_column("crc_ok", |k| if matches!(k, 0 | 1 | 20 | 21) { "0".into() } else { "1".into() })
        .set(20, "fuel_flow_gph", "ERR")
        .csv();
    let raw_log = base
        .clone()
        .rename("time_s", "t")
        .rename("fuel_flow_gph", "pump_V")
        .rename("shaft_speed_rpm", "rpm")
        .drop_column("thrust_n")
        .csv();
    let mut bom_crlf = "\u{feff}".as_bytes().to_vec();
    bom_crlf.extend(base.text(",", "\r\n").as_bytes());
    vec![
        accepted("canonical", plain.clone().into_bytes(), &[]),
        accepted("bom_and_crlf", bom_crlf, &[]),
        accepted("semicolons_and_decimal_commas", base.decimal_commas(";"), &[]),
        accepted("tabs_and_decimal_commas", base.decimal_commas("\t"), &[]),
        accepted("quoted_cells_and_a_text_column", quoted, &[]),
        accepted(
            "comment_lines",
            [b"# logger v2, 10 Hz\n".as_slice(), &insert_line(&plain, 30, "# paused")].concat(),
            &[],
        ),
        accepted("latin1_column_name", latin1, &[]),
        accepted("blank_lines_and_padded_cells", insert_line(&plain.replace(',', " ,\t"), 12, ""), &[]),
        Case {
            name: "raw_log_mapped",
            model: Model::Pump,
            file: Some(raw_log),
            args: vec!["--map", "time=t", "--map", "input=pump_V"],
            refused: None,
        },
        accepted("sample_time", base.clone().drop_column("time_s").csv(), &["--sample-time", "0.1"]),
        accepted("window_in_samples", base.csv(), &["--window", "5:50"]),
        accepted("window_in_seconds", base.csv(), &["--window", "1.5s:4.5s"]),
        accepted("quality_column", quality, &["--quality", "crc_ok"]),
        accepted(
            "invalid_sentinels",
            base.clone().set(10, "ambient_temp_c", "-3276.8").set(11, "ambient_temp_c", "-3276.8").csv(),
            &["--invalid", "ambient_temp_c=-3276.8,3276.8"],
        ),
        accepted("resample_repeats_and_jitter", repeated, &["--resample"]),
        accepted("outlier_interpolated", base.clone().set(25, "fuel_flow_gph", "1e30").csv(), &[]),
        accepted(
            "mapped_aux_channels",
            base.clone().with_column("note", |_| "x".into()).csv(),
            &["--map", "aux=ambient_temp_c", "--map", "aux=ambient_pressure_kpa"],
        ),
        accepted("mapped_output", base.csv(), &["--map", "output=shaft_speed_rpm"]),
    ]
}

fn bad_cases() -> Vec<Case> {
    let base = Cells::base();
    let mut ragged = base.clone();
    ragged.rows[12].pop();
    let mut swapped = base.clone();
    let c = swapped.col("time_s");
    let (a, b) = (swapped.rows[20][c].clone(), swapped.rows[21][c].clone());
    (swapped.rows[20][c], swapped.rows[21][c]) = (b, a);
    let slow = base.clone().drop_column("time_s").with_column("time_s", |k| format!("{:.1}", 0.2 * k as f64));
    vec![
        refused("missing_input", base.clone().rename("fuel_flow_gph", "fuel").csv(), &[], "no input column"),
        refused("missing_time", base.clone().drop_column("time_s").csv(), &[], "no time column"),
        refused(
            "duplicate_column",
            base.clone().rename("ambient_temp_c", "thrust_n").csv(),
            &[],
            "appears twice",
        ),
        refused("map_to_a_missing_column", base.csv(), &["--map", "input=pump_V"], "no column \"pump_V\""),
        refused("nan_cell", base.clone().set(30, "fuel_flow_gph", "NaN").csv(), &[], "missing value"),
        refused("empty_time_cell", base.clone().set(7, "time_s", "").csv(), &[], "missing value"),
        refused("infinite_cell", base.clone().set(9, "fuel_flow_gph", "-inf").csv(), &[], "missing value"),
        refused(
            "non_numeric_cell",
            base.clone().set(15, "fuel_flow_gph", "1.2.3").csv(),
            &[],
            "is not a number",
        ),
        refused(
            "non_numeric_cell_after_a_comment",
            insert_line(&base.clone().set(31, "time_s", "3.1 s").text(",", "\n"), 31, "# restart"),
            &[],
            "is not a number",
        ),
        refused("ragged_row", ragged.csv(), &[], "fields, the header has"),
        refused("time_not_increasing", swapped.csv(), &[], "does not increase"),
        refused(
            "non_uniform_time_step",
            base.clone().shift_time(30, 0.03).csv(),
            &[],
            "differs from the sample time",
        ),
        refused("too_few_samples", base.clone().truncate(6).csv(), &[], "at least 10"),
        refused("empty_file", Vec::new(), &[], "empty file"),
        refused("gzip_file", vec![0x1f, 0x8b, 8, 0, 0, 0, 0, 0, 0, 3], &[], "gzip"),
        refused("binary_file", b"time_s,fuel\0\x01\x02\n".to_vec(), &[], "NUL bytes"),
        refused(
            "quality_value_not_0_or_1",
            base.clone().with_column("crc_ok", |k| if k == 5 { "2".into() } else { "1".into() }).csv(),
            &["--quality", "crc_ok"],
            "is not 0 or 1",
        ),
        refused(
            "too_many_bad_samples",
            base.clone().with_column("crc_ok", |k| if k % 3 == 0 { "1".into() } else { "0".into() }).csv(),
            &["--quality", "crc_ok"],
            "flagged bad",
        ),
        refused(
            "invalid_values_for_an_unknown_channel",
            base.csv(),
            &["--invalid", "T_inlet=-1"],
            "does not have",
        ),
        refused("window_out_of_range", base.csv(), &["--window", "10:500"], "out of range"),
        refused("sampled_slower_than_the_model", slow.csv(), &[], "is sampled every"),
        refused(
            "input_from_another_signal",
            base.csv(),
            &["--map", "input=thrust_n"],
            "identified from the input",
        ),
        refused(
            "missing_inlet_channel",
            base.clone().drop_column("ambient_pressure_kpa").csv(),
            &[],
            "needs the channel",
        ),
        refused(
            "mapped_output_missing_value",
            base.clone().set(40, "thrust_n", "").csv(),
            &["--map", "output=thrust_n"],
            "missing value",
        ),
        Case {
            name: "missing_file",
            model: Model::Main,
            file: None,
            args: Vec::new(),
            refused: Some("cannot read the file"),
        },
    ]
}

/// What one program did with a case: its message when it refused the file, else its prediction.
#[derive(Debug, PartialEq)]
enum Outcome {
    Refused(String),
    Wrote(PathBuf),
}

/// The outcome of a run, from its exit status and stderr (the message after `error: `).
fn outcome(o: &Output, what: &str, out: PathBuf) -> Outcome {
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!stderr.contains("Traceback") && !stderr.contains("panicked"), "{what}: {stderr}");
    if o.status.success() {
        return Outcome::Wrote(out);
    }
    assert_eq!(o.status.code(), Some(1), "{what}: {stderr}");
    let Some(at) = stderr.find("error: ") else { panic!("{what}: no error message: {stderr}") };
    Outcome::Refused(stderr[at + "error: ".len()..].trim_end().to_owned())
}

/// A prediction's header and rows.
fn read_prediction(path: &Path) -> (String, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header = lines.next().unwrap().to_owned();
    let rows = lines.map(|line| line.split(',').map(|cell| cell.parse().unwrap()).collect()).collect();
    (header, rows)
}

/// Both predictions hold the same columns and samples, each sample equal to 1e-6 relative.
fn same_prediction(expected: &Path, actual: &Path, what: &str) {
    let (h_e, r_e) = read_prediction(expected);
    let (h_a, r_a) = read_prediction(actual);
    assert_eq!(h_e, h_a, "{what}: columns");
    assert_eq!(r_e.len(), r_a.len(), "{what}: samples");
    for (k, (e, a)) in r_e.iter().zip(&r_a).enumerate() {
        for (x, y) in e.iter().zip(a) {
            assert!((x - y).abs() <= 1e-6 * x.abs() + 1e-9, "{what}: row {k}: {y}, jetid predict says {x}");
        }
    }
}

/// The exported programs of a model: the Python file, and the C program built from its source.
struct Programs {
    python: Option<PathBuf>,
    c: Option<PathBuf>,
}

fn export(dir: &Path, model: &str, stem: &str, python: bool, c: bool) -> Programs {
    let run = |args: &[&str], what: &str| {
        let o = jetid_in(dir, args);
        assert!(o.status.success(), "{what}: {}", String::from_utf8_lossy(&o.stderr));
    };
    let python = python.then(|| {
        let file = format!("{stem}.py");
        run(&["export", "--model", model, "--format", "python", "--out", &file], "export python");
        dir.join(file)
    });
    let c = c.then(|| {
        let source = format!("{stem}.c");
        run(&["export", "--model", model, "--format", "c", "--out", &source], "export c");
        let o = Command::new("cc")
            .current_dir(dir)
            .args(["-O2", "-std=c99", "-Wall", "-Werror", &source, "-o", stem, "-lm"])
            .output()
            .unwrap();
        assert!(o.status.success(), "cc: {}", String::from_utf8_lossy(&o.stderr));
        dir.join(stem)
    });
    Programs { python, c }
}

#[test]
fn the_programs_accept_and_refuse_what_jetid_predict_does() {
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();
    std::fs::write(dir.join("model.json"), MODEL).unwrap();
    std::fs::write(dir.join("pump.json"), PUMP_MODEL).unwrap();
    let (python, c) = (have_python(), have_cc());
    let programs =
        [export(dir, "model.json", "model", python, c), export(dir, "pump.json", "pump", python, c)];

    let cases: Vec<Case> = good_cases().into_iter().chain(bad_cases()).collect();
    let (mut n_accepted, mut n_refused) = (0, 0);
    for (i, case) in cases.iter().enumerate() {
        let file = format!("{i:02}_{}.csv", case.name);
        if let Some(bytes) = &case.file {
            std::fs::write(dir.join(&file), bytes).unwrap();
        }
        let (model, programs) = match case.model {
            Model::Main => ("model.json", &programs[0]),
            Model::Pump => ("pump.json", &programs[1]),
        };
        let out = format!("{i:02}_jetid.csv");
        let mut args = vec!["predict", "--model", model, "--input", &file, "--out", &out];
        args.extend(&case.args);
        let expected =
            outcome(&jetid_in(dir, &args), &format!("{}: jetid predict", case.name), dir.join(&out));
        match (&expected, case.refused) {
            (Outcome::Wrote(_), None) => n_accepted += 1,
            (Outcome::Refused(message), Some(part)) if message.contains(part) => n_refused += 1,
            (got, want) => {
                panic!("{}: jetid predict: {got:?}, expected {}", case.name, want.unwrap_or("a prediction"))
            }
        }
        let runs = [("python", programs.python.as_ref()), ("c", programs.c.as_ref())];
        for (language, program) in runs.into_iter().filter_map(|(l, p)| p.map(|p| (l, p))) {
            let out = format!("{i:02}_{language}.csv");
            let mut command = match language {
                "python" => {
                    let mut python = python3();
                    python.arg(program);
                    python
                }
                _ => Command::new(program),
            };
            let o = command.current_dir(dir).arg(&file).arg(&out).args(&case.args).output().unwrap();
            let what = format!("{}: the {language} program", case.name);
            match (&expected, outcome(&o, &what, dir.join(&out))) {
                (Outcome::Wrote(want), Outcome::Wrote(got)) => same_prediction(want, &got, &what),
                (Outcome::Refused(want), Outcome::Refused(got)) => assert_eq!(&got, want, "{what}"),
                (want, got) => panic!("{what}: {got:?}, jetid predict: {want:?}"),
            }
        }
    }
    eprintln!(
        "{} cases: {n_accepted} accepted, {n_refused} refused, alike in jetid predict and the programs",
        cases.len()
    );
    assert!(n_accepted >= 15 && n_refused >= 20, "{n_accepted} accepted, {n_refused} refused");
}
