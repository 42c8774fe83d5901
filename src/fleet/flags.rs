//! The engine's normal band for every delta and for the error, and each run's flag in physical
//! words: which delta left the band, by how much, and what that means for the engine.
use crate::core::health::{BAND_SIGMAS, Band, Estimate, local_bands};
use crate::core::run::{Quantity, unit_from_column_name};

use super::finding::Finding;
use super::score::{RunScore, Starved};

/// A run's error is unusual only when it is also this many times the engine's usual error. The
/// reference's error on a healthy run is mostly its structural error (the map's misfit, dynamics it
/// leaves out), and that misfit differs across the operating range: a run that holds where the map
/// fits worst has several times the error of one that holds where it fits best, with nothing wrong
/// with the engine. Three times the usual RMSE — nine times the error energy — is beyond what the
/// choice of operating points does, and a fault that small shows in its delta first.
const ERROR_RATIO: f64 = 3.0;

/// The smallest changes that matter, whatever the statistics say: below them a deviation is within
/// what an instrument or a test day changes with a healthy engine. The input gain: 1 %, a fuel flow
/// meter's calibration tolerance (turbine meters are specified to ±0.5–1 % of reading, and drift by
/// that between calibrations). The time-constant scale: 5 %, what a day's inlet temperature does (±15 K
/// moves the corrected speed by ±2.5 % and with it the spool's time constant, τ ∝ 1/N, by as much,
/// twice over a range of test days). A map shift: 1 % of the output's range, a load cell's or speed
/// pick-up's calibration tolerance plus the day-to-day spread of a bench.
pub const SMALLEST_GAIN_CHANGE: f64 = 0.01;
pub const SMALLEST_TAU_CHANGE: f64 = 0.05;
pub const SMALLEST_MAP_SHIFT_OF_RANGE: f64 = 0.01;

/// The bands of one engine, per run in date order (see `core::health::band`): the shared deltas and,
/// per output (in the reference's order), the map shift; the error's band is the engine's as a whole
/// (a run's error is judged against the engine's usual error, which drifts with nothing).
#[derive(Clone, Debug, Default)]
pub struct EngineBands {
    pub input_gain: Vec<Option<Band>>,
    pub tau_scale: Vec<Option<Band>>,
    pub map_shift: Vec<(String, Vec<Option<Band>>)>,
    pub rmse: Vec<(String, Option<Band>)>,
}

impl EngineBands {
    /// The bands across `runs` (the engine's runs in date order, scored) for the outputs `outputs`.
    pub fn of(runs: &[&RunScore], outputs: &[String]) -> Self {
        let bands = |estimates: Vec<Option<Estimate>>| {
            let values: Vec<f64> = estimates.iter().map(|e| e.map_or(f64::NAN, |e| e.value)).collect();
            let errors: Vec<f64> = estimates.iter().flatten().filter_map(Estimate::std_error).collect();
            local_bands(&values, &errors)
        };
        let of_output = |r: &RunScore, output: &str| r.outputs.iter().find(|o| o.output == output).cloned();
        Self {
            input_gain: bands(runs.iter().map(|r| r.input_gain).collect()),
            tau_scale: bands(runs.iter().map(|r| r.tau_scale).collect()),
            map_shift: outputs
                .iter()
                .map(|o| {
                    (
                        o.clone(),
                        bands(runs.iter().map(|r| of_output(r, o).and_then(|s| s.map_shift)).collect()),
                    )
                })
                .collect(),
            rmse: outputs
                .iter()
                .map(|o| {
                    let errors: Vec<f64> =
                        runs.iter().filter_map(|r| of_output(r, o)).map(|s| s.rmse).collect();
                    (o.clone(), Band::of(&errors, &[]))
                })
                .collect(),
        }
    }

    pub fn rmse_band(&self, output: &str) -> Option<&Band> {
        self.rmse.iter().find(|(name, _)| name == output).and_then(|(_, b)| b.as_ref())
    }

    /// The band of `output`'s map shift for run `index`.
    pub fn map_shift_of(&self, output: &str, index: usize) -> Option<&Band> {
        self.map_shift.iter().find(|(name, _)| name == output).and_then(|(_, b)| b.get(index)?.as_ref())
    }

