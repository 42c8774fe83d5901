//! Sample-level numerics of loading: gap filling, time-axis checks and resampling.

/// Replace NaN entries by linear interpolation (by sample index) between the nearest finite
/// neighbours; NaN at either end takes the nearest finite value. An all-NaN slice is left alone.
pub(super) fn fill_gaps(values: &mut [f64]) {
    let n = values.len();
    let mut prev: Option<usize> = None;
    let mut i = 0;
    while i < n {
        if values.get(i).is_some_and(|v| v.is_finite()) {
            prev = Some(i);
            i += 1;
            continue;
        }
        let next = (i..n).find(|&j| values.get(j).is_some_and(|v| v.is_finite()));
        let left = prev.and_then(|p| values.get(p).map(|&v| (p, v)));
        let right = next.and_then(|q| values.get(q).map(|&v| (q, v)));
        let end = next.unwrap_or(n);
        for k in i..end {
            let value = match (left, right) {
                (Some((p, vp)), Some((q, vq))) => vp + (vq - vp) * (k - p) as f64 / (q - p) as f64,
                (Some((_, v)), None) | (None, Some((_, v))) => v,
                (None, None) => return,
            };
            if let Some(slot) = values.get_mut(k) {
                *slot = value;
            }
        }
        i = end;
    }
}

/// Consecutive pairs `(t[k-1], t[k])`.
fn pairs(t: &[f64]) -> impl Iterator<Item = (f64, f64)> + '_ {
    t.windows(2).filter_map(|w| match w {
        [a, b] => Some((*a, *b)),
        _ => None,
    })
}

/// The median of the steps of `t` (at least two samples), rounded to 12 significant digits to drop
/// the noise of floating-point differences (0.020000000000000018 → 0.02); 0 for fewer samples.
pub(super) fn median_step(t: &[f64]) -> f64 {
    let median = median_of_steps(t);
    format!("{median:.11e}").parse().unwrap_or(median)
}

fn median_of_steps(t: &[f64]) -> f64 {
    let mut steps: Vec<f64> = pairs(t).map(|(a, b)| b - a).collect();
    if steps.is_empty() {
        return 0.0;
    }
    steps.sort_by(f64::total_cmp);
    let mid = steps.len() / 2;
    match (steps.get(mid.wrapping_sub(1)), steps.get(mid)) {
        (Some(a), Some(b)) if steps.len().is_multiple_of(2) => 0.5 * (a + b),
        (_, Some(b)) => *b,
        _ => 0.0,
    }
}

/// What is wrong with a time axis; `k` is the index of the offending sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum TimeProblem {
    NonIncreasing { k: usize, previous: f64, value: f64 },
    NonUniform { k: usize, step: f64, expected: f64 },
}

impl TimeProblem {
    /// The index of the offending sample.
    pub(super) fn index(self) -> usize {
        match self {
            TimeProblem::NonIncreasing { k, .. } | TimeProblem::NonUniform { k, .. } => k,
        }
    }
}

/// Check that `t` strictly increases and that every step is within `tolerance` (relative) of the
/// median step, which is returned. A non-increasing time is reported before any non-uniform step.
pub(super) fn check_time(t: &[f64], tolerance: f64) -> Result<f64, TimeProblem> {
    for (k, (previous, value)) in pairs(t).enumerate() {
        if value <= previous || !value.is_finite() {
            return Err(TimeProblem::NonIncreasing { k: k + 1, previous, value });
        }
    }
    let dt = median_step(t);
    // A little headroom so that steps printed with rounded digits (0.106, 0.107) are not refused
    // for the last bits of floating-point noise.
    let limit = tolerance * dt * (1.0 + 1e-9);
    for (k, (previous, value)) in pairs(t).enumerate() {
        let step = value - previous;
        if (step - dt).abs() > limit {
            return Err(TimeProblem::NonUniform { k: k + 1, step, expected: dt });
        }
    }
    Ok(dt)
}

