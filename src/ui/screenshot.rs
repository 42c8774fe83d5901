//! `jetid --screenshot OUT.png [--view NAME] [PROJECT] [--add-effect ID]…`: open the app on the
//! bundled sample runs (or on a project file, with effects added to every output) at a fixed size,
//! let it settle (background jobs the view starts — a diagnosis, the comparison — are waited for),
//! grab the rendered frame, write it as PNG and close.
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{self, Receiver, Sender};
use std::time::{Duration, Instant};

use anyhow::{Context as _, Result, anyhow};

use crate::core::diagnose::TrialId;
use crate::core::effects::EffectId;

use crate::ui::app::App;
use crate::ui::state::Tab;
use crate::ui::state::command::Command;
use crate::ui::state::session::Session;

/// Frames drawn (and time waited) before the picture is taken, so layout and plot bounds settle.
const WARMUP_FRAMES: u32 = 10;
const WARMUP: Duration = Duration::from_millis(600);
/// Give up when no picture arrived by then (background jobs, e.g. the Compare view's baseline
/// training, are waited for; unoptimised builds take minutes).
const TIMEOUT: Duration = Duration::from_secs(600);

/// The app a screenshot shows: [`app_on_project_or_samples`], every model finished.
pub fn screenshot_app(project: Option<&Path>, add_effects: &[EffectId]) -> Result<App> {
    let mut app = app_on_project_or_samples(project, add_effects)?;
    app.settle();
    Ok(app)
}

/// The app on `project`, opened as File > Open project does, with `add_effects` applied to every
/// output (the models are finished in the background).
pub fn app_on_project(project: &Path, add_effects: &[EffectId]) -> Result<App> {
    app_on_project_or_samples(Some(project), add_effects)
}

/// The app on the bundled sample runs, or `project` opened as File > Open project does; then
/// `add_effects` applied to every identified output, as the Apply button does. Errors (a project
/// that cannot be opened, an unknown effect) are returned, not drawn.
pub fn app_on_project_or_samples(project: Option<&Path>, add_effects: &[EffectId]) -> Result<App> {
    let mut app = match project {
        None => App::startup(None),
        Some(path) => {
            let mut app = App::new(Session::default());
            app.apply(Command::OpenProject(path.to_owned()));
            app
        }
    };
    if let Some(error) = app.view.errors.first() {
        return Err(anyhow!("{error}"));
    }
    app.refresh();
    let outputs: Vec<String> = app.cache.output_names().into_iter().map(ToOwned::to_owned).collect();
    for effect in add_effects {
        for output in &outputs {
            app.apply(Command::ApplyEffect { output: output.clone(), trial: TrialId::Effect(*effect) });
        }
    }
    if let Some(error) = app.view.errors.first() {
        return Err(anyhow!("{error}"));
    }
    if !add_effects.is_empty() {
        // Each Apply named its own output; the last one would name only the last output.
        app.view.status = Some(applied_status(add_effects, &outputs));
    }
    Ok(app)
}

/// "Effect thermal_soak applied to shaft_speed_rpm and thrust_n".
fn applied_status(effects: &[EffectId], outputs: &[String]) -> String {
    let effects: Vec<&str> = effects.iter().map(|e| e.name()).collect();
    let plural = if effects.len() == 1 { "" } else { "s" };
    format!("Effect{plural} {} applied to {}", and_list(&effects), and_list(outputs))
}

/// "a", "a and b", "a, b and c".
fn and_list<S: AsRef<str>>(items: &[S]) -> String {
    match items {
        [] => String::new(),
        [one] => one.as_ref().to_owned(),
        [rest @ .., last] => {
            let rest: Vec<&str> = rest.iter().map(AsRef::as_ref).collect();
            format!("{} and {}", rest.join(", "), last.as_ref())
        }
    }
}

pub struct ScreenshotApp {
    app: App,
    out: PathBuf,
    started: Instant,
    frames: u32,
    /// Frames drawn since the last one with a background job running.
    idle_frames: u32,
    requested: bool,
    image_tx: Sender<Arc<egui::ColorImage>>,
    image_rx: Receiver<Arc<egui::ColorImage>>,
    /// Where the outcome goes (read by the caller after the window closes).
    outcome: Sender<Result<()>>,
    done: bool,
}

