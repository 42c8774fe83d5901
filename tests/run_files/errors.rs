//! Every error case: the variant, and a message naming the file, line, row and column.
use std::path::Path;

use jetid::io::csv_run::{
    ColumnMap, ColumnMapError, LoadOptions, MIN_SAMPLES, MapSpec, Role, RunFileError, Window, load_run,
};

use super::{assert_mentions, canonical, opts_from, parse, with_cell};

#[test]
fn unreadable_file() {
    let path = Path::new("/nonexistent/dir/bench.csv");
    let err = load_run(path, &LoadOptions::default()).unwrap_err();
    assert!(matches!(err, RunFileError::Unreadable { .. }), "{err}");
    assert_mentions(&err, &["/nonexistent/dir/bench.csv", "cannot read"]);
}

#[test]
fn empty_file_and_blank_header() {
    for text in ["", "\n\n", " , ,\n1,2,3\n"] {
        let err = parse(text, &LoadOptions::default()).unwrap_err();
        assert!(matches!(err, RunFileError::Empty { .. }), "{text:?}: {err}");
        assert_mentions(&err, &["no header"]);
    }
}

#[test]
fn missing_input_column_lists_the_columns_present() {
    let text = canonical(20).replace("fuel_flow_gph", "pump_V");
    let err = parse(&text, &LoadOptions::default()).unwrap_err();
    assert!(matches!(&err, RunFileError::MissingColumn { column, .. } if column == "fuel_flow_gph"), "{err}");
    assert_mentions(
        &err,
        &["\"fuel_flow_gph\"", "columns present: time_s, pump_V, shaft_speed_rpm", "--map input="],
    );
}

#[test]
fn missing_time_column_asks_for_a_sample_time() {
    let text = canonical(20).replace("time_s", "clock");
    let err = parse(&text, &LoadOptions::default()).unwrap_err();
    assert!(matches!(&err, RunFileError::MissingColumn { role, .. } if role == "time"), "{err}");
    assert_mentions(&err, &["\"time_s\"", "clock", "--sample-time"]);
}

#[test]
fn duplicate_column() {
    let text = canonical(20).replace("egt_c", "thrust_n");
    let err = parse(&text, &LoadOptions::default()).unwrap_err();
    assert!(matches!(&err, RunFileError::DuplicateColumn { first: 4, second: 5, .. }), "{err}");
    assert_mentions(&err, &["line 1", "\"thrust_n\"", "columns 4 and 5"]);
}

#[test]
fn non_numeric_cell_names_line_row_and_column() {
    let err = parse(&with_cell(20, 5, 2, "12k"), &LoadOptions::default()).unwrap_err();
    assert!(
        matches!(&err, RunFileError::NonNumeric { line: 6, row: 5, column, .. } if column == "shaft_speed_rpm")
    );
    assert_mentions(&err, &["line 6", "data row 5", "column \"shaft_speed_rpm\"", "\"12k\""]);
}

#[test]
fn nan_and_empty_cells_name_line_row_and_column() {
    for cell in ["NaN", "", "inf"] {
        let err = parse(&with_cell(20, 7, 1, cell), &LoadOptions::default()).unwrap_err();
        assert!(
            matches!(&err, RunFileError::MissingValue { line: 8, row: 7, column, .. } if column == "fuel_flow_gph")
        );
        assert_mentions(&err, &["line 8", "column \"fuel_flow_gph\"", "missing value"]);
    }
}

#[test]
fn wrong_number_of_fields() {
    let mut text = canonical(20);
    text.push_str("2.0,1,2\n");
    let err = parse(&text, &LoadOptions::default()).unwrap_err();
    assert!(matches!(err, RunFileError::WrongFieldCount { line: 22, row: 21, expected: 5, found: 3, .. }));
    assert_mentions(&err, &["line 22", "data row 21", "3 fields", "header has 5"]);
}

#[test]
fn non_increasing_time() {
    let err = parse(&with_cell(20, 9, 0, "0.7"), &LoadOptions::default()).unwrap_err();
    assert!(matches!(&err, RunFileError::NonIncreasingTime { line: 10, row: 9, .. }), "{err}");
    assert_mentions(&err, &["line 10", "data row 9", "column \"time_s\"", "does not increase"]);
    // Resampling cannot repair a time that goes back.
    let opts = LoadOptions { resample: true, ..LoadOptions::default() };
    let err = parse(&with_cell(20, 9, 0, "0.7"), &opts).unwrap_err();
    assert!(matches!(err, RunFileError::NonIncreasingTime { row: 9, .. }));
}

