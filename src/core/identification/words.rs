//! How the chain's numbers read in the verdicts and notes: an error in output units and a root
//! with its s-plane figures.
use num_complex::Complex64;

/// An error in output units: whole units from 100 up, three decimals below.
pub fn fmt_error(x: f64) -> String {
    if x.abs() >= 100.0 { format!("{x:.0}") } else { format!("{x:.3}") }
}

/// "pair near 2.31 rad/s (ζ 0.60)" or "real root 0.936 (τ 1.72 s)".
pub fn root_words(z: Complex64, pair: bool, omega_rad_s: f64, zeta: f64) -> String {
    if pair {
        format!("pair near {omega_rad_s:.2} rad/s (ζ {zeta:.2})")
    } else if z.re > 0.0 && z.re < 1.0 && omega_rad_s > 0.0 {
        format!("real root at {:.3} (τ {:.2} s)", z.re, 1.0 / omega_rad_s)
    } else {
        format!("real root at {:.3}", z.re)
    }
}
