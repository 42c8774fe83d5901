//! Engine health against a reference model: the deltas a run needs to be explained by its engine's
//! reference ([`deltas`]: the input's calibration gain, the spool's time-constant scale and each
//! output's steady-map shift, fitted by output error with sandwich intervals), the engine's normal
//! band of each delta across its runs ([`band`]), and the input pinned at its limit while the output
//! falls short ([`saturation`]). Pure numerics: the fleet command reads the files and words the flags.
pub mod band;
pub mod deltas;
pub mod saturation;

pub use band::{BAND_SIGMAS, Band, local_bands};
pub use deltas::{Deltas, Estimate, HealthError, HealthFit, fit_deltas, scale_time_constants, simulate_with};
pub use saturation::{Pinned, pinned_stretches, resolution};
