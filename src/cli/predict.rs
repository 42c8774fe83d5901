//! `jetid predict --model MODEL.json --input RUN.csv --out PRED.csv`: simulate a saved model from a
//! run's input alone.
use std::path::{Path, PathBuf};

use crate::core::numerics::stats::significant;
use anyhow::{Context, Result, anyhow, bail};
use clap::Args;

use crate::core::identification::initial_state::InitialState;
use crate::core::run::{Channel, InputCoverage, Run};
use crate::io::csv_run::{load_run, write_run};
use crate::io::model_file::{ModelFile, OutputModel, read_model};
use crate::io::paths::overwrites_input;

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
    /// How the input run is read (as a batch reads a project's runs).
    #[command(flatten)]
    pub read: super::read_args::ReadArgs,
    /// Where the simulation starts: `steady` (the steady state of the first input sample) or
    /// `estimated` (the state that best fits the first seconds of the run's measured output, which
    /// the run must then hold).
    #[arg(long = "initial-state", value_enum, default_value_t = InitialStateArg::Steady)]
    pub initial_state: InitialStateArg,
    /// Refuse a run whose input leaves the range the model was identified on (or changes sign),
    /// instead of saying so on stderr and extrapolating.
    #[arg(long)]
    pub strict: bool,
}

/// Refuse a model whose linear block has a pole on or outside the unit circle: simulating it
/// diverges (a model file edited by hand, or written by another tool).
fn check_stable(model: &ModelFile, path: &Path) -> Result<()> {
    for out in &model.outputs {
        let unstable = out.wiener.linear.tf.unstable_pole().map_err(|e| {
            anyhow!("{}: output '{}': the linear block's poles: {e}", path.display(), out.name)
        })?;
        if let Some(p) = unstable {
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

/// Which share of the run's input lies outside the range the model was identified on (or that it
/// changes sign), in words; with `strict` the run is refused instead.
fn check_coverage(model: &ModelFile, run: &Run, target: &Target<'_>) -> Result<Option<String>> {
    let Some(range) = model.input_range else { return Ok(None) };
    let coverage = InputCoverage::of(&run.input.values, range);
    let Some(words) = coverage.words(&model.input.unit) else { return Ok(None) };
    if target.strict {
        bail!(
            "{}: {words}; --strict refuses it (without --strict the prediction is written and this is said)",
            target.input.display()
        );
    }
    Ok(Some(format!("{}: {words}", target.input.display())))
}

/// The parameter of largest magnitude in an output's model, with its path in model.json
/// (`wiener.map.coeffs_scaled[2]`), to name when the model overflows.
fn largest_parameter(out: &OutputModel) -> (String, f64) {
    fn walk(value: &serde_json::Value, path: String, best: &mut (String, f64)) {
        match value {
            serde_json::Value::Number(n) => {
                let v = n.as_f64().unwrap_or(f64::INFINITY);
                if v.abs().total_cmp(&best.1.abs()).is_gt() {
                    *best = (path, v);
                }
            }
            serde_json::Value::Array(items) => {
                items.iter().enumerate().for_each(|(i, item)| walk(item, format!("{path}[{i}]"), best));
            }
            serde_json::Value::Object(fields) => {
                fields.iter().for_each(|(k, item)| walk(item, format!("{path}.{k}"), best));
            }
            _ => {}
        }
    }
    let mut best = (String::new(), 0.0);
    if let Ok(value) = serde_json::to_value(out) {
        walk(&value, String::new(), &mut best);
    }
    (best.0.trim_start_matches('.').to_owned(), best.1)
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

/// A prediction's model and run, named as the messages name them, and how it is made.
pub struct Target<'a> {
    /// The model file (or what stands for it).
    pub model: &'a Path,
    /// The run file (or what stands for it).
    pub input: &'a Path,
    pub initial_state: InitialState,
    /// Refuse a run whose input leaves the identified range instead of saying so.
    pub strict: bool,
}

pub fn run(args: &PredictArgs) -> Result<()> {
    let inputs = [("--input", args.input.as_path()), ("--model", args.model.as_path())];
    if let Some(why) = overwrites_input("--out", &args.out, &inputs) {
        bail!(why);
    }
    let model = read_model(&args.model)?;
    let mut opts = args.read.options(&args.input)?;
    // Started from the steady state, the model needs the input alone: a fuel schedule without
    // measured outputs, or with gaps in them, is a run to predict from.
    opts.input_only =
        InitialState::from(args.initial_state) == InitialState::Steady && opts.map.outputs.is_empty();
    let run = load_run(&args.input, &opts)?;
    let target = Target {
        model: &args.model,
        input: &args.input,
        initial_state: args.initial_state.into(),
        strict: args.strict,
    };
    let (prediction, coverage) = predict(&model, &run, &target)?;
    if let Some(words) = coverage {
        eprintln!("jetid: {words}");
    }
    write_run(&args.out, &prediction)?;
    println!(
        "wrote {} ({} samples, outputs: {})",
        args.out.display(),
        run.len(),
        model.outputs.iter().map(|o| o.name.as_str()).collect::<Vec<_>>().join(", ")
    );
    Ok(())
}

/// What `jetid predict` writes: every output of `model` simulated from `run`'s input (time, the
/// input, one channel per output), after the checks that the run fits the model; and which share
/// of the input lies outside the identified range, in words. The Python package predicts here too.
pub fn predict(model: &ModelFile, run: &Run, target: &Target<'_>) -> Result<(Run, Option<String>)> {
    check_stable(model, target.model)?;
    check_run_fits_model(model, run, target)?;
    let coverage = check_coverage(model, run, target)?;
    let outputs = model.outputs.iter().map(|out| predict_output(out, run, target)).collect::<Result<_>>()?;
    let prediction = Run {
        name: format!("{} predicted", run.name),
        dt_secs: run.dt_secs,
        t_secs: run.t_secs.clone(),
        input: run.input.clone(),
        outputs,
        aux: Vec::new(),
    };
    Ok((prediction, coverage))
}

/// The run drives the model as it was identified: the same input signal, the same sample time, and
/// a model with at least one output.
fn check_run_fits_model(model: &ModelFile, run: &Run, args: &Target<'_>) -> Result<()> {
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
            "{} is sampled every {} s but the model {} every {} s; the model is discrete-time: resample the run \
             (--resample puts an irregular log on its median step) or identify a model at its sample time",
            args.input.display(),
            significant(run.dt_secs, 5),
            args.model.display(),
            significant(model.dt_secs, 5)
        );
    }
    if model.outputs.is_empty() {
        bail!("{} holds no output model", args.model.display());
    }
    Ok(())
}

/// One output's prediction on the run, its effects included; an output that overflows names the
/// model's largest parameter.
fn predict_output(out: &OutputModel, run: &Run, args: &Target<'_>) -> Result<Channel> {
    let extended =
        crate::core::effects::ExtendedModel::from_records(&out.name, out.wiener.clone(), &out.effects)
            .with_context(|| format!("{}: output '{}'", args.model.display(), out.name))?;
    let initial = args.initial_state;
    if initial == InitialState::Estimated && run.output(&out.name).is_none() {
        bail!(
            "--initial-state estimated fits the start to the measured '{}', which {} does not hold \
             (map it with --map output=COLUMN, or use --initial-state steady)",
            out.name,
            args.input.display()
        );
    }
    let y = extended
        .simulate_scored(run, initial)
        .with_context(|| format!("simulating output '{}' on {}", out.name, args.input.display()))?;
    if let Some(k) = y.iter().position(|v| !v.is_finite()) {
        let (parameter, value) = largest_parameter(out);
        bail!(
            "{}: output '{}' overflows at sample {k} of {} (value {}): a parameter of the model is out of \
             range (the largest: {parameter} = {value:e}); identify the model again",
            args.model.display(),
            out.name,
            args.input.display(),
            y[k]
        );
    }
    Ok(Channel { name: out.name.clone(), unit: out.unit.clone(), values: y })
}
