//! Run files: reading with column mapping, errors that name file/row/column, atomic writing.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common::jetid;
use std::path::PathBuf;

use jetid::core::run::{Channel, Run};
use jetid::io::csv_run::{
    ColumnMap, LoadOptions, RunFileError, Window, load_run, load_run_with_notes, parse_run,
    parse_run_with_notes, run_to_csv_string, write_run,
};

#[path = "run_files/errors.rs"]
mod errors;
#[path = "run_files/props.rs"]
mod props;

const NAME: &str = "bench.csv";

/// A clean canonical run of `n` samples at 10 Hz.
fn canonical(n: usize) -> String {
    let mut text = String::from("time_s,fuel_flow_gph,shaft_speed_rpm,thrust_n,egt_c\n");
    for k in 0..n {
        let t = k as f64 * 0.1;
        text.push_str(&format!(
            "{t},{},{},{},{}\n",
            1.0 + 0.01 * k as f64,
            50000 + k,
            100.0 + k as f64,
            500.0
        ));
    }
    text
}

/// `canonical(n)` with the cell of data row `row` (1-based) and column `col` replaced.
fn with_cell(n: usize, row: usize, col: usize, cell: &str) -> String {
    let mut lines: Vec<String> = canonical(n).lines().map(str::to_owned).collect();
    let mut cells: Vec<String> = lines[row].split(',').map(str::to_owned).collect();
    cells[col] = cell.to_owned();
    lines[row] = cells.join(",");
    lines.join("\n") + "\n"
}

fn parse(text: &str, opts: &LoadOptions) -> Result<Run, RunFileError> {
    parse_run(NAME, text.as_bytes(), opts)
}

fn opts_from(maps: &[&str]) -> LoadOptions {
    LoadOptions { map: ColumnMap::from_specs(maps).unwrap(), ..LoadOptions::default() }
}

fn assert_mentions(err: &RunFileError, parts: &[&str]) {
    let message = err.to_string();
    assert!(message.contains(NAME) || parts.is_empty(), "no file name in: {message}");
    for part in parts {
        assert!(message.contains(part), "{part:?} not in: {message}");
    }
}

// ---------------------------------------------------------------- reading good files

#[test]
fn canonical_file_loads_with_roles_units_and_dt() {
    let run = parse(&canonical(50), &LoadOptions::default()).unwrap();
    assert_eq!(run.name, "bench");
    assert_eq!(run.len(), 50);
    assert!((run.dt_secs - 0.1).abs() < 1e-12);
    assert_eq!(run.input.name, "fuel_flow_gph");
    assert_eq!(run.input.unit, "gal/h");
    let outputs: Vec<&str> = run.outputs.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(outputs, ["shaft_speed_rpm", "thrust_n"]);
    assert_eq!(run.aux.len(), 1);
    assert_eq!(run.aux[0].name, "egt_c");
    assert_eq!(run.aux[0].unit, "°C");
}

#[test]
fn one_output_is_enough_and_other_numeric_columns_are_aux() {
    let mut text = String::from("time_s,thrust_n,fuel_flow_gph,anything,ambient_pressure_kpa\n");
    for k in 0..20 {
        text.push_str(&format!("{},{},{},{},101.3\n", k as f64 * 0.01, k, 2 * k, 3 * k));
    }
    let run = parse(&text, &LoadOptions::default()).unwrap();
    assert_eq!(run.outputs.len(), 1);
    assert_eq!(run.outputs[0].name, "thrust_n");
    let aux: Vec<&str> = run.aux.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(aux, ["anything", "ambient_pressure_kpa"]);
}

#[test]
fn unmapped_text_columns_are_left_out_and_noted() {
    let mut text = String::from("time_s,fuel_flow_gph,shaft_speed_rpm,comment,egt_c\n");
    for k in 0..20 {
        text.push_str(&format!("{},{},{},note {k},600\n", k as f64 * 0.01, k, 2 * k));
    }
    let (run, notes) = parse_run_with_notes(NAME, text.as_bytes(), &LoadOptions::default()).unwrap();
    assert!(run.channel("comment").is_none());
    assert!(run.aux("egt_c").is_some());
    assert_eq!(notes.dropped_columns.len(), 1);
    assert_eq!(notes.dropped_columns[0].name, "comment");
    assert!(notes.dropped_columns[0].reason.contains("line 2"), "{:?}", notes.dropped_columns);
}

