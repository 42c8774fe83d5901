//! A project's model file, every output built as the batch builds it: the segment fits, the given
//! clusters or the proposal, the polish, the project's effects and the missing-physics loop, and
//! (when asked) the finished model's parameter covariance. A fleet's reference project and the
//! Python package's `identify` build a project's model here; the batch identifies and adds the
//! effects with its baselines beside them, then builds the output through [`with_effects`] too
//! (`batch::effects`).
use anyhow::{Context, Result};

use crate::core::identification::pipeline::Identified;
use crate::io::model_file::{ModelFile, OutputModel};
use crate::io::project::Project;
use crate::workflow::model::{self, Effects, OutputPlan};
use crate::workflow::model_file::{new_model_file, output_entry, take_saved_clusters};
use crate::workflow::runs::{self, Runs};
use crate::workflow::uncertainty::parameter_covariance;

/// One output of a project as built: its plan, the identified model, its effects and its
/// model.json entry, with what the steps said in words.
#[derive(Clone)]
pub struct BuiltOutput {
    pub plan: OutputPlan,
    pub identified: Identified,
    pub effects: Effects,
    pub entry: OutputModel,
    pub notes: Vec<String>,
}

/// Whether [`build_project`] estimates each output's parameter covariance (the batch's model.json
/// holds it; a fleet's reference does not need it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Covariance {
    Estimate,
    Skip,
}

/// Every output of `project`, whose runs are loaded: the outputs the project models
/// ([`runs::outputs_to_model`]), each on its own thread, in output order. `project` takes the
/// clusters of its saved model first ([`take_saved_clusters`]); what that said heads the notes.
pub fn build_project(
    project: &mut Project,
    runs: &Runs,
    covariance: Covariance,
) -> Result<(ModelFile, Vec<BuiltOutput>, Vec<String>)> {
    let outputs = runs::outputs_to_model(project, &runs.ident)?;
    let notes = take_saved_clusters(project, runs.ident.dt_secs, &outputs)?;
    let project = &*project;
    let built: Vec<Result<BuiltOutput>> = std::thread::scope(|scope| {
        let handles: Vec<_> = outputs
            .iter()
            .map(|output| scope.spawn(move || build_output(project, runs, output, covariance)))
            .collect();
        handles
            .into_iter()
            .map(|h| {
                h.join().unwrap_or_else(|_| Err(anyhow::anyhow!("an output's thread stopped unexpectedly")))
            })
            .collect()
    });
    let built = built.into_iter().collect::<Result<Vec<_>>>()?;
    let mut file = new_model_file(&runs.ident);
    file.outputs = built.iter().map(|b| b.entry.clone()).collect();
    Ok((file, built, notes))
}

/// One output of `project` built as the batch builds it.
pub fn build_output(
    project: &Project,
    runs: &Runs,
    output: &str,
    covariance: Covariance,
) -> Result<BuiltOutput> {
    let plan = OutputPlan::of_project(project, output).with_steps_from(&runs.steps_from);
    let identified = model::identify(&runs.ident, &runs.ident_junctions, &plan)
        .with_context(|| format!("identifying '{output}' from '{}'", runs.ident.name))?;
    let effects = model::add_project_effects(&plan, runs, &identified, &mut |_| true);
    with_effects(plan, runs, identified, effects, covariance)
}

/// The output of `identified` with `effects` added: checked (an effect that could not be added is
/// an error), its model.json entry made, its covariance estimated when asked.
pub fn with_effects(
    plan: OutputPlan,
    runs: &Runs,
    identified: Identified,
    effects: Effects,
    covariance: Covariance,
) -> Result<BuiltOutput> {
    let output = plan.output.clone();
    effects.check(&output)?;
    let mut notes: Vec<String> = model::few_segments_note(&identified.fits).into_iter().collect();
    notes.extend(effects.notes(&output, &plan.effects));
    let unit = runs.ident.output(&output).map(|c| c.unit.clone()).unwrap_or_default();
    let mut entry = output_entry(&identified.model, effects.model(), &unit);
    if covariance == Covariance::Estimate {
        entry.covariance =
            parameter_covariance(&identified.fits, effects.model(), &runs.ident, &plan.settings)
                .map_err(|e| notes.push(format!("parameter uncertainty of '{output}': {e}")))
                .ok();
    }
    Ok(BuiltOutput { plan, identified, effects, entry, notes })
}
