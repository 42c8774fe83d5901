//! The History view driven through egui_kittest on a tiny simulated fleet (2 engines × 4 short runs,
//! references as model.json): the engines listed with their flagged runs, a clicked run against its
//! reference, an unreadable manifest shown in the view with the session left as it was, and
//! `--fleet` refused with `--batch`.
#![cfg(feature = "gui")]
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;

use jetid::cli::simulate_fleet::{ReferenceArg, SimulateFleetArgs};
use jetid::core::run::RunRole;
use jetid::ui::views::history::HistoryStatus;
use jetid::ui::{App, Command, Session, Tab};

/// The tiny fleet's manifest, simulated once for every test here.
fn tiny_fleet() -> &'static Path {
    static FLEET: OnceLock<PathBuf> = OnceLock::new();
    FLEET.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("history-fleet");
        let _ = std::fs::remove_dir_all(&dir);
        let args = SimulateFleetArgs {
            engines: 2,
            runs: 4,
            seed: 5,
            run_secs: 100.0,
            fault_rate: 0.3,
            reference: ReferenceArg::Model,
            out: dir.clone(),
        };
        jetid::cli::simulate_fleet::run(&args).unwrap();
        dir.join("manifest.toml")
    })
}

/// An app on one validation run (no identification, so no background model work), under a harness.
fn app_with_a_run() -> Harness<'static, App> {
    let mut app = App::new(Session::default());
    app.apply(Command::load(crate::common::sample("sr30/validation.csv"), RunRole::Validation));
    assert_eq!(app.session.runs.len(), 1, "{:?}", app.view.failures);
    crate::common::app::harness(app)
}

/// Open `manifest` as File > Open fleet manifest… does, and wait for the fleet.
fn open_fleet(harness: &mut Harness<'_, App>, manifest: &Path) {
    harness.state_mut().apply(Command::OpenFleet(manifest.to_owned()));
    assert_eq!(harness.state().view.tab, Tab::History);
    harness.step();
    // Loading, or already done (a bad manifest fails at once).
    assert_ne!(harness.state().view.views.history.status(), HistoryStatus::Empty);
    harness.state_mut().view.views.history.wait();
    harness.run();
}

/// Draw the frames a click takes (the run it opens is simulated on a worker: wait for it after each
/// frame), then draw the result.
fn settle(harness: &mut Harness<'_, App>) {
    for _ in 0..6 {
        harness.step();
        harness.state_mut().view.views.history.wait();
    }
    harness.run();
}

#[test]
fn app_history_lists_engines_flags_runs_and_opens_a_clicked_run_against_its_reference() {
    let mut harness = app_with_a_run();
    let revision = harness.state().session.revision;
    open_fleet(&mut harness, tiny_fleet());
    assert_eq!(harness.state().view.views.history.status(), HistoryStatus::Ready);

    // Every engine listed with its flagged-run count.
    let (names, flagged): (Vec<String>, Vec<(usize, usize, String)>) = {
        let fleet = harness.state().view.views.history.fleet().unwrap();
        assert_eq!(fleet.engines.len(), 2);
        let names = fleet.engines.iter().map(|e| e.name.clone()).collect();
        let flagged = fleet
            .engines
            .iter()
            .enumerate()
            .flat_map(|(e, engine)| {
                engine
                    .runs
                    .iter()
                    .enumerate()
                    .filter(|(_, r)| r.flagged())
                    .map(move |(r, run)| (e, r, run.reasons.first().cloned().unwrap_or_default()))
            })
            .collect();
        (names, flagged)
    };
    for name in &names {
        harness.get_by_label_contains(&format!("{name}: "));
    }
    assert!(!flagged.is_empty(), "the tiny fleet has a flagged run (fault rate 0.3)");

    // The flagged run's engine: its row says why in words.
    let (engine, run, reason) = flagged[0].clone();
    harness.get_by_label_contains(&format!("{}: ", names[engine])).click();
    harness.run();
    assert_eq!(harness.state().view.views.history.engine, engine);
    assert!(!harness.query_all_by_label_contains(&reason).collect::<Vec<_>>().is_empty(), "{reason}");

    // A click on the run's name opens it against its reference.
    let run_name =
        harness.state().view.views.history.fleet().unwrap().engines[engine].runs[run].run.name.clone();
    harness.get_by_label(&run_name).click();
    settle(&mut harness);
    let history = &harness.state().view.views.history;
    assert_eq!(history.run, Some(run));
    let comparison = history.comparison().unwrap().as_ref().unwrap();
    assert_eq!(comparison.run, run_name);
    assert!(!comparison.outputs.is_empty());
    for trace in &comparison.outputs {
        assert_eq!(trace.measured.len(), trace.predicted.len());
        assert_eq!(trace.measured.len(), comparison.t_secs.len());
        assert!(trace.rmse.is_finite());
    }
    harness.get_by_label_contains(&format!("Run {run_name} ("));
    let plotted = harness.query_all_by_label_contains("measured and the reference's prediction").count();
    assert_eq!(plotted, comparison.outputs.len(), "one plot per output");
    assert!(!harness.query_all_by_label_contains(&format!("• {reason}")).collect::<Vec<_>>().is_empty());

    // The session's runs and model are untouched.
    assert_eq!(harness.state().session.revision, revision);
    assert_eq!(harness.state().session.runs.len(), 1);
}

