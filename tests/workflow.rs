//! One workflow: the batch and the app build the same model from the same project; every
//! command-line option applies to the runs however they were named, or is refused with the reason;
//! a failed batch changes nothing in its `--out` folder.
use std::path::{Path, PathBuf};

use crate::common::{jetcat_batch, jetid, sample};

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn path(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn read_json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap()
}

/// Every file of `dir` with its bytes.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut files: Vec<(PathBuf, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .map(|p| {
            let bytes = std::fs::read(&p).unwrap();
            (p, bytes)
        })
        .collect();
    files.sort();
    files
}

// ------------------------------------------------------------------ overrides apply or are refused

#[test]
fn a_map_on_the_command_line_applies_to_the_projects_runs() {
    // The default project names its runs in the file; --map must reach them too.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let o = jetid(&["--batch", "--map", "input=egt_c", "--output", "shaft_speed_rpm", "--out", path(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let model = read_json(&out.join("model.json"));
    assert_eq!(model["input"]["name"], "egt_c", "the model is of the mapped input");
}

#[test]
fn a_map_that_clashes_with_the_projects_own_is_refused_with_the_columns() {
    // The JetCat-style project maps aux=egt_c already; mapping it as the input too gives one column
    // two roles: refused, naming it.
    let dir = tempfile::tempdir().unwrap();
    let project = dir.path().join("p.toml");
    let ident = sample("sr30/ident.csv");
    let text = format!("ident = '{}'\n[load]\nmap = ['aux=egt_c']\n", path(&ident));
    std::fs::write(&project, text).unwrap();
    let o = jetid(&["--batch", path(&project), "--map", "input=egt_c", "--out", path(&dir.path().join("o"))]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("egt_c") && err.contains("two roles"), "{err}");
    assert!(!dir.path().join("o").exists(), "a refused batch writes nothing");
}

#[test]
fn a_sample_time_on_the_command_line_applies_to_the_projects_runs() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let project = sample("hot_day/project.toml");
    let args = ["--batch", path(&project), "--sample-time", "0.2", "--output", "shaft_speed_rpm"];
    let o = jetid(&[&args[..], &["--out", path(&out)]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let model = read_json(&out.join("model.json"));
    assert!((model["dt_secs"].as_f64().unwrap() - 0.2).abs() < 1e-12, "{}", model["dt_secs"]);
    let report = read_json(&out.join("report.json"));
    let notes = report["diagnostics"].to_string();
    assert!(notes.contains("time_s") && notes.contains("sample time is given"), "{notes}");
}

#[test]
fn a_sample_time_for_runs_whose_time_column_is_mapped_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let project = dir.path().join("p.toml");
    let ident = sample("sr30/ident.csv");
    std::fs::write(&project, format!("ident = '{}'\n[load]\nmap = ['time=time_s']\n", path(&ident))).unwrap();
    let o = jetid(&["--batch", path(&project), "--sample-time", "0.2", "--out", path(&dir.path().join("o"))]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("time is given twice") && err.contains("time_s"), "{err}");
}

