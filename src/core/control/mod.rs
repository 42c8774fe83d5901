//! What a controller designer schedules on: operating points with their local linear models, and
//! the continuous-time (zero-order-hold) equivalents of the discrete blocks.
pub mod bands;
pub mod covariance;
pub mod d2c;
pub mod operating_point;

pub use covariance::{CovarianceError, ParameterCovariance};
pub use d2c::{ContinuousTf, D2cError, c2d_zoh, d2c_zoh};
pub use operating_point::{
    LocalPole, OperatingPoint, OperatingPointError, PointSource, StepFigures, effect_dynamics,
    identified_range, local_dynamics, operating_points,
};