#[test]
fn app_history_shows_an_unreadable_manifest_in_the_view_and_keeps_the_session() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("history-bad-manifest");
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("manifest.toml");
    std::fs::write(&bad, "this is [ not a manifest").unwrap();
    let mut harness = app_with_a_run();
    let revision = harness.state().session.revision;
    let run_path = harness.state().session.runs[0].path.clone();
    open_fleet(&mut harness, &bad);
    let HistoryStatus::Failed(message) = harness.state().view.views.history.status() else {
        panic!("{:?}", harness.state().view.views.history.status());
    };
    assert!(message.contains("manifest.toml"), "{message}");
    harness.get_by_label_contains("Could not open the fleet");
    assert!(harness.state().view.errors.is_empty(), "shown in the view, not the error window");
    assert_eq!(harness.state().session.revision, revision);
    assert_eq!(harness.state().session.runs.len(), 1);
    assert_eq!(harness.state().session.runs[0].path, run_path);

    // A missing file too, and the view still answers.
    open_fleet(&mut harness, &dir.join("absent.toml"));
    assert!(matches!(harness.state().view.views.history.status(), HistoryStatus::Failed(_)));
    harness.get_by_label("Open fleet manifest…");
}

#[test]
fn app_history_fleet_is_refused_with_batch() {
    let out = crate::common::jetid(&["--batch", "--fleet", "manifest.toml"]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("--fleet") && stderr.contains("--batch"), "{stderr}");
}

#[test]
fn app_history_file_menu_opens_a_fleet_through_the_path_field_without_a_native_dialog() {
    let mut harness = app_with_a_run();
    harness.state_mut().view.native_dialogs = false;
    harness.run();
    harness.get_by_label("File").click();
    harness.run();
    harness.get_by_label("Open fleet manifest…").click();
    harness.run();

    // The in-app path field asks for the manifest; OK computes the fleet in the History view.
    harness.get_by_label("Open fleet manifest");
    harness.state_mut().view.path_prompt.as_mut().expect("the path window is open").text =
        tiny_fleet().display().to_string();
    harness.get_by_label("OK").click();
    harness.run();
    assert!(harness.state().view.path_prompt.is_none(), "the window closes");
    assert_eq!(harness.state().view.tab, Tab::History);
    harness.state_mut().view.views.history.wait();
    harness.run();
    assert_eq!(harness.state().view.views.history.status(), HistoryStatus::Ready);
    harness.get_by_label_contains("e001: ");
}

#[test]
fn app_history_a_click_on_a_trend_point_opens_that_run() {
    let mut harness = app_with_a_run();
    open_fleet(&mut harness, tiny_fleet());
    let transform = harness.state().view.views.history.last_trend_transform.expect("the trends were drawn");
    let (run, gain) = {
        let engine = &harness.state().view.views.history.fleet().unwrap().engines[0];
        let run = engine.runs.len() - 1;
        (run, engine.runs[run].score.input_gain.expect("the input gain was fitted").value)
    };
    let at = transform.position_from_point(&egui_plot::PlotPoint::new(run as f64, gain));
    harness.hover_at(at);
    harness.step();
    harness.drag_at(at);
    harness.step();
    harness.drop_at(at);
    settle(&mut harness);
    let history = &harness.state().view.views.history;
    assert_eq!(history.run, Some(run));
    let comparison = history.comparison().map(|c| c.as_ref().map(|c| c.run.clone()));
    assert!(matches!(comparison, Some(Ok(_))), "{comparison:?}");
}
