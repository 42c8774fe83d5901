//! Roots as parameters of a polish, and the record of what a polish did. The polish itself is in
//! `core::identification::reduce` (the reduced model, each root kept inside its cluster) and `core::effects` (the
//! model with its effect blocks).
//!
//! Why polish: a high-order ARX fitted to data with output noise is biased, so cluster centroids sit
//! a little off the true roots (0.02 in z on a complex pair at a tenth of the paper's noise), which
//! costs several tenths of a percent of validation error.
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

/// Roots of one kind as refinement parameters: a real root is one parameter, a pair is (re, im).
#[derive(Clone, Debug, PartialEq)]
pub struct RootParams {
    /// For each root group: true if it is a conjugate pair.
    pub pairs: Vec<bool>,
}

impl RootParams {
    /// Group sorted roots: a root with a non-negligible imaginary part is taken with its conjugate.
    pub fn from_roots(roots: &[Complex64]) -> (Self, Vec<f64>) {
        let mut pairs = Vec::new();
        let mut theta = Vec::new();
        for r in roots {
            if r.im.abs() <= 1e-12 {
                pairs.push(false);
                theta.push(r.re);
            } else if r.im > 0.0 {
                pairs.push(true);
                theta.extend([r.re, r.im]);
            }
        }
        (Self { pairs }, theta)
    }

    pub fn n_params(&self) -> usize {
        self.pairs.iter().map(|p| if *p { 2 } else { 1 }).sum()
    }

    pub fn roots(&self, theta: &[f64]) -> Vec<Complex64> {
        let mut out = Vec::new();
        let mut i = 0;
        for &pair in &self.pairs {
            if pair {
                let (re, im) =
                    (theta.get(i).copied().unwrap_or(0.0), theta.get(i + 1).copied().unwrap_or(0.0));
                out.extend([Complex64::new(re, im), Complex64::new(re, -im)]);
                i += 2;
            } else {
                out.push(Complex64::new(theta.get(i).copied().unwrap_or(0.0), 0.0));
                i += 1;
            }
        }
        out
    }
}

/// What the refinement did, for the report and the app.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Refinement {
    pub poles_before: Vec<Complex64>,
    pub zeros_before: Vec<Complex64>,
    pub rms_before: f64,
    pub rms_after: f64,
    pub iterations: usize,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_round_trip() {
        let roots = [Complex64::new(0.9, 0.0), Complex64::new(0.8, 0.2), Complex64::new(0.8, -0.2)];
        let (p, theta) = RootParams::from_roots(&roots);
        assert_eq!(p.n_params(), 3);
        assert_eq!(p.roots(&theta), vec![roots[0], roots[1], roots[2]]);
    }
}
