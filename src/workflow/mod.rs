//! The one place that puts the core's steps together, for the batch and the desktop app alike.
//!
//! ```text
//! project file + command line ──overrides──▶ Project
//!   ──runs──▶ Runs by role: read with their load options, the identification runs joined end to
//!             end, their segments, the scored runs on the identification run's grid
//!   ──model──▶ per output: segment fits → the given clusters or the automatic proposal → the
//!              polished Wiener model → effects added by hand → the missing-physics loop
//!   ──preparation──▶ how much the segmentation channel moves the plain model (report only)
//!   ──model_file──▶ model.json from the models; the clusters of a saved one
//!   ──products──▶ what the figures and the views share: the Bode grid, the chirp's response
//! ```
//!
//! `batch` runs these stages headless for a project; the app's derived caches call the same
//! functions step by step (the slow ones on worker threads) from the session, which a project file
//! opens and saves. Neither composes core steps itself, so the same project gives the same model in
//! both (a test holds them to 1e-9).
pub mod long_runs;
pub mod model;
pub mod model_file;
pub mod overrides;
pub mod preparation;
pub mod products;
pub mod project_model;
pub mod runs;
pub mod uncertainty;

pub use model::{EffectPlan, Effects, EffectsError, ModelSource, OutputPlan};
pub use overrides::Overrides;
pub use runs::Runs;