#[test]
fn whitespace_quotes_bom_crlf_and_blank_lines_are_accepted() {
    let mut text = String::from("\u{feff} time_s , fuel_flow_gph,\"shaft_speed_rpm\"\r\n");
    for k in 0..12 {
        text.push_str(&format!(" {} ,\"{}\",{}\r\n", k as f64 * 0.5, k, 3 * k));
        if k == 5 {
            text.push_str("\r\n");
        }
    }
    let run = parse(&text, &LoadOptions::default()).unwrap();
    assert_eq!(run.len(), 12);
    assert!((run.dt_secs - 0.5).abs() < 1e-12);
    assert!((run.input.values[11] - 11.0).abs() < 1e-12);
}

#[test]
fn sample_time_replaces_a_missing_time_column() {
    let mut text = String::from("fuel_flow_gph,shaft_speed_rpm\n");
    for k in 0..15 {
        text.push_str(&format!("{k},{k}\n"));
    }
    let opts = LoadOptions { sample_time_secs: Some(0.25), ..LoadOptions::default() };
    let run = parse(&text, &opts).unwrap();
    assert!((run.dt_secs - 0.25).abs() < 1e-12);
    assert!((run.t_secs[14] - 3.5).abs() < 1e-12);
}

#[test]
fn sample_time_overrides_a_time_s_column_which_is_then_not_kept() {
    let opts = LoadOptions { sample_time_secs: Some(0.5), ..LoadOptions::default() };
    let (run, notes) = parse_run_with_notes(NAME, canonical(20).as_bytes(), &opts).unwrap();
    assert!((run.dt_secs - 0.5).abs() < 1e-12);
    assert!(run.channel("time_s").is_none());
    assert_eq!(notes.time_column, None);
    assert!(notes.dropped_columns.iter().any(|d| d.name == "time_s"));
}

#[test]
fn jetcat_like_file_loads_through_a_map_with_window_and_quality() {
    let mut text = String::from("sample,t_est_s,rpm,egt_C,pump_V,ecu_state,crc_ok\n");
    for k in 0..200 {
        // Time printed with three decimals at 9.4 Hz, as in the ECU logs: steps of 0.106 and 0.107 s.
        let t = format!("{:.3}", k as f64 / 9.4);
        let (rpm, ok) =
            if k % 17 == 5 { ("garbage".to_owned(), 0) } else { ((30000 + 100 * k).to_string(), 1) };
        text.push_str(&format!("{k},{t},{rpm},{},{},11,{ok}\n", 400 + k, 1.0 + 0.01 * k as f64));
    }
    let mut opts = opts_from(&["input=pump_V", "output=rpm", "time=t_est_s", "aux=egt_C"]);
    opts.window = Some("20:180".parse().unwrap());
    opts.quality = Some("crc_ok".to_owned());
    let (run, notes) = parse_run_with_notes(NAME, text.as_bytes(), &opts).unwrap();
    assert_eq!(run.len(), 160);
    assert_eq!(notes.kept_rows, 20..180);
    assert!(notes.repaired_samples > 5);
    assert_eq!(run.input.name, "pump_V");
    assert_eq!(run.input.unit, "V");
    assert_eq!(run.outputs.len(), 1);
    assert_eq!(run.outputs[0].unit, "", "units come from name suffixes only");
    let aux: Vec<&str> = run.aux.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(aux, ["egt_C"], "only the mapped aux column is kept");
    assert!((run.dt_secs - 0.106).abs() < 1e-9);
    // Row 22 (k = 22, 22 % 17 == 5) was corrupt: rpm is interpolated on the line 30000 + 100 k.
    let i = 22 - 20;
    assert!((run.outputs[0].values[i] - 32200.0).abs() < 1e-6, "{}", run.outputs[0].values[i]);
}

