//! The missing-physics loop in the desktop app, driven through egui_kittest on the real `App` and
//! the bundled sample runs: diagnose, apply the best effect, watch the error fall, remove it again.
//! The app is never told which effect the runs hide.
#![cfg(feature = "gui")]
#![allow(clippy::unwrap_used, clippy::expect_used)]

use egui::accesskit::Role as A11yRole;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use jetid::core::diagnose::{DiagnosisKind, TrialId};
use jetid::core::effects::{EffectId, StructuralChange};
use jetid::core::run::RunRole;
use jetid::ui::{App, Command, Session, Tab};

const SPEED: &str = "shaft_speed_rpm";

use crate::common::app::{harness, run_settled};
use crate::common::sample;

/// The app on a sample project, opened through the app's own command, on the Diagnosis view.
fn open_sample(project: &str) -> Harness<'static, App> {
    let mut app = App::new(Session::default());
    app.apply(Command::OpenProject(sample(project)));
    assert!(app.view.errors.is_empty(), "{:?}", app.view.errors);
    app.apply(Command::SelectOutput(SPEED.into()));
    app.apply(Command::ShowTab(Tab::Diagnosis));
    app.settle();
    let mut harness = harness(app);
    harness.run();
    finish_diagnosis(&mut harness);
    harness
}

/// Let the diagnosis job (started by the view) end and draw its result.
fn finish_diagnosis(harness: &mut Harness<'static, App>) {
    harness.state_mut().view.views.diagnosis.wait();
    harness.run();
}

/// The mean validation RMSPE of the speed model as the live model shows it.
fn live_rmspe(app: &App) -> f64 {
    let output = app.cache.output(SPEED).expect("speed is identified");
    output.live.as_ref().expect("a model").mean_validation_rmspe().expect("a validation run")
}

fn effects_in_setup(app: &App) -> Vec<String> {
    effect_names(app, SPEED)
}

fn effect_names(app: &App, output: &str) -> Vec<String> {
    app.session.setup.output(output).effects.iter().map(|id| id.name().to_owned()).collect()
}

#[test]
fn hot_day_ambient_correction_is_found_applied_and_removed() {
    let mut harness = open_sample("hot_day/project.toml");
    let before = live_rmspe(harness.state());
    {
        let state = &harness.state().view.views.diagnosis;
        let finished = state.result(SPEED).expect("the diagnosis ended");
        let report = finished.outcome.as_ref().expect("the diagnosis succeeded");
        let best = report.best().expect("effects were tried");
        assert_eq!(best.effect.name(), "ambient_correction");
        assert!(best.significant, "{best:?}");
        assert!((best.rmspe_before_pct - before).abs() < 1e-9 * before.max(1.0));
    }
    // The best effect's verdict is shown (the calibration drift, which a day's steady offset also
    // explains, may be significant too).
    assert!(harness.get_all_by_label("significant").next().is_some(), "no verdict 'significant' shown");

    // The first Apply button is the best-ranked effect's.
    let apply = harness.get_all_by_role_and_label(A11yRole::Button, "Apply").next().expect("Apply buttons");
    apply.click();
    run_settled(&mut harness);
    let app = harness.state();
    assert_eq!(effects_in_setup(app), vec!["ambient_correction".to_owned()]);
    let after = live_rmspe(app);
    assert!(after < 0.8 * before, "RMSPE {before} -> {after}");
    let live = app.cache.output(SPEED).unwrap().live.as_ref().unwrap();
    let history: Vec<(String, f64)> =
        live.effects.history.iter().map(|s| (s.step.clone(), s.rmspe_pct)).collect();
    assert_eq!(history.len(), 2, "{history:?}");
    assert_eq!(history[1].0, "+ambient_correction");
    assert!(history[1].1 < history[0].1, "{history:?}");
    assert!((history[1].1 - after).abs() < 1e-9 * after, "the history ends at the live error");
    assert!(live.runs.iter().all(|r| r.without_effects.is_some()));

    // The model file records the effect with its fitted parameters.
    let dir = tempfile::tempdir().unwrap();
    let model_path = dir.path().join("model.json");
    harness.state_mut().apply(Command::ExportModel(model_path.clone()));
    assert!(harness.state().view.errors.is_empty(), "{:?}", harness.state().view.errors);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&model_path).unwrap()).unwrap();
    let speed = json["outputs"].as_array().unwrap().iter().find(|o| o["name"] == SPEED).unwrap();
    assert_eq!(speed["effects"][0]["id"], "ambient_correction");
    assert!(speed["effects"][0]["params"].as_object().is_some_and(|p| !p.is_empty()));

    // The diagnosis is now stale; Remove takes the effect out and the error returns.
    harness.get_by_label("Re-run diagnosis");
    harness.get_by_role_and_label(A11yRole::Button, "Remove").click();
    run_settled(&mut harness);
    assert!(effects_in_setup(harness.state()).is_empty());
    let removed = live_rmspe(harness.state());
    assert!((removed - before).abs() < 1e-9 * before, "{before} vs {removed}");
    // Back at the diagnosed model, the diagnosis is current again.
    assert!(harness.query_by_label("Re-run diagnosis").is_none());

    // Undo brings the effect back, undo again is the state before it was applied.
    harness.state_mut().apply(Command::Undo);
    run_settled(&mut harness);
    assert_eq!(effects_in_setup(harness.state()), vec!["ambient_correction".to_owned()]);
    assert!((live_rmspe(harness.state()) - after).abs() < 1e-9 * after);
    harness.get_by_label("Re-run diagnosis");
    harness.state_mut().apply(Command::Undo);
    run_settled(&mut harness);
    assert!(effects_in_setup(harness.state()).is_empty());
    assert!((live_rmspe(harness.state()) - before).abs() < 1e-9 * before);
    assert!(harness.query_by_label("Re-run diagnosis").is_none(), "no stale banner after the Undo");
    assert!(harness.query_by_label_contains("the ranking below is stale").is_none());
    harness.get_by_label("Run again");
}

