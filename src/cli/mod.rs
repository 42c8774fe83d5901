//! The command line of CONTRACT.md: `jetid`, `jetid --batch`, `jetid predict`, `jetid simulate`,
//! `jetid export`, `jetid fleet`.
use std::path::PathBuf;

use anyhow::Result;
use clap::{Parser, Subcommand};

pub use batch_args::BatchArgs;

pub mod batch_args;
pub mod export;
pub mod fleet;
pub mod inspect;
pub mod predict;
pub mod read_args;
pub mod simulate;
pub mod simulate_fleet;

/// The view `--screenshot` takes unless `--view` says otherwise.
const DEFAULT_VIEW: &str = "data";

#[derive(Debug, Parser)]
#[command(name = "jetid", version, about = "Turbojet test-bench runs to control-oriented gray-box models")]
#[command(args_conflicts_with_subcommands = true)]
pub struct Cli {
    /// Run the headless pipeline instead of opening the desktop app.
    #[arg(long)]
    pub batch: bool,
    #[command(flatten)]
    pub batch_args: BatchArgs,
    /// Open the app on the bundled sample runs (or on PROJECT, with --add-effect applied), save a
    /// PNG of one view to this file, and exit.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// The view to capture with --screenshot: data, zplane, bode, static, traces, compare, diagnosis,
    /// failures (the Diagnosis view's "Where it fails" section), control or history (with --fleet).
    #[arg(long, default_value = DEFAULT_VIEW)]
    pub view: String,
    /// Open a fleet manifest in the app's History view (every engine's runs against its reference);
    /// with --screenshot, picture it with --view history.
    #[arg(long, value_name = "MANIFEST")]
    pub fleet: Option<PathBuf>,
    #[command(subcommand)]
    pub command: Option<Command>,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run the bundled turbojet simulator and write a run file.
    Simulate(simulate::SimulateArgs),
    /// Simulate a saved model from a run's input.
    Predict(predict::PredictArgs),
    /// Load a run file and print what jetid reads from it (channels, sample time, ranges).
    Inspect(inspect::InspectArgs),
    /// Write a saved model as a Python, C99 or MATLAB program that reproduces `jetid predict`.
    Export(export::ExportArgs),
    /// Score every engine's runs against its reference: health deltas, flags, trends.
    Fleet(fleet::FleetArgs),
    /// Simulate a fleet of engines with hidden health states, its manifest and its truth.
    SimulateFleet(simulate_fleet::SimulateFleetArgs),
}

/// A duration on the command line (`--sample-time`): a positive finite number of seconds; a
/// negative one is read as a number (not taken for a flag) to be refused with this message.
pub(crate) fn positive_secs(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        Ok(v) => Err(format!("must be a positive number of seconds, got {v}")),
        Err(_) => Err(format!("must be a positive number of seconds, got \"{text}\"")),
    }
}

/// The error and its causes joined by ": ", each said once: an error whose message already quotes
/// its cause (`segmentation of 'run': no steps found …`) does not get the cause appended again. The
/// binary prints it after "error: "; the Python package raises it.
pub fn error_message(err: &anyhow::Error) -> String {
    let mut out = String::new();
    for cause in err.chain() {
        let text = cause.to_string();
        if out.contains(&text) {
            continue;
        }
        if !out.is_empty() {
            out.push_str(": ");
        }
        out.push_str(&text);
    }
    out
}

/// Dispatch a parsed command line.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Some(Command::Simulate(args)) => simulate::run(&args),
        Some(Command::Inspect(args)) => inspect::run(&args),
        Some(Command::Predict(args)) => predict::run(&args),
        Some(Command::Export(args)) => export::run(&args),
        Some(Command::Fleet(args)) => fleet::run(&args),
        Some(Command::SimulateFleet(args)) => simulate_fleet::run(&args),
        None if cli.batch => {
            if cli.fleet.is_some() {
                anyhow::bail!(
                    "--fleet opens a fleet in the app's History view; it cannot be combined with --batch \
                     (write a fleet's results with `jetid fleet MANIFEST --out DIR`)"
                );
            }
            if cli.screenshot.is_some() {
                anyhow::bail!("--screenshot takes a picture of the app; it cannot be combined with --batch");
            }
            let project = cli.batch_args.project()?;
            crate::batch::run(project, &cli.batch_args.out, cli.batch_args.quiet)
        }
        None if !cli.batch_args.batch_only_flags().is_empty() => anyhow::bail!(
            "{} {} read only by a batch: add --batch to run one (the app and --screenshot take PROJECT, --output and --add-effect)",
            cli.batch_args.batch_only_flags().join(", "),
            if cli.batch_args.batch_only_flags().len() == 1 { "is" } else { "are" }
        ),
        #[cfg(feature = "gui")]
        None if let Some(out) = &cli.screenshot => {
            // `--output NAME` picks the output the model views show (default: the first).
            // PROJECT and `--add-effect ID` picture a project's runs with effects applied.
            let args = &cli.batch_args;
            let output = args.outputs.first().map(String::as_str);
            let fleet = cli.fleet.as_deref();
            crate::ui::screenshot(out, &cli.view, output, args.project.as_deref(), &args.add_effects, fleet)
        }
        None if cli.view != DEFAULT_VIEW => {
            anyhow::bail!("--view {} chooses the view of --screenshot; give --screenshot OUT.png", cli.view)
        }
        None => run_app(&cli.batch_args, cli.fleet.as_deref()),
    }
}

#[cfg(feature = "gui")]
fn run_app(args: &BatchArgs, fleet: Option<&std::path::Path>) -> Result<()> {
    let output = args.outputs.first().map(String::as_str);
    crate::ui::run_app(args.project.as_deref(), output, &args.add_effects, fleet)
}

#[cfg(not(feature = "gui"))]
fn run_app(_: &BatchArgs, _: Option<&std::path::Path>) -> Result<()> {
    anyhow::bail!("this jetid was built without the desktop app (feature `gui`); use `jetid --batch`")
}
