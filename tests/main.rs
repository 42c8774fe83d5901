//! jetid's integration tests: one test target (one link of the library and the app), a module per
//! area, the shared fixtures in `common`. `cargo test` runs them all; `cargo test --test integration
//! diagnosis::` runs one area.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

mod after_the_loop;
mod app;
mod app_compare;
mod app_control;
mod app_diagnosis;
mod app_history;
mod app_roles;
mod app_zplane;
mod architecture;
mod baselines;
mod batch_cli;
mod control;
mod coverage;
mod diagnosis;
mod edges;
mod engine_family;
mod export;
mod export_parity;
mod figures;
mod fleet;
mod hostile;
mod identification;
mod long_runs;
mod parser_props;
mod realdata;
mod residuals;
mod run_files;
mod simulator;
mod validation_stats;
mod workflow;
