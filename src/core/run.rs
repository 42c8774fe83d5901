//! A measured (or simulated) test-bench run: uniformly sampled input, outputs and auxiliary channels.

use serde::{Deserialize, Serialize};

/// What a run is used for: the models are identified on the identification runs (joined end to end
/// when there are several), chosen on the validation runs, and scored on the validation, held-out
/// and chirp runs; the steady run gives the input noise of the Monte Carlo study.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RunRole {
    Identification,
    Validation,
    /// Scored beside the validation runs, never used to choose anything (the diagnosis, the
    /// effects and the live error read only validation runs).
    HeldOut,
    Chirp,
    Steady,
}

impl RunRole {
    pub const ALL: [Self; 5] =
        [Self::Identification, Self::Validation, Self::HeldOut, Self::Chirp, Self::Steady];

    /// The roles whose runs every model is scored on, in the order the reports list them.
    pub const SCORED: [Self; 3] = [Self::Validation, Self::HeldOut, Self::Chirp];

    pub fn label(self) -> &'static str {
        match self {
            Self::Identification => "identification",
            Self::Validation => "validation",
            Self::HeldOut => "held out",
            Self::Chirp => "chirp",
            Self::Steady => "steady",
        }
    }
}

/// What an output measures, as far as the method needs to know: the shaft speed and the thrust
/// each have their own ARX orders, ambient-corrected form and paper figures. Read from the output's
/// column name in one place ([`Quantity::of`]); `None` for any other output (a pressure ratio, a
/// power), which gets the defaults.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Quantity {
    ShaftSpeed,
    Thrust,
}

impl Quantity {
    /// The quantity an output column measures, by its name (any case): `speed` or `rpm` is the
    /// shaft speed, `thrust` the thrust.
    pub fn of(output: &str) -> Option<Self> {
        let name = output.to_ascii_lowercase();
        if name.contains("speed") || name.contains("rpm") {
            Some(Self::ShaftSpeed)
        } else if name.contains("thrust") {
            Some(Self::Thrust)
        } else {
            None
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            Self::ShaftSpeed => "shaft speed",
            Self::Thrust => "thrust",
        }
    }
}

/// How an input covers the range a model was identified on: the share of samples outside it, and
/// whether it changes sign where the identification input never did. A model outside its
/// identified range extrapolates its static map (a polynomial) and says nothing trustworthy.
#[derive(Clone, Debug, PartialEq)]
pub struct InputCoverage {
    /// The identified range, `[lowest, highest]` input of the identification run.
    pub range: [f64; 2],
    /// Samples below and above it.
    pub below: usize,
    pub above: usize,
    pub samples: usize,
    /// The input's own extremes.
    pub min: f64,
    pub max: f64,
    /// The input takes both signs while the identification input kept one.
    pub changes_sign: bool,
}

impl InputCoverage {
    /// The coverage of `u` against `range`.
    pub fn of(u: &[f64], range: [f64; 2]) -> Self {
        let below = u.iter().filter(|v| **v < range[0]).count();
        let above = u.iter().filter(|v| **v > range[1]).count();
        let (min, max) =
            u.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
        let one_sign = range[0] >= 0.0 || range[1] <= 0.0;
        let changes_sign = one_sign && min < 0.0 && max > 0.0;
        Self { range, below, above, samples: u.len(), min, max, changes_sign }
    }

    /// Share of the samples outside the identified range, 0..=1.
    pub fn outside_share(&self) -> f64 {
        (self.below + self.above) as f64 / self.samples.max(1) as f64
    }

    /// True when every sample lies in the identified range and the sign holds.
    pub fn is_inside(&self) -> bool {
        self.below + self.above == 0 && !self.changes_sign
    }

    /// "12.3 % of the input (408 of 3319 samples) lies outside the identified range 2.000 to 7.400
    /// gal/h (the input spans 0.3000 to 15.00): the model extrapolates there", with the sign change
    /// named; `None` when the input is inside.
    pub fn words(&self, unit: &str) -> Option<String> {
        if self.is_inside() {
            return None;
        }
        let s = |x: f64| crate::core::numerics::stats::significant(x, 4);
        let unit = if unit.is_empty() { String::new() } else { format!(" {unit}") };
        let mut text = format!(
            "{:.1} % of the input ({} of {} samples) lies outside the identified range {} to {}{unit} \
             (the input spans {} to {}): the model extrapolates there",
            100.0 * self.outside_share(),
            self.below + self.above,
            self.samples,
            s(self.range[0]),
            s(self.range[1]),
            s(self.min),
            s(self.max)
        );
        if self.changes_sign {
            text.push_str("; the input changes sign, which the identification input never did");
        }
        Some(text)
    }
}

