//! Discrete-time transfer functions in z⁻¹: simulation, steady state, frequency response.
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use crate::core::numerics::poly;

/// How close to the unit circle a pole may come, `1 − |z|`: a pole within it has a time constant
/// over `dt / 1e-6` (a day at 0.1 s), no spool's or sensor's, so it is an integrator in all but
/// rounding, and a model holding one drifts without bound (refused by `predict` and `export`).
pub const STABILITY_MARGIN: f64 = 1e-6;

/// `G(z) = (b0 + b1 z⁻¹ + … + bm z⁻ᵐ) / (1 + a1 z⁻¹ + … + an z⁻ⁿ)`.
///
/// Index k of `num_zinv` / `den_zinv` multiplies z⁻ᵏ, and `den_zinv[0] == 1` (enforced by [`DiscreteTf::new`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DiscreteTf {
    pub num_zinv: Vec<f64>,
    pub den_zinv: Vec<f64>,
    pub dt_secs: f64,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TfError {
    #[error("the denominator is empty or its leading coefficient is zero")]
    BadDenominator,
    #[error("the numerator is empty")]
    EmptyNumerator,
    #[error("coefficient {index} of the {which} is not finite")]
    NonFinite { which: &'static str, index: usize },
    #[error("sample time must be positive and finite, got {dt_secs}")]
    BadSampleTime { dt_secs: f64 },
    #[error("the model has an integrator or a pole at z = 1, so its steady-state gain is unbounded")]
    NoSteadyState,
}

impl DiscreteTf {
    /// Checked constructor; normalises the denominator so that `den_zinv[0] == 1`.
    pub fn new(num_zinv: Vec<f64>, den_zinv: Vec<f64>, dt_secs: f64) -> Result<Self, TfError> {
        if !(dt_secs.is_finite() && dt_secs > 0.0) {
            return Err(TfError::BadSampleTime { dt_secs });
        }
        if num_zinv.is_empty() {
            return Err(TfError::EmptyNumerator);
        }
        for (which, coeffs) in [("numerator", &num_zinv), ("denominator", &den_zinv)] {
            if let Some(index) = coeffs.iter().position(|c| !c.is_finite()) {
                return Err(TfError::NonFinite { which, index });
            }
        }
        let Some(&lead) = den_zinv.first() else { return Err(TfError::BadDenominator) };
        if lead.abs() < f64::MIN_POSITIVE {
            return Err(TfError::BadDenominator);
        }
        Ok(Self {
            num_zinv: num_zinv.iter().map(|b| b / lead).collect(),
            den_zinv: den_zinv.iter().map(|a| a / lead).collect(),
            dt_secs,
        })
    }

    /// Build from zeros, poles and the gain `k` of `k · Π(z − zᵢ) / Π(z − pᵢ)`. Needs at least as many
    /// poles as zeros (a causal model); the relative degree becomes a z⁻ᵈ delay.
    pub fn from_zpk(zeros: &[Complex64], poles: &[Complex64], k: f64, dt_secs: f64) -> Result<Self, TfError> {
        let num = poly::poly_from_roots(zeros);
        let den = poly::poly_from_roots(poles);
        let delay = poles.len().saturating_sub(zeros.len());
        let mut num_zinv = vec![0.0; delay];
        num_zinv.extend(num.iter().map(|b| b * k));
        Self::new(num_zinv, den, dt_secs)
    }

    /// The same transfer function `samples` samples later: z^(−samples) · G.
    pub fn with_input_delay(&self, samples: usize) -> Self {
        let mut num_zinv = vec![0.0; samples];
        num_zinv.extend_from_slice(&self.num_zinv);
        Self { num_zinv, ..self.clone() }
    }

    /// Input dead time in samples beyond what the roots give, for a transfer function built from
    /// zeros and poles ([`DiscreteTf::from_zpk`], possibly [`DiscreteTf::with_input_delay`]): such a
    /// numerator is exactly as long as the denominator, plus one coefficient per sample of delay.
    pub fn input_delay(&self) -> usize {
        self.num_zinv.len().saturating_sub(self.den_zinv.len())
    }

    /// The first pole on or outside the unit circle, or within [`STABILITY_MARGIN`] of it (a pole at
    /// `1 − 1e-16` is a rounded 1: the block integrates and its simulation drifts without bound).
    pub fn unstable_pole(&self) -> Result<Option<Complex64>, poly::PolyError> {
        let poles = self.poles()?;
        Ok(poles.into_iter().find(|p| p.norm().is_nan() || p.norm() >= 1.0 - STABILITY_MARGIN))
    }

    /// Poles (roots of the denominator read in powers of z), sorted.
    pub fn poles(&self) -> Result<Vec<Complex64>, poly::PolyError> {
        poly::roots(&self.den_zinv)
    }

    /// Finite, non-trivial zeros (roots of the numerator without its leading delay), sorted.
    pub fn zeros(&self) -> Result<Vec<Complex64>, poly::PolyError> {
        poly::roots(&self.num_zinv)
    }

    /// Steady-state gain G(1).
    pub fn dc_gain(&self) -> Result<f64, TfError> {
        let den: f64 = self.den_zinv.iter().sum();
        let scale: f64 = self.den_zinv.iter().map(|a| a.abs()).sum();
        if den.abs() <= 1e-12 * scale {
            return Err(TfError::NoSteadyState);
        }
        Ok(self.num_zinv.iter().sum::<f64>() / den)
    }

    /// G(e^{jωT}) at `omega_rad_s`.
    pub fn freq_response(&self, omega_rad_s: f64) -> Complex64 {
        let zinv = Complex64::from_polar(1.0, -omega_rad_s * self.dt_secs);
        let eval = |c: &[f64]| c.iter().rev().fold(Complex64::new(0.0, 0.0), |acc, ck| acc * zinv + ck);
        eval(&self.num_zinv) / eval(&self.den_zinv)
    }

    /// Simulate `y = G u` from the steady state of `u[0]` (past inputs equal `u[0]`, past outputs
    /// equal `G(1)·u[0]`). Falls back to rest (zeros) when the model has no steady state.
    pub fn simulate_from_steady(&self, u: &[f64]) -> Vec<f64> {
        let u0 = u.first().copied().unwrap_or(0.0);
        let y0 = self.dc_gain().map_or(0.0, |g| g * u0);
        self.simulate_with_history(u, u0, y0)
    }

    /// Simulate `y = G u` with all past inputs equal to `u_past` and past outputs equal to `y_past`.
    pub fn simulate_with_history(&self, u: &[f64], u_past: f64, y_past: f64) -> Vec<f64> {
        let mut y = Vec::with_capacity(u.len());
        for k in 0..u.len() {
            let mut acc = 0.0;
            for (j, b) in self.num_zinv.iter().enumerate() {
                acc += b * if k >= j { u[k - j] } else { u_past };
            }
            for (i, a) in self.den_zinv.iter().enumerate().skip(1) {
                acc -= a * if k >= i { y[k - i] } else { y_past };
            }
            y.push(acc);
        }
        y
    }

    /// [`DiscreteTf::simulate_from_steady`] of several blocks, each with its own input, stepped
    /// together sample by sample. One block's samples form a chain (each output feeds the next),
    /// whose latency, not the processor's throughput, sets its pace; independent chains stepped side
    /// by side overlap their latencies. Each response is the one the block gives alone, bit for bit:
    /// the same sums in the same order.
    pub fn simulate_each_from_steady(blocks: &[(&DiscreteTf, &[f64])]) -> Vec<Vec<f64>> {
        let pasts: Vec<(f64, f64)> = blocks
            .iter()
            .map(|(tf, u)| {
                let u0 = u.first().copied().unwrap_or(0.0);
                (u0, tf.dc_gain().map_or(0.0, |g| g * u0))
            })
            .collect();
        let longest = blocks.iter().map(|(_, u)| u.len()).max().unwrap_or(0);
        let mut out: Vec<Vec<f64>> = blocks.iter().map(|(_, u)| Vec::with_capacity(u.len())).collect();
        for k in 0..longest {
            for (((tf, u), (u_past, y_past)), y) in blocks.iter().zip(&pasts).zip(&mut out) {
                if k < u.len() {
                    y.push(tf.next_output(u, y, k, *u_past, *y_past));
                }
            }
        }
        out
    }

    /// Output `k` of [`DiscreteTf::simulate_with_history`], from the inputs `u[..=k]` and the outputs
    /// `y[..k]` before it. Once every coefficient reaches back no further than the first sample, the
    /// sums run over slices of the newest samples, with no test per term: the same products added in
    /// the same order (the same sums, bit for bit), and a loop the compiler keeps in registers.
    fn next_output(&self, u: &[f64], y: &[f64], k: usize, u_past: f64, y_past: f64) -> f64 {
        let (b, a) = (&self.num_zinv, self.den_zinv.get(1..).unwrap_or(&[]));
        let newest_u = (k + 1).checked_sub(b.len()).and_then(|first| u.get(first..=k));
        let newest_y = k.checked_sub(a.len()).and_then(|first| y.get(first..k));
        if let (Some(newest_u), Some(newest_y)) = (newest_u, newest_y) {
            let acc = b.iter().zip(newest_u.iter().rev()).fold(0.0, |acc, (b, x)| acc + b * x);
            return a.iter().zip(newest_y.iter().rev()).fold(acc, |acc, (a, x)| acc - a * x);
        }
        let mut acc = 0.0;
        for (j, b) in self.num_zinv.iter().enumerate() {
            acc += b * if k >= j { u[k - j] } else { u_past };
        }
        for (i, a) in self.den_zinv.iter().enumerate().skip(1) {
            acc -= a * if k >= i { y[k - i] } else { y_past };
        }
        acc
    }

    /// Bode data at the given frequencies: magnitude in dB and unwrapped phase in degrees.
    pub fn bode_response(&self, omegas_rad_s: &[f64]) -> Vec<BodePoint> {
        let mut out: Vec<BodePoint> = Vec::with_capacity(omegas_rad_s.len());
        let mut prev_phase: Option<f64> = None;
        for &omega in omegas_rad_s {
            let g = self.freq_response(omega);
            let mut phase = g.arg().to_degrees();
            if let Some(prev) = prev_phase {
                while phase - prev > 180.0 {
                    phase -= 360.0;
                }
                while phase - prev < -180.0 {
                    phase += 360.0;
                }
            }
            prev_phase = Some(phase);
            out.push(BodePoint {
                omega_rad_s: omega,
                mag_db: 20.0 * g.norm().max(1e-300).log10(),
                phase_deg: phase,
            });
        }
        out
    }
}

/// One point of a Bode plot.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BodePoint {
    pub omega_rad_s: f64,
    pub mag_db: f64,
    pub phase_deg: f64,
}

