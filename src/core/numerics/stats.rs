//! Small statistics and signal helpers written once for the whole core.
use std::f64::consts::PI;

/// Arithmetic mean; 0 for an empty slice.
pub fn mean(x: &[f64]) -> f64 {
    if x.is_empty() { 0.0 } else { x.iter().sum::<f64>() / x.len() as f64 }
}

/// Sum of squares ‖r‖² (the cost the Levenberg–Marquardt loops minimise).
pub fn sum_of_squares(r: &[f64]) -> f64 {
    r.iter().map(|x| x * x).sum()
}

/// Periodic Hann window of `len` samples (the form for spectral analysis).
pub fn hann(len: usize) -> Vec<f64> {
    (0..len).map(|k| 0.5 - 0.5 * (2.0 * PI * k as f64 / len as f64).cos()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn helpers_on_known_values() {
        assert!(mean(&[]).abs() <= f64::MIN_POSITIVE);
        assert!((mean(&[1.0, 2.0, 6.0]) - 3.0).abs() < 1e-15);
        assert!((sum_of_squares(&[3.0, -4.0]) - 25.0).abs() < 1e-12);
        let w = hann(4);
        assert!((w[0] - 0.0).abs() < 1e-15 && (w[2] - 1.0).abs() < 1e-15 && (w[1] - 0.5).abs() < 1e-12);
    }
}
