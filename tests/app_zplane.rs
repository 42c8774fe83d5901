//! The cluster picker and the model views, driven through egui_kittest on the bundled sample runs:
//! drags are scripted one frame per event and the assertions are on the app's state.
#![cfg(feature = "gui")]
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common::app::run_settled;
use egui::{Key, Modifiers, Pos2};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use egui_plot::{PlotPoint, PlotTransform};
use jetid::core::identification::cluster::{Cluster, RootKind};
use jetid::core::run::RunRole;
use jetid::ui::{App, Command, Tab};
use num_complex::Complex64;

const SPEED: &str = "shaft_speed_rpm";
const THRUST: &str = "thrust_n";

fn sample_harness(tab: Tab) -> Harness<'static, App> {
    let mut harness = crate::common::app::sample_app(tab);
    harness.run();
    harness
}

/// The committed model of an output: its poles and the mean validation RMSPE.
fn model_of(app: &App, output: &str) -> (Vec<Complex64>, f64) {
    let live = app.cache.output(output).unwrap().live.as_ref().expect("a model");
    let poles = live.model.wiener.linear.tf.poles().unwrap();
    (poles, live.mean_validation_rmspe().unwrap())
}

fn clusters_of(app: &App, output: &str) -> Vec<Cluster> {
    app.cache.output(output).unwrap().clusters.clone()
}

fn transform(harness: &Harness<'_, App>) -> PlotTransform {
    harness.state().view.views.zplane.last_transform.expect("the z-plane was drawn")
}

fn screen(t: &PlotTransform, z: Complex64) -> Pos2 {
    t.position_from_point(&PlotPoint::new(z.re, z.im))
}

/// Press at `from`, move in steps to `to`, release: one frame per event.
fn drag(harness: &mut Harness<'_, App>, from: Pos2, to: Pos2) {
    harness.hover_at(from);
    harness.step();
    harness.drag_at(from);
    harness.step();
    for k in 1..=4 {
        harness.hover_at(from + (to - from) * (k as f32 / 4.0));
        harness.step();
    }
    harness.drop_at(to);
    run_settled(harness);
}

/// Equal up to the last bit or two (JSON floats are parsed to within an ulp).
fn same_clusters(a: &[Cluster], b: &[Cluster]) -> bool {
    let close = |x: f64, y: f64| (x - y).abs() <= 1e-12 * (1.0 + x.abs());
    a.len() == b.len()
        && a.iter().zip(b).all(|(x, y)| {
            x.kind == y.kind
                && close(x.centre.re, y.centre.re)
                && close(x.centre.im, y.centre.im)
                && close(x.radius, y.radius)
        })
}

fn same_roots(a: &[Complex64], b: &[Complex64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).norm() < 1e-12)
}

#[test]
fn opens_on_the_samples_with_a_model_for_both_outputs() {
    let harness = sample_harness(Tab::ZPlane);
    let app = harness.state();
    for output in [SPEED, THRUST] {
        let cache = app.cache.output(output).unwrap();
        assert!(cache.setup.clusters.is_none(), "the automatic proposal is applied");
        assert!(!cache.clusters.is_empty());
        assert!(cache.evals.as_ref().unwrap().iter().all(|e| e.valid));
        let live = cache.live.as_ref().unwrap();
        assert!(!live.runs.is_empty(), "scored on the validation and chirp runs");
        assert!(live.mean_validation_rmspe().unwrap() < 10.0);
    }
    harness.get_by_label("Reduced model");
}

