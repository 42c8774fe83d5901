//! The desktop app's state machine, driven through egui_kittest (no display, no GPU).
#![cfg(feature = "gui")]
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};

use egui::accesskit::Role as A11yRole;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use jetid::core::run::RunRole;
use jetid::io::csv_run::{ColumnMap, LoadOptions};
use jetid::ui::state::session::{SavedSession, SessionRun};
use jetid::ui::{App, Command, Session, Tab};

/// A small valid run with canonical column names.
fn write_good_run(dir: &Path, name: &str) -> PathBuf {
    let mut text = String::from("time_s,fuel_flow_gph,shaft_speed_rpm,thrust_n,egt_c\n");
    for k in 0..40 {
        let t = f64::from(k) * 0.1;
        let u = if k < 10 { 2.0 } else { 4.0 };
        text += &format!("{t},{u},{},{},{}\n", 40000.0 + 5000.0 * u, 10.0 * u, 400.0 + f64::from(k));
    }
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// A run whose columns have non-canonical names: loads only with a column mapping.
fn write_unmapped_run(dir: &Path) -> PathBuf {
    let mut text = String::from("t,pump_v,rpm\n");
    for k in 0..40 {
        let u = if k < 20 { 1.0 } else { 2.0 };
        text += &format!("{},{u},{}\n", f64::from(k) * 0.05, 30000.0 + 10000.0 * u);
    }
    let path = dir.join("bench_export.csv");
    std::fs::write(&path, text).unwrap();
    path
}

fn session_with(paths: &[(&Path, RunRole)]) -> Session {
    let mut session = Session::default();
    for (path, role) in paths {
        session.runs.push(SessionRun::load(path, *role, LoadOptions::default()).expect("test run loads"));
    }
    session
}

fn harness(app: App) -> Harness<'static, App> {
    crate::common::app::harness_sized(app, [1200.0, 800.0])
}

#[test]
fn a_broken_file_shows_the_error_and_keeps_the_session() {
    let dir = tempfile::tempdir().unwrap();
    let good = write_good_run(dir.path(), "good.csv");
    let broken = dir.path().join("broken.csv");
    std::fs::write(&broken, "time_s,fuel_flow_gph,shaft_speed_rpm\n0.0,1.0,oops\n0.1,1.0,2.0\n").unwrap();

    let mut harness = harness(App::new(session_with(&[(&good, RunRole::Identification)])));
    harness.run();
    let revision = harness.state().session.revision;

    harness.state_mut().apply(Command::load(&broken, RunRole::Validation));
    harness.run();

    let app = harness.state();
    assert_eq!(app.session.runs.len(), 1, "the session keeps its runs");
    assert_eq!(app.session.runs[0].path, good);
    assert_eq!(app.session.revision, revision, "a failed load is not a session change");
    assert_eq!(app.view.failures.len(), 1);
    assert!(app.view.failures[0].message.contains("broken.csv"), "{}", app.view.failures[0].message);
    // The error window is on screen with the whole message.
    harness.get_by_label("Could not load run");
    harness.get_by_label(&app.view.failures[0].message);

    harness.get_by_label("Dismiss").click();
    harness.run();
    assert!(harness.state().view.failures.is_empty());
    assert!(harness.query_by_label("Could not load run").is_none());
}

#[test]
fn a_missing_file_is_an_error_too() {
    let dir = tempfile::tempdir().unwrap();
    let mut app = App::new(Session::default());
    app.apply(Command::load(dir.path().join("nope.csv"), RunRole::Identification));
    assert!(app.session.runs.is_empty());
    assert_eq!(app.session.revision, 0);
    assert_eq!(app.view.failures.len(), 1);
}

#[test]
fn a_role_change_goes_through_a_command_and_bumps_the_revision() {
    let dir = tempfile::tempdir().unwrap();
    let good = write_good_run(dir.path(), "good.csv");
    let mut harness = harness(App::new(session_with(&[(&good, RunRole::Identification)])));
    harness.run();
    let revision = harness.state().session.revision;

    // Open the role selector of the (only) run and pick "validation".
    harness.get_by_role_and_label(A11yRole::ComboBox, "role").click();
    harness.run();
    harness.get_by_label("validation").click();
    harness.run();

    let app = harness.state();
    assert_eq!(app.session.runs[0].role, RunRole::Validation);
    assert_eq!(app.session.revision, revision + 1);

    // Choosing the same role again changes nothing.
    let mut app = harness.into_state();
    app.apply(Command::SetRole(0, RunRole::Validation));
    assert_eq!(app.session.revision, revision + 1);
}

