//! Step segments of an identification run.
//!
//! Steps are found on the input as peaks of the difference between the mean of the next and the
//! previous second of samples, above a threshold that scales with both the input's noise (median
//! absolute first difference) and its range. Each step gets a segment that starts a short baseline
//! before the step (its starting steady state) and ends a baseline before the next step. Everything
//! before the first step is warm-up and is not a segment.
use serde::{Deserialize, Serialize};

/// One step segment: samples `start..end`; the starting steady state is `start..step_at`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Segment {
    pub label: String,
    pub start: usize,
    pub step_at: usize,
    pub end: usize,
}

impl Segment {
    pub fn len(&self) -> usize {
        self.end.saturating_sub(self.start)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The settled tail of the segment (its last `tail` samples, at most half the segment).
    pub fn settled_tail(&self, tail: usize) -> (usize, usize) {
        let tail = tail.min((self.end - self.step_at) / 2).max(1);
        (self.end.saturating_sub(tail), self.end)
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SegmentSettings {
    /// Smallest input change counted as a step, in input units (None: from noise and range).
    pub min_step: Option<f64>,
    /// Steps closer than this are merged (the larger one kept).
    pub min_hold_secs: f64,
    /// Length of the pre-step baseline that defines a segment's starting steady state.
    pub baseline_secs: f64,
}

impl Default for SegmentSettings {
    fn default() -> Self {
        Self { min_step: None, min_hold_secs: 8.0, baseline_secs: 3.0 }
    }
}

/// `x` with four significant digits, however small or large it is (`0.0004213`, `4.213e-7`).
fn significant(x: f64) -> String {
    crate::core::numerics::stats::significant(x, 4)
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SegmentError {
    #[error(
        "no steps found in the input (largest change {} is below the threshold {}); give segments by hand",
        significant(*largest),
        significant(*threshold)
    )]
    NoSteps { largest: f64, threshold: f64 },
    /// The input holds one value: there is nothing to identify from.
    #[error(
        "the input never changes (it holds {} throughout): record steps of the input, each held until the engine settles",
        significant(*value)
    )]
    ConstantInput { value: f64 },
    #[error("the run has {samples} samples, too few to segment")]
    TooShort { samples: usize },
    #[error("segment {label}: bounds {start}..{step_at}..{end} are not ordered inside 0..{samples}")]
    BadBounds { label: String, start: usize, step_at: usize, end: usize, samples: usize },
    #[error("segment settings are invalid: {reason}")]
    BadSettings { reason: String },
}

/// Label number `i`: A, B, …, Z, AA, AB, …
pub fn segment_label(i: usize) -> String {
    let letter = |k: usize| char::from(b'A' + (k % 26) as u8);
    if i < 26 { letter(i).to_string() } else { format!("{}{}", letter(i / 26 - 1), letter(i % 26)) }
}

/// Sample indices where the input steps (the first sample at the new level), sorted.
///
/// Steps are looked for as changes between the means of the previous and the next second. When
/// there are none, the input may still move between holds by ramps (a closed-loop engine follows a
/// ramped set-point): a ramp of rate r changes one-second means by only r·1 s, but means of half the
/// minimum hold apart by r·(hold/2), so the same threshold is tried again at that scale. A ramp is
/// then a step at the start of the ramp (where the half-hold means first differ by the threshold),
/// and its segment holds the ramp and the hold after it; ramps closer than a hold merge into one.
pub fn detect_steps(u: &[f64], dt_secs: f64, settings: &SegmentSettings) -> Result<Vec<usize>, SegmentError> {
    if let Some(&first) = u.first()
        && u.len() >= 2
        && u.iter().all(|v| v.to_bits() == first.to_bits())
    {
        return Err(SegmentError::ConstantInput { value: first });
    }
    let w = ((1.0 / dt_secs).round() as usize).max(3);
    match steps_at_scale(u, w, dt_secs, settings, Landmark::LargestJump) {
        Err(SegmentError::NoSteps { largest, threshold }) => {
            let w_ramp = ((0.5 * settings.min_hold_secs / dt_secs).round() as usize).max(w);
            match steps_at_scale(u, w_ramp, dt_secs, settings, Landmark::FirstAboveThreshold) {
                Ok(steps) if w_ramp > w => Ok(steps),
                // The first scale's figures say what a user can act on (the size of a step).
                _ => Err(SegmentError::NoSteps { largest, threshold }),
            }
        }
        found => found,
    }
}

