//! The last stage of the batch: report.json, report.md and model.json, and the summary on stdout.
use std::collections::BTreeMap;
use std::path::Path;

use anyhow::Result;

use crate::core::compare::OutputModels;
use crate::core::identification::pipeline::Identified;
use crate::io::model_file::{ModelFile, write_model};
use crate::io::project::Project;
use crate::io::report::{
    IdentSummary, OutputReport, REPORT_FORMAT_VERSION, Report, write_report_json, write_report_md,
};

use crate::workflow::runs::Runs;

/// The report's head, before any output is modelled.
pub fn new_report(project: &Project, runs: &Runs, diagnostics: Vec<String>) -> Report {
    Report {
        format_version: REPORT_FORMAT_VERSION,
        project: project.name.clone(),
        input: runs.ident.input.name.clone(),
        runs: runs.roles(),
        outputs: BTreeMap::new(),
        noise_fit: None,
        monte_carlo: None,
        timings_ms: BTreeMap::new(),
        figures: Vec::new(),
        diagnostics,
    }
}

/// The report of one output before it is scored: what was identified and how runs are started.
pub fn output_report(identified: &Identified, models: &OutputModels, unit: String) -> OutputReport {
    OutputReport {
        unit,
        models: BTreeMap::new(),
        identified: IdentSummary::of(identified),
        diagnosis: Vec::new(),
        effects_applied: Vec::new(),
        error_history: Vec::new(),
        error_boxes: BTreeMap::new(),
        cutoff_rad_s: BTreeMap::new(),
        residuals: Vec::new(),
        initial_state: serde_json::to_value(models.initial_state)
            .ok()
            .and_then(|v| v.as_str().map(str::to_owned))
            .unwrap_or_default(),
        initial_state_meaning: models.initial_state.describe().to_owned(),
        steady_states: None,
        failing: Vec::new(),
        failure_reasons: BTreeMap::new(),
        operating_points: Vec::new(),
        continuous: None,
    }
}

/// Write model.json, report.json and report.md to `out_dir`; returns the names of every file of the
/// results (these three and the figures).
pub fn write_all(out_dir: &Path, model_file: &ModelFile, report: &Report) -> Result<Vec<String>> {
    write_model(&out_dir.join("model.json"), model_file)?;
    write_report_json(&out_dir.join("report.json"), report)?;
    write_report_md(&out_dir.join("report.md"), report)?;
    Ok(["model.json", "report.json", "report.md"]
        .into_iter()
        .map(str::to_owned)
        .chain(report.figures.iter().cloned())
        .collect())
}

/// The scores on stdout, where the results went and which stale files were removed.
pub fn print_summary(report: &Report, out_dir: &Path, removed: &[String]) {
    for (output, o) in &report.outputs {
        for (model, runs) in &o.models {
            for (run, m) in runs {
                println!(
                    "{output:>18} {model:<10} {run:<14} RMSPE {:>8.4} %  fit {:>7.2} %",
                    m.rmspe_pct, m.fit_pct
                );
            }
        }
    }
    println!("wrote model.json, report.json and report.md to {}", out_dir.display());
    if !removed.is_empty() {
        println!(
            "removed {} file(s) an earlier run wrote there and this one did not: {}",
            removed.len(),
            removed.join(", ")
        );
    }
}
