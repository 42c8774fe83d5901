//! A one-hidden-layer perceptron with tanh hidden units and a linear output,
//! `ŷ = c + Σⱼ vⱼ·tanh(bⱼ + Σᵢ Wⱼᵢ xᵢ)`, with its analytic gradient (backpropagation).
//!
//! Weight layout: for each hidden unit `j`, `[Wⱼ₁ … Wⱼₙ, bⱼ]`; then `[v₁ … v_H, c]`.
use rand::Rng;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct MlpShape {
    pub n_inputs: usize,
    pub hidden: usize,
}

impl MlpShape {
    pub fn n_weights(&self) -> usize {
        self.hidden * (self.n_inputs + 1) + self.hidden + 1
    }

    /// The network output for input `x`; NaN when `w` or `x` has the wrong length.
    pub fn output(&self, w: &[f64], x: &[f64]) -> f64 {
        let (n, stride, out0) = (self.n_inputs, self.n_inputs + 1, self.hidden * (self.n_inputs + 1));
        if w.len() != self.n_weights() || x.len() != n {
            return f64::NAN;
        }
        // Index loops on checked lengths: this is the training hot path, run unoptimised in tests.
        let mut y = w[out0 + self.hidden];
        for j in 0..self.hidden {
            y += w[out0 + j] * tanh(pre_activation(w, x, j * stride, n));
        }
        y
    }

    /// The hidden units' activations `tanh(bⱼ + Σᵢ Wⱼᵢ xᵢ)` for input `x`, written into `h`; `false`
    /// (and `h` untouched) when a length is wrong.
    pub fn hidden_activations(&self, w: &[f64], x: &[f64], h: &mut [f64]) -> bool {
        let (n, stride) = (self.n_inputs, self.n_inputs + 1);
        if w.len() != self.n_weights() || x.len() != n || h.len() != self.hidden {
            return false;
        }
        for (j, hj) in h.iter_mut().enumerate() {
            *hj = tanh(pre_activation(w, x, j * stride, n));
        }
        true
    }

    /// The network output from the hidden activations `h` of [`Self::hidden_activations`]: the same
    /// sum in the same order as [`Self::output`], so the two agree to the last bit.
    pub fn output_from_hidden(&self, w: &[f64], h: &[f64]) -> f64 {
        let out0 = self.hidden * (self.n_inputs + 1);
        if w.len() != self.n_weights() || h.len() != self.hidden {
            return f64::NAN;
        }
        let mut y = w[out0 + self.hidden];
        for j in 0..self.hidden {
            y += w[out0 + j] * h[j];
        }
        y
    }

    /// The network output for input `x`, writing `∂ŷ/∂w` into `grad`, from the hidden activations `h`
    /// of `x` already computed (the tanh is most of the cost of a training pass); NaN (and `grad`
    /// untouched) when a length is wrong.
    pub fn output_and_gradient_from_hidden(&self, w: &[f64], x: &[f64], h: &[f64], grad: &mut [f64]) -> f64 {
        let (n, stride, out0) = (self.n_inputs, self.n_inputs + 1, self.hidden * (self.n_inputs + 1));
        if w.len() != self.n_weights() || x.len() != n || grad.len() != w.len() || h.len() != self.hidden {
            return f64::NAN;
        }
        let mut y = w[out0 + self.hidden];
        for j in 0..self.hidden {
            let unit = j * stride;
            let v = w[out0 + j];
            y += v * h[j];
            grad[out0 + j] = h[j];
            let delta = v * (1.0 - h[j] * h[j]);
            for i in 0..n {
                grad[unit + i] = delta * x[i];
            }
            grad[unit + n] = delta;
        }
        grad[out0 + self.hidden] = 1.0;
        y
    }

    /// Random weights for standardised inputs: uniform in `±1/√(fan-in + 1)` per layer.
    pub fn random_weights(&self, rng: &mut impl Rng) -> Vec<f64> {
        let hidden_bound = 1.0 / ((self.n_inputs + 1) as f64).sqrt();
        let out_bound = 1.0 / ((self.hidden + 1) as f64).sqrt();
        let n_hidden = self.hidden * (self.n_inputs + 1);
        (0..self.n_weights())
            .map(|i| {
                let bound = if i < n_hidden { hidden_bound } else { out_bound };
                bound * (2.0 * rng.random::<f64>() - 1.0)
            })
            .collect()
    }

    /// A bound on `|ŷ|` over all inputs: `|c| + Σ|vⱼ|`.
    pub fn output_bound(&self, w: &[f64]) -> f64 {
        w.iter().skip(self.hidden * (self.n_inputs + 1)).map(|v| v.abs()).sum()
    }
}