#[test]
fn the_bundled_sr30_runs_hide_no_effect() {
    let mut app = App::startup(None);
    app.apply(Command::SelectOutput(SPEED.into()));
    app.apply(Command::ShowTab(Tab::Diagnosis));
    app.settle();
    let mut harness = harness(app);
    harness.run();
    finish_diagnosis(&mut harness);
    let state = &harness.state().view.views.diagnosis;
    let report = state.result(SPEED).unwrap().outcome.as_ref().unwrap();
    assert!(!report.entries.is_empty());
    // A structural refinement may be needed; no physical effect is.
    let physics: Vec<&str> = report
        .entries
        .iter()
        .filter(|d| d.significant && d.kind == DiagnosisKind::Physics)
        .map(|d| d.effect.name())
        .collect();
    assert!(physics.is_empty(), "{physics:?}");
    assert!(harness.query_by_label("significant").is_none());
}

#[test]
fn a_run_without_the_channels_an_effect_needs_is_a_shown_error() {
    let dir = tempfile::tempdir().unwrap();
    // The hot-day validation run without its ambient columns.
    let text = std::fs::read_to_string(sample("hot_day/validation.csv")).unwrap();
    let stripped: String =
        text.lines().map(|line| line.split(',').take(5).collect::<Vec<_>>().join(",") + "\n").collect();
    let bare = dir.path().join("validation_no_ambient.csv");
    std::fs::write(&bare, stripped).unwrap();

    let mut app = App::new(Session::default());
    app.apply(Command::load(sample("hot_day/ident.csv"), RunRole::Identification));
    app.apply(Command::load(&bare, RunRole::Validation));
    app.apply(Command::ApplyEffect {
        output: SPEED.into(),
        trial: TrialId::Effect(EffectId::AmbientCorrection),
    });
    app.apply(Command::ShowTab(Tab::Traces));
    app.settle();
    let mut harness = harness(app);
    harness.run();
    let live = harness.state().cache.output(SPEED).unwrap().live.as_ref().unwrap();
    assert!(live.effects.model.is_some(), "the effect is fitted on the identification run");
    let problem = live.effects.problems.first().expect("the problem is recorded").clone();
    assert!(problem.contains("ambient_temp_c"), "{problem}");
    harness.get_by_label(&format!("Effects: {problem}"));

    // A refinement of the linear block is no block to add: an error that says where to make it is
    // shown, the setup stays as it was.
    let pair = TrialId::Structure(StructuralChange::PolePair);
    harness.state_mut().apply(Command::ApplyEffect { output: SPEED.into(), trial: pair });
    run_settled(&mut harness);
    assert_eq!(effects_in_setup(harness.state()), vec!["ambient_correction".to_owned()]);
    assert!(
        harness.state().view.errors.iter().any(|e| e.contains("extra_pole_pair") && e.contains("z-plane"))
    );
}

