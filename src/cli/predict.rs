//! `jetid predict --model MODEL.json --input RUN.csv --out PRED.csv`: simulate a saved model from a
//! run's input alone.
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use clap::Args;

use crate::core::identification::initial_state::InitialState;
use crate::core::run::{Channel, Run};
use crate::io::csv_run::{LoadOptions, load_run, write_run};
use crate::io::model_file::{ModelFile, read_model};

#[derive(Debug, Args)]
pub struct PredictArgs {
    /// A model.json written by `jetid --batch` or the app.
    #[arg(long)]
    pub model: PathBuf,
    /// The run whose input drives the model.
    #[arg(long)]
    pub input: PathBuf,
    /// Where the prediction goes: time_s and one column per modelled output.
    #[arg(long)]
    pub out: PathBuf,
    /// Column mapping ROLE=COLUMN for the input run (repeatable).
    #[arg(long = "map")]
    pub maps: Vec<String>,
    /// Sample time in seconds, for files without a time column.
    #[arg(long)]
    pub sample_time: Option<f64>,
    /// Where the simulation starts: `steady` (the steady state of the first input sample) or
    /// `estimated` (the state that best fits the first seconds of the run's measured output, which
    /// the run must then hold).
    #[arg(long = "initial-state", value_enum, default_value_t = InitialStateArg::Steady)]
    pub initial_state: InitialStateArg,
}

/// Whether `a` and `b` name the same file (`b` need not exist yet).
fn same_file(a: &Path, b: &Path) -> bool {
    let absolute = |p: &Path| {
        std::fs::canonicalize(p).ok().or_else(|| {
            let parent = p.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
            Some(std::fs::canonicalize(parent).ok()?.join(p.file_name()?))
        })
    };
    matches!((absolute(a), absolute(b)), (Some(x), Some(y)) if x == y)
}

/// Refuse a model whose linear block has a pole on or outside the unit circle: simulating it
/// diverges (a model file edited by hand, or written by another tool).
fn check_stable(model: &ModelFile, path: &Path) -> Result<()> {
    for out in &model.outputs {
        let poles = out.wiener.linear.tf.poles().map_err(|e| {
            anyhow!("{}: output '{}': the linear block's poles: {e}", path.display(), out.name)
        })?;
        if let Some(p) = poles.iter().find(|p| p.norm().is_nan() || p.norm() >= 1.0) {
            bail!(
                "{}: output '{}' has a pole at {:.4}{:+.4}i (|z| = {:.4}), on or outside the unit circle: the model is \
                 unstable and its simulation diverges; identify it again",
                path.display(),
                out.name,
                p.re,
                p.im,
                p.norm()
            );
        }
    }
    Ok(())
}

/// `--initial-state`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum InitialStateArg {
    Steady,
    Estimated,
}

impl From<InitialStateArg> for InitialState {
    fn from(arg: InitialStateArg) -> Self {
        match arg {
            InitialStateArg::Steady => Self::Steady,
            InitialStateArg::Estimated => Self::Estimated,
        }
    }
}

pub fn run(args: &PredictArgs) -> Result<()> {
    if same_file(&args.input, &args.out) {
        bail!(
            "--out {} is the --input file: the prediction would overwrite the run it is made from; write it elsewhere",
            args.out.display()
        );
    }
    let model = read_model(&args.model)?;
    check_stable(&model, &args.model)?;
    let mut opts = LoadOptions::from_cli(&args.maps, args.sample_time, None, None, false).context("--map")?;
    // Started from the steady state, the model needs the input alone: a fuel schedule without
    // measured outputs, or with gaps in them, is a run to predict from.
    opts.input_only =
        InitialState::from(args.initial_state) == InitialState::Steady && opts.map.outputs.is_empty();
    let run = load_run(&args.input, &opts)?;
    if run.input.name != model.input.name {
        bail!(
            "{} was identified from the input '{}', but {} gives '{}' as its input: a model driven by another \
             signal predicts nonsense (map the same signal with --map input=COLUMN)",
            args.model.display(),
            model.input.name,
            args.input.display(),
            run.input.name
        );
    }
    if ((run.dt_secs / model.dt_secs) - 1.0).abs() > 0.02 {
        bail!(
            "{} is sampled every {:.5} s but the model every {:.5} s; the model is discrete-time",
            args.input.display(),
            run.dt_secs,
            model.dt_secs
        );
    }
    if model.outputs.is_empty() {
        bail!("{} holds no output model", args.model.display());
    }
    let mut outputs = Vec::new();
    for out in &model.outputs {
        let extended =
            crate::core::effects::ExtendedModel::from_records(&out.name, out.wiener.clone(), &out.effects)
                .with_context(|| format!("{}: output '{}'", args.model.display(), out.name))?;
        let initial = InitialState::from(args.initial_state);
        if initial == InitialState::Estimated && run.output(&out.name).is_none() {
            bail!(
                "--initial-state estimated fits the start to the measured '{}', which {} does not hold \
                 (map it with --map output=COLUMN, or use --initial-state steady)",
                out.name,
                args.input.display()
            );
        }
        let y = extended
            .simulate_scored(&run, initial)
            .with_context(|| format!("simulating output '{}' on {}", out.name, args.input.display()))?;
        outputs.push(Channel { name: out.name.clone(), unit: out.unit.clone(), values: y });
    }
    let prediction = Run {
        name: format!("{} predicted", run.name),
        dt_secs: run.dt_secs,
        t_secs: run.t_secs.clone(),
        input: run.input.clone(),
        outputs,
        aux: Vec::new(),
    };
    write_run(&args.out, &prediction)?;
    println!(
        "wrote {} ({} samples, outputs: {})",
        args.out.display(),
        run.len(),
        model.outputs.iter().map(|o| o.name.as_str()).collect::<Vec<_>>().join(", ")
    );
    Ok(())
}
