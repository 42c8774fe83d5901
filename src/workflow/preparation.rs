//! How much a preparation choice moves the model. When the identification run's steps are detected
//! on a channel other than the input (a set-point found in the log, or the one the project names),
//! the plain model (before any effect) is identified again with the steps detected on the input, and
//! both are scored on every compared run. The report says by how much the choice of the channel moves
//! the model, so a user sees whether it matters on their data before trusting either.
use crate::core::identification::pipeline::{Identified, predict_scored};
use crate::core::run::Run;
use crate::io::report::preparation::{RunUnderBoth, SegmentationChoice};
use crate::workflow::model::{self, OutputPlan};
use crate::workflow::runs::{Runs, StepsFrom};

/// The segmentation choice of `plan`'s output, when its steps came from a channel other than the
/// input and were detected (not given as segments); `None` otherwise.
pub fn segmentation_choice(
    runs: &Runs,
    plan: &OutputPlan,
    identified: &Identified,
) -> Option<SegmentationChoice> {
    if plan.segments.is_some() {
        return None;
    }
    let (steps_from, found) = match &runs.steps_from {
        StepsFrom::Input => return None,
        StepsFrom::Named(name) => (name.clone(), false),
        StepsFrom::Found(set_point) => (set_point.channel.clone(), true),
    };
    let on_input = OutputPlan { steps_from: None, ..plan.clone() };
    let alternative = match model::identify(&runs.ident, &runs.ident_junctions, &on_input) {
        Ok(alternative) => alternative,
        Err(e) => {
            return Some(SegmentationChoice {
                steps_from,
                found,
                runs: Vec::new(),
                on_input_fails: Some(e.to_string()),
                moved_pct: None,
            });
        }
    };
    let (output, initial) = (plan.output.as_str(), plan.settings.initial_state);
    let rmse = |identified: &Identified, run: &Run| {
        predict_scored(&identified.model.wiener, run, output, initial).ok().map(|p| p.metrics.rmse)
    };
    let runs: Vec<RunUnderBoth> = runs
        .compared()
        .into_iter()
        .filter_map(|run| {
            Some(RunUnderBoth {
                run: run.name.clone(),
                rmse: rmse(identified, run)?,
                rmse_on_input: rmse(&alternative, run)?,
            })
        })
        .collect();
    let moved_pct = SegmentationChoice::moved_pct_of(&runs);
    Some(SegmentationChoice { steps_from, found, runs, on_input_fails: None, moved_pct })
}
