//! Small signal helpers for the residual analysis: moments, smoothing, slopes, a radix-2 FFT and
//! FFT-based autocorrelations, and the normal tail probability.
use num_complex::Complex64;

pub(super) use crate::core::numerics::stats::mean;

/// `x` minus its mean.
pub(super) fn centred(x: &[f64]) -> Vec<f64> {
    let m = mean(x);
    x.iter().map(|v| v - m).collect()
}

/// Median of `x` (sorted copy); 0 for an empty slice.
pub(super) fn median(x: &[f64]) -> f64 {
    let mut sorted = x.to_vec();
    sorted.sort_by(f64::total_cmp);
    let mid = sorted.len() / 2;
    match (sorted.get(mid.wrapping_sub(1)), sorted.get(mid)) {
        (Some(a), Some(b)) if sorted.len().is_multiple_of(2) => 0.5 * (a + b),
        (_, Some(b)) => *b,
        _ => 0.0,
    }
}

/// Centred moving average over `window` samples; the window shrinks at the ends.
pub(super) fn moving_average(x: &[f64], window: usize) -> Vec<f64> {
    let half = window / 2;
    let prefix = prefix_sums(x.iter().copied());
    (0..x.len())
        .map(|k| {
            let (a, b) = (k.saturating_sub(half), (k + half + 1).min(x.len()));
            window_sum(&prefix, a, b) / (b - a).max(1) as f64
        })
        .collect()
}

/// `prefix[k]` = sum of the first `k` values.
pub(super) fn prefix_sums(values: impl Iterator<Item = f64>) -> Vec<f64> {
    let mut prefix = vec![0.0];
    let mut acc = 0.0;
    for v in values {
        acc += v;
        prefix.push(acc);
    }
    prefix
}

/// Sum of samples `a..b` from prefix sums.
pub(super) fn window_sum(prefix: &[f64], a: usize, b: usize) -> f64 {
    prefix.get(b).copied().unwrap_or(0.0) - prefix.get(a).copied().unwrap_or(0.0)
}

/// Least-squares slope per second over a centred window of `2·half + 1` samples (shrunk at the ends).
pub(super) fn ls_slope_per_sec(y: &[f64], half: usize, dt_secs: f64) -> Vec<f64> {
    (0..y.len())
        .map(|k| {
            let a = k.saturating_sub(half);
            let b = (k + half + 1).min(y.len());
            let seg = y.get(a..b).unwrap_or_default();
            let t_mid = 0.5 * (seg.len().saturating_sub(1)) as f64;
            let (mut num, mut den) = (0.0, 0.0);
            let m = mean(seg);
            for (j, v) in seg.iter().enumerate() {
                let dj = j as f64 - t_mid;
                num += dj * (v - m);
                den += dj * dj;
            }
            if den > 0.0 { num / (den * dt_secs) } else { 0.0 }
        })
        .collect()
}

/// Standard deviation of the centred least-squares slope of white noise of unit σ, per second.
pub(super) fn slope_noise_per_sec(half: usize, dt_secs: f64) -> f64 {
    let h = half as f64;
    let sum_j2 = h * (h + 1.0) * (2.0 * h + 1.0) / 3.0;
    if sum_j2 > 0.0 { 1.0 / (sum_j2.sqrt() * dt_secs) } else { f64::INFINITY }
}

/// Noise σ from second differences, robust to the signal's own motion: 1.4826·MAD(Δ²y)/√6.
pub(super) fn sigma_from_second_differences(y: &[f64]) -> f64 {
    let d2: Vec<f64> =
        y.windows(3).map(|w| w.iter().zip([1.0, -2.0, 1.0]).map(|(v, c)| v * c).sum()).collect();
    let med = median(&d2);
    let abs_dev: Vec<f64> = d2.iter().map(|d| (d - med).abs()).collect();
    1.4826 * median(&abs_dev) / 6f64.sqrt()
}

/// Complementary error function (Numerical Recipes' Chebyshev fit, relative error < 1.2e-7).
pub(super) fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    const C: [f64; 10] = [
        -1.265_512_23,
        1.000_023_68,
        0.374_091_96,
        0.096_784_18,
        -0.186_288_06,
        0.278_868_07,
        -1.135_203_98,
        1.488_515_87,
        -0.822_152_23,
        0.170_872_77,
    ];
    let poly = C.iter().rev().fold(0.0, |acc, c| acc * t + c);
    let ans = t * (-z * z + poly).exp();
    if x >= 0.0 { ans } else { 2.0 - ans }
}

/// Two-sided normal tail probability of `|Z| > z`.
pub(super) fn normal_two_sided_p(z: f64) -> f64 {
    erfc(z.abs() / std::f64::consts::SQRT_2).clamp(0.0, 1.0)
}