/// Where in a stretch of large mean differences a step is placed.
#[derive(Clone, Copy)]
enum Landmark {
    /// At the largest single-sample jump: the edge of a step.
    LargestJump,
    /// Where the means first differ by the threshold: the start of a ramp.
    FirstAboveThreshold,
}

fn steps_at_scale(
    u: &[f64],
    w: usize,
    dt_secs: f64,
    settings: &SegmentSettings,
    landmark: Landmark,
) -> Result<Vec<usize>, SegmentError> {
    if u.len() < 4 * w {
        return Err(SegmentError::TooShort { samples: u.len() });
    }
    let (threshold, _) = step_threshold(u, w, settings);
    let mut prefix = Vec::with_capacity(u.len() + 1);
    prefix.push(0.0);
    for v in u {
        prefix.push(prefix.last().copied().unwrap_or(0.0) + v);
    }
    let mean = |a: usize, b: usize| (prefix[b] - prefix[a]) / (b - a) as f64;
    let diff: Vec<f64> = (w..=u.len() - w).map(|k| mean(k, k + w) - mean(k - w, k)).collect();
    let largest = diff.iter().fold(0.0f64, |m, d| m.max(d.abs()));
    // Runs above threshold → one step each, at the largest single-sample jump inside the run.
    let mut steps: Vec<(usize, f64)> = Vec::new();
    let mut k = 0;
    while k < diff.len() {
        if diff[k].abs() <= threshold {
            k += 1;
            continue;
        }
        let run_start = k;
        while k < diff.len() && diff[k].abs() > threshold {
            k += 1;
        }
        let (lo, hi) = (run_start + w, (k + w).min(u.len() - 1));
        let at = match landmark {
            Landmark::LargestJump => (lo.max(1)..=hi)
                .max_by(|&a, &b| (u[a] - u[a - 1]).abs().total_cmp(&(u[b] - u[b - 1]).abs()))
                .unwrap_or(lo),
            Landmark::FirstAboveThreshold => lo.min(u.len() - 1),
        };
        let size = diff[run_start..k].iter().fold(0.0f64, |m, d| m.max(d.abs()));
        steps.push((at, size));
    }
    if steps.is_empty() {
        return Err(SegmentError::NoSteps { largest, threshold });
    }
    let min_gap = (settings.min_hold_secs / dt_secs).round() as usize;
    let mut merged: Vec<(usize, f64)> = Vec::new();
    for step in steps {
        match merged.last_mut() {
            Some(last) if step.0 - last.0 < min_gap => {
                if step.1 > last.1 {
                    *last = step;
                }
            }
            _ => merged.push(step),
        }
    }
    Ok(merged.into_iter().map(|(at, _)| at).collect())
}

fn step_threshold(u: &[f64], w: usize, settings: &SegmentSettings) -> (f64, f64) {
    let sigma = crate::core::numerics::stats::sigma_from_first_differences(u);
    let (lo, hi) = u.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
    let noise_floor = 10.0 * sigma * (2.0 / w as f64).sqrt();
    // Rounding in the running means is ~ε·|u|: never count that as a step, even on a noiseless input.
    let rounding_floor = 1e-9 * lo.abs().max(hi.abs()).max(f64::MIN_POSITIVE);
    let noise_floor = noise_floor.max(rounding_floor);
    let auto = noise_floor.max(0.02 * (hi - lo));
    (settings.min_step.map_or(auto, |m| m.max(noise_floor)), sigma)
}