/// Merge samples that share a time stamp (a logger that writes several rows per tick): each run of
/// equal times becomes one sample whose channels are the mean of the run's. Returns how many rows
/// were merged away; `None` when the time goes back or is not finite somewhere (that is not a
/// repeat, and is left for [`check_time`] to report).
pub(super) fn merge_repeated_times(t: &mut Vec<f64>, channels: &mut [Vec<f64>]) -> Option<usize> {
    if pairs(t).any(|(previous, value)| value < previous || !value.is_finite()) {
        return None;
    }
    let mut groups: Vec<(usize, usize)> = Vec::new();
    let mut start = 0;
    for k in 1..=t.len() {
        if k == t.len() || t.get(k) != t.get(start) {
            groups.push((start, k));
            start = k;
        }
    }
    let merged = t.len() - groups.len();
    if merged == 0 {
        return Some(0);
    }
    let mean = |values: &[f64], (a, b): (usize, usize)| {
        let part = values.get(a..b).unwrap_or(&[]);
        part.iter().sum::<f64>() / part.len().max(1) as f64
    };
    *t = groups.iter().map(|&(a, _)| t.get(a).copied().unwrap_or(f64::NAN)).collect();
    for values in channels.iter_mut() {
        *values = groups.iter().map(|&g| mean(values, g)).collect();
    }
    Some(merged)
}

/// Resample every channel onto the uniform grid `t[0] + k·dt` (up to the last time) by linear
/// interpolation; `t` must strictly increase. Returns the new time axis.
pub(super) fn resample(t: &[f64], channels: &mut [Vec<f64>], dt_secs: f64) -> Vec<f64> {
    let (Some(&t0), Some(&t_end)) = (t.first(), t.last()) else {
        return Vec::new();
    };
    if !(dt_secs > 0.0 && dt_secs.is_finite()) {
        return t.to_vec();
    }
    let count = ((t_end - t0) / dt_secs + 1e-9).floor() as usize + 1;
    let grid: Vec<f64> = (0..count).map(|k| t0 + k as f64 * dt_secs).collect();
    // For each grid point: the segment [j, j+1] of `t` holding it and the weight of sample j+1.
    let mut weights = Vec::with_capacity(count);
    let mut j = 0;
    for &tk in &grid {
        while j + 2 < t.len() && t.get(j + 1).is_some_and(|&tn| tn <= tk) {
            j += 1;
        }
        let weight = match (t.get(j), t.get(j + 1)) {
            (Some(&ta), Some(&tb)) if tb > ta => ((tk - ta) / (tb - ta)).clamp(0.0, 1.0),
            _ => 0.0,
        };
        weights.push((j, weight));
    }
    for values in channels.iter_mut() {
        let resampled = weights
            .iter()
            .map(|&(j, w)| {
                let a = values.get(j).copied().unwrap_or(f64::NAN);
                let b = values.get(j + 1).copied().unwrap_or(a);
                a + (b - a) * w
            })
            .collect();
        *values = resampled;
    }
    grid
}

/// A sample further than this many times its channel's range (1st to 99th percentile) from the
/// median of its neighbours, and this many times larger in size than the channel's typical values,
/// cannot be a measurement: a real step moves a signal by at most its own range, while a corrupt
/// cell (1e308, a garbled exponent) is off by orders of magnitude. The size condition keeps a rare
/// real event of a two-level channel (a flag that drops to 0 once) from being taken for one.
pub(super) const OUTLIER_RANGES: f64 = 100.0;

/// Neighbours on each side whose median a sample is compared with.
const OUTLIER_HALF_WINDOW: usize = 3;

