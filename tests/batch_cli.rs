//! `jetid --batch` and `jetid predict` end to end on the bundled sample runs, and the errors a user
//! can cause through them.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use crate::common::jetid;
use std::path::{Path, PathBuf};
use std::process::Output;

use jetid::core::identification::fits::segments_for;
use jetid::core::identification::pipeline::identify_output;
use jetid::core::identification::segment::SegmentSettings;
use jetid::core::identification::settings::OutputSettings;
use jetid::io::csv_run::{LoadOptions, load_run};

fn samples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("sample_runs/sr30")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `jetid predict --model MODEL --input INPUT --out OUT` and `extra`, as arguments.
fn predict_args<'a>(model: &'a Path, input: &'a Path, out: &'a Path, extra: &[&'a str]) -> Vec<&'a str> {
    let path = |p: &'a Path| p.to_str().expect("utf-8 path");
    let mut args = vec!["predict", "--model", path(model), "--input", path(input), "--out", path(out)];
    args.extend_from_slice(extra);
    args
}

#[test]
fn batch_on_the_bundled_runs_writes_model_and_reports() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("nested/out");
    let o =
        jetid(&["--batch", samples().join("project.toml").to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["format_version"], 1);
    for output in ["shaft_speed_rpm", "thrust_n"] {
        for model in ["gray_box", "linear", "hammerstein_wiener", "nnarx"] {
            for run in ["validation", "chirp"] {
                let m = &report["outputs"][output]["models"][model][run];
                for key in ["rmspe_pct", "mape_pct", "se", "fit_pct", "rmse", "max_abs_error"] {
                    assert!(m[key].as_f64().is_some_and(f64::is_finite), "{output}/{model}/{run}/{key}: {m}");
                }
            }
        }
        let gray =
            report["outputs"][output]["models"]["gray_box"]["validation"]["rmspe_pct"].as_f64().unwrap();
        let linear =
            report["outputs"][output]["models"]["linear"]["validation"]["rmspe_pct"].as_f64().unwrap();
        assert!(gray < linear, "{output}: the static map should help ({gray} vs {linear})");
        assert!(report["outputs"][output]["error_history"][0]["rmspe_pct"].as_f64().is_some());
    }
    // The simple references stand beside every model, scored on the same runs, in both reports.
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    for output in ["shaft_speed_rpm", "thrust_n"] {
        for model in ["arx", "hammerstein_arx", "static_cubic"] {
            for run in ["validation", "chirp"] {
                let m = &report["outputs"][output]["models"][model][run];
                assert!(m["rmspe_pct"].as_f64().is_some_and(f64::is_finite), "{output}/{model}/{run}: {m}");
            }
        }
    }
    for title in ["reference: linear ARX(2,2)", "reference: Hammerstein ARX", "reference: static cubic map"] {
        assert!(md.contains(title), "report.md lacks {title}");
    }
    // Every root of the bundled models carries the 95 % intervals of its figures, around its value.
    for output in ["shaft_speed_rpm", "thrust_n"] {
        for root in report["outputs"][output]["identified"]["roots"].as_array().unwrap() {
            for field in ["natural_freq_rad_s", "time_constant_secs", "damping"] {
                let Some(value) = root[field].as_f64() else { continue };
                let ci = &root[format!("{field}_ci95")];
                if field == "damping" && root["pair"] == false {
                    assert!(ci.is_null(), "a real root's damping is 1 by definition: {root}");
                    continue;
                }
                let (lo, hi) = (ci[0].as_f64().unwrap(), ci[1].as_f64().unwrap());
                assert!(lo < value && value < hi, "{output} {field}: {root}");
            }
        }
    }
    assert!(
        md.contains("ωn (rad/s) | ζ | τ (s)") && md.contains(" ± "),
        "report.md shows the intervals as ±"
    );
    // Every operating point carries the 95 % interval of its local gain, around the gain and on
    // the physical (positive) side; model.json holds the covariance the intervals come from.
    let model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("model.json")).unwrap()).unwrap();
    for (i, output) in ["shaft_speed_rpm", "thrust_n"].into_iter().enumerate() {
        for p in report["outputs"][output]["operating_points"].as_array().unwrap() {
            let gain = p["gain"].as_f64().unwrap();
            let (lo, hi) = (p["gain_ci95"][0].as_f64().unwrap(), p["gain_ci95"][1].as_f64().unwrap());
            assert!(0.0 < lo && lo < gain && gain < hi, "{output}: gain {gain} in [{lo}, {hi}]");
            for pole in p["poles"].as_array().unwrap() {
                if let Some(tau) = pole["tau_s"].as_f64() {
                    let ci = &pole["tau_s_ci95"];
                    assert!(
                        ci[0].as_f64().unwrap() < tau && tau < ci[1].as_f64().unwrap(),
                        "{output}: {pole}"
                    );
                }
            }
        }
        // The map's coefficients and the continuous-time block's, each inside its interval.
        let numbers = report["outputs"][output]["parameter_intervals"].as_array().unwrap();
        for name in ["static map β0", "static map β1", "G(s) denominator s^0"] {
            let p = numbers.iter().find(|p| p["name"] == name).unwrap_or_else(|| panic!("{output}: {name}"));
            let (v, lo, hi) = (
                p["value"].as_f64().unwrap(),
                p["ci95"][0].as_f64().unwrap(),
                p["ci95"][1].as_f64().unwrap(),
            );
            assert!(lo < v && v < hi, "{output}: {p}");
        }
        let cov = &model["outputs"][i]["covariance"];
        let n = cov["names"].as_array().unwrap().len();
        assert!(n > 0 && cov["matrix"].as_array().unwrap().len() == n, "{output}: {cov}");
    }
    assert!(md.contains("x −a/+b") && md.contains("/+"), "report.md shows the operating points' intervals");
    assert!(md.contains("### Parameter uncertainty"), "report.md lists the parameters' intervals");
    for figure in ["shaft_speed_rpm_traces_validation.png", "thrust_n_bode.png", "thrust_n_zplane.png"] {
        assert!(out.join(figure).exists(), "{figure}");
    }
    for channel in ["fuel_flow_gph", "shaft_speed_rpm", "thrust_n"] {
        let best = report["noise_fit"][channel]["best_by_log_likelihood"].as_str().unwrap();
        assert!(
            ["normal", "logistic", "uniform", "extreme_value", "inverse_gaussian", "nakagami"]
                .contains(&best)
        );
    }
    for output in ["shaft_speed_rpm", "thrust_n"] {
        for model in ["gray_box", "linear", "hammerstein_wiener", "nnarx"] {
            let std = report["monte_carlo"][output][model]["std_difference"].as_f64().unwrap();
            assert!(std.is_finite() && std > 0.0, "{output}/{model}: {std}");
        }
        assert!(report["outputs"][output]["cutoff_rad_s"]["measured"].as_f64().is_some());
        // The noise band of the residual analysis is the steady run's normal fit.
        let normal = report["noise_fit"][output]["fits"]
            .as_array()
            .unwrap()
            .iter()
            .find(|f| f["distribution"]["family"] == "normal")
            .unwrap();
        let residuals = report["outputs"][output]["residuals"].as_array().unwrap();
        assert_eq!(residuals.len(), 2, "validation and chirp");
        for r in residuals {
            assert_eq!(r["noise_sigma"], normal["distribution"]["std"], "{output}");
            assert_eq!(r["regimes"].as_array().unwrap().len(), 8);
        }
    }
    // Every model that explains less than half of a run's variation is flagged, and only those.
    for output in ["shaft_speed_rpm", "thrust_n"] {
        let o = &report["outputs"][output];
        let flagged = o["failing"].as_array().unwrap().len();
        let below: usize = o["models"]
            .as_object()
            .unwrap()
            .values()
            .flat_map(|runs| runs.as_object().unwrap().values())
            .filter(|m| m["fit_pct"].as_f64().unwrap() < 50.0)
            .count();
        assert_eq!(flagged, below, "{output}: {}", o["failing"]);
    }
    assert!(report["timings_ms"]["total"].as_f64().unwrap() > 0.0);
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("Table 1") && md.contains("gray-box (Wiener)") && md.contains("paper RMSPE"));
    assert!(md.contains("Monte Carlo") && md.contains("Noise fit"));
    for figure in
        ["shaft_speed_rpm_bode_compare.png", "thrust_n_monte_carlo_nnarx.png", "thrust_n_error_boxes.png"]
    {
        assert!(out.join(figure).is_file(), "{figure}");
        assert!(md.contains(figure), "report.md shows {figure}");
    }

    // The report names where scored runs start; predict started the same way reproduces the batch's
    // gray-box prediction from model.json alone.
    assert_eq!(report["outputs"]["shaft_speed_rpm"]["initial_state"], "estimated");
    let pred = dir.path().join("pred.csv");
    let val = samples().join("validation.csv");
    let o = jetid(&predict_args(&out.join("model.json"), &val, &pred, &["--initial-state", "estimated"]));
    assert!(o.status.success(), "{}", stderr(&o));
    let predicted = load_run(&pred, &LoadOptions::default()).unwrap();
    let measured = load_run(&val, &LoadOptions::default()).unwrap();
    let y = &measured.output("shaft_speed_rpm").unwrap().values;
    let y_hat = &predicted.output("shaft_speed_rpm").unwrap().values;
    let m = jetid::core::numerics::metrics::metrics(y, y_hat).unwrap();
    let batch = report["outputs"]["shaft_speed_rpm"]["models"]["gray_box"]["validation"]["rmspe_pct"]
        .as_f64()
        .unwrap();
    assert!((m.rmspe_pct - batch).abs() < 1e-6 * batch.max(1.0), "predict {} vs batch {batch}", m.rmspe_pct);

    // A run that lacks one measured output: predict starts it from the steady state; the estimated
    // start needs the measurement and says so.
    let rows: String = (0..40)
        .map(|k| format!("{:.6},{},{}\n", k as f64 / 8.85, if k < 20 { 4.0 } else { 5.0 }, 50 + k))
        .collect();
    let schedule = write(dir.path(), "schedule.csv", &format!("time_s,fuel_flow_gph,thrust_n\n{rows}"));
    let o =
        jetid(&predict_args(&out.join("model.json"), &schedule, &dir.path().join("schedule_pred.csv"), &[]));
    assert!(o.status.success(), "{}", stderr(&o));
    expect_error(
        &predict_args(
            &out.join("model.json"),
            &schedule,
            &dir.path().join("schedule_pred2.csv"),
            &["--initial-state", "estimated"],
        ),
        &["--initial-state estimated", "shaft_speed_rpm", "--initial-state steady"],
    );
}

