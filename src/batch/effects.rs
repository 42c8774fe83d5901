//! Stage 3 of the batch: the project's effects (`--add-effect`, `add_effects`) added in order.
use anyhow::{Context, Result};

use crate::core::diagnose::{EffectSequence, apply_in_order, auto_effects};
use crate::core::effects::ExtendedModel;
use crate::core::identification::pipeline::Identified;
use crate::io::project::Project;

use super::load::Runs;

/// The gray-box model of `output` with the project's effects, each refitted on the identification
/// data, and the validation error after each step. An effect that cannot be added fails the batch;
/// a step without a validation error is a note.
pub fn apply_effects(
    project: &Project,
    runs: &Runs,
    identified: &Identified,
    output: &str,
    notes: &mut Vec<String>,
) -> Result<EffectSequence> {
    let base = ExtendedModel::from_gray_box(&identified.model);
    let settings = project.settings_for(output);
    let validation = runs.validation_of(output);
    let mut sequence =
        apply_in_order(&base, &project.add_effects, &runs.ident, &identified.fits, &settings, &validation);
    if let Some((id, err)) = sequence.failed.take() {
        return Err(err).with_context(|| format!("adding the effect '{id}' to '{output}'"));
    }
    if project.auto_effects > 0 {
        let rounds = auto_effects(
            &mut sequence,
            project.auto_effects,
            &runs.ident,
            &identified.fits,
            &settings,
            &validation,
        )
        .with_context(|| format!("the missing-physics loop on '{output}'"))?;
        if rounds.len() < project.auto_effects {
            notes.push(format!(
                "'{output}': the missing-physics loop stopped after {} of {} rounds: nothing further is significant",
                rounds.len(),
                project.auto_effects
            ));
        }
        for round in &rounds {
            notes.push(format!(
                "'{output}': the loop added {} ({}): {:.3} % → {:.3} %; {}; {}",
                round.added,
                round.kind,
                round.rmspe_before_pct,
                round.rmspe_after_pct,
                round.evidence,
                round.significance
            ));
        }
    }
    notes.extend(sequence.history_gaps.iter().map(|gap| format!("'{output}': {gap}")));
    Ok(sequence)
}
