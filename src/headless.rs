//! jetid's headless core (the `jetid-headless` crate, re-exported by `jetid`): `core` is the
//! numerics; `sim` the turbojet simulator; `io` files; `workflow` the one place that turns a project
//! into models (runs by role, each output's model with its effects, model files, shared products);
//! `batch` the headless pipeline over it; `fleet` many runs of many engines. The command line and
//! the desktop app are the `jetid` crate's.
pub mod batch;
pub mod core;
pub mod fleet;
pub mod io;
pub mod sim;
pub mod workflow;
