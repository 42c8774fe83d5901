//! The Compare view driven through egui_kittest on the bundled sample runs: the background job,
//! its progress, cancel and restart, stale results, the missing steady run, and the chirp's
//! measured points on the Bode view.
#![cfg(feature = "gui")]
#![allow(clippy::unwrap_used, clippy::expect_used)]

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use std::sync::Arc;
use std::time::Duration;

use jetid::core::compare::{Cancelled, CompareInput, Curve, ModelKind, compare_output, compare_stage};
use jetid::core::diagnose::TrialId;
use jetid::core::effects::EffectId;
use jetid::core::numerics::metrics::metrics;
use jetid::core::run::RunRole;
use jetid::ui::views::compare::CompareStatus;
use jetid::ui::views::compare::table::{MODELS, table1_columns};
use jetid::ui::{App, Command, Tab};

const GRAY_BOX: ModelKind = ModelKind::GrayBox;
const LINEAR: ModelKind = ModelKind::Linear;
const HAMMERSTEIN_WIENER: ModelKind = ModelKind::HammersteinWiener;
const NNARX: ModelKind = ModelKind::Nnarx;

const SPEED: &str = "shaft_speed_rpm";
/// Frames stepped (with a short sleep each) before a job is declared stuck: minutes, not a timing goal.
const MAX_FRAMES: usize = 12_000;

fn sample_harness(tab: Tab) -> Harness<'static, App> {
    let mut harness = crate::common::app::sample_app(tab);
    harness.step();
    harness
}

fn status(harness: &Harness<'_, App>) -> CompareStatus {
    harness.state().view.views.compare.status(SPEED)
}

/// Step frames until the speed comparison is no longer running.
fn wait_for_job(harness: &mut Harness<'_, App>) {
    for _ in 0..MAX_FRAMES {
        if !matches!(status(harness), CompareStatus::Running(_)) {
            harness.step();
            return;
        }
        std::thread::sleep(Duration::from_millis(20));
        harness.step();
    }
    panic!("the comparison did not finish within {MAX_FRAMES} frames");
}

#[test]
fn showing_compare_starts_a_job_with_progress_and_fills_table_1() {
    let mut harness = sample_harness(Tab::Compare);
    assert!(matches!(status(&harness), CompareStatus::Running(_)), "{:?}", status(&harness));
    harness.get_by_label("Cancel");
    wait_for_job(&mut harness);
    assert_eq!(status(&harness), CompareStatus::Done);

    let app = harness.state();
    let result = app.view.views.compare.result(SPEED).expect("a result");
    assert_eq!(app.view.views.compare.result_is_current(SPEED, &app.session, &app.cache), Some(true));
    let comparison = &result.comparison;
    assert!(comparison.notes.is_empty(), "{:?}", comparison.notes);
    let columns = table1_columns(comparison);
    let rmspe = columns.iter().find(|c| c.group == "validation" && c.what == "RMSPE %").expect("a column");
    assert!(rmspe.values.iter().all(Option::is_some), "all four models on the validation run: {rmspe:?}");

    // The gray-box figure equals the metrics of the model view's own prediction of the run.
    let live = app.cache.output(SPEED).unwrap().live.as_ref().unwrap();
    let scored = live.runs.iter().find(|r| r.role == RunRole::Validation).unwrap();
    let run = &app.session.runs[scored.index].run;
    let measured = &run.output(SPEED).unwrap().values;
    let expected = metrics(measured, &scored.gray_box.y_hat).unwrap();
    let gray_row = MODELS.iter().position(|m| *m == GRAY_BOX).unwrap();
    let shown = rmspe.values[gray_row].unwrap();
    assert!(
        (shown - expected.rmspe_pct).abs() <= 1e-9 * expected.rmspe_pct,
        "{shown} vs {}",
        expected.rmspe_pct
    );
    let linear = scored.linear.as_ref().unwrap().metrics.rmspe_pct;
    let linear_row = MODELS.iter().position(|m| *m == LINEAR).unwrap();
    assert!((rmspe.values[linear_row].unwrap() - linear).abs() <= 1e-9 * linear);

    // Every baseline is simulated on the validation and the chirp run, and studied by Monte Carlo.
    assert_eq!(comparison.runs.len(), 2);
    for name in [GRAY_BOX, LINEAR, HAMMERSTEIN_WIENER, NNARX] {
        assert!(comparison.runs.iter().all(|r| r.models.iter().any(|m| m.model == name)), "{name}");
        let mc = comparison.monte_carlo.get(&name).expect("a Monte Carlo study");
        assert!(mc.std_difference > 0.0 && mc.std_difference.is_finite());
        assert_eq!(mc.histogram.counts.iter().sum::<usize>(), mc.differences.len());
    }
    let freq = comparison.frequency.as_ref().expect("the chirp's frequency comparison");
    assert!(
        freq.responses.contains_key(&Curve::Measured) && freq.responses.contains_key(&Curve::Model(NNARX))
    );
    assert!(comparison.noise.as_ref().is_some_and(|n| n.used.is_some()));
    // The table is on screen with the paper's values beside ours.
    assert!(harness.query_all_by_label("Hammerstein–Wiener").count() >= 1);
    // The simple references are rows of the same table.
    for reference in ["ARX(2,2)", "Hammerstein ARX", "static cubic"] {
        assert!(harness.query_all_by_label(reference).count() >= 1, "{reference}");
    }
    assert!(harness.query_all_by_label("1.3429").count() >= 1);
    // The notes under the table wrap at its width, so the summary beside it stays in the window
    // and the plots follow below.
    let width = harness.ctx.content_rect().width();
    let summary = harness.get_by_label_contains("cut-off on");
    assert!(summary.rect().max.x <= width, "the summary ends at {} of {width} px", summary.rect().max.x);
    harness.get_by_label("Traces on run:");
    harness.get_by_label_contains("Monte Carlo error propagation");
}