#[test]
fn batch_options_without_batch_are_refused() {
    let o = jetid(&["--ident", path(&sample("sr30/ident.csv")), "--out", "x"]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("--ident") && err.contains("--out") && err.contains("--batch"), "{err}");
    let o = jetid(&["--batch", "--screenshot", "x.png"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--screenshot"), "{}", stderr(&o));
    let o = jetid(&["--view", "bode"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--screenshot"), "{}", stderr(&o));
}

// ------------------------------------------------------------------ results as a set

#[test]
fn a_failed_batch_leaves_the_earlier_results_untouched_and_adds_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("mix");
    let o = jetid(&["--batch", path(&sample("hot_day/project.toml")), "--out", path(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let before = snapshot(&out);
    // The same runs, but the speed output's one cluster holds no segment root (a pole near −0.9),
    // so no model can be built from it: thrust succeeds, speed fails, the batch fails as a whole
    // after it has drawn thrust's figures into its staging folder.
    let project = dir.path().join("bad.toml");
    let text = format!(
        "ident = '{}'\nvalidate = ['{}']\n[output.shaft_speed_rpm]\nclusters = [{{ kind = 'Pole', centre = [-0.9, 0.0], radius = 0.001 }}]\n",
        path(&sample("hot_day/ident.csv")),
        path(&sample("hot_day/validation.csv"))
    );
    std::fs::write(&project, text).unwrap();
    let o = jetid(&["--batch", path(&project), "--out", path(&out)]);
    assert!(!o.status.success(), "the batch fails");
    assert_eq!(snapshot(&out), before, "not one file of the earlier results changed, none was added");
    let leftovers: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(leftovers.len(), 2, "no staging folder is left beside the results: {leftovers:?}");
}

#[test]
fn a_failed_batch_into_a_new_folder_creates_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("new/results");
    let project = dir.path().join("bad.toml");
    let cluster = "clusters = [{ kind = 'Pole', centre = [-0.9, 0.0], radius = 0.001 }]";
    let text = format!("ident = '{}'\n[output.thrust_n]\n{cluster}\n", path(&sample("sr30/ident.csv")));
    std::fs::write(&project, text).unwrap();
    let o = jetid(&["--batch", path(&project), "--out", path(&out)]);
    assert!(!o.status.success());
    let entries: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(entries, vec![std::ffi::OsString::from("bad.toml")], "nothing but the project");
}

// ------------------------------------------------------------------ the same model everywhere

#[cfg(feature = "gui")]
/// Every number of `a` and `b` agrees to `tolerance` (relative to the larger magnitude, at least 1)
/// and every other value is equal; `at` names where they differ.
fn assert_close(a: &serde_json::Value, b: &serde_json::Value, tolerance: f64, at: &str) {
    use serde_json::Value;
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            let scale = x.abs().max(y.abs()).max(1.0);
            assert!((x - y).abs() <= tolerance * scale, "{at}: {x} against {y}");
        }
        (Value::Array(x), Value::Array(y)) => {
            assert_eq!(x.len(), y.len(), "{at}: lengths");
            for (i, (x, y)) in x.iter().zip(y).enumerate() {
                assert_close(x, y, tolerance, &format!("{at}[{i}]"));
            }
        }
        (Value::Object(x), Value::Object(y)) => {
            let keys = |m: &serde_json::Map<String, Value>| m.keys().cloned().collect::<Vec<_>>();
            assert_eq!(keys(x), keys(y), "{at}: keys");
            for (k, v) in x {
                assert_close(v, &y[k], tolerance, &format!("{at}.{k}"));
            }
        }
        _ => assert_eq!(a, b, "{at}"),
    }
}

/// model.json of `project` from the batch, and from the app (File > Open project, every model
/// finished, File > Export model).
#[cfg(feature = "gui")]
fn both_models(project: &Path) -> (serde_json::Value, serde_json::Value) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("batch");
    let o = jetid(&["--batch", path(project), "--out", path(&out), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    (read_json(&out.join("model.json")), app_model(project))
}

/// model.json of `project` from the app: File > Open project, every model finished, File > Export
/// model.
#[cfg(feature = "gui")]
fn app_model(project: &Path) -> serde_json::Value {
    use jetid::ui::{App, Command, Session};
    let dir = tempfile::tempdir().unwrap();
    let mut app = App::new(Session::default());
    app.apply(Command::OpenProject(project.to_owned()));
    app.settle();
    let exported = dir.path().join("app.json");
    app.apply(Command::ExportModel(exported.clone()));
    assert!(app.view.errors.is_empty(), "{:?}", app.view.errors);
    read_json(&exported)
}

/// The batch and the app agree on every number of the model: roots, linear block, static map,
/// effects and their parameters (1e-9 relative).
#[cfg(feature = "gui")]
fn same_model_in_batch_and_app(project: &Path) {
    let (batch, app) = both_models(project);
    assert_close(&batch, &app, 1e-9, "model.json");
}

#[cfg(feature = "gui")]
#[test]
fn sr30_gives_the_same_model_in_the_batch_and_the_app() {
    same_model_in_batch_and_app(&sample("sr30/project.toml"));
}

#[cfg(feature = "gui")]
#[test]
fn hot_day_gives_the_same_model_in_the_batch_and_the_app() {
    same_model_in_batch_and_app(&sample("hot_day/project.toml"));
}

#[cfg(feature = "gui")]
#[test]
fn a_project_starting_from_a_saved_models_clusters_gives_the_same_model_in_the_batch_and_the_app() {
    // The clusters (and the input dead time) of hot_day's speed model, taken up by a project on the
    // same runs: the batch through `clusters_from`, the app through File > Open project.
    let dir = tempfile::tempdir().unwrap();
    let saved = dir.path().join("saved");
    let hot_day = sample("hot_day/project.toml");
    let args = ["--batch", path(&hot_day), "--output", "shaft_speed_rpm", "--quiet"];
    let o = jetid(&[&args[..], &["--out", path(&saved)]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let project = dir.path().join("from_saved.toml");
    let text = format!(
        "ident = '{}'\nvalidate = ['{}']\noutputs = ['shaft_speed_rpm']\nclusters_from = '{}'\n",
        path(&sample("hot_day/ident.csv")),
        path(&sample("hot_day/validation.csv")),
        path(&saved.join("model.json"))
    );
    std::fs::write(&project, text).unwrap();
    let (batch, app) = both_models(&project);
    assert_eq!(
        batch["outputs"][0]["clusters"],
        read_json(&saved.join("model.json"))["outputs"][0]["clusters"]
    );
    assert_close(&batch, &app, 1e-9, "model.json");
}

#[cfg(feature = "gui")]
#[test]
fn soak_gives_the_same_model_in_the_batch_and_the_app() {
    same_model_in_batch_and_app(&sample("soak/project.toml"));
}

#[cfg(feature = "gui")]
#[test]
fn soak_with_an_effect_and_the_loop_gives_the_same_model_in_the_batch_and_the_app() {
    // The soak project with an effect added by hand and one round of the missing-physics loop: the
    // app runs the same loop as the batch.
    let dir = tempfile::tempdir().unwrap();
    let project = dir.path().join("soak.toml");
    let text = format!(
        "ident = '{}'\nvalidate = ['{}']\noutputs = ['shaft_speed_rpm']\nadd_effects = ['thermal_soak']\nauto_effects = 1\n",
        path(&sample("soak/ident.csv")),
        path(&sample("soak/validation.csv"))
    );
    std::fs::write(&project, text).unwrap();
    let (batch, app) = both_models(&project);
    let effects = &batch["outputs"][0]["effects"];
    assert!(effects.as_array().is_some_and(|e| !e.is_empty()), "the model has effects: {effects}");
    assert_close(&batch, &app, 1e-9, "model.json");
}

/// Runs of a family engine with both outputs and the missing-physics loop: the shaft speed's spool
/// blocks are offered to thrust after both loops (`workflow::model::share_spool`), in the app as in
/// the batch.
#[cfg(feature = "gui")]
#[test]
fn shared_spool_blocks_give_the_same_model_in_the_batch_and_the_app() {
    // Engine 6 of the family: its thrust keeps the speed's time-constant schedule (its validation
    // run gives "no worse" p = 0.96). The soak sample's thrust no longer does, since each output
    // soaks its own power.
    let dir = tempfile::tempdir().unwrap();
    for (test, seed) in [("ident", "6"), ("validation", "1006")] {
        let run = dir.path().join(format!("{test}.csv"));
        let o = jetid(&["simulate", "--test", test, "--engine", "6", "--seed", seed, "--out", path(&run)]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let project = dir.path().join("engine6.toml");
    let text = "ident = 'ident.csv'\nvalidate = ['validation.csv']\noutputs = ['shaft_speed_rpm', 'thrust_n']\nauto_effects = 3\n";
    std::fs::write(&project, text).unwrap();
    let (batch, app) = both_models(&project);
    // Whatever thrust kept of the speed's spool blocks carries the speed's parameters exactly; the
    // test needs at least one, or it would not exercise the sharing.
    let effects = |i: usize| batch["outputs"][i]["effects"].as_array().cloned().unwrap_or_default();
    let shared = effects(1).into_iter().filter(|e| effects(0).contains(e)).count();
    assert!(
        shared > 0,
        "thrust shares none of the speed's blocks: {:?} against {:?}",
        effects(1),
        effects(0)
    );
    assert_close(&batch, &app, 1e-9, "model.json");
}

#[cfg(feature = "gui")]
#[test]
#[cfg_attr(not(jetid_realdata), ignore = "needs ../shared/realdata")]
fn the_jetcat_project_with_its_loop_gives_the_same_model_in_the_batch_and_the_app() {
    let batch = read_json(&jetcat_batch().join("model.json"));
    let app = app_model(&sample("jetcat_p300/project.toml"));
    let effects = &batch["outputs"][0]["effects"];
    assert!(effects.as_array().is_some_and(|e| !e.is_empty()), "the loop took effects: {effects}");
    assert_close(&batch, &app, 1e-9, "model.json");
}

/// The JetCat project's text (which names no `steps_from`) with its run paths made absolute,
/// written to `dir`: a closed-loop log whose set-point the user has not named.
fn jetcat_without_steps_from(dir: &Path) -> PathBuf {
    jetcat_with_steps_from(dir, None)
}

/// [`jetcat_without_steps_from`], with `steps_from = CHANNEL` when given.
fn jetcat_with_steps_from(dir: &Path, channel: Option<&str>) -> PathBuf {
    let project = sample("jetcat_p300/project.toml");
    let folder = project.parent().unwrap().to_str().unwrap().to_owned();
    let text = std::fs::read_to_string(&project).unwrap();
    assert!(!text.contains("steps_from ="), "the bundled project names no set-point");
    let mut text: String = text
        .lines()
        .map(|line| format!("{}\n", line.replace("path = \"../", &format!("path = \"{folder}/../"))))
        .collect();
    if let Some(channel) = channel {
        text = text.replacen("[load]", &format!("steps_from = \"{channel}\"\n\n[load]"), 1);
    }
    let path = dir.join(format!("jetcat_{}.toml", channel.unwrap_or("unnamed")));
    std::fs::write(&path, text).unwrap();
    path
}

/// A closed-loop log whose set-point is not named: the set-point is found in the log and the runs
/// are split on it, as on the channel the bundled project names, and the batch says so.
#[test]
#[cfg_attr(not(jetid_realdata), ignore = "needs ../shared/realdata")]
fn a_set_point_in_a_closed_loop_log_is_found_and_split_on() {
    use jetid::io::project::load_project;
    use jetid::workflow::runs::{StepsFrom, load_runs, segments};
    let dir = tempfile::tempdir().unwrap();
    let named = load_project(&jetcat_with_steps_from(dir.path(), Some("rpm_setpoint"))).unwrap();
    assert_eq!(named.steps_from.as_deref(), Some("rpm_setpoint"));
    let unnamed = load_project(&jetcat_without_steps_from(dir.path())).unwrap();
    assert_eq!(unnamed.steps_from, None);
    let (named_runs, runs) = (load_runs(&named).unwrap(), load_runs(&unnamed).unwrap());
    let StepsFrom::Found(found) = &runs.steps_from else {
        panic!("no set-point found: {:?}", runs.steps_from)
    };
    assert_eq!(found.channel, "rpm_setpoint", "{found:?}");
    assert!(runs.notes.iter().any(|n| n.contains("is a set-point")), "{:?}", runs.notes);
    let split = |r: &jetid::workflow::runs::Runs| {
        segments(&r.ident, &r.ident_junctions, None, r.steps_from.channel()).unwrap()
    };
    assert_eq!(split(&runs), split(&named_runs));
}

/// Where the steps come from a set-point found in the log, the report says how far the plain model
/// moves when they are found on the input instead: the second model is the one the input's steps
/// give, scored on every compared run. Open-loop runs, split on the input, carry no such line.
#[test]
#[cfg_attr(not(jetid_realdata), ignore = "needs ../shared/realdata")]
fn the_report_says_how_far_the_segmentation_channel_moves_the_plain_model() {
    use jetid::core::identification::pipeline::predict_scored;
    use jetid::io::project::load_project;
    use jetid::workflow::model::{OutputPlan, identify};
    use jetid::workflow::preparation::segmentation_choice;
    use jetid::workflow::runs::load_runs;
    let dir = tempfile::tempdir().unwrap();
    let project = load_project(&jetcat_without_steps_from(dir.path())).unwrap();
    let runs = load_runs(&project).unwrap();
    let plan = OutputPlan::of_project(&project, "rpm").with_steps_from(&runs.steps_from);
    let identified = identify(&runs.ident, &runs.ident_junctions, &plan).unwrap();
    let choice = segmentation_choice(&runs, &plan, &identified).unwrap();
    assert!(choice.found && choice.steps_from == "rpm_setpoint", "{choice:?}");
    let on_input =
        identify(&runs.ident, &runs.ident_junctions, &OutputPlan { steps_from: None, ..plan.clone() })
            .unwrap();
    let compared = runs.compared();
    assert_eq!(choice.runs.len(), compared.len(), "{choice:?}");
    for (both, run) in choice.runs.iter().zip(compared) {
        let rmse = |m: &jetid::core::identification::pipeline::Identified| {
            predict_scored(&m.model.wiener, run, "rpm", plan.settings.initial_state).unwrap().metrics.rmse
        };
        assert_eq!(both.run, run.name);
        assert!(
            (both.rmse - rmse(&identified)).abs() < 1e-9
                && (both.rmse_on_input - rmse(&on_input)).abs() < 1e-9
        );
    }
    let moved = choice.moved_pct.unwrap();
    assert!(moved.is_finite() && moved.abs() > 0.0, "{choice:?}");
    let words = choice.sentence("rpm");
    assert!(words.contains("rpm_setpoint") && words.contains(&format!("{moved:+.1} %")), "{words}");

    let sr30 = load_project(&sample("sr30/project.toml")).unwrap();
    let sr30_runs = load_runs(&sr30).unwrap();
    let plan = OutputPlan::of_project(&sr30, "shaft_speed_rpm").with_steps_from(&sr30_runs.steps_from);
    let identified = identify(&sr30_runs.ident, &sr30_runs.ident_junctions, &plan).unwrap();
    assert_eq!(segmentation_choice(&sr30_runs, &plan, &identified), None);
}

/// The same project without its set-point named: the app finds the set-point in the log and builds
/// the model the batch builds from the project that names it (the batch's own finding of it is
/// [`a_set_point_in_a_closed_loop_log_is_found_and_split_on`]: the same segments).
#[cfg(feature = "gui")]
#[test]
#[cfg_attr(not(jetid_realdata), ignore = "needs ../shared/realdata")]
fn the_jetcat_project_without_its_set_point_named_gives_the_same_model_in_the_batch_and_the_app() {
    let dir = tempfile::tempdir().unwrap();
    let app = app_model(&jetcat_without_steps_from(dir.path()));
    let batch = read_json(&jetcat_batch().join("model.json"));
    assert_close(&batch, &app, 1e-9, "model.json");
}

/// The bundled open-loop runs hold no set-point: their auxiliary channels are measured (noisy
/// temperatures and pressures), so the steps are found on the input as before.
#[test]
fn no_set_point_is_found_in_open_loop_runs() {
    use jetid::io::project::load_project;
    use jetid::workflow::runs::{StepsFrom, load_runs};
    for name in ["sr30", "hot_day", "soak"] {
        let runs = load_runs(&load_project(&sample(&format!("{name}/project.toml"))).unwrap()).unwrap();
        assert_eq!(runs.steps_from, StepsFrom::Input, "{name}");
    }
}
