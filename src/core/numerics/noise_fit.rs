//! Maximum-likelihood fits of candidate noise distributions to a steady run's channel.
//!
//! Every fit works on centred and scaled data internally (a fuel channel at 5.43 with σ ≈ 0.003 or a
//! speed channel at 73,850 rpm with σ ≈ 51 both become O(1) numbers) and reports its parameters and
//! log-likelihood on the raw data.
pub use crate::core::numerics::special::ln_gamma;
use crate::core::numerics::special::{HALF_LN_2PI, ln_gamma_ratio_half, ln_minus_digamma, stirling_a};
use rand::Rng;
use rand_distr::{Gamma, Open01, StandardNormal};
use serde::{Deserialize, Serialize};

/// Euler–Mascheroni constant, the mean of the standard maximum-value Gumbel.
const EULER_GAMMA: f64 = 0.577_215_664_901_532_9;
/// The smallest sample any of the two-parameter fits accepts (also the shortest Monte Carlo run).
pub const MIN_SAMPLES: usize = 3;

/// The candidate families, in the paper's order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Family {
    Normal,
    Logistic,
    Uniform,
    /// Minimum-value Gumbel, as MATLAB's `evfit`.
    ExtremeValue,
    InverseGaussian,
    Nakagami,
}

impl Family {
    /// Every family, in the paper's order.
    pub const ALL: [Family; 6] = [
        Self::Normal,
        Self::Logistic,
        Self::Uniform,
        Self::ExtremeValue,
        Self::InverseGaussian,
        Self::Nakagami,
    ];

    /// A name for people.
    pub fn name(self) -> &'static str {
        match self {
            Self::Normal => "normal",
            Self::Logistic => "logistic",
            Self::Uniform => "uniform",
            Self::ExtremeValue => "extreme value (min. Gumbel)",
            Self::InverseGaussian => "inverse Gaussian",
            Self::Nakagami => "Nakagami",
        }
    }
}

/// A fitted distribution with its parameters named. Densities, with z = (x − location)/scale:
/// - `Logistic`: e^{−z} / (scale (1 + e^{−z})²).
/// - `ExtremeValue`: the minimum-value Gumbel of MATLAB's `evpdf`, exp(z − e^z)/scale, skewed to the
///   left, mean location − γ·scale. (The maximum-value form is its mirror image.)
/// - `InverseGaussian`: sqrt(shape/(2π x³)) · exp(−shape (x − mean)² / (2 mean² x)), x > 0.
/// - `Nakagami`: 2 mᵐ / (Γ(m) Ωᵐ) · x^{2m−1} · exp(−m x²/Ω), x > 0, with m = `shape` and
///   Ω = `spread` = E(x²).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "family", rename_all = "snake_case")]
pub enum Distribution {
    Normal { mean: f64, std: f64 },
    Logistic { location: f64, scale: f64 },
    Uniform { lower: f64, upper: f64 },
    ExtremeValue { location: f64, scale: f64 },
    InverseGaussian { mean: f64, shape: f64 },
    Nakagami { shape: f64, spread: f64 },
}

/// Why a sample cannot be fitted, or a distribution cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NoiseFitError {
    #[error("{found} samples are too few for a fit; at least {needed} are needed")]
    TooFewSamples { found: usize, needed: usize },
    #[error("sample {index} is not finite")]
    NonFinite { index: usize },
    #[error("every sample equals {value}, so no spread can be fitted")]
    ZeroSpread { value: f64 },
    #[error("the {} distribution needs positive data, but sample {index} is {value}", family.name())]
    NonPositive { family: Family, index: usize, value: f64 },
    #[error("the {} fit did not converge", family.name())]
    NoConvergence { family: Family },
    #[error("parameter {name} of the {} distribution is invalid: {value}", family.name())]
    BadParameter { family: Family, name: &'static str, value: f64 },
}

/// One family's fit on a sample.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FitResult {
    pub distribution: Distribution,
    pub log_likelihood: f64,
    /// Akaike information criterion, 2k − 2 log-likelihood.
    pub aic: f64,
}

/// A family that could not be fitted to this sample, and why.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SkippedFit {
    pub family: Family,
    pub reason: String,
}

/// Every family fitted to one sample, the best named.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NoiseFitReport {
    pub n: usize,
    pub fits: Vec<FitResult>,
    pub skipped: Vec<SkippedFit>,
    pub best_by_log_likelihood: Family,
    pub best_by_aic: Family,
}

