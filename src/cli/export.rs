//! `jetid export --model MODEL.json --format python|c|matlab --out FILE`: a saved model as a
//! self-contained program that reproduces `jetid predict`.
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

use crate::io::atomic::write_atomic;
use crate::io::export::{Format, export};
use crate::io::model_file::read_model;
use crate::io::paths::overwrites_input;

#[derive(Debug, Args)]
pub struct ExportArgs {
    /// A model.json written by `jetid --batch` or the app.
    #[arg(long)]
    pub model: PathBuf,
    /// The language of the program written.
    #[arg(long, value_enum)]
    pub format: FormatArg,
    /// The file to write (a MATLAB file's name is its function's name).
    #[arg(long)]
    pub out: PathBuf,
}

/// `--format`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum FormatArg {
    Python,
    C,
    Matlab,
}

impl From<FormatArg> for Format {
    fn from(arg: FormatArg) -> Self {
        match arg {
            FormatArg::Python => Self::Python,
            FormatArg::C => Self::C,
            FormatArg::Matlab => Self::Matlab,
        }
    }
}

pub fn run(args: &ExportArgs) -> Result<()> {
    if let Some(why) = overwrites_input("--out", &args.out, &[("--model", args.model.as_path())]) {
        anyhow::bail!(why);
    }
    let model = read_model(&args.model)?;
    let source = args
        .model
        .file_name()
        .map_or_else(|| args.model.display().to_string(), |n| n.to_string_lossy().into_owned());
    let stem = args.out.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let text = export(&model, &source, args.format.into(), &stem)
        .with_context(|| format!("exporting {}", args.model.display()))?;
    write_atomic(&args.out, text.as_bytes())?;
    println!(
        "wrote {} ({} model, outputs: {})",
        args.out.display(),
        match args.format {
            FormatArg::Python => "Python",
            FormatArg::C => "C99",
            FormatArg::Matlab => "MATLAB",
        },
        model.outputs.iter().map(|o| o.name.as_str()).collect::<Vec<_>>().join(", ")
    );
    Ok(())
}
