//! Frame cost of the z-plane cluster picker on the bundled sr30 runs, driven through egui_kittest
//! like the app tests: (a) one frame while a cluster's rim is being dragged — the live path on the
//! dragged clusters (reduced model, static map, every validation run simulated, Bode) plus the UI;
//! (b) a whole drag: press, move, release, until the polished model has arrived, then undo;
//! (c) the one frame in which the drag is released: it commits the clusters and shows the
//! unpolished model while the polish (and the effects' refit) runs on a worker thread.
//! Run: `cargo bench --bench drag`.
use egui::Pos2;
use egui_kittest::Harness;
use egui_plot::PlotPoint;
use jetid::core::identification::cluster::Cluster;
use jetid::ui::{App, Command, Tab};
use num_complex::Complex64;

fn main() {
    divan::main();
}

const OUTPUTS: [&str; 2] = ["shaft_speed_rpm", "thrust_n"];

/// The app on the sample runs, z-plane of `output` shown, and the screen positions of the rim of its
/// first real-axis cluster and of a point 30 px further out (well beyond egui's drag threshold).
fn setup(output: &str) -> (Harness<'static, App>, Pos2, Pos2) {
    let mut app = App::startup(None);
    assert!(app.session.runs.len() == 4, "the bench needs the bundled sample runs: {:?}", app.view.failures);
    app.settle();
    app.view.tab = Tab::ZPlane;
    app.view.output = Some(output.to_owned());
    let mut harness = Harness::builder()
        .with_size(egui::vec2(1400.0, 900.0))
        .build_ui_state(|ui, app: &mut App| app.ui(ui), app);
    harness.run();
    let clusters: Vec<Cluster> =
        harness.state().cache.output(output).map(|o| o.clusters.clone()).unwrap_or_default();
    let Some(cluster) = clusters.iter().find(|c| c.is_real_axis()).or(clusters.first()).cloned() else {
        panic!("no cluster for {output}");
    };
    let Some(t) = harness.state().view.views.zplane.last_transform else {
        panic!("the z-plane was not drawn")
    };
    let at = |z: Complex64| t.position_from_point(&PlotPoint::new(z.re, z.im));
    let rim = at(cluster.centre + Complex64::new(cluster.radius, 0.0));
    let out = rim + egui::vec2(30.0, 0.0);
    (harness, rim, out)
}

#[divan::bench(args = OUTPUTS, sample_count = 60)]
fn frame_while_dragging(bencher: divan::Bencher, output: &str) {
    let (mut harness, rim, out) = setup(output);
    harness.hover_at(rim);
    harness.step();
    harness.drag_at(rim);
    harness.step();
    let mut k = 0u32;
    bencher.bench_local(|| {
        // Alternate between two radii so every frame computes a new preview.
        k += 1;
        let f = if k.is_multiple_of(2) { 0.5 } else { 1.0 };
        harness.hover_at(rim + (out - rim) * f);
        harness.step();
    });
    assert!(harness.state().cache.preview.is_some(), "the drag never produced a preview");
}

#[divan::bench(args = OUTPUTS, sample_count = 15)]
fn drag_and_release(bencher: divan::Bencher, output: &str) {
    let (mut harness, rim, out) = setup(output);
    bencher.bench_local(|| {
        harness.hover_at(rim);
        harness.step();
        harness.drag_at(rim);
        harness.step();
        harness.hover_at(rim + (out - rim) * 0.5);
        harness.step();
        harness.hover_at(out);
        harness.step();
        harness.drop_at(out);
        harness.step();
        harness.state_mut().settle();
        harness.step();
        let committed = harness.state().session.setup.outputs.get(output).and_then(|o| o.clusters.clone());
        assert!(committed.is_some(), "the release did not commit the dragged clusters");
        harness.state_mut().apply(Command::Undo);
        harness.step();
    });
}

/// The frame of the release alone (the goal: under 16 ms, one frame at 60 Hz). Each sample starts
/// from a fresh drag, prepared untimed, with the previous release undone.
#[divan::bench(args = OUTPUTS, sample_count = 30, sample_size = 1)]
fn release_frame(bencher: divan::Bencher, output: &str) {
    let (harness, rim, out) = setup(output);
    let harness = std::cell::RefCell::new(harness);
    bencher
        .with_inputs(|| {
            let mut harness = harness.borrow_mut();
            if harness.state().session.setup.outputs.get(output).and_then(|o| o.clusters.as_ref()).is_some() {
                harness.state_mut().apply(Command::Undo);
            }
            harness.state_mut().settle();
            harness.hover_at(rim);
            harness.step();
            harness.drag_at(rim);
            harness.step();
            harness.hover_at(out);
            harness.step();
        })
        .bench_local_values(|()| {
            let mut harness = harness.borrow_mut();
            harness.drop_at(out);
            harness.step();
        });
    let app = harness.borrow();
    let committed = app.state().session.setup.outputs.get(output).and_then(|o| o.clusters.clone());
    assert!(committed.is_some(), "the release did not commit the dragged clusters");
}

/// One frame of the z-plane with nothing changing: what drawing the view costs (the share of
/// `frame_while_dragging` that is not the live path).
#[divan::bench(args = OUTPUTS, sample_count = 60)]
fn frame_idle(bencher: divan::Bencher, output: &str) {
    let (mut harness, _, _) = setup(output);
    bencher.bench_local(|| harness.step());
}
