//! `sensor_dynamics`: load cell or stand resonance and sensor lag.
use super::Evidence;
use super::ParamSpec;
use super::stats::{ResidualTrace, median, welch_spectrum};
use crate::core::numerics::poly::convolve;

/// Load cell / stand resonance and sensor lag: the measured output is the engine's output seen
/// through a first-order lag `lag_s` and a unit-gain second-order resonance (`freq_hz`, `zeta`),
/// `ẍ = ω²(u − x) − 2ζω ẋ`, simulated in continuous time between the samples. Steady states are
/// unchanged.
#[derive(Clone, Debug, PartialEq)]
pub struct SensorDynamics {
    /// Resonance, Hz.
    pub freq_hz: f64,
    /// Damping ratio of the resonance.
    pub zeta: f64,
    /// First-order lag, s.
    pub lag_s: f64,
}

/// Lags shorter than this are a pass-through, s.
const MIN_LAG_S: f64 = 1e-3;
/// Resonances are searched between this and 95 % of the Nyquist frequency, Hz.
const MIN_FREQ_HZ: f64 = 0.05;
/// Welch segment length for the residual spectrum, samples.
const SPECTRUM_SEGMENT: usize = 128;

/// One sample of the resonance as the linear map it is: `(pos, vel)⁺ = m1·pos + m2·vel + n0·w0 +
/// n1·w1`, each column the RK4 integration of a unit state or input.
struct ResonanceMap {
    m1: (f64, f64),
    m2: (f64, f64),
    n0: (f64, f64),
    n1: (f64, f64),
}

impl ResonanceMap {
    fn of(sensor: &SensorDynamics, dt_secs: f64) -> Self {
        let col = |pos, vel, w0, w1| sensor.advance(pos, vel, w0, w1, dt_secs);
        Self {
            m1: col(1.0, 0.0, 0.0, 0.0),
            m2: col(0.0, 1.0, 0.0, 0.0),
            n0: col(0.0, 0.0, 1.0, 0.0),
            n1: col(0.0, 0.0, 0.0, 1.0),
        }
    }

    fn advance(&self, pos: f64, vel: f64, w0: f64, w1: f64) -> (f64, f64) {
        (
            self.m1.0 * pos + self.m2.0 * vel + self.n0.0 * w0 + self.n1.0 * w1,
            self.m1.1 * pos + self.m2.1 * vel + self.n0.1 * w0 + self.n1.1 * w1,
        )
    }
}

impl SensorDynamics {
    /// Highest admissible resonance for a sample time, Hz.
    pub fn max_freq_hz(dt_secs: f64) -> f64 {
        0.95 * 0.5 / dt_secs
    }

    /// The sensor's reading of `y`, from the steady state of `y[0]`. The measured quantity is taken
    /// as linear between samples; the lag is discretised exactly for such an input, the resonance
    /// integrated by RK4 with at least four steps per sample and a quarter radian per step.
    pub fn apply(&self, y: &[f64], dt_secs: f64) -> Vec<f64> {
        let lagged = if self.lag_s > MIN_LAG_S {
            let a = (-dt_secs / self.lag_s).exp();
            let ramp = 1.0 - self.lag_s * (1.0 - a) / dt_secs;
            let mut x = y.first().copied().unwrap_or(0.0);
            let mut out = Vec::with_capacity(y.len());
            out.push(x);
            for w in y.windows(2) {
                x = a * x + (1.0 - a) * w[0] + (w[1] - w[0]) * ramp;
                out.push(x);
            }
            out
        } else {
            y.to_vec()
        };
        // The RK4 sub-steps of one sample are a linear map of (pos, vel, w0, w1): read it off once
        // (see `discrete_tf`) rather than integrating every sample, the diagnosis's hot path.
        let map = ResonanceMap::of(self, dt_secs);
        let mut pos = lagged.first().copied().unwrap_or(0.0);
        let mut vel = 0.0;
        let mut out = Vec::with_capacity(lagged.len());
        out.push(pos);
        for w in lagged.windows(2) {
            (pos, vel) = map.advance(pos, vel, w[0], w[1]);
            out.push(pos);
        }
        out
    }

