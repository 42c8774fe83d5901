//! Residual statistics behind the diagnosis: correlations, spectra, plateaus, and the
//! Diebold–Mariano test with a Newey–West (Bartlett-kernel HAC) variance.
use crate::core::run::Channel;

/// A model's simulation of one run next to the measurement, with what the evidence reads.
#[derive(Clone, Debug, PartialEq)]
pub struct ResidualTrace {
    /// Run name.
    pub run: String,
    /// Sample time, s.
    pub dt_secs: f64,
    /// Input.
    pub u: Vec<f64>,
    /// Measured output.
    pub y: Vec<f64>,
    /// Simulated output.
    pub y_hat: Vec<f64>,
    /// Auxiliary channels of the run (sliced like `u` and `y`).
    pub aux: Vec<Channel>,
}

impl ResidualTrace {
    /// Residual `y − ŷ` in output units.
    pub fn residual(&self) -> Vec<f64> {
        self.y.iter().zip(&self.y_hat).map(|(y, yh)| y - yh).collect()
    }

    /// Residual in percent of the measurement (zero where the measurement is zero).
    pub fn residual_pct(&self) -> Vec<f64> {
        self.y
            .iter()
            .zip(&self.y_hat)
            .map(|(y, yh)| if y.abs() > f64::MIN_POSITIVE { 100.0 * (y - yh) / y } else { 0.0 })
            .collect()
    }
}

pub use crate::core::numerics::stats::mean;

/// Pearson correlation over the samples both have; 0 when either signal is constant.
pub fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    crate::core::numerics::stats::pearson(&a[..n], &b[..n]).unwrap_or(0.0)
}

/// Correlation of `e[k]` with `x[k − lag]` over the samples where both exist.
pub fn lagged_correlation(e: &[f64], x: &[f64], lag: isize) -> f64 {
    let n = e.len().min(x.len());
    let shift = lag.unsigned_abs().min(n);
    if lag >= 0 {
        correlation(&e[shift..n], &x[..n - shift])
    } else {
        correlation(&e[..n - shift], &x[shift..n])
    }
}

/// First difference, same length (the first value is 0).
pub fn diff(x: &[f64]) -> Vec<f64> {
    std::iter::once(0.0).chain(x.windows(2).map(|w| w[1] - w[0])).collect()
}

/// First-order low-pass `s[k] = a s[k−1] + (1 − a) x[k]` from the steady state of `x[0]`.
pub fn low_pass(x: &[f64], dt_secs: f64, tau_s: f64) -> Vec<f64> {
    let a = (-dt_secs / tau_s.max(f64::MIN_POSITIVE)).exp();
    let mut s = x.first().copied().unwrap_or(0.0);
    x.iter()
        .map(|xk| {
            s = a * s + (1.0 - a) * xk;
            s
        })
        .collect()
}

/// Welch power spectrum: Hann windows of `seg_len` samples with half overlap. Returns (Hz, power)
/// for the bins 1..seg_len/2.
pub fn welch_spectrum(x: &[f64], dt_secs: f64, seg_len: usize) -> Vec<(f64, f64)> {
    let seg_len = seg_len.min(x.len());
    if seg_len < 8 {
        return Vec::new();
    }
    let window: Vec<f64> = (0..seg_len)
        .map(|k| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * k as f64 / seg_len as f64).cos())
        .collect();
    let bins = seg_len / 2;
    let mut power = vec![0.0; bins];
    let mut count = 0usize;
    let mut start = 0;
    while start + seg_len <= x.len() {
        let seg = &x[start..start + seg_len];
        let m = mean(seg);
        for (bin, p) in power.iter_mut().enumerate().skip(1) {
            let (mut re, mut im) = (0.0, 0.0);
            for (k, (xk, wk)) in seg.iter().zip(&window).enumerate() {
                let angle = -2.0 * std::f64::consts::PI * (bin * k) as f64 / seg_len as f64;
                re += (xk - m) * wk * angle.cos();
                im += (xk - m) * wk * angle.sin();
            }
            *p += re * re + im * im;
        }
        count += 1;
        start += seg_len / 2;
    }
    let scale = 1.0 / count.max(1) as f64;
    (1..bins).map(|bin| (bin as f64 / (seg_len as f64 * dt_secs), power[bin] * scale)).collect()
}