    /// The reasons a run's flag gives: the shared deltas and the starved stretches (every row of the
    /// run), then each output's own (map shift, error), keyed by output.
    pub fn reasons(&self, index: usize, run: &RunScore) -> (Vec<String>, Vec<(String, Vec<String>)>) {
        let mut shared = Vec::new();
        let (fuel, first) =
            (fuel_word(&run.input_name), run.outputs.first().map(|o| quantity_word(&o.output)));
        if let (Some(Some(band)), Some(gain)) = (self.input_gain.get(index), run.input_gain)
            && band.outside(gain.value, gain.ci95, SMALLEST_GAIN_CHANGE)
        {
            let more = 100.0 * (1.0 / gain.value - 1.0);
            let usual = 100.0 * (1.0 / band.centre - 1.0);
            shared.push(format!(
                "needs {} {fuel} for the same {} than the reference (its trend: {})",
                signed(more, "more", "less"),
                first.clone().unwrap_or_else(|| "output".into()),
                signed(usual, "more", "less")
            ));
        }
        if let (Some(Some(band)), Some(tau)) = (self.tau_scale.get(index), run.tau_scale)
            && band.outside(tau.value, tau.ci95, SMALLEST_TAU_CHANGE)
        {
            let slower = 100.0 * (tau.value - 1.0);
            shared.push(format!(
                "spool {} than the reference (its trend: {})",
                signed(slower, "slower", "faster"),
                signed(100.0 * (band.centre - 1.0), "slower", "faster")
            ));
        }
        // One reason per stretch, on the first output that shows it (speed before thrust).
        let mut said: Vec<usize> = Vec::new();
        for starved in &run.starved {
            let typical = self.rmse_band(&starved.output).map_or(0.0, |b| b.centre);
            if starved.shortfall > BAND_SIGMAS * typical
                && starved.shortfall > 0.0
                && !said.contains(&starved.start)
            {
                said.push(starved.start);
                shared.push(starvation_words(starved));
            }
        }
        // What the diagnosis found on the run (see `fleet::diagnosis`), on the output it acts on.
        let findings = run.diagnosis.iter().flat_map(|d| &d.findings);
        let own: Vec<(String, Vec<String>)> = run
            .outputs
            .iter()
            .map(|o| {
                let mut reasons = self.output_reasons(index, o);
                reasons.extend(findings.clone().filter(|f| f.output == o.output).map(finding_words));
                (o.output.clone(), reasons)
            })
            .collect();
        let flagged = !shared.is_empty() || own.iter().any(|(_, r)| !r.is_empty());
        // A starved run's gain is fitted where the pump is pinned, beyond the reference's range: it
        // says nothing about the calibration, and the starvation is the direction.
        let gain_said = shared.iter().any(|r| r.starts_with("needs ")) || !said.is_empty();
        if let (true, false, Some(gain)) = (flagged, gain_said, run.input_gain)
            && let Some(words) = direction_from_reference(gain, &fuel, first.as_deref())
        {
            shared.push(words);
        }
        (shared, own)
    }

    /// Every reason of run `index`'s flag, each once: the shared ones first, then each output's
    /// own (the History view lists them; fleet.csv gives each output's row its own and the shared).
    pub fn all_reasons(&self, index: usize, run: &RunScore) -> Vec<String> {
        let (mut reasons, own) = self.reasons(index, run);
        for reason in own.into_iter().flat_map(|(_, r)| r) {
            if !reasons.contains(&reason) {
                reasons.push(reason);
            }
        }
        reasons
    }

