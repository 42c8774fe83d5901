//! The test designs of METHOD.md (paper section 4.3) as fuel-flow command profiles.
//!
//! A profile is a list of segments, each a function of the time since it began; the command is a
//! continuous-time signal the simulator evaluates between samples, so ramps, sinusoids and the chirp
//! are smooth and the steps are exactly piecewise constant.
use std::f64::consts::PI;
use std::str::FromStr;

use super::error::SimError;

/// Fuel flow at idle, gal/h (≈45,000 rpm).
pub const IDLE_FUEL_GPH: f64 = 2.0;
/// Fuel flow at the maximum rated speed, gal/h (≈87,000 rpm).
pub const MAX_FUEL_GPH: f64 = 7.6;
/// The paper's mean operating point, gal/h (≈73,850 rpm).
pub const REF_FUEL_GPH: f64 = 5.43;
/// Chirp band of the paper's frequency-domain validation, rad/s.
pub const CHIRP_OMEGA_RAD_S: (f64, f64) = (0.574, 13.78);

/// Times closer than this to a segment boundary count as past it, s.
const BOUNDARY_TOL_SECS: f64 = 1e-9;

/// The four tests of METHOD.md.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TestKind {
    Ident,
    Validation,
    Chirp,
    Steady,
}

impl TestKind {
    pub const ALL: [TestKind; 4] = [Self::Ident, Self::Validation, Self::Chirp, Self::Steady];

    pub fn name(self) -> &'static str {
        match self {
            Self::Ident => "ident",
            Self::Validation => "validation",
            Self::Chirp => "chirp",
            Self::Steady => "steady",
        }
    }
}

impl FromStr for TestKind {
    type Err = SimError;

    fn from_str(name: &str) -> Result<Self, SimError> {
        Self::ALL.into_iter().find(|k| k.name() == name).ok_or_else(|| SimError::UnknownTest {
            name: name.to_owned(),
            known: Self::ALL.iter().map(|k| k.name().to_owned()).collect(),
        })
    }
}

/// The shape of one segment of a fuel command, in gal/h, as a function of the time into it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    Hold {
        fuel_gph: f64,
    },
    Ramp {
        from_gph: f64,
        to_gph: f64,
    },
    Sine {
        mean_gph: f64,
        amplitude_gph: f64,
        period_secs: f64,
    },
    /// Logarithmic sweep from `omega_start_rad_s` to `omega_end_rad_s` over the segment.
    Chirp {
        mean_gph: f64,
        amplitude_gph: f64,
        omega_start_rad_s: f64,
        omega_end_rad_s: f64,
    },
}

/// One segment of a profile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    pub duration_secs: f64,
    pub shape: Shape,
}

/// A fuel-flow command, sampled into a run of `n_samples` samples.
#[derive(Clone, Debug, PartialEq)]
pub struct FuelProfile {
    pub segments: Vec<Segment>,
    pub n_samples: usize,
    /// Where each segment ends, s from the start: the command at a time is found by bisection, so a
    /// long profile (a test repeated for hours) costs log(segments) a sample, not segments.
    ends_secs: Vec<f64>,
}

const fn hold(duration_secs: f64, fuel_gph: f64) -> Segment {
    Segment { duration_secs, shape: Shape::Hold { fuel_gph } }
}

const fn ramp(duration_secs: f64, from_gph: f64, to_gph: f64) -> Segment {
    Segment { duration_secs, shape: Shape::Ramp { from_gph, to_gph } }
}

impl FuelProfile {
    /// A profile of segments, sampled at `dt_secs` for its whole duration.
    pub fn new(segments: Vec<Segment>, dt_secs: f64) -> Result<Self, SimError> {
        if segments.is_empty() {
            return Err(SimError::BadProfile { segment: 0 });
        }
        if let Some(segment) =
            segments.iter().position(|s| !s.duration_secs.is_finite() || s.duration_secs <= 0.0)
        {
            return Err(SimError::BadProfile { segment });
        }
        let total: f64 = segments.iter().map(|s| s.duration_secs).sum();
        let n_samples = (total / dt_secs).floor() as usize + 1;
        let ends_secs = ends_of(&segments);
        Ok(Self { segments, n_samples, ends_secs })
    }

