//! Stage 3 of the batch: which missing effect or structure would help the final model most.
use anyhow::Result;

use crate::core::diagnose;
use crate::core::effects::ExtendedModel;
use crate::core::identification::pipeline::Identified;
use crate::io::report::DiagnosisEntry;
use crate::workflow::OutputPlan;
use crate::workflow::runs::Runs;

/// The diagnosis of `current` (report.json `diagnosis`, best first) and, in words, the candidates
/// not tried and the structure note. `done` is that diagnosis when the missing-physics loop already
/// made it (it ended on `current`): it is not computed twice. `progress` hears the fraction done.
pub fn diagnose_output(
    plan: &OutputPlan,
    runs: &Runs,
    identified: &Identified,
    current: &ExtendedModel,
    done: Option<diagnose::DiagnosisReport>,
    progress: &mut dyn FnMut(f64) -> bool,
) -> Result<(Vec<DiagnosisEntry>, Vec<String>)> {
    let output = plan.output.as_str();
    let validation = runs.validation_of(output);
    let report = match done {
        Some(report) => report,
        None => diagnose::diagnose_admissible(
            current,
            &runs.ident,
            &identified.fits,
            &validation,
            &plan.settings,
            progress,
        )?,
    };
    let skipped = report
        .skipped
        .iter()
        .map(|s| format!("diagnosis of '{output}': {} not tried: {}", s.effect, s.reason))
        .chain(std::iter::once(format!("diagnosis of '{output}': {}", report.held_out_words())))
        .chain(report.structure_note.iter().map(|n| format!("diagnosis of '{output}': {n}")))
        .chain(report.attribution_note.iter().map(|n| format!("diagnosis of '{output}': {n}")))
        .collect();
    let entries = report
        .entries
        .iter()
        .map(|d| DiagnosisEntry {
            effect: d.effect.to_string(),
            kind: d.kind.label().to_owned(),
            significant: d.significant,
            rmspe_before_pct: d.rmspe_before_pct,
            rmspe_after_pct: d.rmspe_after_pct,
            beyond_noise_after: Some(d.beyond_noise_after),
            evidence: d.evidence.clone(),
            p_value: Some(d.test.p_value),
            held_out_rmspe_pct: d.test.held_out.map(|h| h.rmspe_after_pct),
            significance: d.significance_words(),
        })
        .collect();
    Ok((entries, skipped))
}
