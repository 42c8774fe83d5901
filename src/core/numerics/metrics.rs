//! The paper's error metrics (RMSPE, SE, …) and box-plot statistics of the percentage error.
use serde::{Deserialize, Serialize};

/// Metrics of a simulated output `ŷ` against a measurement `y`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// 100·sqrt(mean(((y − ŷ)/y)²)).
    pub rmspe_pct: f64,
    /// 100·mean(|y − ŷ| / |y|).
    pub mape_pct: f64,
    /// Standard error: std(y − ŷ)/sqrt(n).
    pub se: f64,
    /// NRMSE fit: 100·(1 − ‖y − ŷ‖/‖y − mean(y)‖).
    pub fit_pct: f64,
    pub rmse: f64,
    pub max_abs_error: f64,
    pub n: usize,
}

/// A model whose fit is below this, %, leaves more than half of the output's variation about its
/// mean unexplained (‖y − ŷ‖ > ½‖y − ȳ‖): it fails on that run, whatever its RMSPE, and is flagged
/// wherever models are compared.
pub const MIN_FIT_PCT: f64 = 50.0;

impl Metrics {
    /// Whether the model fails on the run (see [`MIN_FIT_PCT`]).
    pub fn fails(&self) -> bool {
        !self.fit_pct.is_finite() || self.fit_pct < MIN_FIT_PCT
    }