    /// A constant command of `n_samples` samples.
    pub fn constant(fuel_gph: f64, n_samples: usize, dt_secs: f64) -> Self {
        let duration_secs = (n_samples as f64 * dt_secs).max(dt_secs);
        let segments = vec![hold(duration_secs, fuel_gph)];
        Self { ends_secs: ends_of(&segments), segments, n_samples }
    }

    /// The same profile played `times` times end to end, sampled at `dt_secs` (a long log: the
    /// engine runs through without a stop, so each repeat starts from where the last one ended).
    pub fn repeated(&self, times: usize, dt_secs: f64) -> Result<Self, SimError> {
        if times == 0 {
            return Err(SimError::BadProfile { segment: 0 });
        }
        let segments = (0..times).flat_map(|_| self.segments.iter().copied()).collect();
        Self::new(segments, dt_secs)
    }

    /// The designs of METHOD.md, all within [`IDLE_FUEL_GPH`, `MAX_FUEL_GPH`].
    pub fn for_test(kind: TestKind, dt_secs: f64) -> Result<Self, SimError> {
        match kind {
            TestKind::Ident => Self::new(ident_segments(), dt_secs),
            TestKind::Validation => Self::new(validation_segments(), dt_secs),
            TestKind::Chirp => Self::new(chirp_segments(), dt_secs),
            TestKind::Steady => Ok(Self::constant(REF_FUEL_GPH, 300, dt_secs)),
        }
    }

    pub fn duration_secs(&self) -> f64 {
        self.segments.iter().map(|s| s.duration_secs).sum()
    }

    /// Times at which one segment ends and the next begins (where the command may jump), s.
    pub fn boundaries_secs(&self) -> Vec<f64> {
        self.ends_secs.iter().take(self.segments.len().saturating_sub(1)).copied().collect()
    }

    /// The command at time `t_secs`; before the start the first value, after the end the last.
    pub fn fuel_at(&self, t_secs: f64) -> f64 {
        // A time within rounding of a boundary belongs to the next segment, so steps fall exactly on
        // the sample (and integration) grid.
        let index = self.ends_secs.partition_point(|&end| end - BOUNDARY_TOL_SECS <= t_secs);
        let Some(segment) = self.segments.get(index).or(self.segments.last()) else {
            return 0.0;
        };
        let start = match index.min(self.segments.len() - 1) {
            0 => 0.0,
            i => self.ends_secs.get(i - 1).copied().unwrap_or(0.0),
        };
        let local = (t_secs - start).max(0.0);
        segment.shape.value_at(local.min(segment.duration_secs), segment.duration_secs)
    }
}

/// The running sums of the segments' durations.
fn ends_of(segments: &[Segment]) -> Vec<f64> {
    segments
        .iter()
        .scan(0.0, |t_secs, s| {
            *t_secs += s.duration_secs;
            Some(*t_secs)
        })
        .collect()
}

impl Shape {
    fn value_at(&self, local_secs: f64, duration_secs: f64) -> f64 {
        match *self {
            Self::Hold { fuel_gph } => fuel_gph,
            Self::Ramp { from_gph, to_gph } => from_gph + (to_gph - from_gph) * local_secs / duration_secs,
            Self::Sine { mean_gph, amplitude_gph, period_secs } => {
                mean_gph + amplitude_gph * (2.0 * PI * local_secs / period_secs).sin()
            }
            Self::Chirp { mean_gph, amplitude_gph, omega_start_rad_s, omega_end_rad_s } => {
                let ratio = omega_end_rad_s / omega_start_rad_s;
                let phase_rad = omega_start_rad_s * duration_secs / ratio.ln()
                    * (ratio.powf(local_secs / duration_secs) - 1.0);
                mean_gph + amplitude_gph * phase_rad.sin()
            }
        }
    }
}

/// Warm-up at idle, then steps A, B, C, D, E, F, H: mid–low weighted, up and down, one top step.
fn ident_segments() -> Vec<Segment> {
    vec![
        hold(60.0, IDLE_FUEL_GPH), // warm-up
        hold(40.0, 3.0),           // A
        hold(50.0, 4.3),           // B
        hold(40.0, 3.6),           // C (down)
        hold(50.0, REF_FUEL_GPH),  // D
        hold(40.0, 4.6),           // E (down)
        hold(45.0, 6.2),           // F
        hold(50.0, 7.4),           // H (top range)
    ]
}

