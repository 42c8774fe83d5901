//! `jetid simulate`: run the bundled turbojet simulator and write a run file (and optionally the
//! noiseless truth to a second file).
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};

use crate::io::csv_run::write_run;
use crate::sim::{Effect, EngineFamily, SimConfig, TestKind, simulate};

/// The test designs of METHOD.md.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum TestArg {
    /// Warm-up at idle, then steps A–H held until settled.
    Ident,
    /// Fast steps, ramps, a sinusoid and whole-range steps.
    Validation,
    /// Logarithmic chirp 0.574–13.78 rad/s around a mid operating point.
    Chirp,
    /// 300 samples at a constant 5.43 gal/h.
    Steady,
}

impl From<TestArg> for TestKind {
    fn from(arg: TestArg) -> Self {
        match arg {
            TestArg::Ident => TestKind::Ident,
            TestArg::Validation => TestKind::Validation,
            TestArg::Chirp => TestKind::Chirp,
            TestArg::Steady => TestKind::Steady,
        }
    }
}

#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// Test design.
    #[arg(long, value_enum)]
    pub test: TestArg,
    /// Switch on an effect of the catalog, ID or ID:name=value,... (repeatable), e.g.
    /// `thermal_soak:gain=0.06,tau_s=40`.
    #[arg(long = "effect", value_name = "ID[:k=v,...]")]
    pub effects: Vec<String>,
    /// Seed of the noise generator.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Simulate the engine of the small-turbojet family named by this seed (fuel system, spool
    /// time-constant law, steady maps, stand and sensor noise all drawn) instead of the bundled
    /// SR-30 calibration.
    #[arg(long, value_name = "SEED")]
    pub engine: Option<u64>,
    /// Play the test design this many times end to end, the engine running through (a long log:
    /// `--test ident --repeat 450` is 1.5 M samples, about 47 hours at 8.85 Hz).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub repeat: u32,
    /// Run file to write (CSV).
    #[arg(long)]
    pub out: PathBuf,
    /// Also write the noiseless outputs to this file (same columns and time base).
    #[arg(long = "truth-out")]
    pub truth_out: Option<PathBuf>,
}

pub fn run(args: &SimulateArgs) -> Result<()> {
    if let Some(truth) = &args.truth_out
        && let Some(why) =
            crate::io::paths::overwrites_input("--truth-out", truth, &[("--out", args.out.as_path())])
    {
        anyhow::bail!("{why}: the truth and the measured run are two files");
    }
    let effects = args
        .effects
        .iter()
        .map(|spec| spec.parse::<Effect>().with_context(|| format!("bad --effect `{spec}`")))
        .collect::<Result<Vec<_>>>()?;
    let kind = TestKind::from(args.test);
    let name =
        args.out.file_stem().map_or_else(|| kind.name().to_owned(), |s| s.to_string_lossy().into_owned());
    let mut cfg = SimConfig::for_test(&name, kind, args.seed)
        .context("setting up the simulation")?
        .with_effects(effects);
    if args.repeat > 1 {
        cfg.profile = cfg
            .profile
            .repeated(args.repeat as usize, crate::sim::DT_SECS)
            .context("repeating the test design")?;
    }
    let cfg = match args.engine {
        Some(seed) => cfg.on_engine(&EngineFamily::small_turbojets().draw(seed)),
        None => cfg,
    };
    let output = simulate(&cfg).with_context(|| format!("simulating the {} test", kind.name()))?;
    write_run(&args.out, &output.measured).with_context(|| format!("writing {}", args.out.display()))?;
    if let Some(truth_path) = &args.truth_out {
        write_run(truth_path, &output.truth).with_context(|| format!("writing {}", truth_path.display()))?;
    }
    Ok(())
}