#[test]
fn cancel_leaves_no_result_and_run_again_restarts() {
    let mut harness = sample_harness(Tab::Compare);
    assert!(matches!(status(&harness), CompareStatus::Running(_)));
    harness.get_by_label("Cancel").click();
    harness.step();
    assert_eq!(status(&harness), CompareStatus::Cancelled);
    assert!(harness.state().view.views.compare.result(SPEED).is_none());
    // A cancelled comparison is not restarted by itself.
    for _ in 0..5 {
        harness.step();
    }
    assert_eq!(status(&harness), CompareStatus::Cancelled);
    harness.get_by_label("Run again").click();
    harness.step();
    assert!(matches!(status(&harness), CompareStatus::Running(_)), "{:?}", status(&harness));
    wait_for_job(&mut harness);
    assert_eq!(status(&harness), CompareStatus::Done);
    assert!(harness.state().view.views.compare.result(SPEED).is_some());
}

#[test]
fn changing_the_clusters_marks_the_result_stale_until_recomputed() {
    let mut harness = sample_harness(Tab::Compare);
    wait_for_job(&mut harness);
    // Drop one cluster (the first whose removal still leaves a model, a different one).
    let clusters = harness.state().cache.output(SPEED).unwrap().clusters.clone();
    let before = harness.state().cache.output(SPEED).unwrap().live.as_ref().unwrap().model.wiener.clone();
    let changed = (0..clusters.len()).any(|drop| {
        let mut fewer = clusters.clone();
        fewer.remove(drop);
        harness.state_mut().apply(Command::SetClusters { output: SPEED.into(), clusters: Some(fewer) });
        harness.step();
        // The committed model is polished on a worker thread: wait for it.
        harness.state_mut().settle();
        harness.step();
        let live = harness.state().cache.output(SPEED).unwrap().live.as_ref();
        live.is_ok_and(|l| l.model.wiener != before)
    });
    assert!(changed, "some cluster change gives another model");
    let app = harness.state();
    assert_ne!(app.view.views.compare.result_is_current(SPEED, &app.session, &app.cache), Some(true));
    // Still shown, not restarted by itself.
    assert_eq!(status(&harness), CompareStatus::Done);
    harness.get_by_label("Recompute").click();
    harness.step();
    assert!(matches!(status(&harness), CompareStatus::Running(_)));
    wait_for_job(&mut harness);
    let app = harness.state();
    assert_eq!(app.view.views.compare.result_is_current(SPEED, &app.session, &app.cache), Some(true));
}

#[test]
fn without_a_steady_run_monte_carlo_is_skipped_and_said_so() {
    let mut harness = sample_harness(Tab::Data);
    let steady = harness.state().session.first_with_role(RunRole::Steady).unwrap();
    harness.state_mut().apply(Command::RemoveRun(steady));
    harness.state_mut().apply(Command::ShowTab(Tab::Compare));
    harness.step();
    wait_for_job(&mut harness);
    let comparison = &harness.state().view.views.compare.result(SPEED).expect("a result").comparison;
    assert!(comparison.monte_carlo.is_empty());
    assert!(comparison.noise.is_none());
    // Everything else is still there.
    assert_eq!(comparison.runs.len(), 2);
    assert!(comparison.frequency.is_some());
    assert!(harness.query_all_by_label_contains("No steady run").count() >= 1);
}

#[test]
fn the_bode_view_has_the_chirps_measured_points() {
    let mut harness = sample_harness(Tab::Bode);
    harness.step();
    let app = harness.state();
    let output = app.cache.output(SPEED).unwrap();
    let points = &output.empirical_bode.points;
    assert!(points.len() >= 20, "a few dozen points in the chirp band, got {}", points.len());
    assert!(points.iter().all(|p| (0.0..=1.0).contains(&p.3)), "coherence in [0, 1]");
    assert!(points.windows(2).all(|w| w[0].0 < w[1].0), "increasing frequency");
    // The chirp excites 0.57–13.8 rad/s; the points lie in (about) that band.
    assert!(points.first().unwrap().0 < 1.0 && points.last().unwrap().0 > 8.0);
    // At the lowest frequency the measurement is within a few dB of the reduced model.
    let live = output.live.as_ref().unwrap();
    let (omega, mag_db, ..) = points[0];
    let model = live.model.wiener.linear.tf.bode_response(&[omega])[0].mag_db;
    assert!((mag_db - model).abs() < 3.0, "measured {mag_db:.2} dB, model {model:.2} dB at {omega:.3} rad/s");
}