#[test]
fn window_in_samples_and_in_seconds() {
    let text = canonical(100);
    let opts = LoadOptions { window: Some("10:30".parse().unwrap()), ..LoadOptions::default() };
    let run = parse(&text, &opts).unwrap();
    assert_eq!(run.len(), 20);
    assert!((run.t_secs[0] - 1.0).abs() < 1e-12);

    let opts = LoadOptions { window: Some("2.5s:5s".parse().unwrap()), ..LoadOptions::default() };
    let run = parse(&text, &opts).unwrap();
    assert_eq!(run.len(), 25);
    assert!((run.t_secs[0] - 2.5).abs() < 1e-9);

    let opts = LoadOptions { window: Some("90:".parse().unwrap()), ..LoadOptions::default() };
    assert_eq!(parse(&text, &opts).unwrap().len(), 10);
}

#[test]
fn window_strings_parse_and_print_back() {
    for spec in ["935:2603", "12.5s:80s", ":100", "3s:", "auto"] {
        let window: Window = spec.parse().unwrap();
        assert_eq!(window.to_string(), spec);
    }
    assert_eq!("935:2603".parse::<Window>().unwrap(), Window::Samples { start: Some(935), end: Some(2603) });
}

#[test]
fn quality_repairs_bad_samples_and_trims_bad_ends() {
    let mut text = String::from("time_s,fuel_flow_gph,shaft_speed_rpm,ok\n");
    for k in 0..30 {
        let ok = u8::from(!(k < 2 || k == 10 || k == 11 || k == 29));
        let rpm = if ok == 0 { "#$%".to_owned() } else { (10 * k).to_string() };
        let time = if k == 11 { "oops".to_owned() } else { format!("{}", k as f64 * 0.1) };
        text.push_str(&format!("{time},{k},{rpm},{ok}\n"));
    }
    let opts = LoadOptions { quality: Some("ok".to_owned()), ..LoadOptions::default() };
    let (run, notes) = parse_run_with_notes(NAME, text.as_bytes(), &opts).unwrap();
    assert_eq!((notes.trimmed_bad_start, notes.trimmed_bad_end, notes.repaired_samples), (2, 1, 2));
    assert_eq!(run.len(), 27);
    assert!(run.channel("ok").is_none(), "the quality column is not a channel");
    let rpm = &run.outputs[0].values;
    // Sample 10 is index 8 after trimming two samples.
    assert!((rpm[8] - 100.0).abs() < 1e-9 && (rpm[9] - 110.0).abs() < 1e-9, "{rpm:?}");
    assert!((run.t_secs[9] - 1.1).abs() < 1e-9);
}

#[test]
fn resample_makes_a_jittered_time_axis_uniform() {
    let mut text = String::from("time_s,fuel_flow_gph,shaft_speed_rpm\n");
    for k in 0..40 {
        let t = k as f64 * 0.1 + if k % 3 == 1 { 0.02 } else { 0.0 };
        text.push_str(&format!("{t},{},{}\n", 2.0 * t + 1.0, 5.0 * t));
    }
    let err = parse(&text, &LoadOptions::default()).unwrap_err();
    assert!(matches!(err, RunFileError::NonUniformTime { row: 2, .. }), "{err}");
    let opts = LoadOptions { resample: true, ..LoadOptions::default() };
    let (run, notes) = parse_run_with_notes(NAME, text.as_bytes(), &opts).unwrap();
    assert!(notes.resampled);
    assert!((run.dt_secs - 0.1).abs() < 1e-9);
    for (k, (&t, &u)) in run.t_secs.iter().zip(&run.input.values).enumerate() {
        assert!((t - k as f64 * 0.1).abs() < 1e-9);
        assert!((u - (2.0 * t + 1.0)).abs() < 1e-9, "a line stays a line");
    }
}