#[test]
fn sr30_models_have_the_papers_structure() {
    let ident = load_run(&samples().join("ident.csv"), &LoadOptions::default()).unwrap();
    let segments = segments_for(&ident, None, &SegmentSettings::default()).unwrap();
    assert_eq!(segments.len(), 7, "steps A–H of the identification design");

    let speed = identify_output(
        &ident,
        "shaft_speed_rpm",
        &OutputSettings::for_output("shaft_speed_rpm"),
        &segments,
        None,
    )
    .unwrap();
    let poles = speed.model.wiener.linear.tf.poles().unwrap();
    let real: Vec<f64> = poles.iter().filter(|p| p.im.abs() < 1e-9).map(|p| p.re).collect();
    assert!(real.iter().any(|r| (0.93..=0.95).contains(r)), "speed poles {poles:?}");
    assert!(poles.iter().any(|p| p.im.abs() > 0.05), "speed needs a complex pair: {poles:?}");

    let thrust =
        identify_output(&ident, "thrust_n", &OutputSettings::for_output("thrust_n"), &segments, None)
            .unwrap();
    let thrust_poles = thrust.model.wiener.linear.tf.poles().unwrap();
    let slowest = thrust_poles.iter().max_by(|a, b| a.norm().total_cmp(&b.norm())).unwrap();
    assert!(slowest.im.abs() < 1e-9 && (0.92..=0.96).contains(&slowest.re), "thrust poles {thrust_poles:?}");
    // Thrust is a static function of spool speed seen through a fast load cell and stand, so its
    // model's slowest pole is the speed model's spool pole, found independently from its own roots.
    // (The pole pairs are not compared: the pair stands in for the fuel system and, once its circle
    // follows the data, for what the fixed linear block misses of the operating-point-dependent
    // spool, which the two outputs weigh differently.)
    let spool = real.iter().copied().fold(0.0_f64, f64::max);
    assert!((slowest.re - spool).abs() < 0.02, "thrust's slowest pole {slowest} against the speed's {spool}");
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn expect_error(args: &[&str], needles: &[&str]) {
    let o = jetid(args);
    assert_eq!(o.status.code(), Some(1), "args {args:?}: {}", stderr(&o));
    let err = stderr(&o);
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(err.contains(n), "expected {n:?} in: {err}");
    }
}

