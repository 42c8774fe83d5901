//! report.md of a fleet: a table per engine, flagged runs first with their reasons, the trend figure.
use std::fmt::Write;

use crate::core::health::{BAND_SIGMAS, Estimate};

use super::EngineResult;
use super::flags::plain;
use super::table::Row;

fn with_interval(e: Option<Estimate>, digits: i32) -> String {
    match e {
        None => "–".to_owned(),
        Some(Estimate { value, ci95: None }) => plain(value, digits),
        Some(Estimate { value, ci95: Some([lo, hi]) }) => {
            format!("{} [{}, {}]", plain(value, digits), plain(lo, digits), plain(hi, digits))
        }
    }
}

/// The whole report.
pub(super) fn markdown(name: &str, results: &[EngineResult<'_>], rows: &[Row], figures: &[String]) -> String {
    let mut md = String::new();
    let runs: usize = results.iter().map(|r| r.scores.len()).sum();
    let mut flagged: Vec<(&str, &str)> =
        rows.iter().filter(|r| !r.flag.is_empty()).map(|r| (r.engine.as_str(), r.run.as_str())).collect();
    flagged.dedup();
    let _ = writeln!(md, "# Fleet: {name}\n");
    let _ = writeln!(
        md,
        "{} engines, {runs} runs, {} flagged. Each run is scored against its engine's reference model and its \
         health deltas are fitted by output error from the reference (input gain u → g·u, time-constant scale, \
         each output's map shift; the input offset is not fitted: it reads as a map shift of every output). \
         A run is flagged when a delta lies more than {BAND_SIGMAS} robust σ from its engine's trend over the \
         runs, by more than the smallest change that matters, and its own 95 % interval excludes the trend, when it fits much worse than the engine's usual error, \
         or when its input sits at its limit while the output falls short of the reference. The runs flagged \
         or fitting worse than their engine's usual error are also diagnosed against the reference (the \
         model-building diagnosis, fitted on the first part of the run and judged on the rest): an effect it \
         finds significant is a reason of the flag, with its test and evidence.\n",
        results.len(),
        flagged.len()
    );
    for (result, figure) in results.iter().zip(figures) {
        let engine = &result.engine.name;
        let _ = writeln!(md, "## Engine {engine}\n");
        let _ = writeln!(md, "Reference: {}.\n", result.reference.described);
        let _ = writeln!(md, "![health trend of {engine}]({figure})\n");
        let _ = writeln!(
            md,
            "| run | date | output | RMSE | RMSPE % | input gain [95 %] | τ scale [95 %] | map shift [95 %] | flag |"
        );
        let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|");
        let mine: Vec<&Row> = rows.iter().filter(|r| r.engine == *engine).collect();
        let ordered =
            mine.iter().filter(|r| !r.flag.is_empty()).chain(mine.iter().filter(|r| r.flag.is_empty()));
        for row in ordered {
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                row.run,
                row.date.as_deref().unwrap_or("–"),
                row.output,
                plain(row.rmse, 3),
                plain(row.rmspe_pct, 3),
                with_interval(row.input_gain, 4),
                with_interval(row.tau_scale, 3),
                with_interval(row.map_shift, 3),
                if row.flag.is_empty() { String::new() } else { format!("**{}**", row.flag) }
            );
        }
        let notes: Vec<&String> = result
            .scores
            .iter()
            .flat_map(|s| s.notes.iter().chain(s.diagnosis.iter().flat_map(|d| &d.notes)))
            .collect();
        if !notes.is_empty() {
            let _ = writeln!(md, "\nNotes:\n");
            for note in notes {
                let _ = writeln!(md, "- {note}");
            }
        }
        let _ = writeln!(md);
    }
    md
}
