//! Input dropouts: short dips of the measured input that the engine does not follow.
//!
//! A flow meter (or any input sensor) may read a dip for a second or two while the fuel actually
//! burnt does not change. A model driven by that reading then predicts a dip of the output that the
//! measurement never shows, and the residual spikes there. Blaming a missing physical effect for
//! those spikes would be wrong: the input channel is at fault. The test compares, over every
//! dropout, the output's excursion from its local level with the excursion the model predicts
//! from the same dips (least squares over the dropouts, so large dips weigh most).
use serde::{Deserialize, Serialize};

use crate::core::numerics::stats::{quantile, sigma_from_first_differences};

/// A dropout lasts at most this long, s: sensor dropouts last 1–3 s; a real fuel change is held
/// longer than a controller's hold (several seconds), so the local level follows it.
pub const MAX_DROPOUT_S: f64 = 3.0;
/// A dip counts when it leaves the local level by more than this share of the input's range
/// (1st to 99th percentile) …
pub const MIN_DEPTH_SHARE: f64 = 0.05;
/// … and by more than this many noise σ of the input (from its first differences).
pub const MIN_DEPTH_SIGMAS: f64 = 6.0;
/// After a dip the output is watched this much longer, s (the spool's lag: a small gas generator
/// answers within a second).
pub const WATCH_AFTER_S: f64 = 1.0;
/// The output does not follow when it shows less than this share of the excursion the model
/// predicts (a real fuel dip would move it by most of it; a lag of the engine longer than the dip
/// would already shrink the model's own prediction, which is what the ratio is taken against).
pub const FOLLOW_SHARE: f64 = 0.3;
/// Fewer dropouts than this are too few to tell a sensor from chance.
pub const MIN_DROPOUTS: usize = 3;

/// What the dropout test found on one run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InputDropouts {
    /// Name of the input channel.
    pub input: String,
    /// Dips found.
    pub count: usize,
    /// The longest dip, s.
    pub longest_secs: f64,
    /// The deepest dip, as a share of the input's range, %.
    pub deepest_pct: f64,
    /// The share of the model's predicted excursion that the measured output shows, %.
    pub output_follows_pct: f64,
    /// The share of the squared residual inside the dips (and the watch time after them), %.
    pub residual_share_pct: f64,
    /// Whether the input sensor reads dips the engine does not see.
    pub sensor_dropouts: bool,
}

/// Dips of `u` that return within [`MAX_DROPOUT_S`], and how the output `y` and the model's `y_hat`
/// move over them; `None` when there are none or the model predicts no visible excursion.
pub fn input_dropouts(
    input: &str,
    u: &[f64],
    y: &[f64],
    y_hat: &[f64],
    residual: &[f64],
    dt_secs: f64,
    output_sigma: f64,
) -> Option<InputDropouts> {
    let n = u.len();
    if n < 8 || y.len() != n || y_hat.len() != n || dt_secs.is_nan() || dt_secs <= 0.0 {
        return None;
    }
    let half = (MAX_DROPOUT_S / dt_secs).ceil() as usize + 1;
    let level = running_median(u, half);
    let (lo, hi) = (quantile(u, 0.01), quantile(u, 0.99));
    let sigma_u = sigma_from_first_differences(u);
    let depth = (MIN_DEPTH_SHARE * (hi - lo)).max(MIN_DEPTH_SIGMAS * sigma_u);
    if depth <= 0.0 {
        return None;
    }
    let max_len = (MAX_DROPOUT_S / dt_secs).round() as usize;
    let watch = (WATCH_AFTER_S / dt_secs).round() as usize;
    let away: Vec<bool> = u.iter().zip(&level).map(|(v, l)| (v - l).abs() > depth).collect();
    let dips: Vec<(usize, usize)> = stretches(&away).into_iter().filter(|(a, b)| b - a <= max_len).collect();
    if dips.is_empty() {
        return None;
    }
    let (mut cross, mut predicted_sq, mut inside_sq) = (0.0, 0.0, 0.0);
    let mut covered = vec![false; n];
    for &(a, b) in &dips {
        let end = (b + watch).min(n);
        // The outputs' local levels are needed over the dips only, not along the whole run.
        let excursion = |x: &[f64]| -> f64 {
            let level = running_median_over(x, half, a..end);
            let xs = x.get(a..end).unwrap_or_default();
            xs.iter().zip(&level).map(|(v, l)| v - l).sum::<f64>() / (end - a).max(1) as f64
        };
        let (measured, predicted) = (excursion(y), excursion(y_hat));
        cross += measured * predicted;
        predicted_sq += predicted * predicted;
        for c in covered.get_mut(a..end).into_iter().flatten() {
            *c = true;
        }
    }
    // The model must predict excursions well above the output's noise, else nothing can be told.
    let rms_predicted = (predicted_sq / dips.len() as f64).sqrt();
    if rms_predicted.is_nan() || rms_predicted <= 3.0 * output_sigma {
        return None;
    }
    let total_sq: f64 = residual.iter().map(|r| r * r).sum();
    for (r, _) in residual.iter().zip(&covered).filter(|(_, c)| **c) {
        inside_sq += r * r;
    }
    let follows = cross / predicted_sq;
    let deepest = dips
        .iter()
        .flat_map(|&(a, b)| u.get(a..b).unwrap_or_default().iter().zip(level.get(a..b).unwrap_or_default()))
        .map(|(v, l)| (v - l).abs())
        .fold(0.0, f64::max);
    let longest = dips.iter().map(|(a, b)| b - a).max().unwrap_or(0);
    Some(InputDropouts {
        input: input.to_owned(),
        count: dips.len(),
        longest_secs: longest as f64 * dt_secs,
        deepest_pct: 100.0 * deepest / (hi - lo).max(f64::MIN_POSITIVE),
        output_follows_pct: 100.0 * follows,
        residual_share_pct: if total_sq > 0.0 { 100.0 * inside_sq / total_sq } else { 0.0 },
        sensor_dropouts: dips.len() >= MIN_DROPOUTS && follows < FOLLOW_SHARE,
    })
}