#[test]
fn batch_errors_name_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let out = out.to_str().unwrap();
    expect_error(&["--batch", "--ident", "/no/such/run.csv", "--out", out], &["/no/such/run.csv"]);
    let mut text = String::from("time_s,fuel_flow_gph,shaft_speed_rpm\n");
    for k in 0..20 {
        text.push_str(&format!(
            "{},{},{}\n",
            k as f64 * 0.1,
            if k == 5 { "x".into() } else { "1".to_string() },
            2
        ));
    }
    let bad = write(dir.path(), "bad.csv", &text);
    expect_error(
        &["--batch", "--ident", bad.to_str().unwrap(), "--out", out],
        &["bad.csv", "fuel_flow_gph", "data row 6"],
    );
    let toml = write(dir.path(), "p.toml", "idnet = \"ident.csv\"\n");
    expect_error(&["--batch", toml.to_str().unwrap(), "--out", out], &["p.toml", "idnet"]);
    let proj = samples().join("project.toml");
    expect_error(
        &["--batch", proj.to_str().unwrap(), "--output", "egt_c", "--out", out],
        &["egt_c", "shaft_speed_rpm"],
    );
    expect_error(&["--batch", proj.to_str().unwrap(), "--map", "banana", "--out", out], &["banana"]);
    expect_error(&["--batch", "--bogus-flag"], &["--bogus-flag"]);
    // A flat input has no steps to identify from, and the message says so in those words.
    let flat: String = std::iter::once("time_s,fuel_flow_gph,shaft_speed_rpm\n".to_owned())
        .chain((0..400).map(|k| format!("{},{},{}\n", k as f64 * 0.113, 5.43, 73850.0 + (k % 7) as f64)))
        .collect();
    let flat = write(dir.path(), "flat.csv", &flat);
    expect_error(&["--batch", "--ident", flat.to_str().unwrap(), "--out", out], &["never changes", "5.430"]);
    let said = stderr(&jetid(&["--batch", "--ident", flat.to_str().unwrap(), "--out", out]));
    assert_eq!(said.matches("never changes").count(), 1, "the cause is said once: {said}");
    assert!(!Path::new(out).join("report.json").exists(), "no report may be left behind by a failed run");
}

