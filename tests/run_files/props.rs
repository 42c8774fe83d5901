//! No panic on any input: arbitrary bytes, CSV-shaped text and nearly valid files.
use jetid::io::csv_run::{ColumnMap, LoadOptions, MIN_SAMPLES, parse_run};
use proptest::prelude::*;

use super::NAME;

fn csv_like() -> impl Strategy<Value = String> {
    let names = prop::sample::select(vec![
        "time_s",
        "fuel_flow_gph",
        "shaft_speed_rpm",
        "thrust_n",
        "egt_c",
        "ok",
        "x",
        "",
        "\"q,uoted\"",
    ]);
    let cells = prop::sample::select(vec![
        "0",
        "1",
        "0.1",
        "-2.5e3",
        "",
        "NaN",
        "inf",
        "abc",
        "1e308",
        "-0",
        "\"7\"",
        "1,2",
        "\u{0}",
        "\u{feff}3",
    ]);
    (prop::collection::vec(names, 0..7), prop::collection::vec(prop::collection::vec(cells, 0..8), 0..40))
        .prop_map(|(header, rows)| {
            let mut text = header.join(",");
            for row in rows {
                text.push('\n');
                text.push_str(&row.join(","));
            }
            text
        })
}

fn options() -> impl Strategy<Value = LoadOptions> {
    let window = prop::option::of(prop::sample::select(vec!["0:10", "2:", ":30", "0.5s:2s", "1s:"]));
    (
        window,
        any::<bool>(),
        any::<bool>(),
        prop::option::of(prop::sample::select(vec![0.1, -1.0, f64::NAN, 1e-300])),
    )
        .prop_map(|(window, quality, resample, sample_time_secs)| LoadOptions {
            map: ColumnMap::default(),
            sample_time_secs,
            window: window.map(|w| w.parse().unwrap()),
            quality: quality.then(|| "ok".to_owned()),
            resample,
            invalid: Default::default(),
            units: Default::default(),
            input_only: false,
        })
}

/// Canonical files with a quality column whose cells are mostly good, sometimes not.
fn nearly_valid() -> impl Strategy<Value = String> {
    let cell = prop_oneof![
        8 => (-1e5f64..1e5).prop_map(|v| format!("{v}")),
        1 => prop::sample::select(vec!["", "NaN", "x", "1e400", "-0"]).prop_map(str::to_owned),
    ];
    let step = prop_oneof![8 => Just(0.1), 1 => 0.0f64..0.3, 1 => Just(-0.1)];
    let row = (step, cell.clone(), cell.clone(), cell, prop::sample::select(vec!["1", "1", "1", "0", "2"]));
    prop::collection::vec(row, 0..60).prop_map(|rows| {
        let mut text = String::from("time_s,fuel_flow_gph,shaft_speed_rpm,egt_c,ok\n");
        let mut t = 0.0;
        for (step, u, y, aux, ok) in rows {
            t += step;
            text.push_str(&format!("{t},{u},{y},{aux},{ok}\n"));
        }
        text
    })
}

proptest! {
    #[test]
    fn nearly_valid_files_never_panic(text in nearly_valid(), opts in options()) {
        if let Ok(run) = parse_run(NAME, text.as_bytes(), &opts) {
            prop_assert!(run.len() >= MIN_SAMPLES);
            let all = std::iter::once(&run.input).chain(&run.outputs).chain(&run.aux);
            for channel in all {
                prop_assert_eq!(channel.values.len(), run.len());
                prop_assert!(channel.values.iter().all(|v| v.is_finite()));
            }
            prop_assert!(run.t_secs.windows(2).all(|w| w[1] > w[0]));
        }
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..2000), opts in options()) {
        let _ = parse_run(NAME, &bytes, &opts);
    }

    #[test]
    fn csv_shaped_text_never_panics(text in csv_like(), opts in options()) {
        if let Ok(run) = parse_run(NAME, text.as_bytes(), &opts) {
            prop_assert!(run.len() >= MIN_SAMPLES);
            prop_assert!(run.dt_secs > 0.0 && run.dt_secs.is_finite());
        }
    }

    #[test]
    fn generated_runs_load_with_exact_values(values in prop::collection::vec(-1e6f64..1e6, 10..60)) {
        let mut text = String::from("time_s,fuel_flow_gph,thrust_n\n");
        for (k, v) in values.iter().enumerate() {
            text.push_str(&format!("{:?},{v:?},{:?}\n", k as f64 * 0.01, -v));
        }
        let run = parse_run(NAME, text.as_bytes(), &LoadOptions::default()).unwrap();
        prop_assert_eq!(&run.input.values, &values);
    }
}