/// One named signal with its unit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Channel {
    pub name: String,
    pub unit: String,
    pub values: Vec<f64>,
}

impl Channel {
    /// A channel whose unit is guessed from the column-name suffix (`_rpm`, `_n`, `_gph`, …).
    pub fn new(name: &str, values: Vec<f64>) -> Self {
        Self { name: name.to_owned(), unit: unit_from_column_name(name).to_owned(), values }
    }
}

/// A run: the input (fuel flow), one or more outputs and any auxiliary channels, on one time base.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Run {
    pub name: String,
    pub dt_secs: f64,
    pub t_secs: Vec<f64>,
    pub input: Channel,
    pub outputs: Vec<Channel>,
    pub aux: Vec<Channel>,
}

impl Run {
    pub fn len(&self) -> usize {
        self.t_secs.len()
    }

    pub fn is_empty(&self) -> bool {
        self.t_secs.is_empty()
    }

    pub fn output(&self, name: &str) -> Option<&Channel> {
        self.outputs.iter().find(|c| c.name == name)
    }

    pub fn aux(&self, name: &str) -> Option<&Channel> {
        self.aux.iter().find(|c| c.name == name)
    }

    /// The run linearly interpolated onto a uniform grid of `dt_secs` over the same span (for runs
    /// already resampled from an irregular log onto a slightly different grid).
    pub fn resampled(&self, dt_secs: f64) -> Run {
        let (Some(&t0), Some(&t_end)) = (self.t_secs.first(), self.t_secs.last()) else {
            return self.clone();
        };
        if dt_secs.is_nan() || dt_secs <= 0.0 || self.len() < 2 {
            return self.clone();
        }
        let n = ((t_end - t0) / dt_secs).floor() as usize + 1;
        let t_secs: Vec<f64> = (0..n).map(|k| t0 + k as f64 * dt_secs).collect();
        let at = |values: &[f64], t: f64| {
            let x = ((t - t0) / self.dt_secs).max(0.0);
            let i = (x.floor() as usize).min(values.len().saturating_sub(2));
            let (a, b) = (values.get(i).copied().unwrap_or(0.0), values.get(i + 1).copied().unwrap_or(0.0));
            a + (b - a) * (x - i as f64).clamp(0.0, 1.0)
        };
        let regrid = |c: &Channel| Channel {
            name: c.name.clone(),
            unit: c.unit.clone(),
            values: t_secs.iter().map(|&t| at(&c.values, t)).collect(),
        };
        Run {
            name: self.name.clone(),
            dt_secs,
            input: regrid(&self.input),
            outputs: self.outputs.iter().map(regrid).collect(),
            aux: self.aux.iter().map(regrid).collect(),
            t_secs,
        }
    }

    /// The samples `range` of the run (clipped to its length), every channel alike.
    pub fn slice(&self, range: std::ops::Range<usize>) -> Run {
        let end = range.end.min(self.len());
        let range = range.start.min(end)..end;
        let cut = |c: &Channel| Channel {
            name: c.name.clone(),
            unit: c.unit.clone(),
            values: c.values.get(range.clone()).unwrap_or_default().to_vec(),
        };
        Run {
            name: self.name.clone(),
            dt_secs: self.dt_secs,
            t_secs: self.t_secs.get(range.clone()).unwrap_or_default().to_vec(),
            input: cut(&self.input),
            outputs: self.outputs.iter().map(cut).collect(),
            aux: self.aux.iter().map(cut).collect(),
        }
    }

