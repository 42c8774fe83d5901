//! The desktop app (eframe/egui).
//!
//! State comes in three tiers (STYLE.md): [`Session`] is what the user loaded and decided (saved on
//! close, runs read again on start), [`ViewState`] is transient (selection, dialogs, each view's
//! zoom and toggles), [`Derived`] is recomputed from the session when its revision changes. Views
//! return [`Command`]s and [`App::apply`] carries them out. See [`views`] for adding a view.
use std::path::{Path, PathBuf};
use std::sync::mpsc;

use anyhow::{Result, anyhow, bail};

pub mod app;
pub mod derived;
mod edit;
pub mod file_dialog;
mod file_picking;
mod files;
pub mod mapping_ui;
pub mod panels_ui;
pub mod path_prompt;
pub mod project_io;
pub mod screenshot;
pub mod state;
pub mod theme;
pub mod views;
pub mod widgets;

pub use app::App;
pub use derived::Derived;
pub use state::command::Command;
pub use state::session::{SavedSession, Session};
pub use state::{Tab, ViewState};

/// The `--screenshot --view` name of the Diagnosis view's "Where it fails" section.
const FAILURES_VIEW: &str = "failures";
/// The key of the saved session in eframe's storage.
const STORAGE_KEY: &str = "jetid_session";
const APP_ID: &str = "jetid";
const WINDOW_SIZE: [f32; 2] = [1400.0, 900.0];
const NO_DISPLAY_HINT: &str = "the desktop app needs a graphical display; \
     run the headless pipeline with `jetid --batch` instead (see `jetid --help`)";

/// The bundled sample runs: `sample_runs/sr30` under the current directory, else under the source
/// tree jetid was built from.
pub fn bundled_sample_dir() -> Option<PathBuf> {
    let relative = Path::new("sample_runs").join("sr30");
    let candidates = [
        std::env::current_dir().ok().map(|d| d.join(&relative)),
        Some(Path::new(env!("CARGO_MANIFEST_DIR")).join(&relative)),
    ];
    candidates.into_iter().flatten().find(|dir| dir.is_dir())
}

/// `jetid` with no arguments: the desktop app, on the saved session or the bundled sample runs;
/// `jetid PROJECT [--output NAME] [--add-effect ID]…` opens it on the project as File > Open project
/// does, with the effects applied to every output (an error in them is returned before any window
/// opens).
pub fn run_app(
    project: Option<&Path>,
    output: Option<&str>,
    add_effects: &[crate::core::effects::EffectId],
    fleet: Option<&Path>,
) -> Result<()> {
    let opened = match project {
        Some(path) => Some(screenshot::app_on_project(path, add_effects)?),
        None if !add_effects.is_empty() => Some(screenshot::app_on_project_or_samples(None, add_effects)?),
        None => None,
    };
    check_display()?;
    let options = native_options(None);
    let output = output.map(ToOwned::to_owned);
    let fleet = fleet.map(Path::to_path_buf);
    eframe::run_native(
        "jetid",
        options,
        Box::new(move |cc| {
            let mut app = DesktopApp::new(cc, opened);
            if output.is_some() {
                app.app.view.output = output;
            }
            if let Some(manifest) = fleet {
                // Computed in the background; the History view shows its progress.
                app.app.apply(Command::OpenFleet(manifest));
            }
            Ok(Box::new(app))
        }),
    )
    .map_err(|err| anyhow!("could not open the app window ({err}): {NO_DISPLAY_HINT}"))
}

/// `jetid --screenshot OUT [--view NAME] [--output NAME] [PROJECT] [--add-effect ID]… [--fleet
/// MANIFEST]`: a picture of one view on the bundled sample runs or on `project` (model views show
/// `output`, else the first output), with `add_effects` applied to every output; with `fleet`, the
/// History view on that fleet, computed first, its first flagged run opened.
pub fn screenshot(
    out: &Path,
    view: &str,
    output: Option<&str>,
    project: Option<&Path>,
    add_effects: &[crate::core::effects::EffectId],
    fleet: Option<&Path>,
) -> Result<()> {
    // `failures`: the Diagnosis view's "Where it fails" section.
    let failures = view.eq_ignore_ascii_case(FAILURES_VIEW);
    let tab = if failures { Some(Tab::Diagnosis) } else { Tab::from_cli_name(view) };
    let Some(tab) = tab else {
        bail!("unknown view `{view}`; the views are: {}, {FAILURES_VIEW}", Tab::cli_names());
    };
    check_display()?;
    // A private storage file, so a screenshot neither reads nor changes the user's saved session.
    let storage = std::env::temp_dir().join(format!("jetid-screenshot-{}.ron", std::process::id()));
    let mut options = native_options(Some(storage.clone()));
    options.persist_window = false;
    options.viewport = options.viewport.with_resizable(false);
    let (tx, rx) = mpsc::channel();
    let out = out.to_owned();
    let mut app = screenshot::screenshot_app(project, add_effects)?;
    app.view.output = output.map(ToOwned::to_owned);
    if failures {
        app.view.views.diagnosis.section = views::diagnosis::Section::WhereItFails;
    }
    if let Some(manifest) = fleet {
        app.apply(Command::OpenFleet(manifest.to_owned()));
        app.view.views.history.wait();
        app.view.views.history.select_first_flagged();
    }
    let result = eframe::run_native(
        "jetid",
        options,
        Box::new(move |_cc| Ok(Box::new(screenshot::ScreenshotApp::new(app, tab, out, tx)))),
    );
    let _ = std::fs::remove_file(&storage);
    result.map_err(|err| anyhow!("could not open the app window ({err}): {NO_DISPLAY_HINT}"))?;
    rx.try_recv().unwrap_or_else(|_| Err(anyhow!("the window closed before the screenshot was taken")))
}

fn native_options(persistence_path: Option<PathBuf>) -> eframe::NativeOptions {
    eframe::NativeOptions {
        renderer: eframe::Renderer::Glow,
        viewport: egui::ViewportBuilder::default()
            .with_title("jetid")
            .with_app_id(APP_ID)
            .with_inner_size(WINDOW_SIZE)
            .with_min_inner_size([800.0, 500.0]),
        persistence_path,
        ..Default::default()
    }
}

/// On Linux and the BSDs a window needs X11 or Wayland; say so plainly instead of letting winit fail.
fn check_display() -> Result<()> {
    if cfg!(all(unix, not(target_os = "macos"), not(target_os = "android"))) {
        let set = |name: &str| std::env::var_os(name).is_some_and(|v| !v.is_empty());
        if !set("DISPLAY") && !set("WAYLAND_DISPLAY") {
            bail!("no display found (neither DISPLAY nor WAYLAND_DISPLAY is set): {NO_DISPLAY_HINT}");
        }
    }
    Ok(())
}

/// The app inside eframe: restores the session from eframe's storage and saves it back.
struct DesktopApp {
    app: App,
}

impl DesktopApp {
    /// The app `opened` on a project, else on the session saved last time.
    fn new(cc: &eframe::CreationContext<'_>, opened: Option<App>) -> Self {
        let app = opened.unwrap_or_else(|| {
            let saved: Option<SavedSession> = cc.storage.and_then(|s| eframe::get_value(s, STORAGE_KEY));
            App::startup(saved.as_ref())
        });
        Self { app }
    }
}

impl eframe::App for DesktopApp {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        self.app.view.cpu_frame_ms = frame.info().cpu_usage.map(|secs| secs * 1000.0);
        self.app.ui(ui);
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        eframe::set_value(storage, STORAGE_KEY, &self.app.saved_session());
    }
}