/// Median of a list (NaN-free input); 0 when empty.
pub fn median(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => 0.0,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// Windows `(start, end)` where the input holds still for at least `hold_secs`: the last
/// `tail_secs` of each such hold (the engine has settled there).
pub fn plateaus(u: &[f64], dt_secs: f64, hold_secs: f64, tail_secs: f64) -> Vec<(usize, usize)> {
    let (lo, hi) = u.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(*x), b.max(*x)));
    let tol = 0.01 * (hi - lo).max(f64::MIN_POSITIVE);
    let need = (hold_secs / dt_secs).ceil() as usize;
    let tail = ((tail_secs / dt_secs).round() as usize).max(2);
    let mut out = Vec::new();
    let mut start = 0;
    for k in 1..=u.len() {
        let breaks = k == u.len() || (u[k] - u[start]).abs() > tol;
        if breaks {
            if k - start >= need.max(tail) {
                out.push((k - tail, k));
            }
            start = k;
        }
    }
    out
}

/// The Diebold–Mariano comparison of two models' per-sample losses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DmTest {
    /// Loss difference (before − after) averaged within each run, then over the runs; positive
    /// when the new model is better.
    pub mean_diff: f64,
    /// `mean_diff` over its standard error, asymptotically standard normal when the models are
    /// equally good.
    pub statistic: f64,
    /// One-sided p-value of "the new model is no better".
    pub p_value: f64,
    /// Largest Bartlett-kernel bandwidth (lags) used for a run's long-run variance.
    pub bandwidth: usize,
    /// Samples over all runs.
    pub n: usize,
}

/// Mean and Newey–West long-run variance of one run's loss differences, with the bandwidth used.
///
/// Bartlett weights `1 − j/(L+1)`; the bandwidth is read from the data: `L = 2·k*`, where k* is the
/// first lag at which the autocorrelation of `d` falls inside the 99 % band of white noise
/// (`2.576/√n`), and L is at most a third of the run. Residuals of simulated models stay correlated
/// over a transient (tens of samples) and then decorrelate, which a fixed rule like `4(n/100)^{2/9}`
/// misses and an AR(1) plug-in (Andrews 1991) overstates by an order of magnitude.
fn long_run_variance(d: &[f64]) -> (f64, f64, usize) {
    let n = d.len();
    let m = mean(d);
    let autocov =
        |lag: usize| d.iter().skip(lag).zip(d).map(|(a, b)| (a - m) * (b - m)).sum::<f64>() / n.max(1) as f64;
    let gamma0 = autocov(0);
    let max_lag = n / 3;
    let band = 2.576 / (n.max(1) as f64).sqrt();
    let first_insignificant =
        (1..=max_lag).find(|&k| gamma0 <= 0.0 || autocov(k) / gamma0 <= band).unwrap_or(max_lag);
    let bandwidth = (2 * first_insignificant).min(max_lag);
    let mut lrv = gamma0;
    for j in 1..=bandwidth {
        lrv += 2.0 * (1.0 - j as f64 / (bandwidth + 1) as f64) * autocov(j);
    }
    (m, lrv.max(0.0), bandwidth)
}

/// Diebold–Mariano test on loss differences `d` given per run. Every run counts equally (the
/// statistic is the average of the runs' mean differences, matching a validation error that
/// averages the runs' RMSPE); runs are independent and each has its own Newey–West long-run
/// variance (see [`long_run_variance`]), so no lag crosses a run boundary.
pub fn diebold_mariano(d_runs: &[Vec<f64>]) -> DmTest {
    let runs: Vec<&Vec<f64>> = d_runs.iter().filter(|d| !d.is_empty()).collect();
    let r = runs.len().max(1) as f64;
    let (mut mean_diff, mut var, mut bandwidth) = (0.0, 0.0, 0);
    for d in &runs {
        let (m, lrv, l) = long_run_variance(d);
        mean_diff += m / r;
        var += lrv / d.len() as f64 / (r * r);
        bandwidth = bandwidth.max(l);
    }
    let se = var.sqrt();
    let statistic = if se > 0.0 {
        mean_diff / se
    } else if mean_diff > 0.0 {
        f64::INFINITY
    } else {
        0.0
    };
    DmTest {
        mean_diff,
        statistic,
        p_value: 1.0 - normal_cdf(statistic),
        bandwidth,
        n: runs.iter().map(|d| d.len()).sum(),
    }
}

