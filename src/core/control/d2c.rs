//! Continuous-time equivalents of the discrete linear blocks: the zero-order-hold `d2c`, and the
//! `c2d` it inverts.
//!
//! `d2c` works mode by mode. A discrete block `G(z) = z^(−d)·(D + Σ rᵢ/(z − pᵢ))` with distinct
//! poles is the zero-order-hold sampling of `Gc(s) = e^(−s·d·T)·(D + Σ cᵢ/(s − λᵢ))` exactly when
//! `λᵢ = ln(pᵢ)/T` and `cᵢ = rᵢ·λᵢ/(pᵢ − 1)`: the ZOH of one mode `c/(s − λ)` is
//! `(c/λ)(e^(λT) − 1)/(z − e^(λT))`. A pole on the negative real axis has no real logarithm (it
//! alternates sign every sample, which no continuous system sampled with a hold does), and repeated
//! poles need Jordan blocks the modal form does not have: both are refused with the pole named.
//!
//! `c2d` takes the other road on purpose, so that a round trip tests one against the other: the
//! controllable canonical state space of `Gc`, the matrix exponential of the augmented matrix
//! `[[A, B], [0, 0]]·T` (which holds `e^(AT)` and `∫₀ᵀ e^(Aτ)dτ·B`), and the transfer function back
//! from the sampled state space by the Faddeev–LeVerrier recursion.
use nalgebra::DMatrix;
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use crate::core::numerics::poly::{self, complex_poly_from_roots, poly_from_roots, polyval_complex};
use crate::core::numerics::tf::{DiscreteTf, TfError, alternates_sign};

/// `Gc(s) = e^(−s·delay)·(b0·sᵐ + … + bm)/(sⁿ + a1·sⁿ⁻¹ + … + an)`, coefficients in descending
/// powers of s (as python-control and MATLAB write them), the denominator monic.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContinuousTf {
    /// Numerator, descending powers of s.
    pub num_s: Vec<f64>,
    /// Denominator, descending powers of s, leading coefficient 1.
    pub den_s: Vec<f64>,
    /// Input dead time, s.
    pub delay_secs: f64,
}