impl NoiseFitReport {
    /// The fit of `family`, when it could be made.
    pub fn get(&self, family: Family) -> Option<&FitResult> {
        self.fits.iter().find(|f| f.distribution.family() == family)
    }

    /// The fit with the highest log-likelihood.
    pub fn best(&self) -> Option<&FitResult> {
        self.get(self.best_by_log_likelihood)
    }
}

/// Fits every family; positive-only families that cannot take this sample go to `skipped`.
pub fn fit_all(data: &[f64]) -> Result<NoiseFitReport, NoiseFitError> {
    Standardized::new(data)?;
    let mut fits = Vec::new();
    let mut skipped = Vec::new();
    for family in Family::ALL {
        match fit(family, data) {
            Ok(distribution) => {
                let log_likelihood = distribution.log_likelihood(data);
                let aic = 2.0 * distribution.params().len() as f64 - 2.0 * log_likelihood;
                fits.push(FitResult { distribution, log_likelihood, aic });
            }
            Err(e) => skipped.push(SkippedFit { family, reason: e.to_string() }),
        }
    }
    let best_by = |key: &dyn Fn(&FitResult) -> f64| {
        fits.iter()
            .filter(|f| key(f).is_finite())
            .max_by(|a, b| key(a).total_cmp(&key(b)))
            .map_or(Family::Normal, |f| f.distribution.family())
    };
    let best_by_log_likelihood = best_by(&|f| f.log_likelihood);
    let best_by_aic = best_by(&|f| -f.aic);
    Ok(NoiseFitReport { n: data.len(), fits, skipped, best_by_log_likelihood, best_by_aic })
}

/// Maximum-likelihood fit of one family.
pub fn fit(family: Family, data: &[f64]) -> Result<Distribution, NoiseFitError> {
    let st = Standardized::new(data)?;
    let (c, s) = (st.centre, st.scale);
    let dist = match family {
        Family::Normal => Distribution::Normal { mean: c, std: s },
        Family::Uniform => {
            let lo = st.z.iter().fold(f64::INFINITY, |m, v| m.min(*v));
            let hi = st.z.iter().fold(f64::NEG_INFINITY, |m, v| m.max(*v));
            Distribution::Uniform { lower: c + s * lo, upper: c + s * hi }
        }
        Family::Logistic => {
            let [location, scale] = fit_logistic_std(&st.z)?;
            Distribution::Logistic { location: c + s * location, scale: s * scale }
        }
        Family::ExtremeValue => {
            let (location, scale) = fit_min_gumbel_std(&st.z)?;
            Distribution::ExtremeValue { location: c + s * location, scale: s * scale }
        }
        Family::InverseGaussian => {
            check_positive(family, data)?;
            // 1/shape = mean(1/x − 1/x̄) = mean(d²/x)/x̄² with d = x − x̄ (free of cancellation).
            let mean_d2_over_x = data.iter().map(|x| (x - c).powi(2) / x).sum::<f64>() / data.len() as f64;
            Distribution::InverseGaussian { mean: c, shape: c * c / mean_d2_over_x }
        }
        Family::Nakagami => {
            check_positive(family, data)?;
            let (shape, spread_over_c2) = fit_nakagami_scaled(data, c)?;
            Distribution::Nakagami { shape, spread: spread_over_c2 * c * c }
        }
    };
    dist.check()?;
    Ok(dist)
}

impl Distribution {
    /// The family this distribution belongs to.
    pub fn family(&self) -> Family {
        match self {
            Self::Normal { .. } => Family::Normal,
            Self::Logistic { .. } => Family::Logistic,
            Self::Uniform { .. } => Family::Uniform,
            Self::ExtremeValue { .. } => Family::ExtremeValue,
            Self::InverseGaussian { .. } => Family::InverseGaussian,
            Self::Nakagami { .. } => Family::Nakagami,
        }
    }

    /// The distribution of `family` with parameters in the order of [`Distribution::params`], checked.
    pub fn from_params(family: Family, [a, b]: [f64; 2]) -> Result<Self, NoiseFitError> {
        let dist = match family {
            Family::Normal => Self::Normal { mean: a, std: b },
            Family::Logistic => Self::Logistic { location: a, scale: b },
            Family::Uniform => Self::Uniform { lower: a, upper: b },
            Family::ExtremeValue => Self::ExtremeValue { location: a, scale: b },
            Family::InverseGaussian => Self::InverseGaussian { mean: a, shape: b },
            Family::Nakagami => Self::Nakagami { shape: a, spread: b },
        };
        dist.check()?;
        Ok(dist)
    }

