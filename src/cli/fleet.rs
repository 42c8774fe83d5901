//! `jetid fleet MANIFEST --out DIR`: every engine's runs against its reference (see `crate::fleet`).
use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

#[derive(Debug, Args)]
pub struct FleetArgs {
    /// The fleet manifest (TOML): engines, each with a reference and its runs.
    pub manifest: PathBuf,
    /// Where fleet.csv, fleet.parquet, report.md and the trend figures go.
    #[arg(long, default_value = "jetid-fleet")]
    pub out: PathBuf,
}

pub fn run(args: &FleetArgs) -> Result<()> {
    let summary = crate::fleet::run(&args.manifest, &args.out)?;
    println!(
        "fleet: {} runs of {} engines scored, {} flagged; wrote {}",
        summary.runs,
        summary.engines,
        summary.flagged.len(),
        summary.out_dir.display()
    );
    for (engine, run, reasons) in &summary.flagged {
        println!("  {engine} / {run}: {reasons}");
    }
    Ok(())
}
