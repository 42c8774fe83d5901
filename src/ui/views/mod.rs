//! The views of the central area, one tab each, and the [`View`] trait they share.
//!
//! A view reads the session and the derived cache, changes only its own state, and returns
//! [`Command`]s; it never imports another view or the app shell (shared pieces are in
//! `ui::widgets`). To add a view: a variant of [`Tab`] with its label and command-line name, a field
//! of [`ViewStates`] holding its state, and `impl View` for that state below.
pub mod bode;
pub mod compare;
pub mod control;
pub mod data;
pub mod diagnosis;
pub mod history;
pub mod static_map;
pub mod traces;
pub mod zplane;

use crate::ui::derived::Derived;
use crate::ui::state::command::Command;
use crate::ui::state::session::Session;
use crate::ui::state::setup::History;
use crate::ui::state::{Tab, ViewState};
use crate::ui::widgets::{self, hint};

/// What every view draws from.
pub struct ViewContext<'a> {
    pub session: &'a Session,
    pub cache: &'a Derived,
    pub history: &'a History,
    pub selected_run: Option<usize>,
}

/// A view of the central area, drawn from its own state.
pub trait View {
    /// True for the views of one output's model (they get the output bar and need a model).
    const MODEL_VIEW: bool = true;

    /// Draw the view; `output` is the output shown (empty for views that are not model views).
    fn ui(&mut self, ui: &mut egui::Ui, output: &str, ctx: &ViewContext<'_>) -> Vec<Command>;
}

/// The Static map view keeps no state of its own.
#[derive(Default)]
pub struct StaticMapViewState;

impl View for data::DataViewState {
    const MODEL_VIEW: bool = false;

    fn ui(&mut self, ui: &mut egui::Ui, _output: &str, ctx: &ViewContext<'_>) -> Vec<Command> {
        data::data_ui(ui, ctx.session, ctx.selected_run, self, ctx.cache)
    }
}

impl View for zplane::ZPlaneViewState {
    fn ui(&mut self, ui: &mut egui::Ui, output: &str, ctx: &ViewContext<'_>) -> Vec<Command> {
        zplane::zplane_ui(ui, output, ctx.history, self, ctx.cache)
    }
}

impl View for bode::BodeViewState {
    fn ui(&mut self, ui: &mut egui::Ui, output: &str, ctx: &ViewContext<'_>) -> Vec<Command> {
        bode::bode_ui(ui, output, self, ctx.cache);
        Vec::new()
    }
}

impl View for StaticMapViewState {
    fn ui(&mut self, ui: &mut egui::Ui, output: &str, ctx: &ViewContext<'_>) -> Vec<Command> {
        static_map::static_map_ui(ui, output, ctx.cache)
    }
}

impl View for traces::TracesViewState {
    fn ui(&mut self, ui: &mut egui::Ui, output: &str, ctx: &ViewContext<'_>) -> Vec<Command> {
        traces::traces_ui(ui, output, self, ctx.session, ctx.cache);
        Vec::new()
    }
}

impl View for compare::CompareViewState {
    fn ui(&mut self, ui: &mut egui::Ui, output: &str, ctx: &ViewContext<'_>) -> Vec<Command> {
        compare::compare_ui(ui, output, self, ctx.session, ctx.cache);
        Vec::new()
    }
}

impl View for control::ControlViewState {
    fn ui(&mut self, ui: &mut egui::Ui, output: &str, ctx: &ViewContext<'_>) -> Vec<Command> {
        control::control_ui(ui, output, self, ctx.session, ctx.cache);
        Vec::new()
    }
}

impl View for diagnosis::DiagnosisViewState {
    fn ui(&mut self, ui: &mut egui::Ui, output: &str, ctx: &ViewContext<'_>) -> Vec<Command> {
        diagnosis::diagnosis_ui(ui, output, self, ctx.session, ctx.cache)
    }
}

impl View for history::HistoryViewState {
    const MODEL_VIEW: bool = false;

    fn ui(&mut self, ui: &mut egui::Ui, _output: &str, _ctx: &ViewContext<'_>) -> Vec<Command> {
        history::history_ui(ui, self)
    }
}

/// Draw `view` as a model view when it is one: the output bar first, and a hint instead when there
/// is no identified output.
fn draw<V: View>(
    ui: &mut egui::Ui,
    view: &mut V,
    output: Option<String>,
    ctx: &ViewContext<'_>,
) -> Vec<Command> {
    if !V::MODEL_VIEW {
        return view.ui(ui, "", ctx);
    }
    let Some(output) = output else {
        hint(ui, "No identification run: give a run the role \"identification\" in the list on the left.");
        return Vec::new();
    };
    let mut commands: Vec<Command> =
        widgets::model::output_bar_ui(ui, ctx.cache, &output).into_iter().collect();
    commands.extend(view.ui(ui, &output, ctx));
    commands
}

/// The output the model views show: the chosen one if it is identified, else the first.
pub fn selected_output(view: &ViewState, cache: &Derived) -> Option<String> {
    let names = cache.output_names();
    let chosen = view.output.as_deref().filter(|name| names.contains(name));
    chosen.or(names.first().copied()).map(ToOwned::to_owned)
}

/// Draw the view of `view.tab`.
pub fn tab_ui(ui: &mut egui::Ui, session: &Session, view: &mut ViewState, cache: &Derived) -> Vec<Command> {
    let output = selected_output(view, cache);
    let ctx = ViewContext { session, cache, history: &view.history, selected_run: view.selected_run };
    let states = &mut view.views;
    match view.tab {
        Tab::Data => draw(ui, &mut states.data, output, &ctx),
        Tab::ZPlane => draw(ui, &mut states.zplane, output, &ctx),
        Tab::Bode => draw(ui, &mut states.bode, output, &ctx),
        Tab::StaticMap => draw(ui, &mut states.static_map, output, &ctx),
        Tab::Traces => draw(ui, &mut states.traces, output, &ctx),
        Tab::Compare => draw(ui, &mut states.compare, output, &ctx),
        Tab::Diagnosis => draw(ui, &mut states.diagnosis, output, &ctx),
        Tab::Control => draw(ui, &mut states.control, output, &ctx),
        Tab::History => draw(ui, &mut states.history, output, &ctx),
    }
}