#[test]
fn removing_the_chirp_run_clears_the_measured_points() {
    let mut harness = sample_harness(Tab::Bode);
    let chirp = harness.state().session.first_with_role(RunRole::Chirp).unwrap();
    assert!(!harness.state().cache.output(SPEED).unwrap().empirical_bode.points.is_empty());
    harness.state_mut().apply(Command::RemoveRun(chirp));
    harness.step();
    assert!(harness.state().cache.output(SPEED).unwrap().empirical_bode.points.is_empty());
}

/// The comparison's input for the speed output of the bundled samples, built from the app's cache.
fn speed_input() -> CompareInput {
    let mut app = App::startup(None);
    app.settle();
    let ident = app.cache.ident.as_ref().unwrap();
    let output = ident.output(SPEED).unwrap();
    let live = output.live.as_ref().unwrap();
    let scored = live
        .runs
        .iter()
        .map(|r| (Arc::clone(&app.session.runs[r.index].run), r.role == RunRole::Chirp))
        .collect();
    let steady = app.session.first_with_role(RunRole::Steady).map(|i| Arc::clone(&app.session.runs[i].run));
    CompareInput {
        output: SPEED.into(),
        ident: Arc::clone(&ident.run),
        fits: Arc::clone(output.fits.as_ref().unwrap()),
        wiener: live.model.wiener.clone(),
        scored,
        steady,
        extended: None,
        initial_state: output.setup.settings.initial_state,
    }
}

#[test]
fn the_comparison_reports_rising_progress_through_every_stage_and_stops_when_told() {
    let input = speed_input();
    let mut seen = Vec::new();
    let comparison = compare_output(&input, &mut |fraction| {
        seen.push(fraction);
        true
    })
    .unwrap();
    assert_eq!(comparison.monte_carlo.len(), 4);
    let back: Vec<_> = seen.windows(2).filter(|w| w[0] > w[1]).collect();
    assert!(back.is_empty(), "progress never goes back: {back:?}");
    assert!(seen.iter().all(|f| (0.0..=1.0).contains(f)));
    assert_eq!(seen.last().copied(), Some(1.0));
    let stages: std::collections::BTreeSet<&str> = seen.iter().map(|f| compare_stage(*f)).collect();
    assert_eq!(stages.len(), 3, "the baselines and the Monte Carlo study each report: {stages:?}");

    // Told to stop during the NNARX training, it stops there.
    let mut last = 0.0;
    let stopped = compare_output(&input, &mut |fraction| {
        last = fraction;
        fraction < 0.5
    });
    assert_eq!(stopped.err(), Some(Cancelled));
    assert!(last < 0.8, "stopped before the Monte Carlo study, at {last}");
}

#[test]
fn with_an_effect_applied_the_gray_box_row_is_the_model_with_its_effect() {
    let project = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("sample_runs/soak/project.toml");
    let mut app = App::new(jetid::ui::Session::default());
    app.apply(Command::OpenProject(project));
    app.settle();
    app.apply(Command::ApplyEffect { output: SPEED.into(), trial: TrialId::Effect(EffectId::ThermalSoak) });
    // The effect is refitted on a worker thread: wait for the finished model.
    app.settle();
    app.view.output = Some(SPEED.into());
    app.view.tab = Tab::Compare;
    let mut harness = Harness::builder()
        .with_size(egui::vec2(1400.0, 900.0))
        .build_ui_state(|ui, app: &mut App| app.ui(ui), app);
    harness.step();
    wait_for_job(&mut harness);
    assert_eq!(status(&harness), CompareStatus::Done);

    let app = harness.state();
    let live = app.cache.output(SPEED).unwrap().live.as_ref().unwrap();
    let scored = live.runs.iter().find(|r| r.role == RunRole::Validation).unwrap();
    let with_effect = scored.gray_box.metrics.rmspe_pct;
    let without = scored.without_effects.as_ref().expect("the model has an effect").metrics.rmspe_pct;
    assert!(with_effect < without, "the soak lowers the error: {without} -> {with_effect}");
    let comparison = &app.view.views.compare.result(SPEED).unwrap().comparison;
    let columns = table1_columns(comparison);
    let rmspe = columns.iter().find(|c| c.group == "validation" && c.what == "RMSPE %").unwrap();
    let shown = rmspe.values[MODELS.iter().position(|m| *m == GRAY_BOX).unwrap()].unwrap();
    assert!(
        (shown - with_effect).abs() <= 1e-9 * with_effect,
        "Compare shows {shown}, the model {with_effect}"
    );

    // Removing the effect makes the comparison stale (once the model without it is finished).
    harness.state_mut().apply(Command::Undo);
    harness.step();
    harness.state_mut().settle();
    harness.step();
    let app = harness.state();
    assert_eq!(app.view.views.compare.result_is_current(SPEED, &app.session, &app.cache), Some(false));
}
