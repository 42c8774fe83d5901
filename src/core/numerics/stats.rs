//! Small statistics and signal helpers written once for the whole core.
use std::f64::consts::PI;

/// Arithmetic mean; 0 for an empty slice.
pub fn mean(x: &[f64]) -> f64 {
    if x.is_empty() { 0.0 } else { x.iter().sum::<f64>() / x.len() as f64 }
}

/// Pearson correlation of two equally long series; `None` when either has no spread.
pub fn pearson(x: &[f64], y: &[f64]) -> Option<f64> {
    let (mx, my) = (mean(x), mean(y));
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        let (da, db) = (a - mx, b - my);
        sxy += da * db;
        sxx += da * da;
        syy += db * db;
    }
    let denom = (sxx * syy).sqrt();
    (denom > f64::MIN_POSITIVE && denom.is_finite()).then(|| (sxy / denom).clamp(-1.0, 1.0))
}

/// Sum of squares ‖r‖² (the cost the Levenberg–Marquardt loops minimise).
pub fn sum_of_squares(r: &[f64]) -> f64 {
    r.iter().map(|x| x * x).sum()
}

/// The `q`-quantile of the finite values of `x` (nearest rank, `q` clamped to 0..=1); 0 when there
/// are none.
pub fn quantile(x: &[f64], q: f64) -> f64 {
    let mut v: Vec<f64> = x.iter().copied().filter(|v| v.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    let k = (v.len().saturating_sub(1) as f64 * q.clamp(0.0, 1.0)).round() as usize;
    v.get(k).copied().unwrap_or(0.0)
}

/// Noise σ of a signal from the median absolute first difference (white noise of σ has differences
/// of σ√2, whose median absolute value is 0.6745·σ√2); steps and dips barely move a median.
pub fn sigma_from_first_differences(x: &[f64]) -> f64 {
    let d: Vec<f64> = x.windows(2).filter_map(|w| Some((w.get(1)? - w.first()?).abs())).collect();
    quantile(&d, 0.5) / (0.6745 * std::f64::consts::SQRT_2)
}

/// Periodic Hann window of `len` samples (the form for spectral analysis).
pub fn hann(len: usize) -> Vec<f64> {
    (0..len).map(|k| 0.5 - 0.5 * (2.0 * PI * k as f64 / len as f64).cos()).collect()
}

/// `x` with `digits` significant digits in plain notation where that stays short (0.001 to
/// 100 000), in scientific notation otherwise: a sample time of 1e-7 s reads `1.000e-7`, not
/// `0.00000`.
pub fn significant(x: f64, digits: usize) -> String {
    let digits = digits.max(1);
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let magnitude = x.abs().log10().floor();
    if (-3.0..5.0).contains(&magnitude) {
        let decimals = (digits as f64 - 1.0 - magnitude).max(0.0) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.prec$e}", prec = digits - 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn helpers_on_known_values() {
        assert!(mean(&[]).abs() <= f64::MIN_POSITIVE);
        assert!((mean(&[1.0, 2.0, 6.0]) - 3.0).abs() < 1e-15);
        assert!((sum_of_squares(&[3.0, -4.0]) - 25.0).abs() < 1e-12);
        assert!((quantile(&[3.0, f64::NAN, 1.0, 2.0], 0.5) - 2.0).abs() < 1e-15);
        assert!((quantile(&[3.0, 1.0, 2.0], 1.0) - 3.0).abs() < 1e-15 && quantile(&[], 0.5).abs() < 1e-15);
        let w = hann(4);
        assert!((w[0] - 0.0).abs() < 1e-15 && (w[2] - 1.0).abs() < 1e-15 && (w[1] - 0.5).abs() < 1e-12);
    }

    #[test]
    fn significant_digits_read_alike_at_every_scale() {
        assert_eq!(super::significant(0.112994, 5), "0.11299");
        assert_eq!(super::significant(2.9, 4), "2.900");
        assert_eq!(super::significant(1e-7, 6), "1.00000e-7");
        assert_eq!(super::significant(123456.0, 4), "1.235e5");
        assert_eq!(super::significant(0.0, 4), "0");
    }
}