/// Fast steps, ramps, a sinusoid and whole-range steps (≈360 s).
fn validation_segments() -> Vec<Segment> {
    let mut s = vec![hold(20.0, 4.0)];
    // Fast steps, too short for the engine to settle.
    for (secs, fuel) in [(5.0, 5.0), (4.0, 4.2), (6.0, 5.6), (3.0, 4.6), (5.0, 5.2), (6.0, 3.6), (5.0, 4.4)] {
        s.push(hold(secs, fuel));
    }
    s.extend([
        ramp(30.0, 4.4, 7.2),
        hold(15.0, 7.2),
        ramp(40.0, 7.2, 2.6),
        hold(15.0, 2.6),
        ramp(10.0, 2.6, 5.0),
    ]);
    s.push(Segment {
        duration_secs: 60.0,
        shape: Shape::Sine { mean_gph: 5.0, amplitude_gph: 1.2, period_secs: 15.0 },
    });
    // Whole-range steps.
    for (secs, fuel) in [(25.0, IDLE_FUEL_GPH), (25.0, MAX_FUEL_GPH), (25.0, 2.2), (20.0, 6.8), (20.0, 3.0)] {
        s.push(hold(secs, fuel));
    }
    s.push(hold(20.0, REF_FUEL_GPH));
    s
}

/// A logarithmic chirp around a mid operating point, between two holds (180 s).
fn chirp_segments() -> Vec<Segment> {
    let (omega_start_rad_s, omega_end_rad_s) = CHIRP_OMEGA_RAD_S;
    vec![
        hold(10.0, 5.0),
        Segment {
            duration_secs: 160.0,
            shape: Shape::Chirp { mean_gph: 5.0, amplitude_gph: 0.8, omega_start_rad_s, omega_end_rad_s },
        },
        hold(10.0, 5.0),
    ]
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    const DT: f64 = 1.0 / 8.85;

    #[test]
    fn designs_stay_in_range_and_have_their_lengths() {
        for kind in TestKind::ALL {
            let p = FuelProfile::for_test(kind, DT).unwrap();
            for k in 0..p.n_samples * 4 {
                let u = p.fuel_at(k as f64 * DT / 4.0);
                assert!((IDLE_FUEL_GPH - 1e-9..=MAX_FUEL_GPH + 1e-9).contains(&u), "{kind:?} {u}");
            }
        }
        assert_eq!(FuelProfile::for_test(TestKind::Steady, DT).unwrap().n_samples, 300);
        let ident = FuelProfile::for_test(TestKind::Ident, DT).unwrap();
        assert!((ident.duration_secs() - 375.0).abs() < 1e-9);
        let validation = FuelProfile::for_test(TestKind::Validation, DT).unwrap();
        assert!((300.0..=400.0).contains(&validation.duration_secs()));
    }

    #[test]
    fn ident_has_seven_clean_steps() {
        let p = FuelProfile::for_test(TestKind::Ident, DT).unwrap();
        let u: Vec<f64> = (0..p.n_samples).map(|k| p.fuel_at(k as f64 * DT)).collect();
        let steps = u.windows(2).filter(|w| (w[1] - w[0]).abs() > 1e-9).count();
        assert_eq!(steps, 7);
    }

    #[test]
    fn chirp_is_continuous_and_sweeps_the_band() {
        let shape = Shape::Chirp {
            mean_gph: 5.0,
            amplitude_gph: 0.8,
            omega_start_rad_s: 0.574,
            omega_end_rad_s: 13.78,
        };
        let d = 160.0;
        assert!((shape.value_at(0.0, d) - 5.0).abs() < 1e-12);
        // Instantaneous frequency from the phase slope at both ends.
        let phase = |t: f64| 0.574 * d / (13.78f64 / 0.574).ln() * ((13.78f64 / 0.574).powf(t / d) - 1.0);
        let h = 1e-4;
        assert!(((phase(h) - phase(0.0)) / h - 0.574).abs() < 1e-3);
        assert!(((phase(d) - phase(d - h)) / h - 13.78).abs() < 1e-2);
    }

    #[test]
    fn unknown_test_is_an_error() {
        assert!(
            matches!("bogus".parse::<TestKind>(), Err(SimError::UnknownTest { known, .. }) if known.len() == 4)
        );
        assert_eq!("chirp".parse::<TestKind>().unwrap(), TestKind::Chirp);
    }
}
