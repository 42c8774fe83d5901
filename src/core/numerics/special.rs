//! Special functions for the noise-distribution fits: ln Γ and ψ by recurrence and their asymptotic
//! series, written free of cancellation for large arguments.

/// ½ ln 2π.
pub const HALF_LN_2PI: f64 = 0.918_938_533_204_672_8;

/// Stirling series tail S(x) in ln Γ(x) = (x − ½) ln x − x + ½ ln 2π + S(x), for x ≥ 10.
pub fn stirling_tail(x: f64) -> f64 {
    let r = 1.0 / (x * x);
    (1.0 / 12.0 - r * (1.0 / 360.0 - r * (1.0 / 1260.0 - r / 1680.0))) / x
}

/// ln Γ(x) for x > 0 (recurrence up to x ≥ 10, then Stirling).
pub fn ln_gamma(x: f64) -> f64 {
    let mut shift = 0.0;
    let mut x = x;
    while x < 10.0 {
        shift += x.ln();
        x += 1.0;
    }
    (x - 0.5) * x.ln() - x + HALF_LN_2PI + stirling_tail(x) - shift
}

/// m ln m − ln Γ(m) − m, free of cancellation for large m.
pub fn stirling_a(m: f64) -> f64 {
    if m >= 10.0 { 0.5 * m.ln() - HALF_LN_2PI - stirling_tail(m) } else { m * m.ln() - ln_gamma(m) - m }
}

/// ln Γ(m + ½) − ln Γ(m) − ½ ln m, free of cancellation for large m.
pub fn ln_gamma_ratio_half(m: f64) -> f64 {
    if m >= 10.0 {
        m * (0.5 / m).ln_1p() - 0.5 + stirling_tail(m + 0.5) - stirling_tail(m)
    } else {
        ln_gamma(m + 0.5) - ln_gamma(m) - 0.5 * m.ln()
    }
}

/// ln x − ψ(x) for x > 0 (recurrence up to x ≥ 10, then the asymptotic series).
pub fn ln_minus_digamma(x: f64) -> f64 {
    let mut correction = 0.0;
    let mut y = x;
    while y < 10.0 {
        correction += 1.0 / y;
        y += 1.0;
    }
    let r = 1.0 / (y * y);
    let tail = 1.0 / (2.0 * y) + r * (1.0 / 12.0 - r * (1.0 / 120.0 - r * (1.0 / 252.0 - r / 240.0)));
    tail - (y / x).ln() + correction
}