    fn output_reasons(&self, index: usize, o: &super::score::OutputScore) -> Vec<String> {
        let mut reasons = Vec::new();
        if let (Some(band), Some(shift)) = (self.map_shift_of(&o.output, index), o.map_shift)
            && band.outside(shift.value, shift.ci95, SMALLEST_MAP_SHIFT_OF_RANGE * o.range)
        {
            reasons.push(format!(
                "{} map {}{} {} ({} % of its range; its trend: {})",
                quantity_word(&o.output),
                plain(shift.value.abs(), 3),
                unit_after(&o.unit),
                if shift.value >= 0.0 { "high" } else { "low" },
                plain(100.0 * shift.value.abs() / o.range.max(f64::MIN_POSITIVE), 2),
                plain(band.centre, 3)
            ));
        }
        if let Some(band) = self.rmse_band(&o.output)
            && o.rmse > band.high()
            && o.rmse > ERROR_RATIO * band.centre
        {
            reasons.push(format!(
                "{} fits {}× worse than usual (RMSE {}{} against {})",
                quantity_word(&o.output),
                plain(o.rmse / band.centre, 2),
                plain(o.rmse, 3),
                unit_after(&o.unit),
                plain(band.centre, 3)
            ));
        }
        reasons
    }
}

/// The direction a flagged run moved from the reference, when the band could not say it (a run
/// flagged for its error, or an engine whose band the flagged runs themselves widen): the input gain
/// against the reference's 1, when its interval excludes 1 and the change is beyond
/// [`SMALLEST_GAIN_CHANGE`]. "against the reference: needs 41 % less fuel for the same PR (gain
/// 1.70, 95 % interval 1.62–1.79)".
fn direction_from_reference(gain: Estimate, fuel: &str, first: Option<&str>) -> Option<String> {
    let [lo, hi] = gain.ci95?;
    let beyond = (gain.value - 1.0).abs() > SMALLEST_GAIN_CHANGE && !(lo..=hi).contains(&1.0);
    beyond.then(|| {
        format!(
            "against the reference: needs {} {fuel} for the same {} (input gain {}, 95 % interval {}–{})",
            signed(100.0 * (1.0 / gain.value - 1.0), "more", "less"),
            first.unwrap_or("output"),
            plain(gain.value, 3),
            plain(lo, 3),
            plain(hi, 3)
        )
    })
}

/// The unit of an effect parameter, read from the suffix its name carries (`ParamSpec::name`):
/// a rate in the output's unit per second (the rate limit acts on the linear block's output, which
/// is in output units), seconds, hertz or samples; `None` for a ratio, or a rate of an output whose
/// unit is unknown.
fn param_unit(name: &str, output: &str) -> Option<String> {
    if name.ends_with("_per_s") {
        let unit = unit_from_column_name(output);
        return (!unit.is_empty()).then(|| format!("{unit}/s"));
    }
    [("_s", "s"), ("_hz", "Hz"), ("_samples", "samples")]
        .iter()
        .find(|(suffix, _)| name.ends_with(suffix))
        .map(|(_, unit)| (*unit).to_owned())
}

/// "missing effect on speed: rate limit (error from 35 to 11 σ beyond the noise, p = 2.6e-4;
/// fall_per_s 1530 rpm/s [1490, 1570], rise_per_s 2980 rpm/s [2900, 3050]): measured peak
/// slopes … : both accelerations and decelerations saturate at a constant rate".
pub fn finding_words(f: &Finding) -> String {
    let params: Vec<String> = f
        .params
        .iter()
        .map(|p| {
            let name = p.name.split_once('.').map_or(p.name.as_str(), |(_, n)| n);
            let unit = param_unit(name, &f.output).map_or(String::new(), |u| format!(" {u}"));
            match p.ci95 {
                Some([lo, hi]) => {
                    format!("{name} {}{unit} [{}, {}]", plain(p.value, 3), plain(lo, 3), plain(hi, 3))
                }
                None => format!("{name} {}{unit}", plain(p.value, 3)),
            }
        })
        .collect();
    let params = if params.is_empty() { String::new() } else { format!("; {}", params.join(", ")) };
    let also: Vec<String> = f
        .also
        .iter()
        .map(|(id, after)| format!("{} (to {} σ)", id.name().replace('_', " "), plain(*after, 2)))
        .collect();
    let also = if also.is_empty() {
        String::new()
    } else {
        format!(" (also significant, explaining less: {})", also.join(", "))
    };
    format!(
        "missing effect on {}: {} (error from {} to {} σ beyond the noise, p = {:.1e}{params}): {}{also}",
        quantity_word(&f.output),
        f.effect.name().replace('_', " "),
        plain(f.beyond_noise_before, 2),
        plain(f.beyond_noise_after, 2),
        f.p_value,
        f.evidence
    )
}

