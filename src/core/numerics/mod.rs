//! Numerical building blocks with no knowledge of engines: least squares (`lstsq`, and under
//! inequalities `constrained`), polynomials
//! and their roots (`poly`), discrete transfer functions (`tf`), Levenberg–Marquardt (`lm`), the
//! paper's metrics (`metrics`), spectral estimates (`spectral`) and their −3 dB cut-offs (`cutoff`)
//! with the error and grid check both use (`spectral_error`; `spectral` imports `cutoff`, not the
//! other way), noise distributions (`noise_fit`, with the special functions in `special`) and small
//! statistics (`stats`).
pub mod constrained;
pub mod cutoff;
pub mod lm;
pub mod lstsq;
pub mod metrics;
pub mod noise_fit;
pub mod poly;
pub mod qr;
pub mod special;
pub mod spectral;
pub mod spectral_error;
pub mod stats;
pub mod tf;