/// Maximal runs of `true`, as `[start, end)`.
fn stretches(flags: &[bool]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = None;
    for (k, &f) in flags.iter().enumerate() {
        match (f, start) {
            (true, None) => start = Some(k),
            (false, Some(s)) => {
                out.push((s, k));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push((s, flags.len()));
    }
    out
}

/// The median of `x` over `k − half ..= k + half` (clipped at the ends), for every `k`.
fn running_median(x: &[f64], half: usize) -> Vec<f64> {
    running_median_over(x, half, 0..x.len())
}

/// [`running_median`] for the samples `at` only.
fn running_median_over(x: &[f64], half: usize, at: std::ops::Range<usize>) -> Vec<f64> {
    let mut window = Vec::with_capacity(2 * half + 1);
    at.map(|k| {
        window.clear();
        window.extend_from_slice(
            x.get(k.saturating_sub(half)..(k + half + 1).min(x.len())).unwrap_or_default(),
        );
        window.sort_by(f64::total_cmp);
        window.get(window.len() / 2).copied().unwrap_or(0.0)
    })
    .collect()
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::indexing_slicing)]
    use super::*;

    /// A ramped input with four 1.5-s dips; `seen` is how much of each dip the engine burns.
    fn case(seen: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let dt = 0.1;
        let n = 3000;
        let mut read = Vec::with_capacity(n);
        let mut burnt = Vec::with_capacity(n);
        for k in 0..n {
            let base = 0.3 + 0.2 * k as f64 / n as f64;
            let dip = [500, 1100, 1700, 2300].iter().any(|&s| (s..s + 15).contains(&k));
            read.push(if dip { base - 0.1 } else { base });
            burnt.push(if dip { base - 0.1 * seen } else { base });
        }
        // Output: a fast first-order response (τ 0.5 s) to fuel, gain 6; model from the reading.
        let lag = |x: &[f64]| {
            let a = (-dt / 0.5f64).exp();
            let mut s = 6.0 * x[0];
            x.iter()
                .map(|v| {
                    s = a * s + (1.0 - a) * 6.0 * v;
                    s
                })
                .collect::<Vec<f64>>()
        };
        (read.clone(), lag(&burnt), lag(&read))
    }

    #[test]
    fn dips_the_engine_does_not_see_are_blamed_on_the_sensor() {
        let (u, y, y_hat) = case(0.0);
        let r: Vec<f64> = y.iter().zip(&y_hat).map(|(a, b)| a - b).collect();
        let d = input_dropouts("fuel", &u, &y, &y_hat, &r, 0.1, 1e-3).unwrap();
        assert_eq!(d.count, 4, "{d:?}");
        assert!(d.sensor_dropouts && d.output_follows_pct.abs() < 5.0, "{d:?}");
        assert!(d.residual_share_pct > 90.0, "{d:?}");
    }

    #[test]
    fn dips_the_engine_follows_are_not_blamed_on_the_sensor() {
        let (u, y, y_hat) = case(1.0);
        let r: Vec<f64> = y.iter().zip(&y_hat).map(|(a, b)| a - b).collect();
        let d = input_dropouts("fuel", &u, &y, &y_hat, &r, 0.1, 1e-3).unwrap();
        assert!(!d.sensor_dropouts && d.output_follows_pct > 95.0, "{d:?}");
    }

    #[test]
    fn a_steady_input_has_no_dropouts() {
        let u: Vec<f64> = (0..500).map(|k| if k < 250 { 0.3 } else { 0.4 }).collect();
        let y: Vec<f64> = u.iter().map(|v| 6.0 * v).collect();
        assert_eq!(input_dropouts("fuel", &u, &y, &y, &vec![0.0; 500], 0.1, 1e-3), None);
    }
}