/// Wilcoxon's signed-rank test of paired differences, one-sided: how consistently `d > 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SignedRankTest {
    /// Differences counted (zeros are left out).
    pub n: usize,
    /// Of them, how many are positive.
    pub wins: usize,
    /// Exact one-sided p-value of "the differences are symmetric about zero" against "they lean
    /// positive".
    pub p_value: f64,
}

/// Wilcoxon signed-rank test of `d` against zero, one-sided, with the exact null distribution:
/// each difference's sign is a fair coin, its rank (of |d|, ties sharing their mean rank) fixed.
/// Distribution-free, so a few large differences cannot carry it and nothing is assumed about
/// their spread: the right test for a handful of independent units such as held-out step
/// responses. Zero differences say nothing either way and are dropped.
pub fn signed_rank_test(d: &[f64]) -> SignedRankTest {
    let mut nonzero: Vec<f64> = d.iter().copied().filter(|x| *x != 0.0 && x.is_finite()).collect();
    nonzero.sort_by(|a, b| a.abs().total_cmp(&b.abs()));
    let n = nonzero.len();
    // Doubled ranks (integers even when ties share a half rank).
    let mut ranks = vec![0usize; n];
    let mut i = 0;
    while i < n {
        let mut j = i;
        // Exact ties only (equal magnitudes), as the rank definition has them.
        while j + 1 < n && nonzero[j + 1].abs().total_cmp(&nonzero[i].abs()).is_eq() {
            j += 1;
        }
        // Ranks i+1..=j+1 share their mean (i + j + 2)/2; doubled: i + j + 2.
        ranks[i..=j].fill(i + j + 2);
        i = j + 1;
    }
    let w_plus: usize = nonzero.iter().zip(&ranks).filter(|(x, _)| **x > 0.0).map(|(_, r)| r).sum();
    let total: usize = ranks.iter().sum();
    // Null distribution of the doubled positive rank sum, by adding one coin at a time.
    let mut dist = vec![0.0; total + 1];
    dist[0] = 1.0;
    for &r in &ranks {
        for s in (0..=total).rev() {
            let with = if s >= r { dist[s - r] } else { 0.0 };
            dist[s] = 0.5 * dist[s] + 0.5 * with;
        }
    }
    SignedRankTest {
        n,
        wins: nonzero.iter().filter(|x| **x > 0.0).count(),
        p_value: if n == 0 { 1.0 } else { dist[w_plus..].iter().sum::<f64>().min(1.0) },
    }
}

/// Stouffer's combination of independent one-sided p-values, equally weighted: each becomes the
/// standard normal score `zᵢ = Φ⁻¹(1 − pᵢ)`, and `Σ zᵢ / √k` is standard normal when every null
/// holds. Unlike Fisher's `−2 Σ ln pᵢ`, which one tiny p carries alone, a witness that points the
/// other way (`pᵢ` near 1, `zᵢ` negative) counts against the rest, and one that has nothing to say
/// (`pᵢ` near ½, `zᵢ` near 0) only dilutes them.
pub fn stouffer_combined(p_values: &[f64]) -> f64 {
    if p_values.is_empty() {
        return 1.0;
    }
    let z: f64 = p_values.iter().map(|p| normal_quantile(1.0 - p)).sum();
    1.0 - normal_cdf(z / (p_values.len() as f64).sqrt())
}