/// Why a discrete block has no zero-order-hold continuous equivalent.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum D2cError {
    #[error(
        "the pole {re:.6}{im:+.6}i lies on the negative real axis: it alternates sign every sample, which no continuous system behind a zero-order hold does"
    )]
    NegativeRealPole { re: f64, im: f64 },
    #[error("the pole {re:.6}{im:+.6}i is repeated: the modal continuous equivalent needs distinct poles")]
    RepeatedPole { re: f64, im: f64 },
    #[error("the pole {re:.6}{im:+.6}i sits at the origin of the z-plane beyond the block's pure delay")]
    PoleAtOrigin { re: f64, im: f64 },
    #[error("the numerator has a higher degree than the denominator: the block is not causal")]
    NotProper,
    #[error("the block's poles: {0}")]
    Roots(#[from] poly::PolyError),
    #[error(transparent)]
    Tf(#[from] TfError),
    #[error("the state-space matrices could not be formed (sample time {dt_secs} s)")]
    BadSampling { dt_secs: f64 },
}

/// Two poles closer than this (relative to 1, the unit circle's scale) count as one repeated pole:
/// their modal residues would grow as 1/distance and lose every digit the round trip keeps.
const REPEATED_POLE_DISTANCE: f64 = 1e-7;

/// The zero-order-hold continuous equivalent of `tf` (see the module documentation).
pub fn d2c_zoh(tf: &DiscreteTf) -> Result<ContinuousTf, D2cError> {
    let dt = tf.dt_secs;
    let (delay, num_z, den_z) = z_polynomials(tf)?;
    let poles = poly::roots(&den_z)?;
    for (i, p) in poles.iter().enumerate() {
        if p.norm() < f64::EPSILON {
            return Err(D2cError::PoleAtOrigin { re: p.re, im: p.im });
        }
        if alternates_sign(*p) {
            return Err(D2cError::NegativeRealPole { re: p.re, im: p.im });
        }
        if poles[..i].iter().any(|q| (p - q).norm() < REPEATED_POLE_DISTANCE) {
            return Err(D2cError::RepeatedPole { re: p.re, im: p.im });
        }
    }
    let (feedthrough, residues) = partial_fractions(&num_z, &den_z, &poles);
    let modes: Vec<(Complex64, Complex64)> = poles
        .iter()
        .zip(residues)
        .map(|(p, residue)| {
            let lambda = Complex64::new(p.norm().ln(), p.arg()) / dt;
            let gain = if (p - 1.0).norm() < 1e-12 { residue / dt } else { residue * lambda / (p - 1.0) };
            (lambda, gain)
        })
        .collect();
    let lambdas: Vec<Complex64> = modes.iter().map(|m| m.0).collect();
    let den_s = poly_from_roots(&lambdas);
    // Numerator D·Π(s − λⱼ) + Σ cᵢ·Π_{j≠i}(s − λⱼ), in complex arithmetic (conjugate modes cancel
    // each other's imaginary parts).
    let mut num = complex_poly_from_roots(&lambdas).into_iter().map(|c| c * feedthrough).collect::<Vec<_>>();
    for (i, (_, c)) in modes.iter().enumerate() {
        let others: Vec<Complex64> =
            lambdas.iter().enumerate().filter(|(j, _)| *j != i).map(|(_, l)| *l).collect();
        let term = complex_poly_from_roots(&others);
        let shift = num.len() - term.len();
        for (k, t) in term.iter().enumerate() {
            num[shift + k] += c * t;
        }
    }
    Ok(ContinuousTf {
        num_s: trim_leading(num.iter().map(|c| c.re).collect()),
        den_s,
        delay_secs: delay as f64 * dt,
    })
}

/// `tf` in positive powers of z without its pure delay: `z^(−delay)·N(z)/A(z)`, with deg N ≤ deg A
/// and no root of A at the origin (poles at the origin are whole samples of delay).
fn z_polynomials(tf: &DiscreteTf) -> Result<(usize, Vec<f64>, Vec<f64>), D2cError> {
    let scale = tf.num_zinv.iter().fold(0.0f64, |m, b| m.max(b.abs()));
    let lead_zeros = tf.num_zinv.iter().take_while(|b| b.abs() <= scale * f64::EPSILON).count();
    let num = &tf.num_zinv[lead_zeros.min(tf.num_zinv.len())..];
    let den_scale = tf.den_zinv.iter().fold(0.0f64, |m, a| m.max(a.abs()));
    let den_len = tf.den_zinv.iter().rposition(|a| a.abs() > den_scale * f64::EPSILON).map_or(1, |i| i + 1);
    let den = tf.den_zinv[..den_len].to_vec();
    let (m, n) = (num.len().saturating_sub(1), den.len() - 1);
    if num.is_empty() {
        return Ok((lead_zeros, vec![0.0], den));
    }
    if m > n {
        return Err(D2cError::NotProper);
    }
    // A zero-order hold delays by up to one sample by itself: one z⁻¹ of the leading zeros is the
    // hold's own (a strictly proper N/A) whenever the rest of the numerator fits under deg A − 1.
    let (delay, degree) = if lead_zeros >= 1 && m < n { (lead_zeros - 1, n - 1) } else { (lead_zeros, n) };
    // Multiplying by zⁿ pads the numerator with zeros at the low end, up to its degree.
    let mut num_z = num.to_vec();
    num_z.extend(std::iter::repeat_n(0.0, degree - m));
    Ok((delay, trim_leading(num_z), den))
}

fn trim_leading(mut c: Vec<f64>) -> Vec<f64> {
    let scale = c.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let first = c.iter().position(|x| x.abs() > scale * 1e-13).unwrap_or(c.len().saturating_sub(1));
    c.drain(..first);
    if c.is_empty() { vec![0.0] } else { c }
}

/// The zero-order-hold sampling of `gc` with sample time `dt_secs` (the delay must be whole
/// samples; see the module documentation for why this road differs from [`d2c_zoh`]'s).
pub fn c2d_zoh(gc: &ContinuousTf, dt_secs: f64) -> Result<DiscreteTf, D2cError> {
    let den = &gc.den_s;
    let n = den.len().saturating_sub(1);
    let bad = D2cError::BadSampling { dt_secs };
    if n == 0 || den[0] == 0.0 || gc.num_s.len() > den.len() || dt_secs.is_nan() || dt_secs <= 0.0 {
        return Err(bad);
    }
    let a: Vec<f64> = den.iter().map(|x| x / den[0]).collect();
    let b: Vec<f64> =
        std::iter::repeat_n(0.0, n + 1 - gc.num_s.len()).chain(gc.num_s.iter().map(|x| x / den[0])).collect();
    let d = b[0];
    // Controllable canonical form: x' = A x + B u, y = C x + D u.
    let mut aug = DMatrix::<f64>::zeros(n + 1, n + 1);
    for j in 0..n {
        aug[(0, j)] = -a[j + 1] * dt_secs;
    }
    for i in 1..n {
        aug[(i, i - 1)] = dt_secs;
    }
    aug[(0, n)] = dt_secs;
    let c: Vec<f64> = (0..n).map(|j| b[j + 1] - d * a[j + 1]).collect();
    let e = aug.exp();
    let ad = e.view((0, 0), (n, n)).into_owned();
    let bd = e.view((0, n), (n, 1)).into_owned();
    // Faddeev–LeVerrier: det(zI − Ad) = Σ cₖ z^(n−k), adj(zI − Ad) = Σ Mₖ z^(n−1−k).
    let mut m = DMatrix::<f64>::identity(n, n);
    let mut char_poly = vec![1.0];
    let mut adj_terms = Vec::with_capacity(n);
    for k in 1..=n {
        adj_terms.push(m.clone());
        let am = &ad * &m;
        let ck = -am.trace() / k as f64;
        char_poly.push(ck);
        m = am + DMatrix::<f64>::identity(n, n) * ck;
    }
    // Numerator: C·adj·B + D·det, descending powers of z (degree n).
    let mut num_z = vec![0.0; n + 1];
    for (k, mk) in adj_terms.iter().enumerate() {
        let v = mk * &bd;
        num_z[k + 1] += c.iter().zip(v.iter()).map(|(ci, vi)| ci * vi).sum::<f64>();
    }
    for (nz, ck) in num_z.iter_mut().zip(&char_poly) {
        *nz += d * ck;
    }
    let delay = (gc.delay_secs / dt_secs).round().max(0.0) as usize;
    Ok(DiscreteTf::new(num_z, char_poly, dt_secs)?.with_input_delay(delay))
}

/// `num/den` (descending powers, deg num ≤ deg den, distinct `roots` of `den`) as `D + Σ rᵢ/(x − rootᵢ)`:
/// the direct feedthrough D and the residues, `rᵢ = (num − D·den)(rootᵢ) / den′(rootᵢ)`.
fn partial_fractions(num: &[f64], den: &[f64], roots: &[Complex64]) -> (f64, Vec<Complex64>) {
    let n = den.len().saturating_sub(1);
    let padded: Vec<f64> =
        std::iter::repeat_n(0.0, (n + 1).saturating_sub(num.len())).chain(num.iter().copied()).collect();
    let lead = den.first().copied().unwrap_or(1.0);
    let feedthrough = padded.first().copied().unwrap_or(0.0) / lead;
    let remainder: Vec<f64> = padded.iter().zip(den).map(|(b, a)| b - feedthrough * a).collect();
    let den_deriv: Vec<f64> = den[..n].iter().enumerate().map(|(i, a)| a * (n - i) as f64).collect();
    let residues =
        roots.iter().map(|r| polyval_complex(&remainder, *r) / polyval_complex(&den_deriv, *r)).collect();
    (feedthrough, residues)
}

/// Unit-step response of `gc` at times `t` (s), from the modal form: `D + Σ cᵢ/λᵢ·(e^(λᵢ·t) − 1)`
/// after the delay. Poles must be distinct and nonzero (as [`d2c_zoh`] gives them).
pub fn step_response(gc: &ContinuousTf, t: &[f64]) -> Result<Vec<f64>, D2cError> {
    let lambdas = poly::roots(&gc.den_s)?;
    let (d, residues) = partial_fractions(&gc.num_s, &gc.den_s, &lambdas);
    let modes: Vec<(Complex64, Complex64)> = lambdas.into_iter().zip(residues).collect();
    Ok(t.iter()
        .map(|&tk| {
            let s = tk - gc.delay_secs;
            if s < 0.0 {
                return 0.0;
            }
            d + modes.iter().map(|(l, c)| (c / l * ((l * s).exp() - 1.0)).re).sum::<f64>()
        })
        .collect())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn roundtrip(tf: &DiscreteTf) -> DiscreteTf {
        let gc = d2c_zoh(tf).unwrap();
        c2d_zoh(&gc, tf.dt_secs).unwrap()
    }

    fn assert_same_response(a: &DiscreteTf, b: &DiscreteTf) {
        let u: Vec<f64> = (0..200).map(|k| if k < 5 { 0.0 } else { 1.0 + (k as f64 * 0.3).sin() }).collect();
        let (ya, yb) = (a.simulate_with_history(&u, 0.0, 0.0), b.simulate_with_history(&u, 0.0, 0.0));
        let scale = ya.iter().fold(0.0f64, |m, y| m.max(y.abs()));
        for (k, (x, y)) in ya.iter().zip(&yb).enumerate() {
            assert!((x - y).abs() <= 1e-9 * scale, "sample {k}: {x} vs {y}");
        }
    }

    #[test]
    fn first_order_lag_has_the_textbook_equivalent() {
        // y[k] = 0.9 y[k−1] + 0.1 u[k−1]: τ = −T/ln 0.9, unit gain.
        let dt = 0.1;
        let tf = DiscreteTf::new(vec![0.0, 0.1], vec![1.0, -0.9], dt).unwrap();
        let gc = d2c_zoh(&tf).unwrap();
        let tau = -dt / 0.9f64.ln();
        assert_eq!(gc.den_s.len(), 2);
        assert!((gc.den_s[1] - 1.0 / tau).abs() < 1e-12, "{:?}", gc);
        assert!((gc.num_s.last().unwrap() / gc.den_s[1] - 1.0).abs() < 1e-12, "{:?}", gc);
        assert!(gc.delay_secs.abs() < 1e-15);
        assert_same_response(&tf, &roundtrip(&tf));
    }

    #[test]
    fn a_damped_pair_with_a_zero_and_dead_time_survives_the_round_trip() {
        let poles = [Complex64::new(0.85, 0.14), Complex64::new(0.85, -0.14), Complex64::new(0.6, 0.0)];
        let tf = DiscreteTf::from_zpk(&[Complex64::new(0.3, 0.0)], &poles, 0.02, 0.05)
            .unwrap()
            .with_input_delay(3);
        let back = roundtrip(&tf);
        assert_same_response(&tf, &back);
        let gc = d2c_zoh(&tf).unwrap();
        // Two samples of the numerator's delay are the zeros' relative degree (3 poles, 1 zero): 3 + 2 − 1 are dead time.
        assert!((gc.delay_secs - 4.0 * 0.05).abs() < 1e-12, "{}", gc.delay_secs);
        // The continuous step response matches the discrete one at the sampling instants.
        let t: Vec<f64> = (0..120).map(|k| k as f64 * 0.05).collect();
        let cont = step_response(&gc, &t).unwrap();
        let disc = tf.simulate_with_history(&vec![1.0; t.len()], 0.0, 0.0);
        for (k, (c, d)) in cont.iter().zip(&disc).enumerate() {
            assert!((c - d).abs() < 1e-9 * tf.dc_gain().unwrap().abs(), "t = {}: {c} vs {d}", t[k]);
        }
        // DC gains agree: Gc(0) = G(1).
        let dc_c = gc.num_s.last().unwrap() / gc.den_s.last().unwrap();
        assert!((dc_c - tf.dc_gain().unwrap()).abs() < 1e-9 * dc_c.abs());
    }

    #[test]
    fn blocks_without_an_equivalent_are_refused_with_the_pole() {
        let alternating = DiscreteTf::new(vec![0.0, 1.5], vec![1.0, 0.5], 0.1).unwrap();
        assert!(
            matches!(d2c_zoh(&alternating), Err(D2cError::NegativeRealPole { re, .. }) if (re + 0.5).abs() < 1e-12)
        );
        let repeated = DiscreteTf::new(vec![0.0, 0.0, 0.01], vec![1.0, -1.8, 0.81], 0.1).unwrap();
        assert!(matches!(d2c_zoh(&repeated), Err(D2cError::RepeatedPole { .. })));
    }
}
