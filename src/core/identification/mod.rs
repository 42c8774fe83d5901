//! The identification chain, in the order the data flow through it: segments of the
//! identification run → one high-order ARX model per segment (`arx`) → candidate clusters of their
//! roots (`cluster`, `cluster_proposal`) and the automatic proposal (`structure`) → the reduced
//! linear block (`reduce`, polished by `refine`) → the static map (`static_map`) → the Wiener model
//! (`wiener`). `pipeline` runs the chain for one output; `initial_state` is where a scored
//! simulation starts.
pub mod arx;
pub mod cluster;
pub mod cluster_proposal;
pub mod cross_validation;
pub mod dead_time;
pub mod direct_fit;
pub mod initial_state;
pub mod pipeline;
pub mod reduce;
pub mod refine;
pub mod segment;
pub mod static_map;
pub mod structure;
pub mod wiener;
