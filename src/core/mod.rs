//! The headless core: pure numerics. No egui, no files, no threads.
pub mod baselines;
pub mod compare;
pub mod control;
pub mod diagnose;
pub mod effects;
pub mod health;
pub mod identification;
pub mod monte_carlo;
pub mod numerics;
pub mod parallel;
pub mod residuals;
pub mod run;
pub mod running_window;