    /// "fit 31.7 % (below 50 %)" when the model fails, for a flag beside its numbers.
    pub fn failure(&self) -> Option<String> {
        self.fails().then(|| format!("fit {:.1} % (below {MIN_FIT_PCT:.0} %)", self.fit_pct))
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MetricsError {
    #[error("measurement has {y} samples but the model gave {yhat}")]
    LengthMismatch { y: usize, yhat: usize },
    #[error("no samples to score")]
    Empty,
    #[error("the model output is not finite at sample {index}")]
    NonFinite { index: usize },
    #[error("the measurement is zero at sample {index}, so percentage errors are undefined")]
    ZeroMeasurement { index: usize },
}

fn check(y: &[f64], yhat: &[f64]) -> Result<(), MetricsError> {
    if y.len() != yhat.len() {
        return Err(MetricsError::LengthMismatch { y: y.len(), yhat: yhat.len() });
    }
    if y.is_empty() {
        return Err(MetricsError::Empty);
    }
    if let Some(index) = yhat.iter().position(|v| !v.is_finite()) {
        return Err(MetricsError::NonFinite { index });
    }
    let scale = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if let Some(index) = y.iter().position(|v| v.abs() <= 1e-12 * scale.max(f64::MIN_POSITIVE)) {
        return Err(MetricsError::ZeroMeasurement { index });
    }
    Ok(())
}

pub fn metrics(y: &[f64], yhat: &[f64]) -> Result<Metrics, MetricsError> {
    check(y, yhat)?;
    let n = y.len() as f64;
    let err: Vec<f64> = y.iter().zip(yhat).map(|(a, b)| a - b).collect();
    let mean_err = err.iter().sum::<f64>() / n;
    let var_err = err.iter().map(|e| (e - mean_err).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    let mean_y = y.iter().sum::<f64>() / n;
    let norm_dev = y.iter().map(|v| (v - mean_y).powi(2)).sum::<f64>().sqrt();
    let norm_err = err.iter().map(|e| e * e).sum::<f64>().sqrt();
    let pct: Vec<f64> = err.iter().zip(y).map(|(e, v)| e / v).collect();
    Ok(Metrics {
        rmspe_pct: 100.0 * (pct.iter().map(|p| p * p).sum::<f64>() / n).sqrt(),
        mape_pct: 100.0 * pct.iter().map(|p| p.abs()).sum::<f64>() / n,
        se: var_err.sqrt() / n.sqrt(),
        fit_pct: if norm_dev > 0.0 { 100.0 * (1.0 - norm_err / norm_dev) } else { f64::NAN },
        rmse: (norm_err * norm_err / n).sqrt(),
        max_abs_error: err.iter().fold(0.0f64, |m, e| m.max(e.abs())),
        n: y.len(),
    })
}

/// Box-plot statistics (Tukey whiskers at 1.5 IQR) of the percentage error 100·(y − ŷ)/y.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BoxStats {
    pub min: f64,
    pub q1: f64,
    pub median: f64,
    pub q3: f64,
    pub max: f64,
    pub whisker_lo: f64,
    pub whisker_hi: f64,
    pub outliers: usize,
}

pub fn percentage_error_box(y: &[f64], yhat: &[f64]) -> Result<BoxStats, MetricsError> {
    check(y, yhat)?;
    let mut pct: Vec<f64> = y.iter().zip(yhat).map(|(a, b)| 100.0 * (a - b) / a).collect();
    pct.sort_by(f64::total_cmp);
    let q = |p: f64| {
        let pos = p * (pct.len() - 1) as f64;
        let (i, frac) = (pos.floor() as usize, pos - pos.floor());
        let next = pct.get(i + 1).copied().unwrap_or(pct[i]);
        pct[i] + frac * (next - pct[i])
    };
    let (q1, median, q3) = (q(0.25), q(0.5), q(0.75));
    let iqr = q3 - q1;
    let (lo_fence, hi_fence) = (q1 - 1.5 * iqr, q3 + 1.5 * iqr);
    let inside: Vec<f64> = pct.iter().copied().filter(|p| *p >= lo_fence && *p <= hi_fence).collect();
    Ok(BoxStats {
        min: pct[0],
        q1,
        median,
        q3,
        max: pct[pct.len() - 1],
        whisker_lo: inside.first().copied().unwrap_or(q1),
        whisker_hi: inside.last().copied().unwrap_or(q3),
        outliers: pct.len() - inside.len(),
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn hand_computed_values() {
        let y = [100.0, 200.0, 100.0, 200.0];
        let yhat = [110.0, 190.0, 100.0, 200.0];
        let m = metrics(&y, &yhat).unwrap();
        // pct errors: -0.1, 0.05, 0, 0 → rmspe = 100·sqrt((0.01 + 0.0025)/4)
        assert!((m.rmspe_pct - 100.0 * (0.0125f64 / 4.0).sqrt()).abs() < 1e-12);
        assert!((m.mape_pct - 100.0 * 0.15 / 4.0).abs() < 1e-12);
        assert!((m.rmse - (200.0f64 / 4.0).sqrt()).abs() < 1e-12);
        assert!((m.max_abs_error - 10.0).abs() < 1e-12);
        assert!((m.fit_pct - 100.0 * (1.0 - 200.0f64.sqrt() / 100.0)).abs() < 1e-9);
        let perfect = metrics(&y, &y).unwrap();
        assert!(perfect.rmspe_pct.abs() < 1e-15 && (perfect.fit_pct - 100.0).abs() < 1e-12);
    }

    #[test]
    fn box_stats_order() {
        let y: Vec<f64> = (1..=101).map(|i| i as f64).collect();
        let yhat: Vec<f64> = y.iter().map(|v| v * 0.99).collect();
        let b = percentage_error_box(&y, &yhat).unwrap();
        assert!((b.median - 1.0).abs() < 1e-9 && b.outliers == 0);
    }

    #[test]
    fn errors() {
        assert_eq!(metrics(&[1.0], &[1.0, 2.0]), Err(MetricsError::LengthMismatch { y: 1, yhat: 2 }));
        assert_eq!(metrics(&[], &[]), Err(MetricsError::Empty));
        assert_eq!(metrics(&[1.0, 0.0], &[1.0, 0.0]), Err(MetricsError::ZeroMeasurement { index: 1 }));
        assert_eq!(metrics(&[1.0], &[f64::NAN]), Err(MetricsError::NonFinite { index: 0 }));
    }
}
