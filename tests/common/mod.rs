//! Set-up shared by the integration tests: sample paths, the binary, the tools the exported programs
//! need, the real-data folder, noise, and the app under a test harness.
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

/// A file or folder under the bundled `sample_runs/`.
pub fn sample(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("sample_runs").join(path)
}

/// Run the `jetid` binary with `args`.
pub fn jetid(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_jetid")).args(args).output().expect("jetid runs")
}

/// Run the `jetid` binary with `args` in the folder `dir` (paths in `args` relative to it).
pub fn jetid_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_jetid")).current_dir(dir).args(args).output().expect("jetid runs")
}

/// Whether `tool` can be used, for the tests that run the exported programs; when it cannot, says
/// so and, with `JETID_REQUIRE_EXPORT_TOOLS=1` (CI), fails.
pub fn have(tool: &str, probe: &mut Command) -> bool {
    let found = probe.output().is_ok_and(|o| o.status.success());
    if !found {
        assert!(
            std::env::var("JETID_REQUIRE_EXPORT_TOOLS").as_deref() != Ok("1"),
            "{tool} is needed to test the exports (JETID_REQUIRE_EXPORT_TOOLS=1)"
        );
        eprintln!("SKIPPED: {tool} is not available, so the exported program is not run");
    }
    found
}

/// python3 with numpy and python-control, which the exported Python program needs.
pub fn have_python() -> bool {
    have(
        "python3 with numpy and python-control",
        Command::new("python3").args(["-c", "import numpy, control"]),
    )
}

/// python3 with pyarrow, which reads the fleet's table as a fleet analyst's tools would.
pub fn have_pyarrow() -> bool {
    have("python3 with pyarrow", Command::new("python3").args(["-c", "import pyarrow.parquet"]))
}

/// A C compiler, for the exported C program.
pub fn have_cc() -> bool {
    have("a C compiler (cc)", Command::new("cc").arg("--version"))
}

/// The shared real-data folder `name` beside the repository (`../shared/realdata/NAME`; real data
/// are never copied into the repository). Tests that need it are marked
/// `#[cfg_attr(not(jetid_realdata), ignore = "needs ../shared/realdata")]`: the build script sets
/// `jetid_realdata` when the folder is there, so they run where the data exist and are listed as
/// ignored, with the reason, where they do not.
pub fn realdata(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/realdata").join(name)
}

/// `x` with seeded white Gaussian noise of standard deviation `sigma`.
pub fn noisy(x: &[f64], sigma: f64, seed: u64) -> Vec<f64> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let normal = Normal::new(0.0, sigma).unwrap_or_else(|e| panic!("σ = {sigma}: {e}"));
    x.iter().map(|v| v + normal.sample(&mut rng)).collect()
}

#[cfg(feature = "gui")]
pub mod app {
    use egui_kittest::Harness;
    use jetid::ui::{App, Tab};

    /// The app under a harness of the given window size, not yet stepped.
    pub fn harness_sized(app: App, size: [f32; 2]) -> Harness<'static, App> {
        Harness::builder()
            .with_size(egui::vec2(size[0], size[1]))
            .build_ui_state(|ui, app: &mut App| app.ui(ui), app)
    }

    /// The app under a harness the size of the app's window, not yet stepped.
    pub fn harness(app: App) -> Harness<'static, App> {
        harness_sized(app, [1400.0, 900.0])
    }

    /// Run the frames a change asks for, wait for the background work it started (the committed
    /// model is polished and its effects refitted on a worker thread), then draw the result.
    pub fn run_settled(harness: &mut Harness<'_, App>) {
        harness.run();
        harness.state_mut().settle();
        harness.run();
    }

    /// The app on the bundled sample runs, every model built, showing `tab`; not yet stepped.
    pub fn sample_app(tab: Tab) -> Harness<'static, App> {
        let mut app = App::startup(None);
        assert_eq!(app.session.runs.len(), 4, "the bundled sample runs load: {:?}", app.view.failures);
        app.settle();
        app.view.tab = tab;
        harness(app)
    }
}
