//! model.json from built models, and the clusters of a saved one: the one place that writes an
//! output's entry (the Wiener part, roots and static map of the model with its effects, the
//! clusters and polish record of the model it was built from), for the batch and the app's File >
//! Export model alike.
use anyhow::Result;

use crate::core::effects::ExtendedModel;
use crate::core::identification::pipeline::GrayBoxModel;
use crate::core::run::Run;
use crate::io::model_file::{ModelFile, OutputModel, SignalInfo, structures_from_model};
use crate::io::project::Project;

/// An empty model file for models identified on `ident`: its sample time and input.
pub fn new_model_file(ident: &Run) -> ModelFile {
    let input = SignalInfo { name: ident.input.name.clone(), unit: ident.input.unit.clone() };
    let mut file = ModelFile::new(ident.dt_secs, input);
    file.input_range = input_range(&ident.input.values);
    file
}

/// The lowest and highest of an identification input (`None` when it has no finite value).
pub fn input_range(u: &[f64]) -> Option<[f64; 2]> {
    let (lo, hi) = u
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
    (lo <= hi).then_some([lo, hi])
}

/// The entry of one output: `current` is the model with its effects (fitted together with the
/// gain, roots and static map beside them, so those are taken from it), `model` the gray-box model
/// it was built from (clusters, polish record).
pub fn output_entry(model: &GrayBoxModel, current: &ExtendedModel, unit: &str) -> OutputModel {
    let plain = &model.wiener.linear.tf;
    // A structural refinement the effects loop added changes the roots.
    let (poles, zeros) = current
        .roots()
        .unwrap_or_else(|_| (plain.poles().unwrap_or_default(), plain.zeros().unwrap_or_default()));
    OutputModel {
        name: model.output.clone(),
        unit: unit.to_owned(),
        wiener: current.wiener.clone(),
        static_map_beta: current.wiener.map.beta(),
        poles,
        zeros,
        clusters: model.clusters.clone(),
        refinement: model.refinement.clone(),
        effects: current.records(),
        covariance: None,
    }
}

/// Take the clusters of the project's saved model (`clusters_from` / `--clusters`) for every output
/// that has none of its own, with the input dead time the saved model carries (unless the project
/// sets one), as the app's File > Import model does; say which outputs fall back to the automatic
/// proposal.
pub fn take_saved_clusters(project: &mut Project, dt_secs: f64, outputs: &[String]) -> Result<Vec<String>> {
    let Some(path) = project.clusters_from.clone() else { return Ok(Vec::new()) };
    let saved = structures_from_model(&path, dt_secs)?;
    let mut notes = Vec::new();
    for output in outputs {
        if project.clusters.contains_key(output) {
            notes.push(format!(
                "'{output}': the project's own clusters take precedence over {}",
                path.display()
            ));
        } else if let Some(structure) = saved.get(output) {
            project.clusters.insert(output.clone(), structure.clusters.clone());
            let settings = project.settings.entry(output.clone()).or_insert_with(|| project_settings(output));
            settings.dead_time_samples = settings.dead_time_samples.or(Some(structure.dead_time_samples));
            notes.push(format!(
                "'{output}': {} clusters taken from {}",
                structure.clusters.len(),
                path.display()
            ));
        } else {
            notes.push(format!(
                "'{output}': {} holds no clusters for it; the automatic proposal is used",
                path.display()
            ));
        }
    }
    Ok(notes)
}

/// The settings an output gets when the project has none for it.
fn project_settings(output: &str) -> crate::core::identification::settings::OutputSettings {
    crate::core::identification::settings::OutputSettings::for_output(output)
}