#[test]
fn repeated_time_stamps_are_refused_with_advice_or_merged_with_resample() {
    // A logger that writes some ticks twice (the two-shaft turbine's T07 logs): the same time stamp
    // on two rows, the second with a fresh reading.
    let mut text = String::from("time_s,fuel_flow_gph,shaft_speed_rpm\n");
    for k in 0..40 {
        let t = k as f64 * 0.1;
        text.push_str(&format!("{t},{},{}\n", 2.0 * t + 1.0, 5.0 * t));
        if k % 10 == 5 {
            text.push_str(&format!("{t},{},{}\n", 2.0 * t + 1.2, 5.0 * t + 1.0));
        }
    }
    let err = parse(&text, &LoadOptions::default()).unwrap_err();
    assert!(matches!(err, RunFileError::NonIncreasingTime { .. }), "{err}");
    assert_mentions(&err, &["does not increase", "--resample"]);
    let opts = LoadOptions { resample: true, ..LoadOptions::default() };
    let (run, notes) = parse_run_with_notes(NAME, text.as_bytes(), &opts).unwrap();
    assert_eq!(notes.merged_repeats, 4);
    assert_eq!(run.len(), 40);
    assert!((run.dt_secs - 0.1).abs() < 1e-9);
    // A repeated tick holds the mean of its rows.
    assert!((run.input.values[5] - (2.0 * 0.5 + 1.1)).abs() < 1e-9, "{}", run.input.values[5]);
    // A time that goes back is not a repeat: still refused with resample.
    let back = text.replacen("0.30000000000000004,", "0.1,", 1);
    let back = if back == text { text.replacen("\n0.3,", "\n0.1,", 1) } else { back };
    assert!(matches!(parse(&back, &opts), Err(RunFileError::NonIncreasingTime { .. })));
}

#[test]
fn invalid_sentinels_become_gaps_and_are_counted_or_refused_with_reason() {
    // A logger that writes ±3276.8 when a channel has no reading (the two-shaft turbine's T_inlet_C).
    let mut text = String::from("time_s,fuel_flow_gph,shaft_speed_rpm,t_inlet_c\n");
    for k in 0..40 {
        let t = k as f64 * 0.1;
        let inlet = match k {
            7 => "3276.8".to_owned(),
            8 => "-3276.8".to_owned(),
            _ => format!("{}", 20.0 + 0.1 * k as f64),
        };
        text.push_str(&format!("{t},{},{},{inlet}\n", 2.0 * t + 1.0, 5.0 * t));
    }
    let opts = LoadOptions::from_cli(&["aux=t_inlet_c"], None, None, None, false)
        .unwrap()
        .with_invalid_specs(&["t_inlet_c=-3276.8,3276.8"])
        .unwrap();
    let (run, notes) = parse_run_with_notes(NAME, text.as_bytes(), &opts).unwrap();
    assert_eq!(notes.invalid_samples, vec![("t_inlet_c".to_owned(), 2)]);
    let inlet = &run.channel("t_inlet_c").unwrap().values;
    for k in [7, 8] {
        let want = 20.0 + 0.1 * k as f64;
        assert!((inlet[k] - want).abs() < 1e-9, "sample {k} interpolated: {}", inlet[k]);
    }

    // A sentinel for a channel the run lacks is named with the channels that are there.
    let typo = LoadOptions::default().with_invalid_specs(&["t_inlet=3276.8"]).unwrap();
    let err = parse(&text, &typo).unwrap_err();
    assert!(matches!(err, RunFileError::UnknownInvalidChannel { .. }), "{err}");
    assert_mentions(&err, &["t_inlet", "t_inlet_c"]);

    // A channel with nothing but sentinels has no reading: refused, not silently flat.
    let dead: String = text
        .lines()
        .enumerate()
        .map(|(k, line)| {
            if k == 0 {
                format!("{line}\n")
            } else {
                format!("{},3276.8\n", line.rsplit_once(',').unwrap().0)
            }
        })
        .collect();
    let err = parse(&dead, &opts).unwrap_err();
    assert!(matches!(err, RunFileError::AllInvalid { .. }), "{err}");

    // A malformed spec is refused before any file is read.
    for spec in ["t_inlet_c", "t_inlet_c=", "t_inlet_c=abc", "=1"] {
        assert!(LoadOptions::default().with_invalid_specs(&[spec]).is_err(), "{spec}");
    }
}