#[test]
fn predict_errors_name_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let pred = dir.path().join("p.csv");
    let val = samples().join("validation.csv");
    expect_error(
        &[
            "predict",
            "--model",
            "/no/model.json",
            "--input",
            val.to_str().unwrap(),
            "--out",
            pred.to_str().unwrap(),
        ],
        &["/no/model.json"],
    );
    let junk = write(dir.path(), "m.json", "{\"format_version\": 1}");
    expect_error(&predict_args(&junk, &val, &pred, &[]), &["m.json", "not a jetid model"]);
    assert!(!pred.exists());
}

#[test]
fn batch_starts_from_the_clusters_of_a_saved_model() {
    let dir = tempfile::tempdir().unwrap();
    let first = dir.path().join("first");
    let project = samples().join("project.toml");
    let o = jetid(&[
        "--batch",
        project.to_str().unwrap(),
        "--output",
        "shaft_speed_rpm",
        "--out",
        first.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));

    // An engineer keeps only the real pole cluster of the automatic proposal and saves the model.
    let mut model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(first.join("model.json")).unwrap()).unwrap();
    let clusters = model["outputs"][0]["clusters"].as_array().unwrap().clone();
    let real_pole = clusters
        .iter()
        .find(|c| c["kind"] == "Pole" && c["centre"][1].as_f64().unwrap().abs() < 1e-9)
        .expect("the proposal has a real pole cluster")
        .clone();
    model["outputs"][0]["clusters"] = serde_json::json!([real_pole]);
    let edited = dir.path().join("edited.json");
    std::fs::write(&edited, serde_json::to_string(&model).unwrap()).unwrap();

    let second = dir.path().join("second");
    let o = jetid(&[
        "--batch",
        project.to_str().unwrap(),
        "--clusters",
        edited.to_str().unwrap(),
        "--out",
        second.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(second.join("report.json")).unwrap()).unwrap();
    let speed = &report["outputs"]["shaft_speed_rpm"]["identified"];
    assert_eq!(speed["clusters"].as_array().unwrap().len(), 1, "{speed}");
    assert_eq!(speed["poles"].as_array().unwrap().len(), 1, "one cluster gives a first-order model");
    // Thrust is not in the saved model: it falls back to the automatic proposal, and the report says so.
    assert!(!report["outputs"]["thrust_n"]["identified"]["clusters"].as_array().unwrap().is_empty());
    let notes = report["diagnostics"].to_string();
    assert!(notes.contains("thrust_n") && notes.contains("automatic proposal"), "{notes}");
}

