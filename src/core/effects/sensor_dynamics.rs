//! `sensor_dynamics`: load cell or stand resonance and sensor lag.
use num_complex::Complex64;

use super::ParamSpec;
use super::stats::{ResidualTrace, median, welch_spectrum};

/// Load cell / stand resonance and sensor lag: the measured output is the engine's output seen
/// through a first-order lag `lag_s` and a unit-gain second-order resonance (`freq_hz`, `zeta`),
/// both discretised by matching poles (`z = e^{s·dt}`). Steady states are unchanged.
#[derive(Clone, Debug, PartialEq)]
pub struct SensorDynamics {
    pub freq_hz: f64,
    pub zeta: f64,
    pub lag_s: f64,
}

/// Lags shorter than this are a pass-through, s.
const MIN_LAG_S: f64 = 1e-3;
/// Resonances are searched between this and 95 % of the Nyquist frequency, Hz.
const MIN_FREQ_HZ: f64 = 0.05;
/// Welch segment length for the residual spectrum, samples.
const SPECTRUM_SEGMENT: usize = 128;

impl SensorDynamics {
    pub const ID: &'static str = "sensor_dynamics";
    pub(super) const PARAMS: &'static [ParamSpec] = &[
        ParamSpec::real("freq_hz", MIN_FREQ_HZ, 1000.0),
        ParamSpec::real("zeta", 0.005, 2.0),
        ParamSpec::real("lag_s", 0.0, 10.0),
    ];

    /// Highest admissible resonance for a sample time, Hz.
    pub fn max_freq_hz(dt_secs: f64) -> f64 {
        0.95 * 0.5 / dt_secs
    }

    /// The sensor's reading of `y`, from the steady state of `y[0]`.
    pub fn apply(&self, y: &[f64], dt_secs: f64) -> Vec<f64> {
        let lagged = if self.lag_s > MIN_LAG_S {
            let b = (-dt_secs / self.lag_s).exp();
            let mut s = y.first().copied().unwrap_or(0.0);
            y.iter()
                .map(|yk| {
                    s = b * s + (1.0 - b) * yk;
                    s
                })
                .collect()
        } else {
            y.to_vec()
        };
        let omega = 2.0 * std::f64::consts::PI * self.freq_hz;
        let root = Complex64::new(self.zeta * self.zeta - 1.0, 0.0).sqrt();
        let z1 = ((-self.zeta + root) * omega * dt_secs).exp();
        let z2 = ((-self.zeta - root) * omega * dt_secs).exp();
        let (a1, a2) = (-(z1 + z2).re, (z1 * z2).re);
        let b0 = 1.0 + a1 + a2;
        let start = lagged.first().copied().unwrap_or(0.0);
        let (mut y1, mut y2) = (start, start);
        lagged
            .iter()
            .map(|xk| {
                let out = b0 * xk - a1 * y1 - a2 * y2;
                y2 = y1;
                y1 = out;
                out
            })
            .collect()
    }

    pub(super) fn free_params(&self) -> Vec<f64> {
        vec![self.freq_hz.ln(), self.zeta.ln(), self.lag_s.max(MIN_LAG_S).ln()]
    }

    pub(super) fn with_free_params(&self, theta: &[f64], dt_secs: f64) -> Option<Self> {
        let (freq_hz, zeta, lag_s) = (theta.first()?.exp(), theta.get(1)?.exp(), theta.get(2)?.exp());
        let admissible = (MIN_FREQ_HZ..=Self::max_freq_hz(dt_secs)).contains(&freq_hz)
            && (0.005..=2.0).contains(&zeta)
            && lag_s <= 10.0;
        admissible.then_some(Self { freq_hz, zeta, lag_s })
    }

    /// Starting points: the residual spectrum's strongest peaks and a coarse frequency grid, each
    /// with light and moderate damping and a short and a longer lag.
    pub(super) fn guesses(residual: &[f64], dt_secs: f64) -> Vec<Self> {
        let max_hz = Self::max_freq_hz(dt_secs);
        let mut freqs: Vec<f64> = spectral_peaks(residual, dt_secs).iter().take(2).map(|p| p.0).collect();
        freqs.extend([0.5, 1.0, 2.0, 3.0].iter().filter(|f| **f < max_hz));
        freqs
            .iter()
            .flat_map(|&freq_hz| {
                [(0.05, 0.05), (0.05, 0.3), (0.3, 0.05), (0.3, 0.3)].map(|(zeta, lag_s)| Self {
                    freq_hz,
                    zeta,
                    lag_s,
                })
            })
            .collect()
    }
}

/// Local maxima of the residual's Welch spectrum above [`MIN_FREQ_HZ`], strongest first, with their
/// ratio to the spectrum's median.
fn spectral_peaks(residual: &[f64], dt_secs: f64) -> Vec<(f64, f64)> {
    let spec = welch_spectrum(residual, dt_secs, SPECTRUM_SEGMENT);
    let med = median(&spec.iter().map(|p| p.1).collect::<Vec<_>>()).max(f64::MIN_POSITIVE);
    let mut peaks: Vec<(f64, f64)> = spec
        .windows(3)
        .filter(|w| w[1].0 >= 0.2 && w[1].1 >= w[0].1 && w[1].1 >= w[2].1)
        .map(|w| (w[1].0, w[1].1 / med))
        .collect();
    peaks.sort_by(|a, b| b.1.total_cmp(&a.1));
    peaks
}

/// The strongest peak of the residual spectrum above 0.2 Hz and its height over the median level.
pub(super) fn evidence(traces: &[ResidualTrace]) -> String {
    let Some(best) = traces
        .iter()
        .flat_map(|t| spectral_peaks(&t.residual(), t.dt_secs).into_iter().take(1))
        .max_by(|a, b| a.1.total_cmp(&b.1))
    else {
        return "runs too short for a residual spectrum".to_owned();
    };
    let (freq_hz, ratio) = best;
    let meaning = if ratio > 20.0 {
        "the sensor or its stand rings at a fixed frequency"
    } else if ratio > 5.0 {
        "some energy at a fixed frequency"
    } else {
        "no sharp resonance"
    };
    format!("residual spectrum peaks at {freq_hz:.2} Hz, {ratio:.0}× its median level: {meaning}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sensor_keeps_steady_states_and_rings() {
        let sensor = SensorDynamics { freq_hz: 1.4, zeta: 0.06, lag_s: 0.0 };
        let dt = 1.0 / 8.85;
        let mut y = vec![1.0; 5];
        y.extend(vec![2.0; 400]);
        let out = sensor.apply(&y, dt);
        assert!((out[3] - 1.0).abs() < 1e-12);
        assert!(out.iter().fold(0.0f64, |m, v| m.max(*v)) > 2.5, "a lightly damped step overshoots");
        assert!((out[404] - 2.0).abs() < 1e-3);
        assert!(sensor.with_free_params(&[(5.0f64).ln(), 0.0, 0.0], dt).is_none());
    }
}
