//! An engine's reference: a saved model.json, or a project identified once with the workflow's
//! model-building steps (the segment fits, the proposal, the polish and the project's effects), as
//! the batch builds it.
use std::path::Path;

use anyhow::{Context, Result, bail};

use crate::core::effects::ExtendedModel;
use crate::core::run::Run;
use crate::io::model_file::{ModelFile, read_model};
use crate::io::project::load_project;
use crate::workflow::model::{self, OutputPlan};
use crate::workflow::model_file::{new_model_file, output_entry};
use crate::workflow::project_model::{Covariance, build_project};
use crate::workflow::runs::load_runs;

use super::manifest::ReferenceSource;

/// The models a run is scored and fitted against, one per output, and what they were built from.
#[derive(Clone, Debug)]
pub struct Reference {
    pub dt_secs: f64,
    pub input: String,
    /// The input range the models were identified on (the top the saturation check compares with).
    pub input_range: Option<[f64; 2]>,
    pub models: Vec<ExtendedModel>,
    pub units: Vec<String>,
    /// "model.json p300/model.json" or "project p300/project.toml (identified on runB+runD)".
    pub described: String,
}

impl Reference {
    /// The reference of a saved model file.
    pub fn of_model_file(file: &ModelFile, described: String) -> Result<Self> {
        if file.outputs.is_empty() {
            bail!("{described} holds no output model");
        }
        let models = file
            .outputs
            .iter()
            .map(|out| {
                ExtendedModel::from_records(&out.name, out.wiener.clone(), &out.effects)
                    .with_context(|| format!("{described}: output '{}'", out.name))
            })
            .collect::<Result<Vec<_>>>()?;
        for (model, out) in models.iter().zip(&file.outputs) {
            if let Some(p) = model.wiener.linear.tf.unstable_pole().ok().flatten() {
                bail!(
                    "{described}: output '{}' has a pole at |z| = {:.4}, on or outside the unit circle",
                    out.name,
                    p.norm()
                );
            }
        }
        Ok(Self {
            dt_secs: file.dt_secs,
            input: file.input.name.clone(),
            input_range: file.input_range,
            models,
            units: file.outputs.iter().map(|o| o.unit.clone()).collect(),
            described,
        })
    }

    /// The reference `source` names.
    pub fn load(source: &ReferenceSource) -> Result<Self> {
        let (file, described) = Self::model_file(source)?;
        Self::of_model_file(&file, described)
    }

    /// The model file of the reference `source` names (read, or identified from its project) and
    /// how the reference is described: what a distributed engine hands from the task that builds an
    /// engine's reference to the tasks that score its runs ([`Self::of_model_file`] rebuilds it).
    pub fn model_file(source: &ReferenceSource) -> Result<(ModelFile, String)> {
        match source {
            ReferenceSource::Model(path) => Ok((read_model(path)?, format!("model.json {}", path.display()))),
            ReferenceSource::Project(path) => {
                let (file, ident) = identify_project(path)?;
                Ok((file, format!("project {} (identified on {ident})", path.display())))
            }
        }
    }
}

/// Identify every output of the project at `path` as the batch does (effects and the loop
/// included); returns the model file and the identification run's name.
pub fn identify_project(path: &Path) -> Result<(ModelFile, String)> {
    let mut project = load_project(path)?;
    let runs = load_runs(&project)?;
    let (file, _, _) = build_project(&mut project, &runs, Covariance::Skip)?;
    Ok((file, runs.ident.name.clone()))
}

/// Identify every output of one commissioning run (steps detected on its input, no effects): the
/// reference of a simulated engine.
pub fn identify_run(run: &Run) -> Result<ModelFile> {
    let mut file = new_model_file(run);
    for channel in &run.outputs {
        let output = channel.name.as_str();
        let plan = OutputPlan {
            output: output.to_owned(),
            settings: crate::core::identification::settings::OutputSettings::for_output(output),
            segments: None,
            steps_from: None,
            clusters: None,
            effects: model::EffectPlan::default(),
        };
        let identified = model::identify(run, &[], &plan)
            .with_context(|| format!("identifying '{output}' from '{}'", run.name))?;
        let extended = ExtendedModel::from_gray_box(&identified.model);
        file.outputs.push(output_entry(&identified.model, &extended, &channel.unit));
    }
    Ok(file)
}