    /// Any channel (input, output or auxiliary) by name.
    pub fn channel(&self, name: &str) -> Option<&Channel> {
        std::iter::once(&self.input).chain(&self.outputs).chain(&self.aux).find(|c| c.name == name)
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RunError {
    #[error("no runs to join")]
    NothingToJoin,
    #[error(
        "run '{run}' is sampled every {} s but '{first}' every {} s; resample it before joining",
        crate::core::numerics::stats::significant(*dt_secs, 5),
        crate::core::numerics::stats::significant(*first_dt_secs, 5)
    )]
    SampleTimeMismatch { run: String, dt_secs: f64, first: String, first_dt_secs: f64 },
    #[error("run '{run}' has input '{input}' but '{first}' has '{first_input}'")]
    InputMismatch { run: String, input: String, first: String, first_input: String },
    #[error("run '{run}' lacks the channel '{channel}' that '{first}' has")]
    MissingChannel { run: String, channel: String, first: String },
}

/// Join runs end to end into one (e.g. several identification runs of an engine): channels are
/// matched by name, time continues one sample after the previous run's end, and `junctions` holds the
/// index where each later run starts. Every run must have the first run's input, outputs and
/// auxiliary channels and its sample time (±2 %). The join is a jump in input and output: segments
/// must not straddle it (the step detector sees it as a step, which is what it is).
pub fn join_runs(runs: &[Run]) -> Result<(Run, Vec<usize>), RunError> {
    let Some(first) = runs.first() else { return Err(RunError::NothingToJoin) };
    let mut joined = first.clone();
    let mut junctions = Vec::new();
    for run in runs.iter().skip(1) {
        if ((run.dt_secs - first.dt_secs) / first.dt_secs).abs() > 0.02 {
            return Err(RunError::SampleTimeMismatch {
                run: run.name.clone(),
                dt_secs: run.dt_secs,
                first: first.name.clone(),
                first_dt_secs: first.dt_secs,
            });
        }
        if run.input.name != first.input.name {
            return Err(RunError::InputMismatch {
                run: run.name.clone(),
                input: run.input.name.clone(),
                first: first.name.clone(),
                first_input: first.input.name.clone(),
            });
        }
        let missing = |c: &Channel| RunError::MissingChannel {
            run: run.name.clone(),
            channel: c.name.clone(),
            first: first.name.clone(),
        };
        junctions.push(joined.len());
        let t0 = joined.t_secs.last().map_or(0.0, |t| t + joined.dt_secs);
        joined.t_secs.extend((0..run.len()).map(|k| t0 + k as f64 * joined.dt_secs));
        joined.input.values.extend_from_slice(&run.input.values);
        for c in &mut joined.outputs {
            let other = run.output(&c.name).ok_or_else(|| missing(c))?;
            c.values.extend_from_slice(&other.values);
        }
        for c in &mut joined.aux {
            let other = run.aux(&c.name).ok_or_else(|| missing(c))?;
            c.values.extend_from_slice(&other.values);
        }
        joined.name = format!("{}+{}", joined.name, run.name);
    }
    Ok((joined, junctions))
}

/// ` [unit]` to follow a quantity's name, or nothing when the unit is unknown (never ` []`).
pub fn bracketed_unit(unit: &str) -> String {
    if unit.is_empty() { String::new() } else { format!(" [{unit}]") }
}

/// `name [unit]`, as axes and buttons label a channel; the name alone when the unit is unknown or
/// when the name is the unit (a column `rpm` in rpm reads "rpm", not "rpm [rpm]").
pub fn name_with_unit(name: &str, unit: &str) -> String {
    if name_is_unit(name, unit) { name.to_owned() } else { format!("{name}{}", bracketed_unit(unit)) }
}

/// Whether a label would only repeat the name by giving the unit: the unit is unknown, or the
/// channel is named for its unit alone.
pub fn name_is_unit(name: &str, unit: &str) -> bool {
    unit.is_empty() || name.trim().eq_ignore_ascii_case(unit.trim())
}