#[test]
fn non_uniform_time_names_the_first_offending_row_and_the_steps() {
    let err = parse(&with_cell(20, 12, 0, "1.13"), &LoadOptions::default()).unwrap_err();
    let RunFileError::NonUniformTime { line, row, step, expected, .. } = &err else { panic!("{err}") };
    assert_eq!((*line, *row), (13, 12));
    assert!((step - 0.13).abs() < 1e-9 && (expected - 0.1).abs() < 1e-9);
    assert_mentions(&err, &["line 13", "column \"time_s\"", "0.1", "--resample"]);
}

#[test]
fn too_few_samples() {
    let err = parse(&canonical(5), &LoadOptions::default()).unwrap_err();
    assert!(matches!(err, RunFileError::TooFewSamples { found: 5, needed: MIN_SAMPLES, .. }));
    assert_mentions(&err, &["5 samples", "at least 10"]);
    let err = parse(&canonical(0), &LoadOptions::default()).unwrap_err();
    assert!(matches!(err, RunFileError::TooFewSamples { found: 0, .. }));
}

#[test]
fn bad_map_syntax_and_unknown_role() {
    assert!(matches!(ColumnMap::from_specs(&["input"]), Err(ColumnMapError::BadSyntax { .. })));
    assert!(matches!(ColumnMap::from_specs(&["input="]), Err(ColumnMapError::BadSyntax { .. })));
    let err = ColumnMap::from_specs(&["outptu=rpm"]).unwrap_err();
    assert!(matches!(&err, ColumnMapError::UnknownRole { role, .. } if role == "outptu"));
    assert!(err.to_string().contains("outptu=rpm") && err.to_string().contains("time, input, output, aux"));
    let err = ColumnMap::from_specs(&["input=a", "input=b"]).unwrap_err();
    assert!(matches!(err, ColumnMapError::RoleTwice { role: Role::Input, .. }));
    let err = ColumnMap::from_specs(&["input=a", "aux=a"]).unwrap_err();
    assert!(matches!(err, ColumnMapError::ColumnInTwoRoles { .. }));
    assert_eq!(
        "Output = rpm".parse::<MapSpec>().unwrap(),
        MapSpec { role: Role::Output, column: "rpm".into() }
    );
}

#[test]
fn bad_map_column_not_in_file() {
    let err = parse(&canonical(20), &opts_from(&["input=pump_V"])).unwrap_err();
    assert!(matches!(&err, RunFileError::MapColumnNotFound { column, .. } if column == "pump_V"), "{err}");
    assert_mentions(&err, &["--map input=pump_V", "columns present: time_s, fuel_flow_gph"]);
}

#[test]
fn inconsistent_map_built_in_code_is_refused() {
    let map = ColumnMap { input: Some("egt_c".into()), aux: vec!["egt_c".into()], ..ColumnMap::default() };
    let err = parse(&canonical(20), &LoadOptions { map, ..LoadOptions::default() }).unwrap_err();
    assert!(matches!(err, RunFileError::BadMap { error: ColumnMapError::ColumnInTwoRoles { .. }, .. }));
    assert_mentions(&err, &["\"egt_c\"", "two roles"]);
}

#[test]
fn no_output_column() {
    let text = canonical(20).replace("shaft_speed_rpm", "speed").replace("thrust_n", "force");
    let err = parse(&text, &LoadOptions::default()).unwrap_err();
    assert!(matches!(err, RunFileError::NoOutput { .. }), "{err}");
    assert_mentions(&err, &["no output column", "speed, force", "--map output="]);
}

#[test]
fn bad_sample_time() {
    for dt in [0.0, -0.1, f64::NAN, f64::INFINITY] {
        let opts = LoadOptions { sample_time_secs: Some(dt), ..LoadOptions::default() };
        let err = parse(&canonical(20), &opts).unwrap_err();
        assert!(matches!(err, RunFileError::BadSampleTime { .. }), "{dt}: {err}");
        assert_mentions(&err, &["sample time", "positive"]);
    }
}

