//! jetid: turbojet test-bench runs to control-oriented gray-box (Wiener) models.
//!
//! `core` is the headless numerics; `sim` the turbojet simulator; `io` files; `workflow` the one
//! place that turns a project into models (runs by role, each output's model with its effects,
//! model files, shared products); `batch` the headless pipeline over it; `cli` the command line;
//! `ui` the desktop app over it (feature `gui`).
pub mod batch;
pub mod cli;
pub mod core;
pub mod fleet;
pub mod io;
pub mod sim;
#[cfg(feature = "gui")]
pub mod ui;
pub mod workflow;
