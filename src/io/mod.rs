//! Files: run CSVs, project files, model.json, reports, figures.
pub mod atomic;
pub mod csv_run;
pub mod export;
pub mod figures;
pub mod model_file;
pub mod paths;
pub mod project;
pub mod report;
pub mod staging;