#[test]
fn time_given_twice() {
    let mut opts = opts_from(&["time=time_s"]);
    opts.sample_time_secs = Some(0.1);
    let err = parse(&canonical(20), &opts).unwrap_err();
    assert!(matches!(err, RunFileError::TimeGivenTwice { .. }), "{err}");
    assert_mentions(&err, &["\"time_s\"", "0.1 s"]);
}

#[test]
fn bad_window_syntax_range_and_empty() {
    for spec in ["935", "a:b", "1.5:3", "1s:30", "5:5", "4s:2s", ":"] {
        let err = spec.parse::<Window>().unwrap_err();
        assert!(err.to_string().contains(spec), "{err}");
    }
    for spec in ["10:500", "30:", "100s:200s", "-5s:-1s"] {
        let opts = LoadOptions { window: Some(spec.parse().unwrap()), ..LoadOptions::default() };
        let err = parse(&canonical(20), &opts).unwrap_err();
        assert!(matches!(err, RunFileError::BadWindow { .. }), "{spec}: {err}");
        assert_mentions(&err, &["--window", "out of range"]);
    }
    let opts = LoadOptions { window: Some("0:5".parse().unwrap()), ..LoadOptions::default() };
    assert!(matches!(parse(&canonical(20), &opts), Err(RunFileError::TooFewSamples { found: 5, .. })));
}

#[test]
fn bad_quality_value_and_missing_quality_column() {
    let text = canonical(20).replace("egt_c", "ok").replace(",500\n", ",1\n");
    let mut lines: Vec<&str> = text.lines().collect();
    let bad = lines[4].replace(",1", ",yes");
    lines[4] = &bad;
    let opts = LoadOptions { quality: Some("ok".to_owned()), ..LoadOptions::default() };
    let err = parse(&(lines.join("\n") + "\n"), &opts).unwrap_err();
    assert!(matches!(&err, RunFileError::BadQualityValue { line: 5, row: 4, .. }), "{err}");
    assert_mentions(&err, &["line 5", "quality column \"ok\"", "\"yes\""]);

    let opts = LoadOptions { quality: Some("crc_ok".to_owned()), ..LoadOptions::default() };
    let err = parse(&canonical(20), &opts).unwrap_err();
    assert!(matches!(&err, RunFileError::MissingColumn { role, .. } if role == "quality"), "{err}");
}

#[test]
fn too_many_bad_samples() {
    let text = canonical(20).replace("egt_c", "ok");
    let text: String = text
        .lines()
        .enumerate()
        .map(|(i, line)| {
            if i == 0 {
                format!("{line}\n")
            } else {
                line.replace(",500", &format!(",{}", u8::from(i % 3 == 0))) + "\n"
            }
        })
        .collect();
    let opts = LoadOptions { quality: Some("ok".to_owned()), ..LoadOptions::default() };
    let err = parse(&text, &opts).unwrap_err();
    assert!(matches!(err, RunFileError::TooManyBadSamples { bad: 14, total: 20, .. }), "{err}");
    assert_mentions(&err, &["\"ok\"", "14 of 20", "50 %"]);
}

#[test]
fn line_numbers_count_crlf_and_blank_lines() {
    let mut text = canonical(20).replace('\n', "\r\n");
    text = text.replacen("\r\n", "\r\n\r\n", 3);
    let text = text.replace(",50005,", ",x,");
    let err = parse(&text, &LoadOptions::default()).unwrap_err();
    // Data row 6 is on line 7, plus the three blank lines inserted after lines 1, 2 and 3.
    assert!(matches!(err, RunFileError::NonNumeric { line: 10, row: 6, .. }), "{err}");
    let mut text = String::from("time_s,fuel_flow_gph,shaft_speed_rpm\n");
    for k in 0..12 {
        let cell = if k == 4 { "\"multi\nline\"" } else { "1" };
        text.push_str(&format!("{k},{cell},2\n"));
    }
    let err = parse(&(text + "12,x,1\n"), &LoadOptions::default()).unwrap_err();
    assert!(matches!(err, RunFileError::NonNumeric { line: 6, row: 5, .. }), "{err}");
}