/// "pump at its limit (7.09 V) for 160 s while speed falls 21000 rpm short of the 101000 rpm the
/// reference gives at 4.96 V: fuel supply".
fn starvation_words(s: &Starved) -> String {
    let device = if s.input.to_ascii_lowercase().contains("pump") {
        "pump".to_owned()
    } else if s.input.to_ascii_lowercase().contains("fuel") {
        "fuel flow".to_owned()
    } else {
        format!("input '{}'", s.input)
    };
    format!(
        "{device} at its limit ({}{}) for {} s while {} falls {}{} short of the {}{} the reference gives at {}{}: fuel supply",
        plain(s.limit, 3),
        unit_after(&s.input_unit),
        plain(s.duration_secs, 2),
        quantity_word(&s.output),
        plain(s.shortfall, 2),
        unit_after(&s.unit),
        plain(s.expected, 3),
        unit_after(&s.unit),
        plain(s.probe_input, 3),
        unit_after(&s.input_unit)
    )
}

/// "6.1 % more" or "6.1 % less" of a percentage `pct`.
fn signed(pct: f64, up: &str, down: &str) -> String {
    format!("{} % {}", plain(pct.abs(), 2), if pct >= 0.0 { up } else { down })
}

/// A unit after a number: " rpm", or nothing for a ratio ("-") or an unknown unit.
fn unit_after(unit: &str) -> String {
    if unit.is_empty() || unit == "-" { String::new() } else { format!(" {unit}") }
}

/// "fuel" for a fuel flow or a fuel pump's signal, else the input's name.
fn fuel_word(input: &str) -> String {
    let lower = input.to_ascii_lowercase();
    if lower.contains("fuel") || lower.contains("pump") { "fuel".to_owned() } else { format!("'{input}'") }
}

/// "speed", "thrust" or the output's name.
pub fn quantity_word(output: &str) -> String {
    match Quantity::of(output) {
        Some(Quantity::ShaftSpeed) => "speed".to_owned(),
        Some(Quantity::Thrust) => "thrust".to_owned(),
        None => output.to_owned(),
    }
}

/// `x` rounded to `digits` significant digits, written plainly (101234 → "101000", 0.01234 → "0.0123").
pub fn plain(x: f64, digits: i32) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    if x.abs() < f64::MIN_POSITIVE {
        return "0".to_owned();
    }
    let magnitude = x.abs().log10().floor() as i32;
    let decimals = (digits - 1 - magnitude).max(0) as usize;
    let unit = 10f64.powi(magnitude - digits + 1);
    format!("{:.decimals$}", (x / unit).round() * unit)
}

#[cfg(test)]
mod tests {
    #[test]
    fn numbers_read_plainly() {
        assert_eq!(super::plain(101_234.0, 3), "101000");
        assert_eq!(super::plain(0.012_34, 3), "0.0123");
        assert_eq!(super::plain(6.149, 2), "6.1");
        assert_eq!(super::plain(-350.4, 2), "-350");
    }

    #[test]
    fn effect_parameters_carry_their_units() {
        use super::param_unit;
        assert_eq!(param_unit("fall_per_s", "shaft_speed_rpm").as_deref(), Some("rpm/s"));
        assert_eq!(param_unit("rise_per_s", "thrust_n").as_deref(), Some("N/s"));
        // A rate of an output whose unit is unknown, and ratios, get no unit.
        assert_eq!(param_unit("rise_per_s", "speed"), None);
        assert_eq!(param_unit("decel_factor", "shaft_speed_rpm"), None);
        assert_eq!(param_unit("zeta", "thrust_n"), None);
        assert_eq!(param_unit("tau_s", "thrust_n").as_deref(), Some("s"));
        assert_eq!(param_unit("delay_samples", "thrust_n").as_deref(), Some("samples"));
        assert_eq!(param_unit("freq_hz", "thrust_n").as_deref(), Some("Hz"));
    }
}
