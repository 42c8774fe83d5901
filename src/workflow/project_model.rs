//! A project's model file, every output built as the batch builds it: the segment fits, the given
//! clusters or the proposal, the polish, the project's effects and the missing-physics loop, the
//! shaft speed's spool blocks shared with the other outputs, and (when asked) the finished model's
//! parameter covariance. A fleet's reference project and the
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
/// ([`runs::outputs_to_model`]), each identified with its effects on its own thread, the shaft
/// speed's spool blocks then shared with the others ([`model::share_spool`]), and each output built
/// from the result, in output order. `project` takes the clusters of its saved model first
/// ([`take_saved_clusters`]); what that said heads the notes.
pub fn build_project(
    project: &mut Project,
    runs: &Runs,
    covariance: Covariance,
) -> Result<(ModelFile, Vec<BuiltOutput>, Vec<String>)> {
    let outputs = runs::outputs_to_model(project, &runs.ident)?;
    let notes = take_saved_clusters(project, runs.ident.dt_secs, &outputs)?;
    let project = &*project;
    let mut stages = on_own_threads(&outputs, |output| identify_with_effects(project, runs, output))
        .into_iter()
        .collect::<Result<Vec<_>>>()?;
    share_the_spool(
        &mut stages.iter_mut().map(|(plan, _, effects)| (&*plan, effects)).collect::<Vec<_>>(),
        runs,
    );
    let built = on_own_threads(stages, |(plan, identified, effects)| {
        with_effects(plan, runs, identified, effects, covariance)
    })
    .into_iter()
    .collect::<Result<Vec<_>>>()?;
    let mut file = new_model_file(&runs.ident);
    file.outputs = built.iter().map(|b| b.entry.clone()).collect();
    Ok((file, built, notes))
}

/// One output of a project identified with its effects: what [`with_effects`] builds it from.
pub type WithEffects = (OutputPlan, Identified, Effects);

/// One output of `project` identified, with the project's effects and the missing-physics loop.
pub fn identify_with_effects(project: &Project, runs: &Runs, output: &str) -> Result<WithEffects> {
    let plan = OutputPlan::of_project(project, output).with_steps_from(&runs.steps_from);
    let identified = model::identify(&runs.ident, &runs.ident_junctions, &plan)
        .with_context(|| format!("identifying '{output}' from '{}'", runs.ident.name))?;
    let effects = model::add_project_effects(&plan, runs, &identified, &mut |_| true);
    Ok((plan, identified, effects))
}

/// The shaft speed's spool blocks shared with every other output's effects ([`model::share_spool`]),
/// each judged on that output's validation runs; nothing without a speed output whose effects
/// were all added. `stages`: each output's plan and effects.
pub fn share_the_spool(stages: &mut [(&OutputPlan, &mut Effects)], runs: &Runs) {
    let outputs: Vec<String> = stages.iter().map(|(plan, _)| plan.output.clone()).collect();
    let Some(speed) = model::spool_output(&outputs) else { return };
    let Some(spool) = stages
        .iter()
        .find(|(plan, effects)| plan.output == speed && effects.check(speed).is_ok())
        .map(|(_, effects)| effects.model().clone())
    else {
        return;
    };
    for (plan, effects) in stages.iter_mut() {
        let validation = runs.validation_of(&plan.output);
        model::share_spool(effects, &spool, &plan.settings, &runs.ident, &validation);
    }
}

/// `f` of each item on its own thread, the results in the items' order.
pub fn on_own_threads<I: Send, R: Send>(
    items: impl IntoIterator<Item = I>,
    f: impl Fn(I) -> Result<R> + Sync,
) -> Vec<Result<R>> {
    let f = &f;
    std::thread::scope(|scope| {
        let handles: Vec<_> = items.into_iter().map(|item| scope.spawn(move || f(item))).collect();
        handles
            .into_iter()
            .map(|h| {
                h.join().unwrap_or_else(|_| Err(anyhow::anyhow!("an output's thread stopped unexpectedly")))
            })
            .collect()
    })
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