/// `n` log-spaced frequencies from `lo` to `hi` (rad/s).
/// Whether the z-plane pole `z` lies on the negative real axis: its mode alternates sign every
/// sample. A zero-order hold maps every continuous-time pole `s` to `e^(sT)`, and a real `s` to a
/// point on the *positive* real axis, so no continuous system sampled behind a hold has such a pole,
/// and it has no continuous-time equivalent.
pub fn alternates_sign(z: Complex64) -> bool {
    z.im.abs() <= 1e-12 && z.re < 0.0
}

pub fn log_space(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    if n < 2 || lo <= 0.0 || hi <= lo {
        return vec![lo; n.min(1)];
    }
    let (a, b) = (lo.ln(), hi.ln());
    (0..n).map(|i| (a + (b - a) * i as f64 / (n - 1) as f64).exp()).collect()
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn paper_gs() -> DiscreteTf {
        // Gs(z) = 82.70 / ((z − 0.936)(z² − 1.608 z + 0.692)), T = 1/8.85 s.
        let den = poly::poly_from_roots(&[Complex64::new(0.936, 0.0)]);
        let den2 = [1.0, -1.608, 0.692];
        let mut full = vec![0.0; den.len() + den2.len() - 1];
        for (i, a) in den.iter().enumerate() {
            for (j, b) in den2.iter().enumerate() {
                full[i + j] += a * b;
            }
        }
        DiscreteTf::new(vec![0.0, 0.0, 0.0, 82.70], full, 1.0 / 8.85).unwrap()
    }

    #[test]
    fn paper_operating_point() {
        // METHOD.md: Gs(1) · 5.43 = 83,530.
        let g = paper_gs().dc_gain().unwrap();
        assert!((g * 5.43 - 83_530.0).abs() < 150.0, "Gs(1)·5.43 = {}", g * 5.43);
    }

    #[test]
    fn zpk_round_trip() {
        let poles = [Complex64::new(0.936, 0.0), Complex64::new(0.8, 0.21), Complex64::new(0.8, -0.21)];
        let zeros = [Complex64::new(-0.5, 0.0)];
        let tf = DiscreteTf::from_zpk(&zeros, &poles, 2.0, 0.1).unwrap();
        let p = tf.poles().unwrap();
        let z = tf.zeros().unwrap();
        for (a, b) in poly::poly_from_roots(&poles).iter().zip(&tf.den_zinv) {
            assert!((a - b).abs() < 1e-12);
        }
        assert_eq!(z.len(), 1);
        assert!((z[0] - zeros[0]).norm() < 1e-12);
        assert!((p[0] - poles[0]).norm() < 1e-9);
        assert!(tf.num_zinv[0].abs() < 1e-300); // relative degree 2 → z⁻² delay
        assert!(tf.num_zinv[1].abs() < 1e-300);
    }

    #[test]
    fn simulation_settles_at_dc_gain_and_matches_frequency_response() {
        let tf = paper_gs();
        let u = vec![1.0; 400];
        let y = tf.simulate_with_history(&u, 0.0, 0.0);
        let g = tf.dc_gain().unwrap();
        assert!((y[399] - g).abs() < 1e-6 * g);
        assert!((tf.freq_response(0.0).re - g).abs() < 1e-9 * g);
        // Steady sinusoid amplitude equals |G(e^{jωT})|.
        let omega = 2.0;
        let u: Vec<f64> = (0..4000).map(|k| (omega * k as f64 * tf.dt_secs).sin()).collect();
        let y = tf.simulate_with_history(&u, 0.0, 0.0);
        let amp = y[3000..].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let expect = tf.freq_response(omega).norm();
        assert!((amp - expect).abs() < 0.01 * expect, "{amp} vs {expect}");
    }

    /// Blocks stepped side by side give each the response it gives alone, bit for bit, with inputs
    /// of different lengths (and an empty one).
    #[test]
    fn blocks_stepped_together_respond_as_each_alone() {
        let fast = DiscreteTf::new(vec![0.0, 0.3, 0.1], vec![1.0, -0.6], 0.1).unwrap();
        let u: Vec<f64> = (0..300).map(|k| (0.07 * k as f64).sin() + 2.0).collect();
        let blocks: [(&DiscreteTf, &[f64]); 4] =
            [(&paper_gs(), &u), (&fast, &u[..111]), (&fast, &[]), (&fast, &u)];
        let together = DiscreteTf::simulate_each_from_steady(&blocks);
        for ((tf, u), y) in blocks.iter().zip(&together) {
            let alone = tf.simulate_from_steady(u);
            assert_eq!(alone.len(), y.len());
            assert!(alone.iter().zip(y).all(|(a, b)| a.to_bits() == b.to_bits()));
        }
        assert_eq!(together[1].len(), 111);
    }

    #[test]
    fn steady_start_stays_put() {
        let tf = paper_gs();
        let y = tf.simulate_from_steady(&[5.43; 50]);
        let g = tf.dc_gain().unwrap();
        assert!(y.iter().all(|v| (v - g * 5.43).abs() < 1e-6 * g * 5.43));
    }

    #[test]
    fn bad_inputs_are_errors() {
        assert_eq!(DiscreteTf::new(vec![1.0], vec![0.0, 1.0], 0.1), Err(TfError::BadDenominator));
        assert_eq!(DiscreteTf::new(vec![], vec![1.0], 0.1), Err(TfError::EmptyNumerator));
        assert_eq!(DiscreteTf::new(vec![1.0], vec![1.0], 0.0), Err(TfError::BadSampleTime { dt_secs: 0.0 }));
        let integ = DiscreteTf::new(vec![0.0, 1.0], vec![1.0, -1.0], 0.1).unwrap();
        assert_eq!(integ.dc_gain(), Err(TfError::NoSteadyState));
    }
}