/// In-place iterative radix-2 FFT; `data.len()` must be a power of two (other lengths are left
/// untouched). `inverse` uses the positive exponent and no 1/n scaling.
pub(super) fn fft_in_place(data: &mut Vec<Complex64>, inverse: bool) {
    let n = data.len();
    if n < 2 || !n.is_power_of_two() {
        return;
    }
    let bits = n.trailing_zeros();
    let mut permuted = vec![Complex64::default(); n];
    for (i, x) in data.iter().enumerate() {
        let j = i.reverse_bits() >> (usize::BITS - bits);
        if let Some(slot) = permuted.get_mut(j) {
            *slot = *x;
        }
    }
    *data = permuted;
    let sign = if inverse { 1.0 } else { -1.0 };
    let twiddles: Vec<Complex64> = (0..n / 2)
        .map(|k| Complex64::from_polar(1.0, sign * 2.0 * std::f64::consts::PI * k as f64 / n as f64))
        .collect();
    let mut len = 2;
    while len <= n {
        let stride = n / len;
        for block in data.chunks_exact_mut(len) {
            let (lo, hi) = block.split_at_mut(len / 2);
            for ((a, b), w) in lo.iter_mut().zip(hi.iter_mut()).zip(twiddles.iter().step_by(stride)) {
                let t = *b * w;
                *b = *a - t;
                *a += t;
            }
        }
        len *= 2;
    }
}

/// Biased autocorrelations ρ(0..=max_lag) of two real series at once (one forward and one inverse
/// FFT: `x + i·y` packs both, and the inverse of `|X|² + i·|Y|²` returns both autocovariances).
/// Series are centred; a series without spread gets all zeros.
pub(super) fn autocorrelation_pair(x: &[f64], y: &[f64], max_lag: usize) -> (Vec<f64>, Vec<f64>) {
    let n = x.len().max(y.len());
    let size = (n + max_lag + 1).next_power_of_two();
    let (xc, yc) = (centred(x), centred(y));
    let mut data: Vec<Complex64> = (0..size)
        .map(|k| Complex64::new(xc.get(k).copied().unwrap_or(0.0), yc.get(k).copied().unwrap_or(0.0)))
        .collect();
    fft_in_place(&mut data, false);
    let spectrum: Vec<Complex64> = (0..size)
        .map(|k| {
            let a = data.get(k).copied().unwrap_or_default();
            let b = data.get((size - k) % size).copied().unwrap_or_default().conj();
            let (fx, fy) = (0.5 * (a + b), Complex64::new(0.0, -0.5) * (a - b));
            Complex64::new(fx.norm_sqr(), fy.norm_sqr())
        })
        .collect();
    let mut cov = spectrum;
    fft_in_place(&mut cov, true);
    let normalise = |values: Vec<f64>| -> Vec<f64> {
        let c0 = values.first().copied().unwrap_or(0.0);
        if c0 > f64::MIN_POSITIVE { values.iter().map(|v| v / c0).collect() } else { vec![0.0; values.len()] }
    };
    let take = max_lag.min(n.saturating_sub(1)) + 1;
    let rx = cov.iter().take(take).map(|c| c.re).collect();
    let ry = cov.iter().take(take).map(|c| c.im).collect();
    (normalise(rx), normalise(ry))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::indexing_slicing)]
    use super::*;

    #[test]
    fn fft_matches_the_direct_transform() {
        let x: Vec<f64> = (0..16).map(|k| (0.7 * k as f64).sin() + 0.1 * k as f64).collect();
        let mut data: Vec<Complex64> = x.iter().map(|v| Complex64::new(*v, 0.0)).collect();
        fft_in_place(&mut data, false);
        for (k, got) in data.iter().enumerate() {
            let want: Complex64 = x
                .iter()
                .enumerate()
                .map(|(j, v)| {
                    v * Complex64::from_polar(1.0, -2.0 * std::f64::consts::PI * (j * k) as f64 / 16.0)
                })
                .sum();
            assert!((got - want).norm() < 1e-10, "bin {k}");
        }
    }

    #[test]
    fn packed_autocorrelations_match_the_direct_sums() {
        let x: Vec<f64> = (0..50).map(|k| (0.3 * k as f64).cos() + 0.01 * (k * k) as f64).collect();
        let y: Vec<f64> = (0..50).map(|k| ((k * 7919) % 13) as f64).collect();
        let (rx, ry) = autocorrelation_pair(&x, &y, 10);
        for (series, got) in [(&x, &rx), (&y, &ry)] {
            let c = centred(series);
            let c0: f64 = c.iter().map(|v| v * v).sum();
            for (lag, g) in got.iter().enumerate() {
                let want: f64 = c.iter().zip(&c[lag..]).map(|(a, b)| a * b).sum::<f64>() / c0;
                assert!((g - want).abs() < 1e-10, "lag {lag}");
            }
        }
    }

    #[test]
    fn erfc_and_slopes() {
        assert!((erfc(0.0) - 1.0).abs() < 1e-7);
        assert!((erfc(2.0) - 0.004_677_734_981).abs() < 1e-8);
        assert!((erfc(-1.0) - 1.842_700_792_9).abs() < 1e-7);
        let ramp: Vec<f64> = (0..20).map(|k| 3.0 * k as f64).collect();
        assert!(ls_slope_per_sec(&ramp, 3, 0.5).iter().all(|s| (s - 6.0).abs() < 1e-9));
        assert!((median(&[3.0, 1.0, 2.0, 10.0]) - 2.5).abs() < 1e-12);
    }
}
