//! "Where it fails": the residual of the model on one scored run, taken apart
//! ([`crate::core::residuals`]).
use super::command::Command;
use super::model_cache::LiveModel;
use super::model_ui::hint;
use super::session::Session;

/// The residual analyses of the current model, computed once per model.
#[derive(Default)]
pub struct ResidualsState {
    /// The scored run shown (its index in the session).
    pub run: Option<usize>,
}

pub fn where_it_fails_ui(
    ui: &mut egui::Ui,
    _output: &str,
    _state: &mut ResidualsState,
    _session: &Session,
    _live: &LiveModel,
) -> Vec<Command> {
    hint(ui, "Residual analysis: not drawn yet.");
    Vec::new()
}