#[test]
fn saved_clusters_from_another_sample_time_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let first = dir.path().join("first");
    let project = samples().join("project.toml");
    let o = jetid(&[
        "--batch",
        project.to_str().unwrap(),
        "--output",
        "thrust_n",
        "--out",
        first.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(first.join("model.json")).unwrap()).unwrap();
    model["dt_secs"] = serde_json::json!(0.01);
    let edited = write(dir.path(), "fast.json", &serde_json::to_string(&model).unwrap());
    expect_error(
        &[
            "--batch",
            project.to_str().unwrap(),
            "--clusters",
            edited.to_str().unwrap(),
            "--out",
            first.to_str().unwrap(),
        ],
        &["fast.json", "sample time", "0.01000"],
    );
    expect_error(
        &["--batch", project.to_str().unwrap(), "--clusters", "/nonexistent/model.json"],
        &["/nonexistent/model.json"],
    );
}

#[test]
fn add_effect_lowers_the_error_and_predict_honours_it() {
    let dir = tempfile::tempdir().unwrap();
    let project = Path::new(env!("CARGO_MANIFEST_DIR")).join("sample_runs/soak/project.toml");
    let out = dir.path().join("out");
    let o = jetid(&[
        "--batch",
        project.to_str().unwrap(),
        "--output",
        "shaft_speed_rpm",
        "--add-effect",
        "thermal_soak",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let speed = &report["outputs"]["shaft_speed_rpm"];
    assert_eq!(speed["effects_applied"], serde_json::json!(["thermal_soak"]));
    let history = speed["error_history"].as_array().unwrap();
    assert_eq!(history.len(), 2, "{history:?}");
    let (base, after) =
        (history[0]["rmspe_pct"].as_f64().unwrap(), history[1]["rmspe_pct"].as_f64().unwrap());
    assert!(after < base, "adding the soak must lower the validation error: {base} -> {after}");
    assert!(!speed["diagnosis"].as_array().unwrap().is_empty());

    // Where it fails: the residuals are those of the final model, with its effect.
    let residuals = speed["residuals"].as_array().unwrap();
    let validation = residuals.iter().find(|r| r["run"] == "validation").expect("validation residuals");
    let whole_run = &validation["regimes"][0];
    assert_eq!(whole_run["regime"], "Run", "{whole_run}");
    let (rmse, batch_rmse) = (
        whole_run["rmse"].as_f64().unwrap(),
        speed["models"]["gray_box"]["validation"]["rmse"].as_f64().unwrap(),
    );
    assert!((rmse - batch_rmse).abs() < 1e-9 * batch_rmse, "residual RMSE {rmse} vs model RMSE {batch_rmse}");
    assert!(!validation["summary"].as_str().unwrap().is_empty());
    let figure = validation["figure"].as_str().unwrap();
    assert!(out.join(figure).is_file(), "{figure}");
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("Where it fails") && md.contains(figure));

    // model.json records the effect and predict simulates it: same error as the batch reports.
    let model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("model.json")).unwrap()).unwrap();
    assert_eq!(model["outputs"][0]["effects"][0]["id"], "thermal_soak");
    let val = project.parent().unwrap().join("validation.csv");
    let pred = dir.path().join("pred.csv");
    let o = jetid(&predict_args(&out.join("model.json"), &val, &pred, &["--initial-state", "estimated"]));
    assert!(o.status.success(), "{}", stderr(&o));
    let y = load_run(&val, &LoadOptions::default()).unwrap();
    let y_hat = load_run(&pred, &LoadOptions::default()).unwrap();
    let m = jetid::core::numerics::metrics::metrics(
        &y.output("shaft_speed_rpm").unwrap().values,
        &y_hat.output("shaft_speed_rpm").unwrap().values,
    )
    .unwrap();
    let batch = speed["models"]["gray_box"]["validation"]["rmspe_pct"].as_f64().unwrap();
    assert!((m.rmspe_pct - batch).abs() < 1e-6 * batch, "predict {} vs batch {batch}", m.rmspe_pct);
}

