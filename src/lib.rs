//! jetid: turbojet test-bench runs to control-oriented gray-box (Wiener) models.
//!
//! The headless core is the `jetid-headless` crate (`src/headless.rs` says what each of its modules
//! holds), re-exported here. This crate adds `cli`, the command line, and `ui`, the desktop app over
//! the workflow (feature `gui`).
pub use jetid_headless::{batch, core, fleet, io, sim, workflow};
pub mod cli;
#[cfg(feature = "gui")]
pub mod ui;