    /// One sample of the resonance: position and velocity after `dt_secs`, the input going linearly
    /// from `w0` to `w1`.
    fn advance(&self, mut pos: f64, mut vel: f64, w0: f64, w1: f64, dt_secs: f64) -> (f64, f64) {
        let omega = 2.0 * std::f64::consts::PI * self.freq_hz;
        let steps = ((omega * dt_secs / 0.25).ceil() as usize).max(4);
        let h = dt_secs / steps as f64;
        let deriv = |pos: f64, vel: f64, input: f64| {
            (vel, omega * omega * (input - pos) - 2.0 * self.zeta * omega * vel)
        };
        let input_at = |s: f64| w0 + (w1 - w0) * s / dt_secs;
        for step in 0..steps {
            let t = step as f64 * h;
            let (u0, u1, u2) = (input_at(t), input_at(t + 0.5 * h), input_at(t + h));
            let k1 = deriv(pos, vel, u0);
            let k2 = deriv(pos + 0.5 * h * k1.0, vel + 0.5 * h * k1.1, u1);
            let k3 = deriv(pos + 0.5 * h * k2.0, vel + 0.5 * h * k2.1, u1);
            let k4 = deriv(pos + h * k3.0, vel + h * k3.1, u2);
            pos += h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0);
            vel += h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1);
        }
        (pos, vel)
    }

    /// The sensor as a discrete transfer function in z⁻¹ (numerator, denominator): exactly what
    /// [`SensorDynamics::apply`] does to small deviations, lag and resonance in series. The
    /// resonance's one-sample map `x⁺ = M·x + n₀·w[k] + n₁·w[k+1]` is read off [`Self::advance`] on
    /// unit states and inputs (it is linear), and `pos = e₁ᵀ(zI − M)⁻¹(n₀ + z·n₁)·w`.
    pub fn discrete_tf(&self, dt_secs: f64) -> (Vec<f64>, Vec<f64>) {
        let ResonanceMap { m1, m2, n0, n1 } = ResonanceMap::of(self, dt_secs);
        // M = [[m1.0, m2.0], [m1.1, m2.1]].
        let (m11, m12, m21, m22) = (m1.0, m2.0, m1.1, m2.1);
        let num = vec![n1.0, n0.0 - m22 * n1.0 + m12 * n1.1, -m22 * n0.0 + m12 * n0.1];
        let den = vec![1.0, -(m11 + m22), m11 * m22 - m12 * m21];
        if self.lag_s <= MIN_LAG_S {
            return (num, den);
        }
        let a = (-dt_secs / self.lag_s).exp();
        let ramp = 1.0 - self.lag_s * (1.0 - a) / dt_secs;
        (convolve(&num, &[ramp, 1.0 - a - ramp]), convolve(&den, &[1.0, -a]))
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

/// Lowest frequency searched for a sensor resonance, Hz (below it the residual is the engine's).
const MIN_PEAK_HZ: f64 = 0.3;
/// Half-width of the neighbourhood a peak is compared with, bins.
const NEIGHBOURHOOD_BINS: usize = 8;

/// Local maxima of the residual's Welch spectrum above [`MIN_PEAK_HZ`], most prominent first, with
/// their prominence: the peak's power over the median power of its neighbourhood (the bins within
/// [`NEIGHBOURHOOD_BINS`], the peak's own three left out). A resonance stands out of its
/// neighbourhood; the broad low-frequency error of a model does not.
fn spectral_peaks(residual: &[f64], dt_secs: f64) -> Vec<(f64, f64)> {
    let spec = welch_spectrum(residual, dt_secs, SPECTRUM_SEGMENT);
    let max_hz = SensorDynamics::max_freq_hz(dt_secs);
    let mut peaks: Vec<(f64, f64)> = (1..spec.len().saturating_sub(1))
        .filter_map(|i| {
            let (f, p) = *spec.get(i)?;
            let is_peak = p >= spec.get(i - 1)?.1 && p >= spec.get(i + 1)?.1;
            if !is_peak || f < MIN_PEAK_HZ || f > max_hz {
                return None;
            }
            let lo = i.saturating_sub(NEIGHBOURHOOD_BINS);
            let hi = (i + NEIGHBOURHOOD_BINS).min(spec.len() - 1);
            let around: Vec<f64> =
                (lo..=hi).filter(|j| j.abs_diff(i) > 1).filter_map(|j| spec.get(j).map(|s| s.1)).collect();
            Some((f, p / median(&around).max(f64::MIN_POSITIVE)))
        })
        .collect();
    peaks.sort_by(|a, b| b.1.total_cmp(&a.1));
    peaks
}

/// The most prominent peak of the residual spectrum above 0.3 Hz.
pub(super) fn evidence(traces: &[ResidualTrace]) -> Evidence {
    let Some(best) = traces
        .iter()
        .flat_map(|t| spectral_peaks(&t.residual(), t.dt_secs).into_iter().take(1))
        .max_by(|a, b| a.1.total_cmp(&b.1))
    else {
        return Evidence::none("runs too short for a residual spectrum");
    };
    let (freq_hz, ratio) = best;
    let meaning = if ratio > 10.0 {
        "the sensor or its stand rings at a fixed frequency"
    } else if ratio > 4.0 {
        "some energy at a fixed frequency"
    } else {
        "no sharp resonance"
    };
    Evidence {
        sentence: format!(
            "residual spectrum peaks at {freq_hz:.2} Hz, {ratio:.0}× its neighbourhood: {meaning}"
        ),
        supports: ratio > 4.0,
    }
}

block_impl!(
    SensorDynamics { freq_hz, zeta, lag_s },
    params: &[
        ParamSpec::real("freq_hz", MIN_FREQ_HZ, 1000.0),
        ParamSpec::real("zeta", 0.005, 2.0),
        ParamSpec::real("lag_s", 0.0, 10.0),
    ],
    physics: "load cell or stand resonance and sensor lag: a second-order sensor block",
    evidence: evidence
);

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
