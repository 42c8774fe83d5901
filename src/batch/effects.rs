//! Stage 2 of the batch: the project's effects (`add_effects`, then the `auto_effects` loop) added
//! by the workflow ([`effects_of`]); then, once the shaft speed's spool blocks are shared, the
//! output built from them as every project's model is ([`project_model::with_effects`]: checked,
//! its model.json entry and covariance), and the diagnosis of the final model
//! ([`built_and_diagnosed`]).
use anyhow::Result;

use crate::core::identification::pipeline::Identified;
use crate::io::report::DiagnosisEntry;
use crate::workflow::model::{self, OutputPlan};
use crate::workflow::project_model::{self, BuiltOutput, Covariance};
use crate::workflow::runs::Runs;

use super::Timings;
use super::diagnose::diagnose_output;

/// The output built with its final effects and what the diagnosis says of it.
pub struct Built {
    /// The identified model with its effects, its model.json entry and the steps' notes.
    pub output: BuiltOutput,
    /// report.json `diagnosis`, best first.
    pub diagnosis: Vec<DiagnosisEntry>,
    /// The candidates not tried and what the trials were judged on, or why there is no diagnosis.
    pub diagnosis_notes: Vec<String>,
}

/// The gray-box model of the plan's output with its effects, each refitted on the identification
/// data, and the validation error after each step (timed as the effects stage). The shaft speed's
/// spool blocks are shared after this, once every output has its effects.
pub fn effects_of(
    plan: &OutputPlan,
    runs: &Runs,
    identified: &Identified,
    timings: &mut Timings,
) -> model::Effects {
    timings.time_with_fraction(&format!("effects_{}", plan.output), |progress| {
        model::add_project_effects(plan, runs, identified, progress)
    })
}

/// The output built from its effects (its parameter covariance timed as the uncertainty stage)
/// and the diagnosis of the result. An effect that cannot be added, or a loop that fails, fails
/// the batch; a step without a validation error is a note (in the output's notes, as the loop's
/// rounds are).
pub fn built_and_diagnosed(
    plan: &OutputPlan,
    runs: &Runs,
    identified: &Identified,
    mut effects: model::Effects,
    timings: &mut Timings,
) -> Result<Built> {
    let output = plan.output.as_str();
    // The loop's last diagnosis is of the final model (unless a shared block changed it since): it
    // is not computed again.
    let done = effects.sequence.final_diagnosis.take();
    let built = timings.time(&format!("uncertainty_{output}"), || {
        project_model::with_effects(plan.clone(), runs, identified.clone(), effects, Covariance::Estimate)
    })?;
    let diagnosis = timings.time_with_fraction(&format!("diagnosis_{output}"), |progress| {
        diagnose_output(plan, runs, identified, built.effects.model(), done, progress)
    });
    let (diagnosis, diagnosis_notes) = match diagnosis {
        Ok((entries, skipped)) => (entries, skipped),
        Err(e) => (Vec::new(), vec![format!("diagnosis of '{output}': {e}")]),
    };
    Ok(Built { output: built, diagnosis, diagnosis_notes })
}
