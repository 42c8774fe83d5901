//! `jetid inspect RUN.csv`: load a run file as the pipeline would and print what was read.
use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

use crate::core::run::{Channel, Run};
use crate::io::csv_run::{LoadNotes, load_run_with_notes};

#[derive(Debug, Args)]
pub struct InspectArgs {
    /// The run file (CSV).
    pub file: PathBuf,
    #[command(flatten)]
    pub read: super::read_args::ReadArgs,
}

pub fn run(args: &InspectArgs) -> Result<()> {
    let opts = args.read.options(&args.file)?;
    // The loader's errors already name the file, row and column.
    let (run, notes) = load_run_with_notes(&args.file, &opts).context("cannot load the run file")?;
    print!("{}", summary(&run, &notes));
    Ok(())
}

/// The text `jetid inspect` prints.
pub fn summary(run: &Run, notes: &LoadNotes) -> String {
    let mut out = String::new();
    // Writing into a String cannot fail; the results are ignored below.
    let (Some(t0), Some(t_end)) = (run.t_secs.first(), run.t_secs.last()) else {
        let _ = writeln!(out, "run {}: no samples", run.name);
        return out;
    };
    let _ = writeln!(out, "run {}", run.name);
    let _ = writeln!(
        out,
        "samples   {} (rows {}..{} of {} in the file)",
        run.len(),
        notes.kept_rows.start,
        notes.kept_rows.end,
        notes.rows_in_file
    );
    let _ = writeln!(
        out,
        "dt        {} s ({} Hz)",
        crate::core::numerics::stats::significant(run.dt_secs, 6),
        crate::core::numerics::stats::significant(1.0 / run.dt_secs, 5)
    );
    let sig = |x: f64| crate::core::numerics::stats::significant(x, 4);
    let _ = writeln!(out, "duration  {} s (t = {} s to {} s)", sig(t_end - t0), sig(*t0), sig(*t_end));
    let time_source = notes.time_column.as_ref().map_or("sample time".to_owned(), |c| format!("column {c}"));
    let merged = match notes.merged_repeats {
        0 => String::new(),
        n => format!(" ({n} rows repeating a time stamp merged into their mean)"),
    };
    let resampled = if notes.resampled { ", resampled" } else { "" };
    let _ = writeln!(out, "time      from {time_source}{resampled}{merged}");
    if notes.repaired_samples + notes.trimmed_bad_start + notes.trimmed_bad_end > 0 {
        let _ = writeln!(
            out,
            "quality   {} bad samples interpolated, {} trimmed at the start, {} at the end",
            notes.repaired_samples, notes.trimmed_bad_start, notes.trimmed_bad_end
        );
    }
    for note in notes.reading_notes() {
        let _ = writeln!(out, "note      {note}");
    }
    if let Some(window) = &notes.running_window {
        let _ = writeln!(out, "window    auto: {}", window.reason);
    }
    for (channel, count) in &notes.invalid_samples {
        let _ = writeln!(out, "invalid   {channel}: {count} sentinel samples interpolated");
    }
    for dropped in &notes.dropped_columns {
        let _ = writeln!(out, "left out  {}: {}", dropped.name, dropped.reason);
    }
    let rows: Vec<(&str, &Channel)> = std::iter::once(("input", &run.input))
        .chain(run.outputs.iter().map(|c| ("output", c)))
        .chain(run.aux.iter().map(|c| ("aux", c)))
        .collect();
    let width = rows.iter().map(|(_, c)| c.name.chars().count()).max().unwrap_or(0).max(7);
    let _ = writeln!(
        out,
        "\n{:<7} {:<width$} {:<6} {:>14} {:>14} {:>14}",
        "role", "channel", "unit", "min", "mean", "max"
    );
    for (role, channel) in rows {
        let (min, mean, max) = stats(&channel.values);
        let _ = writeln!(
            out,
            "{role:<7} {:<width$} {:<6} {:>14} {:>14} {:>14}",
            channel.name,
            channel.unit,
            number(min),
            number(mean),
            number(max)
        );
    }
    out
}

fn stats(values: &[f64]) -> (f64, f64, f64) {
    let min = values.iter().copied().fold(f64::INFINITY, f64::min);
    let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mean = values.iter().sum::<f64>() / values.len().max(1) as f64;
    (min, mean, max)
}

/// Six significant digits, in exponent form outside a readable range.
fn number(v: f64) -> String {
    let magnitude = v.abs();
    if magnitude != 0.0 && !(1e-3..1e7).contains(&magnitude) {
        format!("{v:.5e}")
    } else {
        let decimals =
            if magnitude == 0.0 { 0 } else { (5 - magnitude.log10().floor() as i32).max(0) as usize };
        format!("{v:.decimals$}")
    }
}