#[test]
fn dragging_a_rim_changes_the_radius_the_model_and_the_error_and_undo_redo_walk_back_and_forth() {
    let mut harness = sample_harness(Tab::ZPlane);
    let (poles_before, rmspe_before) = model_of(harness.state(), SPEED);
    let clusters = clusters_of(harness.state(), SPEED);
    let (i, p1) = clusters.iter().enumerate().find(|(_, c)| c.is_real_axis()).unwrap();
    let t = transform(&harness);
    let rim = screen(&t, p1.centre + Complex64::new(p1.radius, 0.0));
    let target_radius = 0.25 * p1.radius;
    let inside = screen(&t, p1.centre + Complex64::new(target_radius, 0.0));

    // Halfway through the drag the live preview already runs on the shrinking circle.
    harness.hover_at(rim);
    harness.step();
    harness.drag_at(rim);
    harness.step();
    harness.hover_at(rim + (inside - rim) * 0.5);
    harness.step();
    harness.hover_at(inside);
    harness.step();
    {
        let app = harness.state();
        let preview = app.cache.preview.as_ref().expect("a live preview while dragging");
        assert!(preview.clusters[i].radius < p1.radius);
        assert!(app.cache.live_view(SPEED).unwrap().is_preview);
        assert_eq!(clusters_of(app, SPEED)[i], *p1, "nothing committed yet");
    }
    harness.drop_at(inside);
    run_settled(&mut harness);

    let app = harness.state();
    assert!(app.cache.preview.is_none());
    let after = clusters_of(app, SPEED);
    assert!(
        (after[i].radius - target_radius).abs() < 0.2 * p1.radius,
        "{} vs {target_radius}",
        after[i].radius
    );
    assert_eq!(after[i].centre, p1.centre, "a rim drag keeps the centre");
    let eval = &app.cache.output(SPEED).unwrap().evals.as_ref().unwrap()[i];
    assert!(!eval.valid, "too few members left: {:?}", eval.status);
    let (poles_after, rmspe_after) = model_of(app, SPEED);
    assert_eq!(poles_after.len(), poles_before.len() - 1, "the cluster's pole is dropped");
    assert!((rmspe_after - rmspe_before).abs() > 1e-6, "the validation error follows the model");

    // Undo (Ctrl+Z) brings back the same model; redo (Ctrl+Shift+Z) the dragged one.
    harness.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    run_settled(&mut harness);
    let (poles, rmspe) = model_of(harness.state(), SPEED);
    assert!(same_roots(&poles, &poles_before));
    assert!((rmspe - rmspe_before).abs() < 1e-9);
    assert_eq!(clusters_of(harness.state(), SPEED), clusters);

    harness.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    run_settled(&mut harness);
    let (poles, rmspe) = model_of(harness.state(), SPEED);
    assert!(same_roots(&poles, &poles_after));
    assert!((rmspe - rmspe_after).abs() < 1e-9);

    // The buttons do the same.
    harness.get_by_label("Undo").click();
    run_settled(&mut harness);
    assert_eq!(clusters_of(harness.state(), SPEED), clusters);
    harness.get_by_label("Redo").click();
    run_settled(&mut harness);
    assert_eq!(clusters_of(harness.state(), SPEED), after);
}

#[test]
fn moving_a_centre_off_the_roots_invalidates_the_cluster_and_drops_its_poles() {
    let mut harness = sample_harness(Tab::ZPlane);
    let (poles_before, _) = model_of(harness.state(), SPEED);
    let clusters = clusters_of(harness.state(), SPEED);
    let (i, pair) = clusters.iter().enumerate().find(|(_, c)| !c.is_real_axis()).unwrap();
    let t = transform(&harness);
    // Up and to the left, where no segment has a pole.
    let empty = pair.centre + Complex64::new(-0.08, 0.09);
    drag(&mut harness, screen(&t, pair.centre), screen(&t, empty));

    let app = harness.state();
    let moved = &clusters_of(app, SPEED)[i];
    assert!((moved.centre - empty).norm() < 0.01, "centre {} vs {empty}", moved.centre);
    assert_eq!(moved.radius.to_bits(), pair.radius.to_bits(), "a centre drag keeps the radius");
    let eval = &app.cache.output(SPEED).unwrap().evals.as_ref().unwrap()[i];
    assert!(!eval.valid);
    let (poles, _) = model_of(app, SPEED);
    assert_eq!(poles.len(), poles_before.len() - 2, "the conjugate pair is dropped");
    assert!(poles.iter().all(|p| p.im.abs() < 1e-9), "no complex pole left: {poles:?}");
    // The other output is untouched.
    assert!(app.cache.output(THRUST).unwrap().setup.clusters.is_none());
}

