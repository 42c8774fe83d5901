//! `jetid export`: a saved model as a self-contained Python, C99 or MATLAB program that simulates
//! it exactly as `jetid predict` does (from the steady state of the first input sample).
//!
//! [`plan::Plan`] lists, per output, the steps of the signal path with their numbers (splits and
//! gains worked out here); each language module renders that plan together with a fixed runtime
//! of the same recursions as `core::effects` (same initial conditions, same order of operations),
//! so the generated programs agree with jetid to rounding.
use crate::core::effects::EffectError;
use crate::io::model_file::ModelFile;

mod c;
mod matlab;
mod parts;
pub mod plan;
mod python;

pub use plan::Plan;

/// The languages a model can be exported to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// One Python file needing numpy and python-control.
    Python,
    /// One C99 file needing libm only.
    C,
    /// One MATLAB/Octave function file (`tf` objects need the Control System Toolbox or Octave's
    /// control package; the simulation needs neither).
    Matlab,
}

/// What keeps a model from being exported.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ExportError {
    /// The model file lists no output.
    #[error("the model holds no output model")]
    NoOutputs,
    /// An effect record cannot be rebuilt or does not fit the output's linear block.
    #[error("output '{output}': {source}")]
    Effect {
        output: String,
        #[source]
        source: EffectError,
    },
    /// The linear block cannot be simulated from a steady state.
    #[error("output '{output}': the linear block cannot be exported: {reason}")]
    BadLinearBlock { output: String, reason: String },
    /// A signal name that the generated code could not carry as a string or CSV header cell.
    #[error("the {what} name {name:?} cannot be exported: {reason}")]
    UnsupportedName { what: &'static str, name: String, reason: String },
    /// Two outputs whose names become the same identifier.
    #[error("outputs '{first}' and '{second}' would both be called '{ident}' in the generated code")]
    NameClash { first: String, second: String, ident: String },
    /// The MATLAB function is named after its file.
    #[error(
        "a MATLAB file is called by its name, and '{name}' is not a MATLAB identifier (letters, digits and \
         '_', starting with a letter, at most 63 characters): name the --out file e.g. jetid_model.m"
    )]
    BadMatlabName { name: String },
    /// A stored covariance that does not describe the output's parameters (a hand-edited file).
    #[error("output '{output}': the stored parameter covariance cannot be exported: {reason}")]
    BadCovariance { output: String, reason: String },
}

/// The program text of `model` in `format`. `source` names the model file in the generated
/// header; `name` is the generated file's stem (MATLAB calls a function file by it).
pub fn export(model: &ModelFile, source: &str, format: Format, name: &str) -> Result<String, ExportError> {
    let plan = Plan::new(model, source)?;
    Ok(match format {
        Format::Python => python::render(&plan),
        Format::C => c::render(&plan),
        Format::Matlab => matlab::render(&plan, name)?,
    })
}

/// `x` with the fewest digits that read back to the same f64 (valid in all three languages).
fn num(x: f64) -> String {
    format!("{x:?}")
}

/// `xs` as `open x0, x1, … close`.
fn list(xs: &[f64], open: &str, close: &str) -> String {
    let items: Vec<String> = xs.iter().map(|x| num(*x)).collect();
    format!("{open}{}{close}", items.join(", "))
}

/// The header lines every generated file starts with (without comment markers).
fn header(plan: &Plan, language: &str) -> Vec<String> {
    let mut lines = vec![
        format!("jetid model exported from {} as {language}.", plan.source),
        format!(
            "Input '{}', sample time {} s. Every output is simulated as `jetid predict` does: from the steady",
            plan.input,
            num(plan.dt_secs)
        ),
        "state of the first input sample, along u -> [effects] -> G(z) -> v -> f(v) -> [effects] -> y."
            .to_owned(),
    ];
    for out in &plan.outputs {
        let effects = if out.effects.is_empty() { "none".to_owned() } else { out.effects.join(", ") };
        lines.push(format!("Output '{}' [{}]: effects {effects}.", out.name, out.unit));
    }
    lines
}