/// Φ⁻¹(q) by bisection on [`normal_cdf`], clamped to ±8 (q within 10⁻¹⁵ of 0 or 1); as accurate as
/// `normal_cdf` itself.
pub fn normal_quantile(q: f64) -> f64 {
    let (mut lo, mut hi) = (-8.0_f64, 8.0_f64);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if normal_cdf(mid) < q {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Standard normal cumulative distribution.
pub fn normal_cdf(x: f64) -> f64 {
    if x.is_infinite() {
        return if x > 0.0 { 1.0 } else { 0.0 };
    }
    0.5 * erfc(-x / std::f64::consts::SQRT_2)
}

/// Complementary error function (Numerical Recipes' Chebyshev fit, relative error < 1.2e-7).
fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let r = t * poly.exp();
    if x >= 0.0 { r } else { 2.0 - r }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    #[test]
    fn normal_cdf_matches_known_values() {
        assert!((normal_cdf(0.0) - 0.5).abs() < 1e-7);
        assert!((normal_cdf(2.326_348) - 0.99).abs() < 1e-6);
        assert!((normal_cdf(-1.959_964) - 0.025).abs() < 1e-6);
    }

    #[test]
    fn dm_test_is_calibrated_on_autocorrelated_noise() {
        // AR(1) loss differences with zero mean: the 1 % test rejects rarely.
        let mut rejections = 0;
        for seed in 0..100 {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let normal = Normal::new(0.0, 1.0).unwrap();
            let mut x = 0.0;
            let d: Vec<f64> = (0..2000)
                .map(|_| {
                    x = 0.95 * x + normal.sample(&mut rng);
                    x
                })
                .collect();
            if diebold_mariano(&[d]).p_value < 0.01 {
                rejections += 1;
            }
        }
        assert!(rejections <= 5, "{rejections} of 100 rejections at the 1 % level");
    }

    #[test]
    fn signed_rank_test_matches_its_exact_distribution() {
        // All of n positive: p = 2⁻ⁿ; one negative at the smallest rank: the two largest sums.
        assert!((signed_rank_test(&[1.0, 2.0, 3.0, 4.0, 5.0]).p_value - 1.0 / 32.0).abs() < 1e-12);
        let t = signed_rank_test(&[-1.0, 2.0, 3.0, 4.0, 5.0]);
        assert_eq!((t.n, t.wins), (5, 4));
        assert!((t.p_value - 2.0 / 32.0).abs() < 1e-12, "{t:?}");
        // Symmetric about zero: about one half; zeros are dropped; ties share a rank.
        assert!((signed_rank_test(&[-1.0, 1.0]).p_value - 0.75).abs() < 1e-12);
        assert!((signed_rank_test(&[0.0, 0.0]).p_value - 1.0).abs() < 1e-15);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let normal = Normal::new(0.0, 1.0).unwrap();
        let rejections = (0..400)
            .filter(|_| {
                let d: Vec<f64> = (0..10).map(|_| normal.sample(&mut rng)).collect();
                signed_rank_test(&d).p_value < 0.05
            })
            .count();
        assert!(rejections <= 30, "{rejections} of 400 at the 5 % level");
    }

    #[test]
    fn stouffer_combination_adds_normal_scores() {
        assert!((normal_quantile(0.975) - 1.959_964).abs() < 1e-5);
        assert!((stouffer_combined(&[0.05]) - 0.05).abs() < 1e-6);
        // Two witnesses at p = 0.05: z = 1.645 each, (1.645 + 1.645)/√2 = 2.326, p = 0.01.
        assert!((stouffer_combined(&[0.05, 0.05]) - 0.01).abs() < 1e-4);
        // A witness with nothing to say dilutes; one against cancels.
        assert!((stouffer_combined(&[0.05, 0.5]) - (1.0 - normal_cdf(1.644_854 / 2f64.sqrt()))).abs() < 1e-5);
        assert!((stouffer_combined(&[0.05, 0.95]) - 0.5).abs() < 1e-6);
    }

    #[test]
    fn spectrum_finds_a_sinusoid_and_correlation_finds_a_lag() {
        let dt = 0.1;
        let x: Vec<f64> =
            (0..1000).map(|k| (2.0 * std::f64::consts::PI * 1.5 * k as f64 * dt).sin()).collect();
        let spec = welch_spectrum(&x, dt, 128);
        let peak = spec.iter().max_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
        assert!((peak.0 - 1.5).abs() < 0.1, "{peak:?}");
        let e: Vec<f64> = (0..1000).map(|k| if k >= 3 { x[k - 3] } else { 0.0 }).collect();
        assert!(lagged_correlation(&e, &x, 3) > 0.99);
        let u = [1.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0, 2.0, 2.0];
        assert_eq!(plateaus(&u, 1.0, 3.0, 2.0), vec![(2, 4), (7, 9)]);
    }
}