#[test]
fn no_valid_pole_cluster_shows_an_error_instead_of_a_model() {
    let mut harness = sample_harness(Tab::ZPlane);
    let zero_only = vec![Cluster::new(RootKind::Zero, Complex64::new(0.5, 0.5), 0.01)];
    harness.state_mut().apply(Command::SetClusters { output: SPEED.into(), clusters: Some(zero_only) });
    run_settled(&mut harness);
    assert!(harness.state().cache.output(SPEED).unwrap().live.is_err());
    harness.get_by_label_contains("No model");
    harness.state_mut().view.tab = Tab::Traces;
    harness.run();
    harness.get_by_label_contains("No model for shaft_speed_rpm");
    harness.state_mut().apply(Command::Undo);
    run_settled(&mut harness);
    assert!(harness.state().cache.output(SPEED).unwrap().live.is_ok());
}

#[test]
fn adding_and_deleting_clusters_and_accepting_the_proposal() {
    let mut harness = sample_harness(Tab::ZPlane);
    let auto = clusters_of(harness.state(), SPEED);
    harness.get_by_label("+ Zero cluster").click();
    run_settled(&mut harness);
    let app = harness.state();
    assert_eq!(clusters_of(app, SPEED).len(), auto.len() + 1);
    assert_eq!(clusters_of(app, SPEED).last().unwrap().kind, RootKind::Zero);
    assert_eq!(app.view.views.zplane.selected, Some(auto.len()), "the new cluster is selected");
    harness.get_by_label("Delete").click();
    run_settled(&mut harness);
    assert_eq!(clusters_of(harness.state(), SPEED), auto);
    assert!(harness.state().cache.output(SPEED).unwrap().setup.clusters.is_some(), "edited");
    harness.get_by_label("Accept automatic proposal").click();
    run_settled(&mut harness);
    assert!(harness.state().cache.output(SPEED).unwrap().setup.clusters.is_none());
}

#[test]
fn a_broken_model_file_shows_an_error_and_keeps_the_clusters() {
    let dir = tempfile::tempdir().unwrap();
    let broken = dir.path().join("model.json");
    std::fs::write(&broken, "{ \"format_version\": 1, \"outputs\": [ oops").unwrap();
    let mut harness = sample_harness(Tab::ZPlane);
    let before = clusters_of(harness.state(), SPEED);
    let revision = harness.state().session.revision;

    harness.state_mut().apply(Command::ImportModel(broken));
    run_settled(&mut harness);
    let app = harness.state();
    assert_eq!(app.session.revision, revision);
    assert_eq!(clusters_of(app, SPEED), before);
    assert_eq!(app.view.errors.len(), 1);
    assert!(app.view.errors[0].contains("model.json"), "{}", app.view.errors[0]);
    harness.get_by_label("Error");
    harness.get_by_label("Dismiss").click();
    run_settled(&mut harness);
    assert!(harness.state().view.errors.is_empty());
}