impl ScreenshotApp {
    pub fn new(mut app: App, tab: Tab, out: PathBuf, outcome: Sender<Result<()>>) -> Self {
        app.view.tab = tab;
        let (image_tx, image_rx) = mpsc::channel();
        Self {
            app,
            out,
            started: Instant::now(),
            frames: 0,
            idle_frames: 0,
            requested: false,
            image_tx,
            image_rx,
            outcome,
            done: false,
        }
    }

    fn finish(&mut self, ctx: &egui::Context, outcome: Result<()>) {
        // The receiver lives in `screenshot()` until the window closes.
        let _ = self.outcome.send(outcome);
        self.done = true;
        ctx.send_viewport_cmd(egui::ViewportCommand::Close);
    }
}

impl eframe::App for ScreenshotApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        self.app.ui(ui);
        let ctx = ui.ctx().clone();
        if self.done {
            return;
        }
        if self.app.view.views.history.is_running() {
            // Picture the computed fleet, as the diagnosis below.
            self.app.view.views.history.wait();
            self.frames = 0;
            ctx.request_repaint();
            return;
        }
        if self.app.view.views.diagnosis.is_running() {
            // Picture the finished diagnosis: wait for it, then let the frame settle again.
            self.app.view.views.diagnosis.wait();
            self.frames = 0;
            ctx.request_repaint();
            return;
        }
        self.frames += 1;
        let proposing = self.app.cache.ident.as_ref().is_some_and(|i| i.is_busy());
        self.idle_frames =
            if self.app.view.views.compare.any_running() || proposing { 0 } else { self.idle_frames + 1 };
        if let Ok(image) = self.image_rx.try_recv() {
            let outcome = write_png(&self.out, &image);
            self.finish(&ctx, outcome);
            return;
        }
        if self.started.elapsed() > TIMEOUT {
            self.finish(&ctx, Err(anyhow!("no screenshot arrived within {} s", TIMEOUT.as_secs())));
            return;
        }
        if !self.requested && self.idle_frames >= WARMUP_FRAMES && self.started.elapsed() >= WARMUP {
            let tx = self.image_tx.clone();
            let repaint = ctx.clone();
            ctx.request_screenshot(move |image| {
                let _ = tx.send(image);
                repaint.request_repaint();
            });
            self.requested = true;
        }
        ctx.request_repaint_after(Duration::from_millis(30));
    }

    /// Keep the picture free of hover effects: the pointer of the (virtual) screen is ignored.
    fn raw_input_hook(&mut self, _ctx: &egui::Context, raw_input: &mut egui::RawInput) {
        raw_input.events.retain(|event| {
            !matches!(
                event,
                egui::Event::PointerMoved(_)
                    | egui::Event::PointerButton { .. }
                    | egui::Event::PointerGone
                    | egui::Event::MouseWheel { .. }
            )
        });
    }

    fn persist_egui_memory(&self) -> bool {
        false
    }
}

/// Write an RGB PNG next to `out` under a temporary name, then rename it into place.
pub fn write_png(out: &Path, image: &egui::ColorImage) -> Result<()> {
    let [width, height] = image.size;
    let rgb: Vec<u8> = image
        .pixels
        .iter()
        .flat_map(|p| {
            let [r, g, b, _] = p.to_srgba_unmultiplied();
            [r, g, b]
        })
        .collect();
    let (w, h) = (u32::try_from(width)?, u32::try_from(height)?);
    let file_name = out.file_name().ok_or_else(|| anyhow!("{} is not a file path", out.display()))?;
    let tmp = out.with_file_name(format!(".{}.tmp-{}", file_name.to_string_lossy(), std::process::id()));
    let written =
        image::save_buffer_with_format(&tmp, &rgb, w, h, image::ColorType::Rgb8, image::ImageFormat::Png)
            .with_context(|| format!("writing {}", tmp.display()))
            .and_then(|()| {
                std::fs::rename(&tmp, out).with_context(|| format!("renaming to {}", out.display()))
            });
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written
}
