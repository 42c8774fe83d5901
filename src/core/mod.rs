//! The headless core: pure numerics. No egui, no files, no threads.
pub mod arx;
pub mod cluster;
pub mod cluster_proposal;
pub mod diagnose;
pub mod effects;
pub mod lm;
pub mod lstsq;
pub mod metrics;
pub mod pipeline;
pub mod poly;
pub mod refine;
pub mod run;
pub mod segment;
pub mod static_map;
pub mod tf;
pub mod wiener;
