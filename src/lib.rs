//! jetid: turbojet test-bench runs to control-oriented gray-box (Wiener) models.
//!
//! The headless core is the `jetid-headless` crate (`src/headless.rs`), whose modules this crate
//! re-exports: `core` the numerics; `sim` the turbojet simulator; `io` files; `workflow` the one
//! place that turns a project into models (runs by role, each output's model with its effects,
//! model files, shared products); `batch` the headless pipeline over it; `fleet` many runs of many
//! engines. This crate adds `cli`, the command line, and `ui`, the desktop app over the workflow
//! (feature `gui`).
pub use jetid_headless::{batch, core, fleet, io, sim, workflow};
pub mod cli;
#[cfg(feature = "gui")]
pub mod ui;