#[test]
fn a_column_mapping_retries_the_load() {
    let dir = tempfile::tempdir().unwrap();
    let unmapped = write_unmapped_run(dir.path());
    let mut harness = harness(App::new(Session::default()));
    harness.run();

    harness.state_mut().apply(Command::load(&unmapped, RunRole::Identification));
    harness.run();
    assert!(harness.state().session.runs.is_empty());
    assert!(harness.state().view.failures[0].column_problem, "{}", harness.state().view.failures[0].message);

    harness.get_by_label("Map columns…").click();
    harness.run();
    {
        let dialog = harness.state_mut().view.mapping.as_mut().expect("the mapping dialog is open");
        assert_eq!(dialog.headers.as_deref(), Ok(&["t".to_owned(), "pump_v".into(), "rpm".into()][..]));
        // Time and output are guessed from the names; the input is not, so Load is disabled.
        assert_eq!(dialog.time, Some(0));
        assert_eq!(dialog.outputs, vec![false, false, true]);
        assert!(dialog.options().is_err());
        dialog.input = Some(1);
    }
    harness.run();
    harness.get_by_label("Load").click();
    harness.run();

    let app = harness.state();
    assert!(app.view.mapping.is_none(), "the dialog closes");
    assert!(app.view.failures.is_empty(), "the failure is resolved");
    assert_eq!(app.session.runs.len(), 1);
    assert_eq!(app.session.revision, 1);
    let run = &app.session.runs[0];
    assert_eq!(run.run.input.name, "pump_v");
    assert_eq!(run.run.outputs[0].name, "rpm");
    assert_eq!(
        run.options.map,
        ColumnMap {
            time: Some("t".into()),
            input: Some("pump_v".into()),
            outputs: vec!["rpm".into()],
            aux: vec![]
        }
    );
}

#[test]
fn removing_runs_keeps_the_selection_valid() {
    let dir = tempfile::tempdir().unwrap();
    let a = write_good_run(dir.path(), "a.csv");
    let b = write_good_run(dir.path(), "b.csv");
    let mut app = App::new(session_with(&[(&a, RunRole::Identification), (&b, RunRole::Validation)]));
    app.apply(Command::SelectRun(1));
    app.apply(Command::RemoveRun(1));
    assert_eq!(app.view.selected_run, Some(0));
    assert_eq!(app.session.revision, 1);
    app.apply(Command::RemoveRun(0));
    assert_eq!(app.view.selected_run, None);
    app.apply(Command::RemoveRun(0));
    assert_eq!(app.session.revision, 2, "removing a run that is not there changes nothing");
}

#[test]
fn the_saved_session_restores_paths_roles_and_options() {
    let dir = tempfile::tempdir().unwrap();
    let a = write_good_run(dir.path(), "a.csv");
    let unmapped = write_unmapped_run(dir.path());
    let mut app = App::new(session_with(&[(&a, RunRole::Chirp)]));
    let options = LoadOptions {
        map: ColumnMap {
            time: Some("t".into()),
            input: Some("pump_v".into()),
            outputs: vec!["rpm".into()],
            aux: vec![],
        },
        ..LoadOptions::default()
    };
    app.apply(Command::LoadRun { path: unmapped.clone(), role: RunRole::Steady, options: options.clone() });
    assert_eq!(app.session.runs.len(), 2);

    let json = serde_json::to_string(&app.saved_session()).unwrap();
    let saved: SavedSession = serde_json::from_str(&json).unwrap();
    let restored = App::startup(Some(&saved));
    assert!(restored.view.failures.is_empty());
    let runs: Vec<_> =
        restored.session.runs.iter().map(|r| (r.path.clone(), r.role, r.options.clone())).collect();
    assert_eq!(runs, vec![(a, RunRole::Chirp, LoadOptions::default()), (unmapped, RunRole::Steady, options)]);
}

#[test]
fn a_saved_run_that_no_longer_loads_is_shown_and_still_saved() {
    let dir = tempfile::tempdir().unwrap();
    let a = write_good_run(dir.path(), "a.csv");
    let gone = write_good_run(dir.path(), "gone.csv");
    let saved = App::new(session_with(&[(&a, RunRole::Identification), (&gone, RunRole::Validation)]))
        .saved_session();
    std::fs::remove_file(&gone).unwrap();

    let app = App::startup(Some(&saved));
    assert_eq!(app.session.runs.len(), 1);
    assert_eq!(app.view.failures.len(), 1);
    assert_eq!(app.saved_session(), saved, "closing now loses nothing");
}

#[test]
fn the_data_view_draws_every_channel() {
    let dir = tempfile::tempdir().unwrap();
    let good = write_good_run(dir.path(), "good.csv");
    let mut harness = harness(App::new(session_with(&[(&good, RunRole::Identification)])));
    harness.run();
    assert_eq!(harness.state().view.tab, Tab::Data);
    assert_eq!(harness.state().cache.runs[0].traces.len(), 4, "input, two outputs, one aux");
    // The auxiliary channel is offered but hidden until asked for.
    harness.get_by_label("egt_c [°C]").click();
    harness.run();
    assert!(harness.state().view.views.data.shown_aux.contains("egt_c"));
}

#[test]
fn views_are_named_on_the_command_line() {
    for tab in Tab::ALL {
        assert_eq!(Tab::from_cli_name(tab.cli_name()), Some(tab));
    }
    assert_eq!(Tab::from_cli_name("DATA"), Some(Tab::Data));
    assert_eq!(Tab::from_cli_name("nope"), None);
}