#[test]
fn effect_errors_name_what_is_wrong() {
    let project = samples().join("project.toml");
    expect_error(
        &["--batch", project.to_str().unwrap(), "--add-effect", "warp_drive"],
        &["warp_drive", "thermal_soak"],
    );
    // Reading an output off the speed's model is the spool sharing's to offer, not an effect fitted
    // on one output: asked for by hand, it is refused with the reason.
    expect_error(
        &["--batch", project.to_str().unwrap(), "--output", "thrust_n", "--add-effect", "read_off_speed"],
        &["read_off_speed", "'thrust_n'", "not fitted on the output alone", "spool sharing"],
    );
    // A model that needs the inlet channels cannot predict a run without them.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = jetid(&[
        "--batch",
        project.to_str().unwrap(),
        "--output",
        "thrust_n",
        "--add-effect",
        "ambient_correction",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let rows: String = (0..40).map(|k| format!("{:.4},5,80\n", k as f64 / 8.85)).collect();
    let bare = write(dir.path(), "bare.csv", &format!("time_s,fuel_flow_gph,thrust_n\n{rows}"));
    expect_error(
        &predict_args(&out.join("model.json"), &bare, &dir.path().join("p.csv"), &[]),
        &["ambient_correction", "ambient_temp_c"],
    );
}

#[cfg(feature = "gui")]
#[test]
fn an_unknown_screenshot_view_lists_the_views() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("x.png");
    expect_error(
        &["--screenshot", png.to_str().unwrap(), "--view", "nonsense"],
        &["unknown view `nonsense`", "compare", "diagnosis", "failures"],
    );
    assert!(!png.exists());
}

#[test]
fn the_missing_physics_loop_chooses_on_validation_runs_and_scores_held_out_runs() {
    // The sr30 samples: identification, validation and chirp; the chirp run is also given as a
    // held-out run. The loop may add only what the diagnosis of the validation run finds
    // significant, and each round it takes must lower the validation error it records.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let s = samples();
    let path = |name: &str| s.join(name).to_str().unwrap().to_owned();
    let (ident, validate, held) = (path("ident.csv"), path("validation.csv"), path("chirp.csv"));
    let o = jetid(&[
        "--batch",
        "--ident",
        &ident,
        "--validate",
        &validate,
        "--held-out",
        &held,
        "--output",
        "shaft_speed_rpm",
        "--auto-effects",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["runs"]["held-out 1"], "chirp");
    let speed = &report["outputs"]["shaft_speed_rpm"];
    let held_out = &speed["models"]["gray_box"]["chirp"]["rmse"];
    assert!(held_out.as_f64().is_some_and(f64::is_finite), "the held-out run is scored: {held_out}");
    let history = speed["error_history"].as_array().unwrap();
    assert!(!history.is_empty() && history.len() <= 3, "{history:?}");
    for pair in history.windows(2) {
        let (before, after) =
            (pair[0]["rmspe_pct"].as_f64().unwrap(), pair[1]["rmspe_pct"].as_f64().unwrap());
        assert!(after < before, "a round of the loop must lower the validation error: {history:?}");
        assert!(pair[1]["step"].as_str().unwrap().ends_with("(auto)"), "{history:?}");
    }
    let notes = report["diagnostics"].to_string();
    assert!(
        notes.contains("missing-physics loop") || history.len() == 3,
        "the loop says why it stopped: {notes}"
    );
    // A negative number of rounds is refused by the command line.
    let bad = jetid(&["--batch", "--ident", &ident, "--auto-effects", "-1"]);
    assert!(!bad.status.success());
}

/// A model.json by hand: one first-order speed model with the pole `pole`, driven by `input`,
/// with `effects` (a JSON list).
fn hand_model(dir: &Path, name: &str, pole: f64, input: &str, effects: &str) -> PathBuf {
    let text = format!(
        r#"{{"format_version": 1, "convention": "", "dt_secs": 0.112994350282,
            "input": {{"name": "{input}", "unit": ""}},
            "outputs": [{{"name": "shaft_speed_rpm", "unit": "rpm",
              "wiener": {{"linear": {{"tf": {{"num_zinv": [0.0, {gain}], "den_zinv": [1.0, {minus_pole}],
                                             "dt_secs": 0.112994350282}}, "offset": 0.0}},
                          "map": {{"v_center": 0.0, "v_scale": 1.0, "coeffs_scaled": [30000.0, 1.0]}}}},
              "static_map_beta": [30000.0, 1.0], "poles": [[{pole}, 0.0]], "zeros": [], "clusters": [],
              "effects": {effects}}}]}}"#,
        gain = 8000.0 * (1.0 - pole),
        minus_pole = -pole,
    );
    write(dir, name, &text)
}

