//! The fleet's table: one row per run and output, written as fleet.csv and fleet.parquet (the same
//! columns; an empty cell in the CSV is a null in the parquet file).
use std::path::Path;
use std::sync::Arc;

use anyhow::{Context, Result};
use parquet::data_type::{BoolType, ByteArray, ByteArrayType, DoubleType};
use parquet::file::writer::SerializedFileWriter;
use parquet::schema::parser::parse_message_type;

use crate::core::health::Estimate;
use crate::io::atomic::write_atomic;

/// One row of the table.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Row {
    pub engine: String,
    pub run: String,
    pub date: Option<String>,
    pub output: String,
    pub rmse: f64,
    pub rmspe_pct: f64,
    pub input_gain: Option<Estimate>,
    /// Held at zero (see `core::health::deltas`): never fitted, always empty.
    pub input_offset: Option<Estimate>,
    pub tau_scale: Option<Estimate>,
    pub map_shift: Option<Estimate>,
    pub map_shift_pct: Option<Estimate>,
    /// Whether the run was diagnosed against the reference (see `fleet::diagnosis`: the screened
    /// runs are).
    pub diagnosed: bool,
    /// The effects the diagnosis finds significant on this output, by id, "; "-separated; empty when
    /// none was found or the run was not diagnosed.
    pub effects: String,
    /// Empty when the run is normal.
    pub flag: String,
}

/// The numeric columns after `rmse` and `rmspe_pct`, each with its `_ci95_low` and `_ci95_high`.
pub const DELTAS: [&str; 5] = ["input_gain", "input_offset", "tau_scale", "map_shift", "map_shift_pct"];

/// Every column, in order.
pub fn columns() -> Vec<String> {
    let mut names: Vec<String> =
        ["engine", "run", "date", "output", "rmse", "rmspe_pct"].map(String::from).to_vec();
    for delta in DELTAS {
        names.extend([delta.to_owned(), format!("{delta}_ci95_low"), format!("{delta}_ci95_high")]);
    }
    names.extend(["diagnosed", "effects", "flag"].map(String::from));
    names
}

impl Row {
    /// The numeric cells from `rmse` on, `None` where empty (the CSV's empty cells).
    pub fn numbers(&self) -> Vec<Option<f64>> {
        let mut cells = vec![Some(self.rmse), Some(self.rmspe_pct)];
        for e in [self.input_gain, self.input_offset, self.tau_scale, self.map_shift, self.map_shift_pct] {
            let ci = e.and_then(|e| e.ci95);
            cells.extend([e.map(|e| e.value), ci.map(|c| c[0]), ci.map(|c| c[1])]);
        }
        cells.into_iter().map(|c| c.filter(|v| v.is_finite())).collect()
    }
}

/// fleet.csv.
pub fn write_csv(path: &Path, rows: &[Row]) -> Result<()> {
    let mut out = csv::Writer::from_writer(Vec::new());
    out.write_record(columns())?;
    for row in rows {
        let mut record = vec![
            row.engine.clone(),
            row.run.clone(),
            row.date.clone().unwrap_or_default(),
            row.output.clone(),
        ];
        record.extend(row.numbers().into_iter().map(|c| c.map(|v| v.to_string()).unwrap_or_default()));
        record.extend([row.diagnosed.to_string(), row.effects.clone(), row.flag.clone()]);
        out.write_record(&record)?;
    }
    let bytes = out.into_inner().context("fleet.csv")?;
    write_atomic(path, &bytes).with_context(|| format!("writing {}", path.display()))
}

/// fleet.parquet: one row group, no compression; text columns UTF-8, numbers optional doubles.
pub fn write_parquet(path: &Path, rows: &[Row]) -> Result<()> {
    let names = columns();
    let mut schema = String::from("message fleet {\n");
    for name in &names {
        let line = match name.as_str() {
            "engine" | "run" | "output" | "effects" | "flag" => {
                format!("  REQUIRED BYTE_ARRAY {name} (UTF8);\n")
            }
            "diagnosed" => format!("  REQUIRED BOOLEAN {name};\n"),
            "date" => format!("  OPTIONAL BYTE_ARRAY {name} (UTF8);\n"),
            _ => format!("  OPTIONAL DOUBLE {name};\n"),
        };
        schema.push_str(&line);
    }
    schema.push('}');
    let schema = Arc::new(parse_message_type(&schema).context("the parquet schema")?);
    let mut bytes = Vec::new();
    {
        let mut writer = SerializedFileWriter::new(&mut bytes, schema, Default::default())?;
        let mut group = writer.next_row_group()?;
        let numbers: Vec<Vec<Option<f64>>> = rows.iter().map(Row::numbers).collect();
        let text = |pick: &dyn Fn(&Row) -> Option<String>| -> Vec<Option<String>> {
            rows.iter().map(pick).collect()
        };
        let mut index = 0;
        while let Some(mut column) = group.next_column()? {
            let name = names.get(index).map(String::as_str).unwrap_or_default();
            match name {
                "engine" => {
                    write_text(column.typed::<ByteArrayType>(), &text(&|r| Some(r.engine.clone())), false)?
                }
                "run" => write_text(column.typed::<ByteArrayType>(), &text(&|r| Some(r.run.clone())), false)?,
                "date" => write_text(column.typed::<ByteArrayType>(), &text(&|r| r.date.clone()), true)?,
                "output" => {
                    write_text(column.typed::<ByteArrayType>(), &text(&|r| Some(r.output.clone())), false)?
                }
                "diagnosed" => {
                    let cells: Vec<bool> = rows.iter().map(|r| r.diagnosed).collect();
                    column.typed::<BoolType>().write_batch(&cells, None, None)?;
                }
                "effects" => {
                    write_text(column.typed::<ByteArrayType>(), &text(&|r| Some(r.effects.clone())), false)?
                }
                "flag" => {
                    write_text(column.typed::<ByteArrayType>(), &text(&|r| Some(r.flag.clone())), false)?
                }
                _ => {
                    let cells: Vec<Option<f64>> =
                        numbers.iter().map(|n| n.get(index - 4).copied().flatten()).collect();
                    let values: Vec<f64> = cells.iter().flatten().copied().collect();
                    let levels: Vec<i16> = cells.iter().map(|c| i16::from(c.is_some())).collect();
                    column.typed::<DoubleType>().write_batch(&values, Some(&levels), None)?;
                }
            }
            column.close()?;
            index += 1;
        }
        group.close()?;
        writer.close()?;
    }
    write_atomic(path, &bytes).with_context(|| format!("writing {}", path.display()))
}

fn write_text(
    column: &mut parquet::column::writer::ColumnWriterImpl<'_, ByteArrayType>,
    cells: &[Option<String>],
    optional: bool,
) -> Result<()> {
    let values: Vec<ByteArray> = cells.iter().flatten().map(|s| ByteArray::from(s.as_str())).collect();
    let levels: Vec<i16> = cells.iter().map(|c| i16::from(c.is_some())).collect();
    column.write_batch(&values, optional.then_some(levels.as_slice()), None)?;
    Ok(())
}