/// Turn every outlier of `values` (see [`OUTLIER_RANGES`]) into a gap; their indices and values.
pub(super) fn mark_outliers(values: &mut [f64]) -> Vec<(usize, f64)> {
    let mut sorted: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    if sorted.len() < 2 * OUTLIER_HALF_WINDOW + 1 {
        return Vec::new();
    }
    sorted.sort_by(f64::total_cmp);
    let at = |q: f64| sorted.get(((sorted.len() - 1) as f64 * q).round() as usize).copied().unwrap_or(0.0);
    let (p1, p50, p99) = (at(0.01), at(0.5), at(0.99));
    let range = (p99 - p1).max(1e-9 * p50.abs()).max(f64::MIN_POSITIVE);
    let limit = OUTLIER_RANGES * range;
    let size_limit = OUTLIER_RANGES * p1.abs().max(p99.abs()).max(f64::MIN_POSITIVE);
    let mut found = Vec::new();
    let mut neighbours = Vec::with_capacity(2 * OUTLIER_HALF_WINDOW);
    for k in 0..values.len() {
        let Some(&v) = values.get(k) else { continue };
        if !v.is_finite() {
            continue;
        }
        neighbours.clear();
        let lo = k.saturating_sub(OUTLIER_HALF_WINDOW);
        let hi = (k + OUTLIER_HALF_WINDOW + 1).min(values.len());
        neighbours.extend(
            (lo..hi).filter(|&j| j != k).filter_map(|j| values.get(j).copied()).filter(|x| x.is_finite()),
        );
        neighbours.sort_by(f64::total_cmp);
        let Some(&median) = neighbours.get(neighbours.len() / 2) else { continue };
        if (v - median).abs() > limit && v.abs() > size_limit {
            found.push((k, v));
        }
    }
    for &(k, _) in &found {
        if let Some(v) = values.get_mut(k) {
            *v = f64::NAN;
        }
    }
    if !found.is_empty() {
        fill_gaps(values);
    }
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaps_are_filled_linearly() {
        let mut v = [f64::NAN, 1.0, f64::NAN, f64::NAN, 4.0, f64::NAN];
        fill_gaps(&mut v);
        let expected = [1.0, 1.0, 2.0, 3.0, 4.0, 4.0];
        assert!(v.iter().zip(expected).all(|(a, b)| (a - b).abs() < 1e-12), "{v:?}");
    }

    #[test]
    fn median_of_steps() {
        assert!((median_step(&[0.0, 0.1, 0.2, 0.35, 0.45]) - 0.1).abs() < 1e-12);
        assert!((median_step(&[0.0, 1.0, 3.0]) - 1.5).abs() < 1e-12);
    }

    #[test]
    fn time_checks_name_the_first_offending_sample() {
        assert_eq!(
            check_time(&[0.0, 1.0, 2.0, 2.0, 3.0], 0.01),
            Err(TimeProblem::NonIncreasing { k: 3, previous: 2.0, value: 2.0 })
        );
        let Err(TimeProblem::NonUniform { k, .. }) = check_time(&[0.0, 1.0, 2.0, 3.5, 4.5], 0.01) else {
            panic!("expected a non-uniform step");
        };
        assert_eq!(k, 3);
        assert!(check_time(&[0.0, 0.106, 0.213, 0.319, 0.425], 0.01).is_ok());
        // Repeated stamps are merged into their mean; a time going back is not a repeat.
        let (mut t, mut ch) = (vec![0.0, 1.0, 1.0, 1.0, 2.0], vec![vec![0.0, 3.0, 4.0, 5.0, 6.0]]);
        assert_eq!(merge_repeated_times(&mut t, &mut ch), Some(2));
        assert_eq!((t, ch), (vec![0.0, 1.0, 2.0], vec![vec![0.0, 4.0, 6.0]]));
        assert_eq!(merge_repeated_times(&mut vec![0.0, 2.0, 1.0], &mut []), None);
    }

    #[test]
    fn resampling_a_line_keeps_the_line() {
        let t = [0.0, 0.9, 2.1, 3.0, 4.05];
        let mut ch = vec![t.iter().map(|x| 2.0 * x + 1.0).collect::<Vec<f64>>()];
        let grid = resample(&t, &mut ch, 1.0);
        assert_eq!(grid.len(), 5);
        for (tk, y) in grid.iter().zip(&ch[0]) {
            assert!((y - (2.0 * tk + 1.0)).abs() < 1e-12);
        }
    }
}