#[test]
fn exporting_then_importing_a_model_restores_the_clusters() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("model.json");
    let mut harness = sample_harness(Tab::ZPlane);
    let (speed, thrust) = (clusters_of(harness.state(), SPEED), clusters_of(harness.state(), THRUST));
    let (poles, rmspe) = model_of(harness.state(), SPEED);
    harness.state_mut().apply(Command::ExportModel(path.clone()));
    assert!(harness.state().view.errors.is_empty(), "{:?}", harness.state().view.errors);
    let file = jetid::io::model_file::read_model(&path).unwrap();
    assert_eq!(file.outputs.len(), 2, "both outputs, as --batch writes them");

    for output in [SPEED, THRUST] {
        harness.state_mut().apply(Command::SetClusters { output: output.into(), clusters: Some(Vec::new()) });
    }
    harness.run();
    assert!(clusters_of(harness.state(), SPEED).is_empty());

    harness.state_mut().apply(Command::ImportModel(path));
    run_settled(&mut harness);
    let app = harness.state();
    assert!(app.view.errors.is_empty(), "{:?}", app.view.errors);
    assert!(same_clusters(&clusters_of(app, SPEED), &speed));
    assert!(same_clusters(&clusters_of(app, THRUST), &thrust));
    let (poles_again, rmspe_again) = model_of(app, SPEED);
    assert!(
        poles_again.len() == poles.len()
            && poles_again.iter().zip(&poles).all(|(a, b)| (a - b).norm() < 1e-9),
        "{poles:?} vs {poles_again:?}"
    );
    assert!((rmspe_again - rmspe).abs() < 1e-6);
}

#[test]
fn a_broken_run_file_keeps_the_session_and_the_model() {
    let dir = tempfile::tempdir().unwrap();
    let broken = dir.path().join("broken.csv");
    std::fs::write(&broken, "time_s,fuel_flow_gph,shaft_speed_rpm\n0.0,1.0,oops\n").unwrap();
    let mut harness = sample_harness(Tab::ZPlane);
    let (poles, _) = model_of(harness.state(), SPEED);
    harness.state_mut().apply(Command::load(&broken, RunRole::Validation));
    run_settled(&mut harness);
    let app = harness.state();
    assert_eq!(app.session.runs.len(), 4);
    assert_eq!(app.view.failures.len(), 1);
    assert!(same_roots(&model_of(app, SPEED).0, &poles));
    harness.get_by_label("Could not load run");
}

#[test]
fn dragging_a_segment_boundary_refits_on_release_and_undoes() {
    let mut harness = sample_harness(Tab::Data);
    let ident = harness.state().cache.ident.as_ref().unwrap();
    let segments = ident.segments.clone().unwrap();
    let fits_before = ident.output(SPEED).unwrap().fits.clone().unwrap();
    // The boundary between segments A and B, dragged 4 s earlier (later is limited by B's step).
    let (run, dt) = (&harness.state().session.runs[0].run, harness.state().session.runs[0].run.dt_secs);
    let t_boundary = run.t_secs[0] + segments[0].end as f64 * dt;
    let t = harness.state().view.views.data.last_transform.expect("the data plots were drawn");
    let y = t.frame().center().y;
    let from = Pos2::new(t.position_from_point_x(t_boundary), y);
    let to = Pos2::new(t.position_from_point_x(t_boundary - 4.0), y);
    drag(&mut harness, from, to);

    let app = harness.state();
    let ident = app.cache.ident.as_ref().unwrap();
    let moved = ident.segments.as_ref().unwrap();
    let shift = moved[0].end as i64 - segments[0].end as i64;
    assert!((shift + (4.0 / dt).round() as i64).abs() <= 2, "moved by {shift} samples");
    assert_eq!(moved[1].start, moved[0].end, "a shared boundary moves for both segments");
    assert!(!ident.segments_are_automatic());
    let fits_after = ident.output(SPEED).unwrap().fits.clone().unwrap();
    assert_ne!(fits_after.segments, fits_before.segments, "the fits were redone");

    harness.state_mut().apply(Command::Undo);
    run_settled(&mut harness);
    let ident = harness.state().cache.ident.as_ref().unwrap();
    assert_eq!(ident.segments.as_ref().unwrap(), &segments);
    assert!(ident.segments_are_automatic());
}

