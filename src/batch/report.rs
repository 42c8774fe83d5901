//! The last stage of the batch: report.json, report.md and model.json, and the summary on stdout.
use std::collections::BTreeMap;
use std::path::Path;

use anyhow::Result;

use crate::core::compare::{ModelKind, OutputModels};
use crate::core::identification::pipeline::Identified;
use crate::core::numerics::metrics::Metrics;
use crate::io::model_file::{ModelFile, write_model};
use crate::io::project::Project;
use crate::io::report::markdown::write_report_md;
use crate::io::report::{IdentSummary, OutputReport, REPORT_FORMAT_VERSION, Report, write_report_json};

use crate::workflow::runs::Runs;

/// The report's head, before any output is modelled.
pub fn new_report(project: &Project, runs: &Runs, diagnostics: Vec<String>) -> Report {
    Report {
        format_version: REPORT_FORMAT_VERSION,
        project: project.name.clone(),
        input: runs.ident.input.name.clone(),
        input_unit: runs.ident.input.unit.clone(),
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
        parameter_intervals: Vec::new(),
        continuous: None,
        preparation: None,
        shared_spool: Vec::new(),
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
    for line in summary_table(report) {
        println!("{line}");
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

/// The scores as a table: a header, then one line per output, model and scored run with the run's
/// role (a held-out run says so).
pub fn summary_table(report: &Report) -> Vec<String> {
    let scores = report.outputs.iter().flat_map(|(output, o)| {
        o.models.iter().flat_map(move |(model, runs)| {
            runs.iter().map(move |(run, m)| Score { output, model: *model, run, metrics: m })
        })
    });
    format_summary(&report.runs, scores)
}

/// One line of the summary: a model's metrics on one run for one output.
struct Score<'a> {
    output: &'a str,
    model: ModelKind,
    run: &'a str,
    metrics: &'a Metrics,
}

/// The summary's columns; the first `TEXT_COLUMNS` are text, the rest numbers.
const COLUMNS: usize = 6;
const TEXT_COLUMNS: usize = 4;

/// Every column as wide as its widest cell, text left-aligned and numbers right-aligned, so the
/// columns line up whatever the names' lengths; `runs` is report.json's role → run map.
fn format_summary<'a>(
    runs: &BTreeMap<String, String>,
    scores: impl Iterator<Item = Score<'a>>,
) -> Vec<String> {
    let roles = run_roles(runs);
    let header: [String; COLUMNS] = ["output", "model", "run", "role", "RMSPE %", "fit %"].map(str::to_owned);
    let mut rows = vec![header];
    rows.extend(scores.map(|s| {
        [
            s.output.to_owned(),
            s.model.to_string(),
            s.run.to_owned(),
            roles.get(s.run).copied().unwrap_or_default().to_owned(),
            format!("{:.4}", s.metrics.rmspe_pct),
            format!("{:.2}", s.metrics.fit_pct),
        ]
    }));
    let widths: Vec<usize> = (0..COLUMNS)
        .map(|c| rows.iter().filter_map(|r| r.get(c)).map(|s| s.chars().count()).max().unwrap_or(0))
        .collect();
    rows.iter()
        .map(|row| {
            let cells: Vec<String> = row
                .iter()
                .zip(&widths)
                .enumerate()
                .map(
                    |(c, (cell, w))| {
                        if c < TEXT_COLUMNS { format!("{cell:<w$}") } else { format!("{cell:>w$}") }
                    },
                )
                .collect();
            cells.join("  ").trim_end().to_owned()
        })
        .collect()
}

/// Each run's role in words ("validation", "held out", "chirp", …) from report.json's `runs`, whose
/// keys number the runs of a role ("held-out 2").
fn run_roles(runs: &BTreeMap<String, String>) -> BTreeMap<&str, &'static str> {
    runs.iter()
        .map(|(role, run)| {
            let kind = role.trim_end_matches(|c: char| c.is_ascii_digit() || c == ' ');
            let words = match kind {
                "held-out" => "held out",
                "validation" => "validation",
                "chirp" => "chirp",
                "steady" => "steady",
                "identification" => "identification",
                _ => "",
            };
            (run.as_str(), words)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn metrics(rmspe_pct: f64, fit_pct: f64) -> Metrics {
        Metrics { rmspe_pct, mape_pct: 0.0, se: 0.0, fit_pct, rmse: 0.0, max_abs_error: 0.0, n: 1 }
    }

    /// Character offsets of each column's start in `line` (columns are separated by two or more spaces).
    fn column_starts(line: &str) -> Vec<usize> {
        let chars: Vec<char> = line.chars().collect();
        (0..chars.len())
            .filter(|&i| {
                chars[i] != ' ' && (i == 0 || (i >= 2 && chars[i - 1] == ' ' && chars[i - 2] == ' '))
            })
            .collect()
    }

    #[test]
    fn the_summary_columns_line_up_for_long_names_and_mark_held_out_runs() {
        let runs = BTreeMap::from([
            ("validation 1".to_owned(), "F".to_owned()),
            ("held-out 1".to_owned(), "runA_2023-01-09_steps60k-34k-100k".to_owned()),
        ]);
        let (good, bad) = (metrics(0.9056, 95.78), metrics(31.9875, -221.63));
        let mut scores = Vec::new();
        for output in ["rpm", "shaft_speed_rpm"] {
            for model in [
                ModelKind::Arx,
                ModelKind::HammersteinWiener,
                ModelKind::HammersteinArx,
                ModelKind::StaticCubic,
            ] {
                scores.push(Score { output, model, run: "F", metrics: &good });
                scores.push(Score { output, model, run: "runA_2023-01-09_steps60k-34k-100k", metrics: &bad });
            }
        }
        let lines = format_summary(&runs, scores.into_iter());
        assert_eq!(lines.len(), 17);
        // Numbers are right-aligned: every line as wide as the header means the number columns end
        // together; the text columns start together.
        let header = &lines[0];
        let width = header.chars().count();
        for line in &lines {
            assert_eq!(line.chars().count(), width, "every line as wide as the header: {line:?}");
            assert_eq!(
                column_starts(line)[..4],
                column_starts(header)[..4],
                "text columns start together: {line:?}"
            );
        }
        let held_out: Vec<&String> = lines.iter().filter(|l| l.contains("runA_")).collect();
        assert_eq!(held_out.len(), 8);
        assert!(held_out.iter().all(|l| l.contains("held out")), "{held_out:?}");
        assert!(lines.iter().filter(|l| l.contains(" F ")).all(|l| l.contains("validation")));
    }
}
