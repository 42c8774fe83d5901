//! The input pinned at its limit: a stretch of a run where the logged input sits at its maximum
//! (within its resolution). A pump or valve at its limit while the output falls short of what the
//! engine gives with less input is a supply fault (a filter, a pump, air in the line): the
//! controller asks for everything the actuator has and the engine still does not get the fuel.
//! Here only the stretches are found; the fleet compares the output over them with the reference.

/// A stretch of samples where the input sits at its limit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pinned {
    /// The input's limit (its maximum on the run).
    pub limit: f64,
    pub start: usize,
    /// Samples in the stretch.
    pub len: usize,
}

impl Pinned {
    pub fn end(&self) -> usize {
        self.start + self.len
    }
}

/// The input's resolution: the smallest step between its distinct values (a logger's quantum, e.g.
/// 0.01 V), or, for a continuous signal whose every value differs, a millionth of its range (the
/// relative precision a logged decimal keeps). `None` for an empty or constant input.
pub fn resolution(u: &[f64]) -> Option<f64> {
    let mut sorted: Vec<f64> = u.iter().copied().filter(|v| v.is_finite()).collect();
    sorted.sort_by(f64::total_cmp);
    let range = sorted.last()? - sorted.first()?;
    if range <= 0.0 {
        return None;
    }
    let floor = 1e-6 * range;
    let step = sorted.windows(2).map(|w| w[1] - w[0]).filter(|d| *d > floor).fold(f64::INFINITY, f64::min);
    Some(if step.is_finite() { step.max(floor) } else { floor })
}

/// The stretches of at least `min_samples` consecutive samples at the input's maximum (within half
/// its resolution), in order. An input that never changes has no limit to be pinned at.
pub fn pinned_stretches(u: &[f64], min_samples: usize) -> Vec<Pinned> {
    let Some(step) = resolution(u) else { return Vec::new() };
    let limit = u.iter().copied().filter(|v| v.is_finite()).fold(f64::NEG_INFINITY, f64::max);
    let at_limit = |v: f64| v >= limit - 0.5 * step;
    let mut found = Vec::new();
    let mut start = None;
    for (k, &v) in u.iter().chain(std::iter::once(&f64::NEG_INFINITY)).enumerate() {
        match (at_limit(v), start) {
            (true, None) => start = Some(k),
            (false, Some(s)) => {
                if k - s >= min_samples.max(2) {
                    found.push(Pinned { limit, start: s, len: k - s });
                }
                start = None;
            }
            _ => {}
        }
    }
    found
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn finds_a_quantised_pump_at_its_limit() {
        let mut u: Vec<f64> = (0..100).map(|k| 3.0 + 0.01 * ((k % 7) as f64)).collect();
        u.extend(std::iter::repeat_n(7.09, 40));
        u.extend((0..50).map(|k| 4.5 + 0.01 * ((k % 3) as f64)));
        assert!((resolution(&u).unwrap() - 0.01).abs() < 1e-9);
        let found = pinned_stretches(&u, 20);
        assert_eq!(found, vec![Pinned { limit: 7.09, start: 100, len: 40 }]);
        assert!(pinned_stretches(&u, 41).is_empty());
    }

    #[test]
    fn a_noisy_input_is_never_pinned() {
        let u: Vec<f64> = (0..500).map(|k| 5.0 + 0.003 * ((k as f64 * 1.3).sin())).collect();
        assert!(pinned_stretches(&u, 5).is_empty());
        assert!(pinned_stretches(&[2.0; 50], 5).is_empty());
    }
}