#[test]
fn units_given_per_channel_replace_the_guess_from_the_name_and_a_typo_is_named() {
    let text = "time_s,fuel_flow_Lpm,PR,power_kW\n".to_owned()
        + &(0..40).map(|k| format!("{},{},{},{}\n", k as f64 * 0.1, 0.3, 1.5, 10.0)).collect::<String>();
    let mut opts = LoadOptions::from_cli(
        &["input=fuel_flow_Lpm", "output=PR", "output=power_kW"],
        None,
        None,
        None,
        false,
    )
    .unwrap();
    let guessed = parse(&text, &opts).unwrap();
    assert_eq!(guessed.input.unit, "L/min", "the suffix _Lpm names litres per minute");
    assert_eq!(guessed.output("power_kW").unwrap().unit, "kW");
    assert_eq!(guessed.output("PR").unwrap().unit, "", "a bare name has no unit to guess");

    opts.units.insert("PR".to_owned(), "-".to_owned());
    let given = parse(&text, &opts).unwrap();
    assert_eq!(given.output("PR").unwrap().unit, "-");
    assert_eq!(given.output("power_kW").unwrap().unit, "kW", "channels without a given unit keep the guess");

    opts.units.insert("P_R".to_owned(), "-".to_owned());
    let err = parse(&text, &opts).unwrap_err();
    assert!(matches!(err, RunFileError::UnknownUnitChannel { .. }), "{err}");
    assert_mentions(&err, &["P_R", "PR", "power_kW"]);
}

#[test]
fn rounded_time_stamps_within_one_percent_are_uniform() {
    let run = parse(&with_cell(30, 10, 0, "0.9005"), &LoadOptions::default()).unwrap();
    assert!((run.dt_secs - 0.1).abs() < 1e-9);
}

#[test]
fn sixteen_thousand_rows_load() {
    let run = parse(&canonical(16_000), &LoadOptions::default()).unwrap();
    assert_eq!(run.len(), 16_000);
}

// ---------------------------------------------------------------- writing

fn sample_run(name: &str) -> Run {
    let n = 50;
    let t_secs: Vec<f64> = (0..n).map(|k| k as f64 * 0.02).collect();
    let noisy = |k: usize, scale: f64| scale * (1.0 + 0.001 * ((k * 7919 % 101) as f64 / 101.0 - 0.5)) / 3.0;
    Run {
        name: name.to_owned(),
        dt_secs: 0.02,
        t_secs,
        input: Channel::new("fuel_flow_gph", (0..n).map(|k| noisy(k, 1.7)).collect()),
        outputs: vec![
            Channel::new("shaft_speed_rpm", (0..n).map(|k| noisy(k, 1.2e5)).collect()),
            Channel::new("thrust_n", (0..n).map(|k| noisy(k, 1e-9)).collect()),
        ],
        aux: vec![Channel::new("egt_c", (0..n).map(|k| noisy(k, 650.0) - 1e17).collect())],
    }
}

#[test]
fn write_then_read_round_trips_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nested/dir/rt.csv");
    let run = sample_run("rt");
    write_run(&path, &run).unwrap();
    let back = load_run(&path, &LoadOptions::default()).unwrap();
    assert_eq!(back, run);
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.starts_with("time_s,fuel_flow_gph,shaft_speed_rpm,thrust_n,egt_c\n"));
    assert_eq!(text, run_to_csv_string(&run).unwrap());
    let leftovers: Vec<PathBuf> =
        std::fs::read_dir(path.parent().unwrap()).unwrap().map(|e| e.unwrap().path()).collect();
    assert_eq!(leftovers, [path], "no temporary file is left behind");
}

#[test]
fn writing_replaces_an_existing_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.csv");
    std::fs::write(&path, "old").unwrap();
    write_run(&path, &sample_run("run")).unwrap();
    assert_eq!(load_run(&path, &LoadOptions::default()).unwrap(), sample_run("run"));
}

#[test]
fn unwritable_runs_are_refused_and_leave_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.csv");
    let mut run = sample_run("bad");
    run.outputs[0].values[3] = f64::NAN;
    let err = write_run(&path, &run).unwrap_err();
    assert!(matches!(&err, RunFileError::NonFiniteValue { sample: 3, .. }), "{err}");
    assert!(err.to_string().contains("shaft_speed_rpm"));
    let mut run = sample_run("bad");
    run.aux[0].values.pop();
    assert!(matches!(
        write_run(&path, &run),
        Err(RunFileError::ChannelLength { found: 49, expected: 50, .. })
    ));
    let mut run = sample_run("bad");
    run.aux[0].name = "thrust_n".into();
    assert!(matches!(write_run(&path, &run), Err(RunFileError::DuplicateChannel { .. })));
    assert!(!path.exists());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn write_error_names_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let blocker = dir.path().join("file");
    std::fs::write(&blocker, "x").unwrap();
    let path = blocker.join("run.csv");
    let err = write_run(&path, &sample_run("run")).unwrap_err();
    assert!(matches!(err, RunFileError::Write { .. }), "{err}");
    assert!(err.to_string().contains("run.csv"));
}

