//! The headless core: pure numerics. No egui, no files, no threads.
pub mod run;
pub mod lstsq;
pub mod poly;
pub mod tf;
pub mod arx;
pub mod segment;
pub mod cluster;
pub mod cluster_proposal;
pub mod metrics;
pub mod pipeline;
pub mod static_map;
pub mod wiener;
pub mod lm;
pub mod refine;
