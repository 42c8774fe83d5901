//! Real polynomials: roots by companion-matrix eigenvalues, and back.
//!
//! Coefficients are in **descending powers**: `[c0, c1, …, cn]` is `c0·xⁿ + c1·xⁿ⁻¹ + … + cn`.
//! A denominator stored in z⁻¹ (`[1, a1, …, an]`) is the same vector read in descending powers of z,
//! so `roots(den_zinv)` gives the poles.
use faer::Mat;
use num_complex::Complex64;

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PolyError {
    #[error("polynomial coefficient {index} is not finite")]
    NonFinite { index: usize },
    #[error("eigenvalue computation did not converge for a polynomial of degree {degree}")]
    NoConvergence { degree: usize },
}

/// All roots of `coeffs` (descending powers), sorted by [`sort_roots`]. Leading zeros are dropped
/// (lower degree); a zero polynomial or a constant has no roots.
pub fn roots(coeffs: &[f64]) -> Result<Vec<Complex64>, PolyError> {
    if let Some(index) = coeffs.iter().position(|c| !c.is_finite()) {
        return Err(PolyError::NonFinite { index });
    }
    let scale = coeffs.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    if scale <= 0.0 {
        return Ok(Vec::new());
    }
    let tiny = scale * f64::EPSILON;
    let Some(first) = coeffs.iter().position(|c| c.abs() > tiny) else {
        return Ok(Vec::new());
    };
    let trimmed = &coeffs[first..];
    // Trailing zeros are roots at the origin, exactly.
    let nonzero_end = trimmed.iter().rposition(|c| c.abs() > tiny).map_or(0, |i| i + 1);
    let zero_roots = trimmed.len() - nonzero_end;
    let core = &trimmed[..nonzero_end];
    let degree = core.len().saturating_sub(1);
    let mut out = vec![Complex64::new(0.0, 0.0); zero_roots];
    if degree == 1 {
        out.push(Complex64::new(-core[1] / core[0], 0.0));
    } else if degree > 1 {
        let lead = core[0];
        let companion = Mat::from_fn(degree, degree, |i, j| {
            if i == 0 {
                -core[j + 1] / lead
            } else if i == j + 1 {
                1.0
            } else {
                0.0
            }
        });
        let eig = companion.eigenvalues().map_err(|_| PolyError::NoConvergence { degree })?;
        out.extend(eig.into_iter().map(|c| Complex64::new(c.re, c.im)));
    }
    sort_roots(&mut out);
    Ok(out)
}

/// Sort roots by angle magnitude (low frequency first), then by modulus, then imaginary part, so
/// conjugate pairs sit next to each other (positive imaginary part first).
pub fn sort_roots(roots: &mut [Complex64]) {
    roots.sort_by(|a, b| {
        let key = |z: &Complex64| (z.im.abs().atan2(z.re), z.norm(), -z.im);
        let (ka, kb) = (key(a), key(b));
        ka.0.total_cmp(&kb.0).then(ka.1.total_cmp(&kb.1)).then(ka.2.total_cmp(&kb.2))
    });
}

/// Monic real polynomial with the given roots (descending powers). Complex roots should come with
/// their conjugates; the imaginary parts of the product are discarded.
pub fn poly_from_roots(roots: &[Complex64]) -> Vec<f64> {
    complex_poly_from_roots(roots).into_iter().map(|c| c.re).collect()
}

/// Monic complex polynomial with the given roots (descending powers).
pub fn complex_poly_from_roots(roots: &[Complex64]) -> Vec<Complex64> {
    let mut coeffs = vec![Complex64::new(1.0, 0.0)];
    for r in roots {
        let mut next = vec![Complex64::new(0.0, 0.0); coeffs.len() + 1];
        for (i, c) in coeffs.iter().enumerate() {
            next[i] += c;
            next[i + 1] -= c * r;
        }
        coeffs = next;
    }
    coeffs
}

/// Product of two polynomials (the coefficient order is kept: descending powers, or powers of z⁻¹).
pub fn convolve(a: &[f64], b: &[f64]) -> Vec<f64> {
    if a.is_empty() || b.is_empty() {
        return Vec::new();
    }
    let mut out = vec![0.0; a.len() + b.len() - 1];
    for (i, x) in a.iter().enumerate() {
        for (j, y) in b.iter().enumerate() {
            out[i + j] += x * y;
        }
    }
    out
}

/// Evaluate a real polynomial (descending powers) at a complex point, by Horner's rule.
pub fn polyval_complex(coeffs: &[f64], z: Complex64) -> Complex64 {
    coeffs.iter().fold(Complex64::new(0.0, 0.0), |acc, c| acc * z + c)
}

/// Evaluate a real polynomial (descending powers) at a real point.
pub fn polyval(coeffs: &[f64], x: f64) -> f64 {
    coeffs.iter().fold(0.0, |acc, c| acc * x + c)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn known_roots() {
        // (z − 0.936)(z² − 1.608 z + 0.692): the paper's speed denominator.
        let den = poly_from_roots(&[
            Complex64::new(0.936, 0.0),
            Complex64::new(0.804, 0.2078),
            Complex64::new(0.804, -0.2078),
        ]);
        let r = roots(&den).unwrap();
        assert_eq!(r.len(), 3);
        assert!((r[0] - Complex64::new(0.936, 0.0)).norm() < 1e-10);
        assert!((r[1] - Complex64::new(0.804, 0.2078)).norm() < 1e-10);
        assert!((r[2] - Complex64::new(0.804, -0.2078)).norm() < 1e-10);
    }

    #[test]
    fn degenerate_polynomials() {
        assert!(roots(&[]).unwrap().is_empty());
        assert!(roots(&[0.0, 0.0]).unwrap().is_empty());
        assert!(roots(&[5.0]).unwrap().is_empty());
        assert_eq!(roots(&[0.0, 2.0, -1.0]).unwrap(), vec![Complex64::new(0.5, 0.0)]);
        assert_eq!(roots(&[1.0, 0.0, 0.0]).unwrap().len(), 2);
        assert_eq!(roots(&[1.0, f64::INFINITY]), Err(PolyError::NonFinite { index: 1 }));
    }

    proptest! {
        /// poly_from_roots(roots(p)) ≈ p for monic polynomials with roots inside the unit disc.
        #[test]
        fn roots_round_trip(
            re in proptest::collection::vec(-0.95f64..0.95, 1..10),
            im in proptest::collection::vec(0.0f64..0.3, 1..10),
        ) {
            let mut truth = Vec::new();
            for (i, r) in re.iter().enumerate() {
                match im.get(i) {
                    Some(&b) if i % 2 == 0 && b > 0.05 => {
                        truth.push(Complex64::new(*r, b));
                        truth.push(Complex64::new(*r, -b));
                    }
                    _ => truth.push(Complex64::new(*r, 0.0)),
                }
            }
            let p = poly_from_roots(&truth);
            let back = poly_from_roots(&roots(&p).unwrap());
            prop_assert_eq!(back.len(), p.len());
            for (a, b) in back.iter().zip(&p) {
                prop_assert!((a - b).abs() < 1e-8 * (1.0 + b.abs()));
            }
        }
    }
}
