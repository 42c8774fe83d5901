//! Set-up shared by the integration tests: sample paths, the binary, the tools the exported programs
//! need, the real-data folder, noise, and the app under a test harness.
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

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

/// `python3`, for the exported programs and the scripts that read them. Its BLAS on one thread:
/// the tests already run two at a time on every core, and numpy's BLAS threads would only wait on
/// each other (spinning) for the small matrices the programs use.
pub fn python3() -> Command {
    let mut python = Command::new("python3");
    python.env("OPENBLAS_NUM_THREADS", "1");
    python
}

/// Whether `tool` can be used, for the tests that run the exported programs; when it cannot, says
/// so and, with `JETID_REQUIRE_EXPORT_TOOLS=1` (CI), fails. `probe` runs once per test process
/// (`found` keeps its answer): python3's imports python-control, two seconds each time.
fn have(tool: &str, found: &OnceLock<bool>, probe: &mut Command) -> bool {
    let found = *found.get_or_init(|| probe.output().is_ok_and(|o| o.status.success()));
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
    static FOUND: OnceLock<bool> = OnceLock::new();
    have("python3 with numpy and python-control", &FOUND, python3().args(["-c", "import numpy, control"]))
}

/// python3 with pyarrow, which reads the fleet's table as a fleet analyst's tools would.
pub fn have_pyarrow() -> bool {
    static FOUND: OnceLock<bool> = OnceLock::new();
    have("python3 with pyarrow", &FOUND, python3().args(["-c", "import pyarrow.parquet"]))
}

/// A C compiler, for the exported C program.
pub fn have_cc() -> bool {
    static FOUND: OnceLock<bool> = OnceLock::new();
    have("a C compiler (cc)", &FOUND, Command::new("cc").arg("--version"))
}

/// The shared real-data folder `name` beside the repository (`../shared/realdata/NAME`; real data
/// are never copied into the repository). Tests that need it are marked
/// `#[cfg_attr(not(jetid_realdata), ignore = "needs ../shared/realdata")]`: the build script sets
/// `jetid_realdata` when the folder is there, so they run where the data exist and are listed as
/// ignored, with the reason, where they do not.
pub fn realdata(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/realdata").join(name)
}

/// The bundled JetCat project's batch (`jetid --batch sample_runs/jetcat_p300/project.toml`), run
/// once for all the tests that read what it writes: a minute of work each time otherwise. Its
/// `--out` folder, under the tests' scratch folder in `target/`.
pub fn jetcat_batch() -> &'static Path {
    static OUT: OnceLock<PathBuf> = OnceLock::new();
    OUT.get_or_init(|| {
        let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("jetcat_batch");
        let project = sample("jetcat_p300/project.toml");
        let o = jetid(&["--batch", path_str(&project), "--out", path_str(&out), "--quiet"]);
        assert!(o.status.success(), "the JetCat batch: {}", String::from_utf8_lossy(&o.stderr));
        out
    })
}

/// The model `jetid --batch` writes for the project `text` (a project file's TOML), built in this
/// process by [`build_project_at`] with the parameter covariance, as the batch stores it. Written as
/// `dir/model.json` (beside `dir/project.toml`), whose path is returned.
pub fn build_model(text: &str, dir: &Path) -> PathBuf {
    use jetid::io::model_file::write_model;
    use jetid::workflow::project_model::Covariance;
    let project_path = dir.join("project.toml");
    std::fs::write(&project_path, text).unwrap_or_else(|e| panic!("{}: {e}", project_path.display()));
    let (file, _) = build_project_at(&project_path, Covariance::Estimate);
    let model = dir.join("model.json");
    write_model(&model, &file).unwrap_or_else(|e| panic!("{}: {e:#}", model.display()));
    model
}

/// Every output of the project file at `path`, built in this process by the batch's own steps
/// (`workflow::project_model::build_project`; the Python package's tests hold it to the batch's
/// model.json to 1e-12) without the baselines, figures and Monte Carlo study the batch adds around
/// them: the model file and each output as built.
pub fn build_project_at(
    path: &Path,
    covariance: jetid::workflow::project_model::Covariance,
) -> (jetid::io::model_file::ModelFile, Vec<jetid::workflow::project_model::BuiltOutput>) {
    use jetid::io::project::load_project;
    use jetid::workflow::project_model::build_project;
    use jetid::workflow::runs::load_runs;
    let at = path.display();
    let mut project = load_project(path).unwrap_or_else(|e| panic!("{at}: {e:#}"));
    let runs = load_runs(&project).unwrap_or_else(|e| panic!("{at}: {e:#}"));
    let (file, built, _) =
        build_project(&mut project, &runs, covariance).unwrap_or_else(|e| panic!("{at}: {e:#}"));
    (file, built)
}

/// A path as the `&str` a command line takes.
pub fn path_str(p: &Path) -> &str {
    p.to_str().unwrap_or_else(|| panic!("not UTF-8: {}", p.display()))
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
    ///
    /// While that work runs the app asks for frame after frame (it polls for the result), as many
    /// as the work takes on a loaded machine, so the first frames may end at the harness's step
    /// limit rather than at rest: that is not an error here, as the wait follows. After the wait
    /// the app must come to rest within the limit.
    pub fn run_settled(harness: &mut Harness<'_, App>) {
        if let Err(still_polling) = harness.try_run() {
            eprintln!("frames before the wait: {still_polling}");
        }
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