/// The unit implied by a canonical column-name suffix; empty when unknown.
pub fn unit_from_column_name(name: &str) -> &'static str {
    let lower = name.to_ascii_lowercase();
    const SUFFIXES: [(&str, &str); 15] = [
        ("_gph", "gal/h"),
        ("_rpm", "rpm"),
        ("_n", "N"),
        ("_c", "°C"),
        ("_k", "K"),
        ("_kpa", "kPa"),
        ("_pct", "%"),
        ("_s", "s"),
        ("_v", "V"),
        ("_a", "A"),
        ("_krpm", "krpm"),
        ("_bar", "bar"),
        ("_kw", "kW"),
        ("_lpm", "L/min"),
        ("_psi", "psi"),
    ];
    SUFFIXES.iter().find(|(suffix, _)| lower.ends_with(suffix)).map_or("", |(_, unit)| unit)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn run(name: &str, n: usize, dt_secs: f64) -> Run {
        Run {
            name: name.into(),
            dt_secs,
            t_secs: (0..n).map(|k| k as f64 * dt_secs).collect(),
            input: Channel::new("pump_v", vec![1.0; n]),
            outputs: vec![Channel::new("rpm", (0..n).map(|k| k as f64).collect())],
            aux: vec![Channel::new("egt_c", vec![500.0; n])],
        }
    }

    #[test]
    fn a_channel_named_for_its_unit_is_labelled_once() {
        assert_eq!(name_with_unit("rpm", "rpm"), "rpm");
        assert_eq!(name_with_unit("RPM", "rpm"), "RPM");
        assert_eq!(name_with_unit("pump_V", "V"), "pump_V [V]");
        assert_eq!(name_with_unit("shaft_speed_rpm", "rpm"), "shaft_speed_rpm [rpm]");
        assert_eq!(name_with_unit("PR", ""), "PR");
    }

    #[test]
    fn resampling_onto_another_grid_keeps_a_line_a_line() {
        let mut r = run("a", 50, 0.1);
        r.input.values = r.t_secs.iter().map(|t| 2.0 * t + 1.0).collect();
        let fine = r.resampled(0.0975);
        assert!((fine.dt_secs - 0.0975).abs() < 1e-12 && fine.len() == 51, "{}", fine.len());
        for (t, u) in fine.t_secs.iter().zip(&fine.input.values) {
            assert!((u - (2.0 * t + 1.0)).abs() < 1e-9, "{t}: {u}");
        }
        assert_eq!(r.resampled(-1.0), r, "a bad step leaves the run as it is");
    }

    #[test]
    fn joined_runs_continue_in_time_and_mark_junctions() {
        let (j, junctions) = join_runs(&[run("a", 3, 0.1), run("b", 2, 0.1005)]).unwrap();
        assert_eq!(j.len(), 5);
        assert_eq!(junctions, vec![3]);
        assert_eq!(j.name, "a+b");
        assert!((j.t_secs[3] - 0.3).abs() < 1e-12 && (j.t_secs[4] - 0.4).abs() < 1e-12);
        assert_eq!(j.outputs[0].values, vec![0.0, 1.0, 2.0, 0.0, 1.0]);
        assert_eq!(j.aux[0].values.len(), 5);
    }

    #[test]
    fn runs_that_do_not_match_are_not_joined() {
        assert_eq!(join_runs(&[]), Err(RunError::NothingToJoin));
        assert!(matches!(
            join_runs(&[run("a", 3, 0.1), run("b", 3, 0.2)]),
            Err(RunError::SampleTimeMismatch { .. })
        ));
        let mut b = run("b", 3, 0.1);
        b.aux.clear();
        assert!(matches!(
            join_runs(&[run("a", 3, 0.1), b]),
            Err(RunError::MissingChannel { channel, .. }) if channel == "egt_c"
        ));
        let mut c = run("c", 3, 0.1);
        c.input.name = "fuel".into();
        assert!(matches!(join_runs(&[run("a", 3, 0.1), c]), Err(RunError::InputMismatch { .. })));
    }

    #[test]
    fn units_follow_suffixes() {
        assert_eq!(unit_from_column_name("shaft_speed_rpm"), "rpm");
        assert_eq!(unit_from_column_name("thrust_n"), "N");
        assert_eq!(unit_from_column_name("fuel_flow_gph"), "gal/h");
        assert_eq!(unit_from_column_name("ambient_pressure_kpa"), "kPa");
        assert_eq!(unit_from_column_name("egt_C"), "°C");
        assert_eq!(unit_from_column_name("power_kW"), "kW");
        assert_eq!(unit_from_column_name("fuel_flow_Lpm"), "L/min");
        assert_eq!(unit_from_column_name("mystery"), "");
    }
}