#[test]
fn the_saved_session_keeps_segments_settings_and_clusters() {
    let mut app = App::startup(None);
    app.settle();
    let mut clusters = app.cache.output(SPEED).unwrap().clusters.clone();
    clusters[0].radius *= 1.5;
    app.apply(Command::SetClusters { output: SPEED.into(), clusters: Some(clusters.clone()) });
    let json = serde_json::to_string(&app.saved_session()).unwrap();
    let restored = App::startup(Some(&serde_json::from_str(&json).unwrap()));
    let setup = &restored.session.setup;
    assert_eq!(setup.outputs.keys().collect::<Vec<_>>(), vec![SPEED]);
    assert_eq!(setup.output(SPEED).settings, app.session.setup.output(SPEED).settings);
    assert!(same_clusters(&setup.output(SPEED).clusters.unwrap(), &clusters));
}

#[test]
fn a_saved_project_reads_back_with_io_project_and_opens_in_the_app() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bench.toml");
    let mut app = App::startup(None);
    app.settle();
    let mut clusters = app.cache.output(THRUST).unwrap().clusters.clone();
    clusters[0].radius *= 1.2;
    app.apply(Command::SetClusters { output: THRUST.into(), clusters: Some(clusters.clone()) });
    let mut segments = app.cache.ident.as_ref().unwrap().segments.clone().unwrap();
    segments[0].start += 5;
    app.apply(Command::SetSegments(Some(segments.clone())));
    app.apply(Command::SaveProject(path.clone()));
    assert!(app.view.errors.is_empty(), "{:?}", app.view.errors);

    let project = jetid::io::project::load_project(&path).unwrap();
    assert_eq!(project.ident[0].path, app.session.runs[0].path);
    assert_eq!(project.validate.len(), 1);
    assert!(project.chirp.is_some() && project.steady.is_some());
    assert_eq!(project.clusters[THRUST], clusters);
    assert_eq!(project.segments[SPEED], segments);
    assert_eq!(project.settings_for(SPEED), app.session.setup.output(SPEED).settings);

    let mut other = App::new(jetid::ui::Session::default());
    other.apply(Command::OpenProject(path));
    assert!(other.view.errors.is_empty(), "{:?}", other.view.errors);
    let roles: Vec<RunRole> = other.session.runs.iter().map(|r| r.role).collect();
    assert_eq!(roles, vec![RunRole::Identification, RunRole::Validation, RunRole::Chirp, RunRole::Steady]);
    assert_eq!(other.session.setup.segments, Some(segments));
    assert_eq!(other.session.setup.output(THRUST).clusters, Some(clusters));
    other.settle();
    assert!(other.cache.output(THRUST).unwrap().live.is_ok());
}

#[test]
fn a_broken_project_shows_an_error_and_keeps_the_session() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.toml");
    std::fs::write(&path, "idnet = \"x.csv\"").unwrap();
    let mut app = App::startup(None);
    let runs = app.session.runs.len();
    app.apply(Command::OpenProject(path));
    assert_eq!(app.session.runs.len(), runs);
    assert_eq!(app.view.errors.len(), 1);
}

#[test]
fn escape_cancels_a_cluster_drag() {
    let mut harness = sample_harness(Tab::ZPlane);
    let clusters = clusters_of(harness.state(), SPEED);
    let revision = harness.state().session.revision;
    let t = transform(&harness);
    let from = screen(&t, clusters[0].centre);
    let to = from + egui::vec2(40.0, -30.0);
    harness.hover_at(from);
    harness.step();
    harness.drag_at(from);
    harness.step();
    harness.hover_at(to);
    harness.step();
    assert!(harness.state().view.views.zplane.drag.is_some());
    harness.key_press(Key::Escape);
    harness.step();
    harness.drop_at(to);
    run_settled(&mut harness);
    let app = harness.state();
    assert_eq!(app.session.revision, revision);
    assert_eq!(clusters_of(app, SPEED), clusters);
    assert!(app.cache.preview.is_none());
}