    /// The parameters with their names, in declaration order.
    pub fn params(&self) -> [(&'static str, f64); 2] {
        match *self {
            Self::Normal { mean, std } => [("mean", mean), ("std", std)],
            Self::Logistic { location, scale } | Self::ExtremeValue { location, scale } => {
                [("location", location), ("scale", scale)]
            }
            Self::Uniform { lower, upper } => [("lower", lower), ("upper", upper)],
            Self::InverseGaussian { mean, shape } => [("mean", mean), ("shape", shape)],
            Self::Nakagami { shape, spread } => [("shape", shape), ("spread", spread)],
        }
    }

    /// Checks that the parameters are finite and in range (scales positive, `lower < upper`).
    pub fn check(&self) -> Result<(), NoiseFitError> {
        let family = self.family();
        let [first, second] = self.params();
        let positive = |(name, value): (&'static str, f64)| (value <= 0.0).then_some((name, value));
        let problem = [first, second].into_iter().find(|(_, v)| !v.is_finite()).or(match *self {
            Self::Uniform { upper, lower } => (upper <= lower).then_some(("upper", upper)),
            Self::InverseGaussian { .. } | Self::Nakagami { .. } => positive(first).or(positive(second)),
            Self::Normal { .. } | Self::Logistic { .. } | Self::ExtremeValue { .. } => positive(second),
        });
        match problem {
            Some((name, value)) => Err(NoiseFitError::BadParameter { family, name, value }),
            None => Ok(()),
        }
    }

    /// Natural log of the density at `x` (−∞ outside the support).
    pub fn ln_pdf(&self, x: f64) -> f64 {
        match *self {
            Self::Normal { mean, std } => {
                let z = (x - mean) / std;
                -0.5 * z * z - std.ln() - HALF_LN_2PI
            }
            Self::Logistic { location, scale } => {
                -scale.ln() - 2.0 * ln_two_cosh(0.5 * (x - location) / scale)
            }
            Self::Uniform { lower, upper } if (lower..=upper).contains(&x) => -(upper - lower).ln(),
            Self::Uniform { .. } => f64::NEG_INFINITY,
            Self::ExtremeValue { location, scale } => {
                let z = (x - location) / scale;
                z - z.exp() - scale.ln()
            }
            Self::InverseGaussian { .. } | Self::Nakagami { .. } if x <= 0.0 => f64::NEG_INFINITY,
            Self::InverseGaussian { mean, shape } => {
                0.5 * (shape / (2.0 * std::f64::consts::PI)).ln()
                    - 1.5 * x.ln()
                    - shape * (x - mean).powi(2) / (2.0 * mean * mean * x)
            }
            Self::Nakagami { shape, spread } => {
                // ln pdf = ln 2 + (m ln m − ln Γ(m) − m) + m (ln r − r + 1) − ln x with r = x²/Ω:
                // every term stays O(1) per sample even when m is in the millions.
                let e = x * x / spread - 1.0;
                std::f64::consts::LN_2 + stirling_a(shape) + shape * (e.ln_1p() - e) - x.ln()
            }
        }
    }

    /// The density at `x`, e.g. to draw the fitted curve over a histogram.
    pub fn pdf(&self, x: f64) -> f64 {
        self.ln_pdf(x).exp()
    }

    /// Sum of [`Distribution::ln_pdf`] over `data`.
    pub fn log_likelihood(&self, data: &[f64]) -> f64 {
        data.iter().map(|x| self.ln_pdf(*x)).sum()
    }

    /// The distribution's mean.
    pub fn mean(&self) -> f64 {
        match *self {
            Self::Normal { mean, .. } | Self::InverseGaussian { mean, .. } => mean,
            Self::Logistic { location, .. } => location,
            Self::Uniform { lower, upper } => 0.5 * (lower + upper),
            Self::ExtremeValue { location, scale } => location - EULER_GAMMA * scale,
            Self::Nakagami { shape, spread } => spread.sqrt() * ln_gamma_ratio_half(shape).exp(),
        }
    }

    /// One draw. Parameters that fail [`Distribution::check`] give NaN.
    pub fn sample(&self, rng: &mut impl Rng) -> f64 {
        if self.check().is_err() {
            return f64::NAN;
        }
        match *self {
            Self::Normal { mean, std } => mean + std * rng.sample::<f64, _>(StandardNormal),
            Self::Logistic { location, scale } => {
                let p: f64 = rng.sample(Open01);
                location + scale * (p / (1.0 - p)).ln()
            }
            Self::Uniform { lower, upper } => lower + (upper - lower) * rng.random::<f64>(),
            Self::ExtremeValue { location, scale } => {
                let p: f64 = rng.sample(Open01);
                location + scale * (-p.ln()).ln()
            }
            Self::InverseGaussian { mean, shape } => {
                // Michael, Schucany & Haas (1976).
                let nu: f64 = rng.sample(StandardNormal);
                let y = nu * nu;
                let x = mean + mean * mean * y / (2.0 * shape)
                    - mean / (2.0 * shape) * (4.0 * mean * shape * y + (mean * y).powi(2)).sqrt();
                if rng.random::<f64>() <= mean / (mean + x) { x } else { mean * mean / x }
            }
            Self::Nakagami { shape, spread } => {
                Gamma::new(shape, spread / shape).map_or(f64::NAN, |g| rng.sample::<f64, _>(g).sqrt())
            }
        }
    }
}

/// The sample centred on its mean and divided by its standard deviation (population form).
struct Standardized {
    centre: f64,
    scale: f64,
    z: Vec<f64>,
}

impl Standardized {
    fn new(data: &[f64]) -> Result<Self, NoiseFitError> {
        if data.len() < MIN_SAMPLES {
            return Err(NoiseFitError::TooFewSamples { found: data.len(), needed: MIN_SAMPLES });
        }
        if let Some(index) = data.iter().position(|v| !v.is_finite()) {
            return Err(NoiseFitError::NonFinite { index });
        }
        let n = data.len() as f64;
        let centre = data.iter().sum::<f64>() / n;
        let scale = (data.iter().map(|x| (x - centre).powi(2)).sum::<f64>() / n).sqrt();
        let magnitude = data.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if scale <= 4.0 * f64::EPSILON * magnitude || scale <= 0.0 {
            return Err(NoiseFitError::ZeroSpread { value: centre });
        }
        Ok(Self { centre, scale, z: data.iter().map(|x| (x - centre) / scale).collect() })
    }
}

fn check_positive(family: Family, data: &[f64]) -> Result<(), NoiseFitError> {
    match data.iter().enumerate().find(|(_, v)| **v <= 0.0) {
        Some((index, &value)) => Err(NoiseFitError::NonPositive { family, index, value }),
        None => Ok(()),
    }
}

/// ln(2 cosh a), without overflow.
fn ln_two_cosh(a: f64) -> f64 {
    a.abs() + (-2.0 * a.abs()).exp().ln_1p()
}

/// Logistic MLE on standardised data by damped Newton on (location, scale).
fn fit_logistic_std(z: &[f64]) -> Result<[f64; 2], NoiseFitError> {
    let n = z.len() as f64;
    let eval = |[mu, s]: [f64; 2]| -> Option<(f64, [f64; 2], [[f64; 2]; 2])> {
        if !(s > 0.0 && s.is_finite() && mu.is_finite()) {
            return None;
        }
        let (mut ll, mut g, mut h) = (0.0, [0.0; 2], [[0.0; 2]; 2]);
        for x in z {
            let t = (x - mu) / s;
            let th = (0.5 * t).tanh();
            let dth = 0.5 * (1.0 - th * th);
            ll += -s.ln() - 2.0 * ln_two_cosh(0.5 * t);
            g[0] += th / s;
            g[1] += (t * th - 1.0) / s;
            h[0][0] -= dth / (s * s);
            h[0][1] -= (t * dth + th) / (s * s);
            h[1][1] -= (2.0 * t * th + t * t * dth - 1.0) / (s * s);
        }
        h[1][0] = h[0][1];
        Some((ll, g, h))
    };
    maximize_2d(eval, [0.0, 3f64.sqrt() / std::f64::consts::PI], n)
        .ok_or(NoiseFitError::NoConvergence { family: Family::Logistic })
}

/// Newton ascent with step halving; falls back to the gradient where the Hessian is not negative
/// definite. Once the predicted gain is below what the log-likelihood's rounding can show, Newton steps
/// are taken without the (then meaningless) comparison. Stops when the gradient is below 1e-8 per
/// sample; `None` when it never gets there.
fn maximize_2d(
    f: impl Fn([f64; 2]) -> Option<(f64, [f64; 2], [[f64; 2]; 2])>,
    start: [f64; 2],
    n: f64,
) -> Option<[f64; 2]> {
    let mut theta = start;
    for _ in 0..200 {
        let (ll, g, h) = f(theta)?;
        if g[0].hypot(g[1]) < 1e-8 * n {
            return Some(theta);
        }
        let det = h[0][0] * h[1][1] - h[0][1] * h[1][0];
        let newton = [-(h[1][1] * g[0] - h[0][1] * g[1]) / det, -(h[0][0] * g[1] - h[1][0] * g[0]) / det];
        let gain = newton[0] * g[0] + newton[1] * g[1];
        let ascent = h[0][0] < 0.0 && det > 0.0 && gain > 0.0;
        if ascent && gain < 1e-9 * (1.0 + ll.abs()) {
            theta = [theta[0] + newton[0], theta[1] + newton[1]];
            continue;
        }
        let dir = if ascent { newton } else { [g[0] / n, g[1] / n] };
        let mut step = 1.0;
        theta = loop {
            let cand = [theta[0] + step * dir[0], theta[1] + step * dir[1]];
            if f(cand).is_some_and(|(l, _, _)| l >= ll) {
                break cand;
            }
            step *= 0.5;
            if step < 1e-12 {
                return None;
            }
        };
    }
    None
}

/// Minimum-value Gumbel MLE on standardised data: the scale σ solves
/// `Σ x·w(σ) − x̄ − σ = 0` with weights `w ∝ e^{x/σ}` (strictly decreasing in σ, so bisection is safe),
/// and then `location = σ ln(mean e^{x/σ})`.
fn fit_min_gumbel_std(z: &[f64]) -> Result<(f64, f64), NoiseFitError> {
    let zmax = z.iter().fold(f64::NEG_INFINITY, |m, v| m.max(*v));
    let zbar = z.iter().sum::<f64>() / z.len() as f64;
    // (weighted mean of z, ln Σ e^{(z − zmax)/σ})
    let weighted = |sigma: f64| {
        let w: Vec<f64> = z.iter().map(|x| ((x - zmax) / sigma).exp()).collect();
        let sum: f64 = w.iter().sum();
        (w.iter().zip(z).map(|(w, x)| w * x).sum::<f64>() / sum, sum.ln())
    };
    let h = |sigma: f64| weighted(sigma).0 - zbar - sigma;
    let (mut lo, mut hi) = (1e-6, 1.0);
    while h(hi) > 0.0 {
        hi *= 2.0;
        if hi > 1e6 {
            return Err(NoiseFitError::NoConvergence { family: Family::ExtremeValue });
        }
    }
    if h(lo) <= 0.0 {
        return Err(NoiseFitError::NoConvergence { family: Family::ExtremeValue });
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if h(mid) > 0.0 {
            lo = mid
        } else {
            hi = mid
        }
        if hi - lo <= 1e-15 * hi {
            break;
        }
    }
    let sigma = 0.5 * (lo + hi);
    let ln_sum = weighted(sigma).1;
    Ok((zmax + sigma * (ln_sum - (z.len() as f64).ln()), sigma))
}

/// Nakagami MLE of `x / c`: spread Ω = mean(y²), shape m solving ln m − ψ(m) = ln Ω − mean(ln y²),
/// with both sides computed from the small deviations of y = x/c from 1.
fn fit_nakagami_scaled(data: &[f64], c: f64) -> Result<(f64, f64), NoiseFitError> {
    let n = data.len() as f64;
    let e: Vec<f64> = data.iter().map(|x| x / c - 1.0).collect();
    let mean_sq_minus_one = e.iter().map(|e| 2.0 * e + e * e).sum::<f64>() / n;
    let mean_ln_sq = e.iter().map(|e| 2.0 * e.ln_1p()).sum::<f64>() / n;
    let delta = mean_sq_minus_one.ln_1p() - mean_ln_sq;
    if !(delta.is_finite() && delta > 0.0) {
        return Err(NoiseFitError::NoConvergence { family: Family::Nakagami });
    }
    // ln m − ψ(m) decreases from +∞ to 0: bisect on ln m.
    let (mut lo, mut hi) = ((1e-8f64).ln(), (1e18f64).ln());
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if ln_minus_digamma(mid.exp()) > delta { lo = mid } else { hi = mid }
    }
    Ok(((0.5 * (lo + hi)).exp(), 1.0 + mean_sq_minus_one))
}