/// Segments for the given step indices: baseline before each step, end a baseline before the next.
pub fn segments_from_steps(
    steps: &[usize],
    n_samples: usize,
    dt_secs: f64,
    settings: &SegmentSettings,
) -> Vec<Segment> {
    let baseline = ((settings.baseline_secs / dt_secs).round() as usize).max(2);
    steps
        .iter()
        .enumerate()
        .map(|(i, &at)| {
            let start = at.saturating_sub(baseline);
            let end = steps.get(i + 1).map_or(n_samples, |next| next.saturating_sub(baseline).max(at + 1));
            Segment { label: segment_label(i), start, step_at: at, end }
        })
        .collect()
}

/// Detect steps and build their segments.
pub fn auto_segments(
    u: &[f64],
    dt_secs: f64,
    settings: &SegmentSettings,
) -> Result<Vec<Segment>, SegmentError> {
    if !(settings.min_hold_secs >= 0.0 && settings.baseline_secs > 0.0) {
        return Err(SegmentError::BadSettings {
            reason: "min_hold_secs ≥ 0 and baseline_secs > 0 are required".into(),
        });
    }
    let steps = detect_steps(u, dt_secs, settings)?;
    Ok(segments_from_steps(&steps, u.len(), dt_secs, settings))
}

/// Segments of a run made of parts joined end to end (`core::run::join_runs`): each part
/// `[junctions[i-1], junctions[i])` is segmented on its own, so no segment straddles a join, and the
/// labels run on (A, B, … across all parts). `step_signal` is the signal steps are detected on: the
/// input, or e.g. a set-point channel when the input is a controller's output.
pub fn auto_segments_joined(
    step_signal: &[f64],
    junctions: &[usize],
    dt_secs: f64,
    settings: &SegmentSettings,
) -> Result<Vec<Segment>, SegmentError> {
    let mut bounds = vec![0];
    bounds.extend(junctions.iter().copied().filter(|&j| j > 0 && j < step_signal.len()));
    bounds.push(step_signal.len());
    let mut all = Vec::new();
    for pair in bounds.windows(2) {
        let &[a, b] = pair else { continue };
        let Some(part) = step_signal.get(a..b) else { continue };
        for seg in auto_segments(part, dt_secs, settings)? {
            all.push(Segment {
                label: segment_label(all.len()),
                start: seg.start + a,
                step_at: seg.step_at + a,
                end: seg.end + a,
            });
        }
    }
    Ok(all)
}

