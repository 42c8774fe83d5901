//! jetid: turbojet test-bench runs to control-oriented gray-box (Wiener) models.
//!
//! `core` is the headless numerics; `sim` the turbojet simulator; `io` files; `batch` the headless
//! pipeline; `cli` the command line; `ui` the desktop app (feature `gui`).
pub mod batch;
pub mod cli;
pub mod core;
pub mod io;
pub mod sim;
#[cfg(feature = "gui")]
pub mod ui;
