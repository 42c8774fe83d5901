//! Numerical building blocks with no knowledge of engines: least squares (`lstsq`), polynomials
//! and their roots (`poly`), discrete transfer functions (`tf`), Levenberg–Marquardt (`lm`), the
//! paper's metrics (`metrics`), spectral estimates (`spectral`) and noise distributions
//! (`noise_fit`).
pub mod lm;
pub mod lstsq;
pub mod metrics;
pub mod noise_fit;
pub mod poly;
pub mod spectral;
pub mod stats;
pub mod tf;