/// Check user-given segments against the run length.
pub fn check_segments(segments: &[Segment], n_samples: usize) -> Result<(), SegmentError> {
    for s in segments {
        if !(s.start < s.step_at && s.step_at < s.end && s.end <= n_samples) {
            return Err(SegmentError::BadBounds {
                label: s.label.clone(),
                start: s.start,
                step_at: s.step_at,
                end: s.end,
                samples: n_samples,
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    #[test]
    fn joined_parts_are_segmented_apart() {
        let (a, steps_a) = staircase(&[(2.0, 300), (4.0, 300), (3.0, 300)], 0.003, 1);
        let (b, steps_b) = staircase(&[(2.5, 300), (5.0, 300)], 0.003, 2);
        let mut u = a.clone();
        u.extend(&b);
        let segs = auto_segments_joined(&u, &[a.len()], 0.113, &SegmentSettings::default()).unwrap();
        let steps: Vec<usize> = segs.iter().map(|s| s.step_at).collect();
        let mut expected = steps_a.clone();
        expected.extend(steps_b.iter().map(|s| s + a.len()));
        assert_eq!(steps.len(), expected.len(), "{steps:?} vs {expected:?}");
        for (got, want) in steps.iter().zip(&expected) {
            assert!(got.abs_diff(*want) <= 2, "{steps:?} vs {expected:?}");
        }
        assert!(segs.iter().all(|s| s.end <= a.len() || s.start >= a.len()), "no segment straddles the join");
        assert_eq!(segs.last().unwrap().label, segment_label(expected.len() - 1));
    }

    fn staircase(levels: &[(f64, usize)], noise: f64, seed: u64) -> (Vec<f64>, Vec<usize>) {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let normal = Normal::new(0.0, noise).unwrap();
        let (mut u, mut steps) = (Vec::new(), Vec::new());
        for (i, &(level, len)) in levels.iter().enumerate() {
            if i > 0 {
                steps.push(u.len());
            }
            u.extend((0..len).map(|_| level + normal.sample(&mut rng)));
        }
        (u, steps)
    }

    #[test]
    fn finds_every_step_of_a_noisy_staircase() {
        for seed in 0..5 {
            let (u, truth) = staircase(
                &[(2.5, 400), (3.2, 300), (2.9, 300), (4.5, 350), (5.4, 300), (3.0, 300)],
                0.00327,
                seed,
            );
            let steps = detect_steps(&u, 1.0 / 8.85, &SegmentSettings::default()).unwrap();
            assert_eq!(steps, truth, "seed {seed}");
            let segs = segments_from_steps(&steps, u.len(), 1.0 / 8.85, &SegmentSettings::default());
            assert_eq!(segs.len(), 5);
            assert_eq!(segs[0].label, "A");
            assert!(segs[0].start < segs[0].step_at && segs[4].end == u.len());
            check_segments(&segs, u.len()).unwrap();
        }
    }

    #[test]
    fn ramps_between_holds_are_steps_at_the_ramp_starts() {
        // Holds joined by ramps of 0.2 /s (a closed loop following a ramped set-point): no
        // one-second change reaches the step threshold, but each ramp moves the level by 5–10 %.
        let dt = 0.143;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let normal = Normal::new(0.0, 0.02).unwrap();
        let plan = [(56.0, 40.0), (62.0, 30.0), (60.5, 35.0), (65.0, 30.0), (72.0, 40.0)];
        let (mut u, mut starts) = (Vec::new(), Vec::new());
        let mut level: f64 = plan[0].0;
        for &(target, hold_s) in &plan {
            if (target - level).abs() > 1e-9 {
                starts.push(u.len());
                let n_ramp = ((target - level).abs() / 0.2 / dt).round() as usize;
                for i in 1..=n_ramp {
                    u.push(level + (target - level) * i as f64 / n_ramp as f64 + normal.sample(&mut rng));
                }
                level = target;
            }
            u.extend((0..(hold_s / dt) as usize).map(|_| level + normal.sample(&mut rng)));
        }
        let one_second = steps_at_scale(&u, 7, dt, &SegmentSettings::default(), Landmark::LargestJump);
        assert!(matches!(one_second, Err(SegmentError::NoSteps { .. })), "the ramps are no 1-s steps");
        let steps = detect_steps(&u, dt, &SegmentSettings::default()).unwrap();
        assert_eq!(steps.len(), starts.len(), "{steps:?} vs ramp starts {starts:?}");
        let half_hold = (4.0 / dt) as usize;
        for (got, start) in steps.iter().zip(&starts) {
            assert!(got.abs_diff(*start) <= half_hold, "{steps:?} vs ramp starts {starts:?}");
        }
    }

    #[test]
    fn flat_input_has_no_steps() {
        let (u, _) = staircase(&[(5.43, 500)], 0.00327, 1);
        assert!(matches!(
            detect_steps(&u, 0.113, &SegmentSettings::default()),
            Err(SegmentError::NoSteps { .. })
        ));
        assert!(matches!(
            detect_steps(&u[..10], 0.113, &SegmentSettings::default()),
            Err(SegmentError::TooShort { .. })
        ));
    }

    #[test]
    fn noiseless_flat_input_has_no_steps() {
        let u = vec![5.43; 400];
        let err = detect_steps(&u, 0.113, &SegmentSettings::default()).unwrap_err();
        assert!(matches!(err, SegmentError::ConstantInput { .. }), "{err}");
        assert!(err.to_string().contains("never changes") && err.to_string().contains("5.43"), "{err}");
    }

    #[test]
    fn labels_continue_past_z() {
        assert_eq!(segment_label(0), "A");
        assert_eq!(segment_label(25), "Z");
        assert_eq!(segment_label(26), "AA");
    }

    #[test]
    fn bad_user_bounds_are_errors() {
        let s = Segment { label: "A".into(), start: 10, step_at: 5, end: 20 };
        assert!(matches!(check_segments(&[s], 100), Err(SegmentError::BadBounds { .. })));
    }
}
