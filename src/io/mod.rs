//! Files: run CSVs, project files, model.json, reports, figures.
pub mod csv_run;
pub mod atomic;
pub mod model_file;
pub mod project;
pub mod report;