// ---------------------------------------------------------------- the real engine files

#[test]
#[cfg_attr(not(jetid_realdata), ignore = "needs ../shared/realdata")]
fn real_jetcat_run_a_loads_with_map_window_and_quality() {
    let dir = crate::common::realdata("jetcat_p300pro_ecu");
    let path = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(Result::ok)
        .map(|e| e.path())
        .find(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("runA") && n.ends_with(".csv"))
        })
        .unwrap_or_else(|| panic!("no JetCat runA file under {}", dir.display()));
    let opts = LoadOptions::from_cli(
        &["input=pump_V", "output=rpm", "time=t_est_s", "aux=egt_C"],
        None,
        Some("935:2603"),
        Some("crc_ok"),
        false,
    )
    .unwrap();
    let (run, notes) = load_run_with_notes(&path, &opts).unwrap();
    assert_eq!(run.len(), 2603 - 935 - notes.trimmed_bad_start - notes.trimmed_bad_end);
    assert!((run.dt_secs - 0.106).abs() < 0.002, "dt {}", run.dt_secs);
    let rpm = &run.outputs[0].values;
    let (lo, hi) = rpm.iter().fold((f64::MAX, f64::MIN), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    assert!(lo > 25_000.0 && hi < 110_000.0 && hi > 90_000.0, "rpm {lo}..{hi}");
    assert_eq!(run.aux.len(), 1);
}

// ---------------------------------------------------------------- the binary

