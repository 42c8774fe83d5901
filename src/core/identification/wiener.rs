//! The Wiener model `u → G(z) → v → f(v) → y`, and the reduced linear block built from clusters.
//!
//! The reduced transfer function takes one pole (zero) per valid cluster. Its shape is normalised to
//! unit steady-state gain; the gain `K` and an offset `c` are then fitted by least squares of
//! `y ≈ K·w + c` on the identification data (w the unit-gain simulation), so `v = K·w + c` is in
//! output units and `f` is close to the identity plus the curvature the linear block cannot give.
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use crate::core::identification::initial_state::{InitialState, fit_free_response};

use crate::core::identification::static_map::StaticMap;
use crate::core::numerics::lstsq::{LstsqError, solve_lstsq};
use crate::core::numerics::tf::{DiscreteTf, TfError};

/// `v = G(z) u + offset`, simulated from the steady state of the first input sample.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LinearBlock {
    pub tf: DiscreteTf,
    pub offset: f64,
}

impl LinearBlock {
    pub fn simulate(&self, u: &[f64]) -> Vec<f64> {
        let mut v = self.tf.simulate_from_steady(u);
        for x in &mut v {
            *x += self.offset;
        }
        v
    }

    /// Simulate a run to score it against its measured output `y`: from the steady state of
    /// `u[0]`, or with the free response that best fits the first seconds of `y` (see
    /// `core::identification::initial_state`).
    pub fn simulate_scored(&self, u: &[f64], y: &[f64], initial: InitialState) -> Vec<f64> {
        let v = self.simulate(u);
        match initial {
            InitialState::Steady => v,
            InitialState::Estimated => {
                let poles = self.tf.poles().unwrap_or_default();
                fit_free_response(&poles, &v, y, <[f64]>::to_vec)
            }
        }
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum WienerError {
    #[error("no valid pole cluster: the reduced model needs at least one pole")]
    NoPoles,
    #[error("the reduced model has {zeros} zeros but only {poles} poles (not causal); remove a zero cluster")]
    Improper { zeros: usize, poles: usize },
    #[error("a zero at z = 1 makes the steady-state gain zero; move or remove that zero cluster")]
    ZeroDcGain,
    #[error("the reduced model has an unstable pole at |z| = {modulus:.4}")]
    Unstable { modulus: f64 },
    #[error("too few samples ({samples}) to fit the gain")]
    TooFewSamples { samples: usize },
    #[error(transparent)]
    Tf(#[from] TfError),
    #[error(transparent)]
    Lstsq(#[from] LstsqError),
}

/// Unit-steady-state-gain transfer function with these poles and zeros.
pub fn unit_gain_tf(
    poles: &[Complex64],
    zeros: &[Complex64],
    dt_secs: f64,
) -> Result<DiscreteTf, WienerError> {
    if poles.is_empty() {
        return Err(WienerError::NoPoles);
    }
    if zeros.len() > poles.len() {
        return Err(WienerError::Improper { zeros: zeros.len(), poles: poles.len() });
    }
    if let Some(p) = poles.iter().find(|p| p.norm() >= 1.0) {
        return Err(WienerError::Unstable { modulus: p.norm() });
    }
    let shape = DiscreteTf::from_zpk(zeros, poles, 1.0, dt_secs)?;
    let g = shape.dc_gain()?;
    if g.abs() < 1e-12 {
        return Err(WienerError::ZeroDcGain);
    }
    Ok(DiscreteTf::from_zpk(zeros, poles, 1.0 / g, dt_secs)?)
}

/// Fit gain and offset of the reduced model to `y` driven by `u`.
pub fn fit_linear_block(
    poles: &[Complex64],
    zeros: &[Complex64],
    u: &[f64],
    y: &[f64],
    dt_secs: f64,
) -> Result<LinearBlock, WienerError> {
    fit_linear_block_excluding(poles, zeros, 0, u, y, dt_secs, None)
}

/// [`fit_linear_block`] with `delay` samples of input dead time and the samples of `held_out` left
/// out of the least squares (the block is still simulated through them): what a cross-validation
/// fold fits on.
pub fn fit_linear_block_excluding(
    poles: &[Complex64],
    zeros: &[Complex64],
    delay: usize,
    u: &[f64],
    y: &[f64],
    dt_secs: f64,
    held_out: Option<std::ops::Range<usize>>,
) -> Result<LinearBlock, WienerError> {
    let shape = unit_gain_tf(poles, zeros, dt_secs)?.with_input_delay(delay);
    let w = shape.simulate_from_steady(u);
    linear_block_on(shape, &w, y, held_out)
}

/// Gain and offset of [`fit_linear_block_excluding`] from the unit-gain block's response `w` (as
/// long as the input); fewer than 3 samples, or `w` and `y` of different lengths, are refused.
pub fn linear_block_on(
    shape: DiscreteTf,
    w: &[f64],
    y: &[f64],
    held_out: Option<std::ops::Range<usize>>,
) -> Result<LinearBlock, WienerError> {
    if w.len() < 3 || w.len() != y.len() {
        return Err(WienerError::TooFewSamples { samples: w.len().min(y.len()) });
    }
    let kept: Vec<usize> = match &held_out {
        Some(out) => (0..w.len()).filter(|k| !out.contains(k)).collect(),
        None => (0..w.len()).collect(),
    };
    if kept.len() < 3 {
        return Err(WienerError::TooFewSamples { samples: kept.len() });
    }
    let a = faer::Mat::from_fn(kept.len(), 2, |r, c| if c == 0 { w[kept[r]] } else { 1.0 });
    let y_kept: Vec<f64> = kept.iter().map(|&k| y[k]).collect();
    let sol = solve_lstsq(&a, &y_kept)?;
    let (k, offset) = (sol.x[0], sol.x[1]);
    let tf = DiscreteTf::new(shape.num_zinv.iter().map(|b| b * k).collect(), shape.den_zinv, shape.dt_secs)?;
    Ok(LinearBlock { tf, offset })
}

/// Linear block followed by the static map.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WienerModel {
    pub linear: LinearBlock,
    pub map: StaticMap,
}

impl WienerModel {
    /// Simulate from the input alone: returns (v, y).
    pub fn simulate(&self, u: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let v = self.linear.simulate(u);
        let y = v.iter().map(|x| self.map.eval(*x)).collect();
        (v, y)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn gain_and_offset_are_recovered() {
        let poles = [Complex64::new(0.9, 0.0)];
        let truth = LinearBlock { tf: unit_gain_tf(&poles, &[], 0.1).unwrap(), offset: 0.0 };
        let u: Vec<f64> = (0..300).map(|k| if (k / 50) % 2 == 0 { 1.0 } else { 2.0 }).collect();
        let y: Vec<f64> = truth.simulate(&u).iter().map(|w| 3.0 * w + 7.0).collect();
        let block = fit_linear_block(&poles, &[], &u, &y, 0.1).unwrap();
        assert!((block.tf.dc_gain().unwrap() - 3.0).abs() < 1e-9);
        assert!((block.offset - 7.0).abs() < 1e-9);
    }

    #[test]
    fn structural_errors() {
        let p = [Complex64::new(0.9, 0.0)];
        let z2 = [Complex64::new(0.5, 0.0), Complex64::new(0.2, 0.0)];
        assert_eq!(unit_gain_tf(&[], &[], 0.1), Err(WienerError::NoPoles));
        assert_eq!(unit_gain_tf(&p, &z2, 0.1), Err(WienerError::Improper { zeros: 2, poles: 1 }));
        assert_eq!(unit_gain_tf(&p, &[Complex64::new(1.0, 0.0)], 0.1), Err(WienerError::ZeroDcGain));
        assert!(matches!(
            unit_gain_tf(&[Complex64::new(1.01, 0.0)], &[], 0.1),
            Err(WienerError::Unstable { .. })
        ));
    }
}