/// predict refuses what it cannot trust, with a message about the model or the files: an unstable
/// linear block, a model driven by another signal, an unknown effect, and an output over its input.
#[test]
fn predict_refuses_models_it_cannot_trust() {
    let dir = tempfile::tempdir().unwrap();
    let val = samples().join("validation.csv");
    let pred = dir.path().join("p.csv");
    let good = hand_model(dir.path(), "good.json", 0.9, "fuel_flow_gph", "[]");
    let o = jetid(&predict_args(&good, &val, &pred, &[]));
    assert!(o.status.success(), "the hand-made stable model predicts: {}", stderr(&o));

    let unstable = hand_model(dir.path(), "unstable.json", 1.02, "fuel_flow_gph", "[]");
    let out = dir.path().join("u.csv");
    expect_error(
        &predict_args(&unstable, &val, &out, &[]),
        &["unstable.json", "shaft_speed_rpm", "1.0200", "unstable"],
    );
    assert!(!out.exists(), "nothing is written for a refused model");

    let other_input = hand_model(dir.path(), "pump.json", 0.9, "pump_V", "[]");
    expect_error(&predict_args(&other_input, &val, &out, &[]), &["pump_V", "fuel_flow_gph", "--map input="]);

    let unknown =
        hand_model(dir.path(), "warp.json", 0.9, "fuel_flow_gph", r#"[{"id": "warp_drive", "params": {}}]"#);
    expect_error(
        &predict_args(&unknown, &val, &out, &[]),
        &["warp.json", "unknown effect 'warp_drive'", "thermal_soak"],
    );
    let unknown_bare =
        hand_model(dir.path(), "warp2.json", 0.9, "fuel_flow_gph", r#"[{"id": "warp_drive"}]"#);
    expect_error(&predict_args(&unknown_bare, &val, &out, &[]), &["unknown effect 'warp_drive'"]);

    let copy = dir.path().join("run.csv");
    std::fs::copy(&val, &copy).unwrap();
    let before = std::fs::read(&copy).unwrap();
    expect_error(&predict_args(&good, &copy, &copy, &[]), &["--out", "--input", "destroy"]);
    let relative_twin = dir.path().join(".").join("run.csv");
    expect_error(&predict_args(&good, &copy, &relative_twin, &[]), &["destroy"]);
    expect_error(&predict_args(&good, &copy, &good, &[]), &["--out", "--model", "destroy"]);
    assert_eq!(std::fs::read(&copy).unwrap(), before, "the run is untouched");
}

/// Settings for an output the run does not have would be silently ignored: an error that lists the
/// outputs there are.
#[test]
fn a_project_section_for_an_unknown_output_is_an_error_naming_the_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let ident = samples().join("ident.csv");
    let project = write(
        dir.path(),
        "typo.toml",
        &format!(
            "ident = \"{}\"\n[output.shaft_sped_rpm]\nna = 5\n",
            ident.to_str().unwrap().replace('\\', "/")
        ),
    );
    let out = dir.path().join("out");
    expect_error(
        &["--batch", project.to_str().unwrap(), "--out", out.to_str().unwrap()],
        &["[output.shaft_sped_rpm]", "shaft_speed_rpm", "thrust_n"],
    );
    assert!(!out.join("report.json").exists());
}

/// A fuel schedule is a run to predict from: no measured output is needed, and a gap in one that
/// is there does not block a prediction started from the steady state.
#[test]
fn predict_runs_on_a_fuel_schedule_without_measured_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let model = hand_model(dir.path(), "good.json", 0.9, "fuel_flow_gph", "[]");
    let rows = |k: usize| format!("{:.6},{}", k as f64 * 0.112994350282, if k < 100 { 4.0 } else { 5.0 });
    let bare: String = std::iter::once("time_s,fuel_flow_gph\n".to_owned())
        .chain((0..200).map(|k| format!("{}\n", rows(k))))
        .collect();
    let with_gap: String = std::iter::once("time_s,fuel_flow_gph,shaft_speed_rpm\n".to_owned())
        .chain((0..200).map(|k| {
            format!("{},{}\n", rows(k), if k == 50 { "nan".to_owned() } else { "60000".to_owned() })
        }))
        .collect();
    for (name, text) in [("bare.csv", bare), ("gap.csv", with_gap)] {
        let input = write(dir.path(), name, &text);
        let out = dir.path().join(format!("pred_{name}"));
        let o = jetid(&predict_args(&model, &input, &out, &[]));
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        let predicted = load_run(&out, &LoadOptions::default()).unwrap();
        let y = &predicted.output("shaft_speed_rpm").unwrap().values;
        assert_eq!(y.len(), 200);
        // Steady at 4 gal/h (v = 8000·4), then climbing towards 5 gal/h after the step.
        assert!((y[0] - (30000.0 + 8000.0 * 4.0)).abs() < 1e-6, "{}", y[0]);
        assert!(y[199] > y[99] + 7000.0, "{} vs {}", y[199], y[99]);
    }
}