#[test]
fn inspect_prints_a_good_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("good.csv");
    std::fs::write(&path, canonical(30)).unwrap();
    let out = jetid(&["inspect", path.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", String::from_utf8_lossy(&out.stderr));
    for part in
        ["samples   30", "dt        0.100000 s", "duration  2.900 s", "input", "shaft_speed_rpm", "gal/h"]
    {
        assert!(stdout.contains(part), "{part:?} not in:\n{stdout}");
    }
}

#[test]
fn inspect_fails_with_status_1_naming_row_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.csv");
    std::fs::write(&path, with_cell(20, 5, 2, "oops")).unwrap();
    let out = jetid(&["inspect", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    for part in ["error:", "bad.csv", "line 6", "column \"shaft_speed_rpm\"", "oops"] {
        assert!(stderr.contains(part), "{part:?} not in:\n{stderr}");
    }
}

#[test]
fn inspect_with_a_bad_map_fails_with_status_1() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("good.csv");
    std::fs::write(&path, canonical(30)).unwrap();
    let out = jetid(&["inspect", path.to_str().unwrap(), "--map", "input=pump_V"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("no column \"pump_V\"") && stderr.contains("fuel_flow_gph"), "{stderr}");
    let out = jetid(&["inspect", path.to_str().unwrap(), "--map", "speed:rpm", "--window", "1:2"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("speed:rpm"));
}

/// A spreadsheet's export with `;` between fields and decimal commas reads as the same run, and
/// the notes say how it was read.
#[test]
fn semicolon_separated_files_with_decimal_commas_read_as_the_same_run() {
    let text = canonical(40);
    let european: String = text.replace(',', ";").replace('.', ",");
    let (plain, _) = parse_run_with_notes(NAME, text.as_bytes(), &LoadOptions::default()).unwrap();
    let (read, notes) = parse_run_with_notes(NAME, european.as_bytes(), &LoadOptions::default()).unwrap();
    assert_eq!(read, plain);
    assert_eq!(notes.separator, Some(';'));
    assert!(notes.reading_notes().iter().any(|n| n.contains("';'")), "{:?}", notes.reading_notes());
    let tabs = text.replace(',', "\t");
    let (read, notes) = parse_run_with_notes(NAME, tabs.as_bytes(), &LoadOptions::default()).unwrap();
    assert_eq!((read, notes.separator), (plain, Some('\t')));
}

/// A column name in Latin-1 (a Windows logger's "témp") is read as such and named in the notes,
/// not turned into a replacement character.
#[test]
fn a_header_that_is_not_utf8_is_read_as_latin1_and_named() {
    let mut bytes = b"time_s,fuel_flow_gph,shaft_speed_rpm,t\xe9mp\n".to_vec();
    for k in 0..40 {
        bytes.extend(
            format!("{},{},{},{}\n", k as f64 * 0.1, 1.0 + 0.01 * k as f64, 50000 + k, 20).as_bytes(),
        );
    }
    let (run, notes) = parse_run_with_notes(NAME, &bytes, &LoadOptions::default()).unwrap();
    assert!(run.aux("témp").is_some(), "{:?}", run.aux.iter().map(|c| &c.name).collect::<Vec<_>>());
    assert_eq!(notes.latin1_names, vec![("t\\xe9mp".to_owned(), "témp".to_owned())]);
    assert!(notes.reading_notes().iter().any(|n| n.contains("t\\xe9mp") && n.contains("Latin-1")));
}

/// One corrupt cell (1e308) is reported at its data row and interpolated; a two-level channel's
/// single real event (a flag dropping to 0 once) is not taken for one.
#[test]
fn a_corrupt_cell_is_an_outlier_at_its_row_and_a_rare_flag_is_not() {
    let mut text = String::from("time_s,fuel_flow_gph,shaft_speed_rpm,flag\n");
    for k in 0..60 {
        let speed = if k == 25 { "1e308".to_owned() } else { format!("{}", 50000 + 10 * k) };
        text.push_str(&format!(
            "{},{},{speed},{}\n",
            k as f64 * 0.1,
            2.0 + 0.01 * k as f64,
            if k == 40 { 0 } else { 1 }
        ));
    }
    let (run, notes) = parse_run_with_notes(NAME, text.as_bytes(), &LoadOptions::default()).unwrap();
    assert_eq!(notes.outliers, vec![("shaft_speed_rpm".to_owned(), 25, 1e308)]);
    let speed = &run.output("shaft_speed_rpm").unwrap().values;
    assert!((speed[25] - 50250.0).abs() < 1e-6, "interpolated: {}", speed[25]);
    assert!(run.aux("flag").unwrap().values[40].abs() < 1e-12, "the flag's real event stays");
    assert!(notes.reading_notes().iter().any(|n| n.contains("data row 25") && n.contains("shaft_speed_rpm")));
}

/// Columns held in memory (the Python package's data frames) read as the run file they would be:
/// every number back bit for bit; a NaN is an empty cell, refused with its row and column as a
/// file's empty cell is (a quality column marks rows to repair); columns of different lengths are
/// refused with the column named.
#[test]
fn columns_in_memory_read_as_their_file() {
    let t: Vec<f64> = (0..200).map(|k| k as f64 * 0.1).collect();
    let u: Vec<f64> = (0..200).map(|k| 1.0 + (k as f64 * 0.37).sin() / 3.0).collect();
    let mut y: Vec<f64> = (0..200).map(|k| 50_000.0 + 1e-7 * k as f64 + 1.0 / 3.0).collect();
    let columns =
        [("time_s", t.as_slice()), ("fuel_flow_gph", u.as_slice()), ("shaft_speed_rpm", y.as_slice())];
    let text = jetid::io::csv_run::table_to_csv(NAME, &columns).unwrap();
    let run = parse_run(NAME, text.as_bytes(), &LoadOptions::default()).unwrap();
    assert_eq!(run.t_secs, t);
    assert_eq!(run.input.values, u);
    assert_eq!(run.output("shaft_speed_rpm").unwrap().values, y);

    y[50] = f64::NAN;
    let columns =
        [("time_s", t.as_slice()), ("fuel_flow_gph", u.as_slice()), ("shaft_speed_rpm", y.as_slice())];
    let text = jetid::io::csv_run::table_to_csv(NAME, &columns).unwrap();
    let err = parse_run(NAME, text.as_bytes(), &LoadOptions::default()).unwrap_err();
    assert!(matches!(err, RunFileError::MissingValue { row: 51, .. }), "{err}");
    assert_mentions(&err, &["shaft_speed_rpm"]);

    let short = [("time_s", t.as_slice()), ("fuel_flow_gph", &u[..10])];
    let err = jetid::io::csv_run::table_to_csv(NAME, &short).unwrap_err();
    assert_mentions(&err, &["fuel_flow_gph"]);
}
