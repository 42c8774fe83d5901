//! `jetid simulate-fleet --engines N --runs M --seed S --out DIR`: a simulated fleet for `jetid
//! fleet` (see `sim::fleet`): per engine a commissioning run and its reference (identified once
//! here, or left to the fleet as a project), M runs with a hidden health state, DIR/manifest.toml and
//! DIR/truth.csv (the injected health, which `jetid fleet` never reads). Written through a staging
//! folder: an interrupted generation leaves nothing.
use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};

use crate::core::parallel::on_two_threads;
use crate::io::atomic::write_atomic;
use crate::io::csv_run::write_run;
use crate::io::model_file::write_model;
use crate::io::staging::Staging;
use crate::sim::fleet::{FleetConfig, SimulatedEngine, check, simulate_engine};

/// What each engine's manifest entry names as its reference.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ReferenceArg {
    /// Identify each engine's reference here, once, and name the model.json.
    Model,
    /// Name a project with the commissioning run: `jetid fleet` identifies it.
    Project,
}

#[derive(Debug, Args)]
pub struct SimulateFleetArgs {
    /// Engines drawn from the small-turbojet family.
    #[arg(long, default_value_t = 4)]
    pub engines: usize,
    /// Runs per engine.
    #[arg(long, default_value_t = 10)]
    pub runs: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Length of each run, s (holds of 25 s after a first of 20 s; at least 95 s).
    #[arg(long = "run-secs", default_value_t = 220.0)]
    pub run_secs: f64,
    /// Probability that a run has a fault (a calibration step, a slow spool or fuel starvation).
    #[arg(long = "fault-rate", default_value_t = 0.03)]
    pub fault_rate: f64,
    #[arg(long, value_enum, default_value_t = ReferenceArg::Model)]
    pub reference: ReferenceArg,
    /// The folder the fleet is written to.
    #[arg(long)]
    pub out: PathBuf,
}

/// The date of run `r` (0-based): weekly, four runs a month.
fn date_of(r: usize) -> String {
    format!("{:04}-{:02}-{:02}", 2024 + r / 48, 1 + (r / 4) % 12, 1 + 7 * (r % 4))
}

pub fn run(args: &SimulateFleetArgs) -> Result<()> {
    let cfg = FleetConfig {
        engines: args.engines,
        runs: args.runs,
        seed: args.seed,
        run_secs: args.run_secs,
        fault_rate: args.fault_rate,
    };
    check(&cfg)?;
    let indices: Vec<usize> = (0..cfg.engines).collect();
    let identify = args.reference == ReferenceArg::Model;
    let engines = on_two_threads(&indices, |&i| -> Result<_> {
        let engine = simulate_engine(&cfg, i).with_context(|| format!("simulating engine {}", i + 1))?;
        let reference = identify
            .then(|| crate::fleet::reference::identify_run(&engine.commissioning))
            .transpose()
            .with_context(|| format!("identifying the reference of engine {}", i + 1))?;
        Ok((engine, reference))
    });
    let staging = Staging::new(&args.out)?;
    let dir = staging.path();
    let mut written = Vec::new();
    let mut manifest = format!(
        "# A simulated fleet (jetid simulate-fleet --engines {} --runs {} --seed {}): truth.csv holds the\n\
         # injected health of every run; jetid fleet never reads it.\nname = \"simulated fleet (seed {})\"\n",
        cfg.engines, cfg.runs, cfg.seed, cfg.seed
    );
    let mut truth = String::from("engine,run,date,meter_gain,input_gain,tau_scale,thrust_shift_n,fault\n");
    for (i, engine) in engines.into_iter().enumerate() {
        let (engine, reference) = engine?;
        let name = format!("e{:03}", i + 1);
        let mut file = |file_name: String| {
            written.push(file_name.clone());
            dir.join(file_name)
        };
        write_run(&file(format!("{name}_commissioning.csv")), &engine.commissioning)?;
        let reference_line = match reference {
            Some(model) => {
                write_model(&file(format!("{name}_reference.json")), &model)?;
                format!("reference = \"{name}_reference.json\"")
            }
            None => {
                let project =
                    format!("name = \"{name} commissioning\"\nident = \"{name}_commissioning.csv\"\n");
                write_atomic(&file(format!("{name}_project.toml")), project.as_bytes())?;
                format!("reference_project = \"{name}_project.toml\"")
            }
        };
        let _ = write!(
            manifest,
            "\n# {}\n[[engine]]\nname = \"{name}\"\n{reference_line}\nruns = [\n",
            engine.drawn.describe()
        );
        write_runs(&engine, &name, &mut file, &mut manifest, &mut truth)?;
        manifest.push_str("]\n");
    }
    write_atomic(&dir.join("manifest.toml"), manifest.as_bytes())?;
    write_atomic(&dir.join("truth.csv"), truth.as_bytes())?;
    written.extend(["manifest.toml".to_owned(), "truth.csv".to_owned()]);
    staging.commit(&written)?;
    println!(
        "wrote a fleet of {} engines × {} runs to {} (manifest.toml, truth.csv)",
        cfg.engines,
        cfg.runs,
        args.out.display()
    );
    Ok(())
}

fn write_runs(
    engine: &SimulatedEngine,
    name: &str,
    file: &mut dyn FnMut(String) -> PathBuf,
    manifest: &mut String,
    truth: &mut String,
) -> Result<()> {
    for (r, (run, health)) in engine.runs.iter().enumerate() {
        let run_name = format!("r{:02}", r + 1);
        write_run(&file(format!("{name}_{run_name}.csv")), run)?;
        let date = date_of(r);
        let _ = writeln!(
            manifest,
            "  {{ path = \"{name}_{run_name}.csv\", date = \"{date}\", name = \"{run_name}\" }},"
        );
        let _ = writeln!(
            truth,
            "{name},{run_name},{date},{},{},{},{},{}",
            health.meter_gain,
            health.input_gain,
            health.tau_scale,
            health.thrust_shift_n,
            health.fault.map_or("none", |f| f.name())
        );
    }
    Ok(())
}