/// A reused `--out` folder: what an earlier run wrote and this one did not is removed (and said),
/// a file the user put there is left alone. The stage lines on stderr, and `--quiet`.
#[test]
fn a_reused_out_folder_keeps_no_stale_results() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let out_s = out.to_str().unwrap();
    let ident = samples().join("ident.csv");
    let val = samples().join("validation.csv");
    let base =
        ["--batch", "--ident", ident.to_str().unwrap(), "--validate", val.to_str().unwrap(), "--out", out_s];
    let o = jetid(&base);
    assert!(o.status.success(), "{}", stderr(&o));
    // The batch says what it is doing on stderr while it works (plain lines when not a terminal).
    let stages = stderr(&o);
    for stage in ["loading the runs", "identifying shaft_speed_rpm", "fitting the baselines of thrust_n"] {
        assert!(stages.lines().any(|l| l.starts_with("jetid: [") && l.ends_with(stage)), "{stage}: {stages}");
    }
    let thrust_figures: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("thrust_n") && n.ends_with(".png"))
        .collect();
    assert!(!thrust_figures.is_empty());
    std::fs::write(out.join("my_notes.txt"), "mine").unwrap();

    let mut speed_only = base.to_vec();
    speed_only.extend(["--output", "shaft_speed_rpm", "--quiet"]);
    let o = jetid(&speed_only);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(o.stderr.is_empty(), "--quiet prints no stage lines: {}", stderr(&o));
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(said.contains(&format!("removed {} file(s)", thrust_figures.len())), "{said}");
    for name in &thrust_figures {
        assert!(!out.join(name).exists(), "{name} is stale and must go");
    }
    assert_eq!(std::fs::read_to_string(out.join("my_notes.txt")).unwrap(), "mine");
    assert!(out.join("shaft_speed_rpm_bode.png").is_file() && out.join("report.json").is_file());
}

/// What reading a run had to interpret reaches the report: a column left out (with why), a
/// corrupt cell interpolated (at its row), the separator of a spreadsheet export.
#[test]
fn the_report_names_what_reading_the_runs_interpreted() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(samples().join("ident.csv")).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    lines[0].push_str(",operator");
    for (i, line) in lines.iter_mut().enumerate().skip(1) {
        line.push_str(if i % 2 == 0 { ",bob" } else { ",alice" });
    }
    let mut cells: Vec<String> = lines[701].split(',').map(str::to_owned).collect();
    cells[2] = "1e308".to_owned();
    lines[701] = cells.join(",");
    let ident = write(dir.path(), "ident.csv", &(lines.join("\n") + "\n"));
    let validation = std::fs::read_to_string(samples().join("validation.csv")).unwrap();
    let validation = write(dir.path(), "val.csv", &validation.replace(',', ";").replace('.', ","));
    let out = dir.path().join("out");
    let o = jetid(&[
        "--batch",
        "--ident",
        ident.to_str().unwrap(),
        "--validate",
        validation.to_str().unwrap(),
        "--output",
        "shaft_speed_rpm",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let notes = report["diagnostics"].to_string();
    assert!(notes.contains("column 'operator' left out"), "{notes}");
    assert!(notes.contains("data row 700: shaft_speed_rpm = 1e308"), "{notes}");
    assert!(notes.contains("run 'val': fields separated by ';'"), "{notes}");
}