/// `tanh x` within a few ulp, at about a third of the cost of libm's (which goes through `expm1`,
/// and was a third of a whole batch's CPU time in NNARX training):
/// - `|x| < 0.1`: the Taylor series through `x¹³` (Horner in `x²`). The first term left out,
///   `(929569/638512875)·x¹⁵`, is below `1.5·10⁻¹⁸` there, under 2·10⁻¹⁷ of `tanh x`: the error is
///   the rounding of the sum, about an ulp.
/// - `0.1 ≤ |x| < 22`: `(1 − t)/(1 + t)` with `t = e^{−2|x|}` from libm's `exp` (correctly rounded
///   to within an ulp). The subtraction turns `t`'s ulp (≤ 1.1·10⁻¹⁶) into a relative error of at
///   most `1.1·10⁻¹⁶ / (1 − e^{−0.2}) ≈ 6·10⁻¹⁶` (3 ulp) at `|x| = 0.1`, falling to 1 ulp by
///   `|x| ≈ 0.5`.
/// - `|x| ≥ 22`: `tanh x` is ±1 in f64 (`1 − tanh 22 ≈ 1.6·10⁻¹⁹`).
///
/// Against libm's `tanh`, NNARX scores move in the seventh significant digit or later (sr30
/// validation 1434.365734 rpm either way; JetCat run F 1551.4388 → 1551.4386 rpm).
///
#[inline]
fn tanh(x: f64) -> f64 {
    let a = x.abs();
    if a < 0.1 {
        let z = a * a;
        let p = 21_844.0 / 6_081_075.0;
        let p = p * z - 1_382.0 / 155_925.0;
        let p = p * z + 62.0 / 2_835.0;
        let p = p * z - 17.0 / 315.0;
        let p = p * z + 2.0 / 15.0;
        let p = p * z - 1.0 / 3.0;
        (a + a * z * p).copysign(x)
    } else if a < 22.0 {
        let t = (-2.0 * a).exp();
        ((1.0 - t) / (1.0 + t)).copysign(x)
    } else {
        1.0_f64.copysign(x)
    }
}

/// Hidden unit `unit`'s input: its bias `w[unit + n]` plus its weights times `x` (lengths checked by
/// the callers).
#[inline]
fn pre_activation(w: &[f64], x: &[f64], unit: usize, n: usize) -> f64 {
    let mut a = w[unit + n];
    for i in 0..n {
        a += w[unit + i] * x[i];
    }
    a
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use rand::SeedableRng;

    /// Distance in units in the last place between two finite f64 of the same sign.
    fn ulps(a: f64, b: f64) -> u64 {
        (a.to_bits() as i64 - b.to_bits() as i64).unsigned_abs()
    }

    /// The bound of [`tanh`]'s doc comment (≤ 6·10⁻¹⁶ relative from the subtraction, up to 5.5 ulp
    /// at the bottom of a binade, plus the division's rounding) and libm's own error (≤ 1 ulp): 8.
    #[test]
    fn tanh_is_within_eight_ulp_of_libm_everywhere() {
        // Dense on the Taylor range and its edge, then log-spaced out to saturation, both signs.
        let mut xs: Vec<f64> = (0..20_000).map(|k| k as f64 * 1.2e-5).collect();
        xs.extend((0..20_000).map(|k| 1e-300_f64.powf(1.0 - k as f64 / 20_000.0) * 30.0));
        xs.extend([0.0, 0.1, 0.1 - 1e-17, 21.999, 22.0, 700.0, f64::MIN_POSITIVE]);
        let worst = xs
            .iter()
            .flat_map(|&x| [x, -x])
            .map(|x| (ulps(tanh(x), x.tanh()), x))
            .max_by_key(|(u, _)| *u)
            .unwrap();
        assert!(worst.0 <= 8, "{} ulp at x = {}", worst.0, worst.1);
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let shape = MlpShape { n_inputs: 4, hidden: 10 };
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let w = shape.random_weights(&mut rng);
        assert_eq!(w.len(), 61);
        let x = [0.3, -1.2, 0.7, 2.0];
        let mut h = vec![0.0; shape.hidden];
        assert!(shape.hidden_activations(&w, &x, &mut h));
        assert_eq!(shape.output_from_hidden(&w, &h).to_bits(), shape.output(&w, &x).to_bits());
        let mut grad = vec![0.0; w.len()];
        let y = shape.output_and_gradient_from_hidden(&w, &x, &h, &mut grad);
        assert_eq!(y.to_bits(), shape.output(&w, &x).to_bits());
        for j in 0..w.len() {
            let h = 1e-6;
            let mut wp = w.clone();
            wp[j] += h;
            let mut wm = w.clone();
            wm[j] -= h;
            let fd = (shape.output(&wp, &x) - shape.output(&wm, &x)) / (2.0 * h);
            assert!((fd - grad[j]).abs() < 1e-8, "weight {j}: {fd} vs {}", grad[j]);
        }
        assert!(y.abs() <= shape.output_bound(&w));
    }
}
