//! The worst stretches of a run: non-overlapping windows with the largest residual RMS.
use serde::{Deserialize, Serialize};

use super::regimes::Motion;
use super::signal::{prefix_sums, window_sum};

/// One window of the run where the model does worst.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stretch {
    /// First sample of the window.
    pub start_sample: usize,
    /// One past the last sample of the window.
    pub end_sample: usize,
    /// Time of the first sample, s.
    pub start_secs: f64,
    /// Time of the last sample, s.
    pub end_secs: f64,
    /// Residual RMS over the window, output unit.
    pub rms: f64,
    /// Mean residual over the window, output unit.
    pub mean_error: f64,
    /// The motion most samples of the window share.
    pub motion: Motion,
}

/// The `count` non-overlapping windows of `window` samples with the largest residual RMS, worst
/// first (greedy: take the worst window, drop every window overlapping it, repeat).
pub(super) fn worst_stretches(
    residual: &[f64],
    t_secs: &[f64],
    motion: &[Motion],
    window: usize,
    count: usize,
) -> Vec<Stretch> {
    let n = residual.len();
    let w = window.clamp(1, n.max(1));
    let sq = prefix_sums(residual.iter().map(|r| r * r));
    let sum = prefix_sums(residual.iter().copied());
    let mut starts: Vec<(usize, f64)> =
        (0..=n.saturating_sub(w)).map(|s| (s, window_sum(&sq, s, s + w))).collect();
    starts.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    let mut chosen: Vec<usize> = Vec::new();
    for (s, _) in starts {
        if chosen.len() >= count {
            break;
        }
        if chosen.iter().all(|c| s + w <= *c || c + w <= s) {
            chosen.push(s);
        }
    }
    chosen
        .into_iter()
        .map(|s| {
            let e = (s + w).min(n);
            let len = (e - s).max(1) as f64;
            Stretch {
                start_sample: s,
                end_sample: e,
                start_secs: t_secs.get(s).copied().unwrap_or(0.0),
                end_secs: t_secs.get(e.saturating_sub(1)).copied().unwrap_or(0.0),
                rms: (window_sum(&sq, s, e) / len).sqrt(),
                mean_error: window_sum(&sum, s, e) / len,
                motion: dominant_motion(motion.get(s..e).unwrap_or_default()),
            }
        })
        .collect()
}

fn dominant_motion(motion: &[Motion]) -> Motion {
    let count = |m: Motion| motion.iter().filter(|x| **x == m).count();
    [Motion::Steady, Motion::Accelerating, Motion::Decelerating]
        .into_iter()
        .max_by_key(|m| count(*m))
        .unwrap_or(Motion::Steady)
}