/// Step frames (sleeping between them) until no automatic proposal is being computed.
fn wait_for_proposals(harness: &mut Harness<'_, App>) {
    for _ in 0..3000 {
        if !harness.state().cache.ident.as_ref().is_some_and(|i| i.is_busy()) {
            harness.run();
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
        harness.step();
    }
    panic!("the automatic proposal did not end within a minute");
}

#[test]
fn the_proposal_runs_off_the_ui_thread_and_the_table_shows_the_models_roots_and_why() {
    let mut app = App::startup(None);
    app.view.tab = Tab::ZPlane;
    app.view.output = Some(SPEED.into());
    app.refresh();
    // Refreshing only starts the structure search: it takes seconds, far longer than a frame.
    assert!(app.cache.ident.as_ref().unwrap().is_proposing(), "the proposal ran on the calling thread");
    let mut harness = Harness::builder()
        .with_size(egui::vec2(1400.0, 900.0))
        .build_ui_state(|ui, app: &mut App| app.ui(ui), app);
    harness.step();
    harness.get_by_label("The automatic proposal is being computed.");
    wait_for_proposals(&mut harness);

    let app = harness.state();
    let output = app.cache.output(SPEED).unwrap();
    let proposal = output.proposal.proposal().expect("the proposal arrived");
    let live = output.live.as_ref().expect("the model follows the proposal");
    assert_eq!(output.clusters, proposal.clusters);
    // Every model root that came from a cluster is listed with the root actually in the model
    // (after the polish), not the cluster's centroid.
    let poles = live.model.wiener.linear.tf.poles().unwrap();
    let from_clusters: Vec<_> = live.model.roots.iter().filter(|g| g.cluster.is_some()).collect();
    assert!(!from_clusters.is_empty());
    for group in from_clusters {
        assert!(
            poles
                .iter()
                .chain(&live.model.wiener.linear.tf.zeros().unwrap())
                .any(|p| (p - group.root).norm() < 1e-6)
        );
        let text = if group.pair {
            format!("{:.4}±{:.4}i", group.root.re, group.root.im.abs())
        } else {
            format!("{:.4}", group.root.re)
        };
        harness.get_by_label(&text);
    }
    // Each candidate's verdict is said in words.
    harness.get_by_label("Why the automatic proposal chose these");
    for verdict in &proposal.verdicts {
        harness.get_by_label(&verdict.verdict.to_string());
    }
    harness.get_by_label(&proposal.dead_time.decision.to_string());
}

#[test]
fn editing_the_proposed_clusters_keeps_the_proposals_dead_time_and_accepting_it_again_drops_it() {
    let mut harness = sample_harness(Tab::ZPlane);
    let proposed = {
        let output = harness.state().cache.output(SPEED).unwrap();
        output.proposal.dead_time_samples().expect("a proposal built from clusters")
    };
    assert_eq!(harness.state().session.setup.output(SPEED).settings.dead_time_samples, None);
    let clusters = clusters_of(harness.state(), SPEED);
    harness.state_mut().apply(Command::SetClusters { output: SPEED.into(), clusters: Some(clusters) });
    run_settled(&mut harness);
    assert_eq!(harness.state().session.setup.output(SPEED).settings.dead_time_samples, Some(proposed));
    harness.state_mut().apply(Command::SetClusters { output: SPEED.into(), clusters: None });
    run_settled(&mut harness);
    assert_eq!(harness.state().session.setup.output(SPEED).settings.dead_time_samples, None);
}

/// A project's `steps_from` reaches the app: its segments are detected on that channel (as the
/// batch does), a channel the run lacks is named in the error, and saving keeps the setting.
#[test]
fn the_app_finds_steps_on_the_projects_steps_from_channel_and_saves_it() {
    use jetid::core::identification::segment::{SegmentSettings, auto_segments};
    let dir = tempfile::tempdir().unwrap();
    let ident = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("sample_runs/sr30/ident.csv");
    let write = |name: &str, channel: &str| {
        let path = dir.path().join(name);
        let text = format!(
            "ident = \"{}\"\nsteps_from = \"{channel}\"\n",
            ident.to_str().unwrap().replace('\\', "/")
        );
        std::fs::write(&path, text).unwrap();
        path
    };
    let mut app = App::new(jetid::ui::Session::default());
    app.apply(Command::OpenProject(write("egt.toml", "egt_c")));
    assert!(app.view.errors.is_empty(), "{:?}", app.view.errors);
    app.settle();
    let run = &app.session.runs[0].run;
    let egt = &run.channel("egt_c").unwrap().values;
    let on_egt = auto_segments(egt, run.dt_secs, &SegmentSettings::default());
    let on_input = auto_segments(&run.input.values, run.dt_secs, &SegmentSettings::default()).unwrap();
    let segments = app.cache.ident.as_ref().unwrap().segments.clone();
    match on_egt {
        Ok(expected) => {
            assert_eq!(segments.unwrap(), expected);
            assert_ne!(expected, on_input, "the channel must make a difference for this test to tell");
        }
        Err(e) => assert!(segments.unwrap_err().to_string().contains(&e.to_string())),
    }
    let saved = dir.path().join("saved.toml");
    app.apply(Command::SaveProject(saved.clone()));
    assert_eq!(jetid::io::project::load_project(&saved).unwrap().steps_from.as_deref(), Some("egt_c"));

    let mut typo = App::new(jetid::ui::Session::default());
    typo.apply(Command::OpenProject(write("typo.toml", "egt")));
    typo.settle();
    let err = typo.cache.ident.as_ref().unwrap().segments.clone().unwrap_err().to_string();
    assert!(err.contains("steps_from = \"egt\"") && err.contains("no such channel"), "{err}");
}

#[test]
fn an_invalid_clusters_status_fits_the_window_and_the_pointer_readout_is_under_the_plot() {
    let mut harness = sample_harness(Tab::ZPlane);
    let mut clusters = clusters_of(harness.state(), SPEED);
    // A cluster where no segment has a root: valid for no segment.
    clusters.push(Cluster::new(RootKind::Pole, Complex64::new(0.5, 0.5), 0.01));
    harness.state_mut().apply(Command::SetClusters { output: SPEED.into(), clusters: Some(clusters) });
    harness.state_mut().settle();
    harness.run();

    let status = harness.get_by_label("too few");
    let width = harness.ctx.content_rect().width();
    assert!(status.rect().max.x <= width, "the status ends at {} of {width} px", status.rect().max.x);

    let t = transform(&harness);
    let plot = *t.frame();
    harness.hover_at(plot.center());
    harness.run();
    let readout = harness.get_by_label_contains("pointer: z = ");
    assert!(
        readout.rect().min.y >= plot.max.y,
        "the readout {:?} is below the plot {plot:?}",
        readout.rect()
    );
}

#[test]
fn a_committed_change_shows_the_unpolished_model_at_once_and_the_polished_one_from_a_worker() {
    let mut app = App::startup(None);
    app.settle();
    let clusters = clusters_of(&app, SPEED);
    assert!(app.session.setup.output(SPEED).settings.refine, "the bundled setup polishes the centroids");
    let mut moved = clusters.clone();
    moved[0].radius *= 0.9;
    app.apply(Command::SetClusters { output: SPEED.into(), clusters: Some(moved.clone()) });
    app.refresh();
    // The refresh only starts the polish: the model shown meanwhile is the unpolished one.
    assert!(app.cache.ident.as_ref().unwrap().is_finishing(), "the polish ran on the calling thread");
    let first = app.cache.output(SPEED).unwrap().live.as_ref().expect("a first model at once").clone();
    assert!(first.finishing && first.model.refinement.is_none());
    assert_eq!(clusters_of(&app, SPEED), moved);

    app.settle();
    let output = app.cache.output(SPEED).unwrap();
    let finished = output.live.as_ref().expect("the finished model");
    assert!(!finished.finishing && finished.polish_requested);
    assert!(!app.cache.ident.as_ref().unwrap().is_busy());
    assert_ne!(finished.id, first.id, "the finished model replaced the first look");
}