#[test]
fn a_clicked_worst_stretch_shows_that_window_in_the_traces_view() {
    let mut harness = open_sample("soak/project.toml");
    harness.get_by_label("Where it fails").click();
    run_settled(&mut harness);
    let (index, first) = {
        let state = &harness.state().view.views.diagnosis.residuals;
        let analyses = state.current().expect("the residuals are analysed");
        let run = analyses.runs.first().expect("a scored run");
        let stretch = run.analysis.as_ref().unwrap().worst_stretches.first().cloned().expect("stretches");
        (run.index, stretch)
    };
    let label = format!("1. {:.1}–{:.1} s", first.start_secs, first.end_secs);
    harness.get_by_label(&label).click();
    run_settled(&mut harness);
    let app = harness.state();
    assert_eq!(app.view.tab, Tab::Traces);
    let traces = &app.view.views.traces;
    assert_eq!(traces.run, Some(index));
    assert_eq!(traces.focus_window, Some((first.start_secs, first.end_secs)));
    harness.get_by_label("Reset zoom").click();
    run_settled(&mut harness);
    assert_eq!(harness.state().view.views.traces.focus_window, None);
}

#[test]
fn soak_speed_ranks_thermal_soak_first_and_a_screenshot_app_can_apply_it() {
    let harness = open_sample("soak/project.toml");
    let report =
        harness.state().view.views.diagnosis.result(SPEED).unwrap().outcome.as_ref().unwrap().clone();
    assert_eq!(report.best().unwrap().effect.name(), "thermal_soak");
    let before = live_rmspe(harness.state());

    // What `jetid --screenshot OUT --view diagnosis PROJECT --add-effect ID` shows.
    let app =
        jetid::ui::screenshot::screenshot_app(Some(&sample("soak/project.toml")), &[EffectId::ThermalSoak])
            .unwrap();
    assert_eq!(effects_in_setup(&app), vec!["thermal_soak".to_owned()]);
    // The status bar names every output the effect went to, not only the last one.
    assert_eq!(
        app.view.status.as_deref(),
        Some("Effect thermal_soak applied to shaft_speed_rpm and thrust_n")
    );
    let after = live_rmspe(&app);
    assert!(after < before, "{before} -> {after}");
    // An unknown id never reaches the app: the command line refuses it (see batch_cli).
    assert!("warp_drive".parse::<EffectId>().is_err());
}

#[test]
fn effects_are_saved_in_the_project_file_and_opened_again() {
    let dir = tempfile::tempdir().unwrap();
    let mut app = App::new(Session::default());
    app.apply(Command::load(sample("hot_day/ident.csv"), RunRole::Identification));
    app.apply(Command::load(sample("hot_day/validation.csv"), RunRole::Validation));
    for output in [SPEED, "thrust_n"] {
        app.apply(Command::ApplyEffect {
            output: output.into(),
            trial: TrialId::Effect(EffectId::AmbientCorrection),
        });
    }
    let project = dir.path().join("hot.toml");
    app.apply(Command::SaveProject(project.clone()));
    assert!(app.view.errors.is_empty(), "{:?}", app.view.errors);
    let text = std::fs::read_to_string(&project).unwrap();
    assert!(text.contains("add_effects = [\"ambient_correction\"]"), "{text}");

    let mut reopened = App::new(Session::default());
    reopened.apply(Command::OpenProject(project));
    assert_eq!(effects_in_setup(&reopened), vec!["ambient_correction".to_owned()]);
    assert_eq!(effect_names(&reopened, "thrust_n"), vec!["ambient_correction".to_owned()]);

    // Effects that differ between the outputs cannot all be written: the status says which.
    app.apply(Command::ApplyEffect { output: SPEED.into(), trial: TrialId::Effect(EffectId::ThermalSoak) });
    app.apply(Command::SaveProject(dir.path().join("mixed.toml")));
    let status = app.view.status.clone().unwrap_or_default();
    assert!(status.contains("thermal_soak was not saved"), "{status}");
}
