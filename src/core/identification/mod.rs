//! The identification chain, in the order the data flow through it; every step imports only the
//! steps before it, and none imports `pipeline`, which runs the chain:
//! - the building blocks: `segment`, `set_point` (a set-point channel found in a log), `arx`, `cluster`, `cluster_proposal`, `static_map`,
//!   `initial_state`, `wiener`, `refine`;
//! - the chain's vocabulary: `settings` (how an output is identified), `error`, `fits` (the
//!   segments and their ARX models);
//! - the reduced model: `reduce` (root groups, the one assembly, the polish inside the clusters),
//!   `uncertainty` (how well the data fix its roots);
//! - the automatic proposal: `words` (how its numbers read), `parsimony` (when a candidate beats
//!   the simpler model), `cross_validation` (held-out errors across segments), `dead_time` (the
//!   input delay as a candidate), `direct_fit` (free roots when no cluster gives a model),
//!   `verdict` (what became of each candidate), `selection` (the forward selection), `follow` (a
//!   circle follows a root the polish stops on its rim) and `structure` (the proposal);
//! - `pipeline`: the chain for one output and the live path.
pub mod arx;
pub mod cluster;
pub mod cluster_proposal;
pub mod initial_state;
pub mod refine;
pub mod segment;
pub mod set_point;
pub mod static_map;
pub mod wiener;

pub mod error;
pub mod fits;
pub mod settings;

pub mod reduce;
pub mod uncertainty;

pub mod cross_validation;
pub mod dead_time;
pub mod direct_fit;
pub mod follow;
pub mod parsimony;
pub mod selection;
pub mod structure;
pub mod verdict;
pub mod words;

pub mod pipeline;

#[cfg(test)]
pub(crate) mod test_system;