#[test]
fn screenshots_are_written_as_png() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("shot.png");
    let mut image = egui::ColorImage::filled([4, 3], egui::Color32::from_rgb(10, 20, 30));
    image.pixels[0] = egui::Color32::WHITE;
    jetid::ui::screenshot::write_png(&out, &image).unwrap();
    let back = image::open(&out).unwrap().to_rgb8();
    assert_eq!(back.dimensions(), (4, 3));
    assert_eq!(back.get_pixel(0, 0).0, [255, 255, 255]);
    assert_eq!(back.get_pixel(3, 2).0, [10, 20, 30]);
    let leftovers: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(leftovers.len(), 1, "no temporary file left: {leftovers:?}");
}

/// The app on one good run in `dir`, with no native file dialog (as on a bare X server).
fn app_without_native_dialogs(dir: &Path) -> Harness<'static, App> {
    let good = write_good_run(dir, "good.csv");
    let mut app = App::new(session_with(&[(&good, RunRole::Identification)]));
    app.view.native_dialogs = false;
    let mut harness = harness(app);
    harness.run();
    harness
}

#[test]
fn without_a_native_dialog_save_project_asks_for_the_path_in_the_app() {
    let dir = tempfile::tempdir().unwrap();
    let mut harness = app_without_native_dialogs(dir.path());

    harness.get_by_label("File").click();
    harness.run();
    harness.get_by_label("Save project…").click();
    harness.run();

    // The window is prefilled with a project file beside the run.
    harness.get_by_label("Save project");
    let expected = dir.path().join("project.toml");
    let field = harness.get_by_role_and_label(A11yRole::TextInput, "Path");
    assert_eq!(field.value().as_deref(), Some(expected.display().to_string().as_str()));

    harness.get_by_label("OK").click();
    harness.run();
    let text = std::fs::read_to_string(&expected).expect("OK writes the project");
    assert!(text.contains("good.csv"), "{text}");
    assert!(harness.state().view.path_prompt.is_none(), "the window closes once written");
    assert!(harness.query_by_label("Save project").is_none());
    let status = harness.state().view.status.clone().unwrap_or_default();
    assert!(status.starts_with("Saved the project as"), "{status}");
}

#[test]
fn a_path_that_cannot_be_written_keeps_the_window_open_with_the_error() {
    let dir = tempfile::tempdir().unwrap();
    let mut harness = app_without_native_dialogs(dir.path());

    harness.state_mut().apply(Command::ChooseFile(jetid::ui::state::command::FileAction::ExportModel));
    harness.run();
    harness.get_by_label("Export model");
    // A folder under a file cannot be created.
    let blocked = dir.path().join("good.csv").join("model.json");
    harness.state_mut().view.path_prompt.as_mut().expect("the path window is open").text =
        blocked.display().to_string();
    harness.get_by_label("OK").click();
    harness.run();

    let prompt = harness.state().view.path_prompt.as_ref().expect("the window stays open");
    let error = prompt.error.clone().expect("the failure is shown");
    assert!(error.contains("exporting the model to"), "{error}");
    assert!(harness.query_by_label_contains("exporting the model to").is_some(), "the error is on screen");
    assert!(!blocked.exists());

    harness.get_by_label("Cancel").click();
    harness.run();
    assert!(harness.state().view.path_prompt.is_none());
    assert!(harness.query_by_label("Export model").is_none());
}

#[test]
fn a_restored_session_says_so_and_can_start_fresh() {
    let dir = tempfile::tempdir().unwrap();
    let a = write_good_run(dir.path(), "a.csv");
    let saved = App::new(session_with(&[(&a, RunRole::Identification)])).saved_session();

    let mut harness = harness(App::startup(Some(&saved)));
    harness.run();
    harness.get_by_label("Restored the last session (1 run) —");
    harness.get_by_label("Start fresh").click();
    harness.run();

    // The first start's session: the bundled sample runs.
    let fresh = App::startup(None);
    let paths = |app: &App| app.session.runs.iter().map(|r| r.path.clone()).collect::<Vec<_>>();
    assert_eq!(paths(harness.state()), paths(&fresh));
    assert!(!paths(harness.state()).contains(&a));
    assert!(harness.query_by_label_contains("Restored the last session").is_none(), "the notice goes");
    assert_eq!(harness.state().saved_session(), fresh.saved_session(), "the fresh session is saved on close");
}

#[test]
fn a_first_start_has_no_restore_notice_and_keep_hides_it() {
    let mut harness = harness(App::startup(None));
    harness.run();
    assert!(harness.query_by_label_contains("Restored the last session").is_none());

    let saved = harness.state().saved_session();
    let mut harness = self::harness(App::startup(Some(&saved)));
    harness.run();
    harness.get_by_label("Restored the last session (4 runs) —");
    harness.get_by_label("Keep").click();
    harness.run();
    assert!(harness.query_by_label_contains("Restored the last session").is_none());
    assert_eq!(harness.state().session.runs.len(), 4, "Keep keeps the session");
}
