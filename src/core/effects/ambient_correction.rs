//! `ambient_correction`: the engine scales with inlet conditions.
use super::Evidence;
use super::stats::{ResidualTrace, correlation};
use super::{EffectError, ParamSpec};
use crate::core::run::Run;

/// ISA sea-level temperature, K.
const T_STD_K: f64 = 288.15;
/// ISA sea-level pressure, kPa.
const P_STD_KPA: f64 = 101.325;
const KELVIN_FROM_CELSIUS: f64 = 273.15;

/// Inlet conditions: the engine runs on corrected quantities, θ = T/288.15 K, δ = p/101.325 kPa.
/// The model is identified in corrected quantities: the input becomes `u/(δ√θ)` and the output
/// `y/(θ^a δ^b)` — `N/√θ` for shaft speed (a = ½, b = 0), `F/δ` for thrust (a = 0, b = 1) — and the
/// model's corrected output is turned back with the same factor. Reads the run's
/// `ambient_temp_c` and `ambient_pressure_kpa` channels; no parameter is fitted.
#[derive(Clone, Debug, PartialEq)]
pub struct AmbientCorrection {
    /// Exponent a of θ in the output's correction factor.
    pub output_theta_exp: f64,
    /// Exponent b of δ in the output's correction factor.
    pub output_delta_exp: f64,
}

/// θ and δ through a run.
#[derive(Clone, Debug, PartialEq)]
pub struct Conditions {
    /// θ = T / 288.15 K per sample.
    pub theta: Vec<f64>,
    /// δ = p / 101.325 kPa per sample.
    pub delta: Vec<f64>,
}

impl AmbientCorrection {
    /// Channels read from every run.
    pub const CHANNELS: &'static [&'static str] = &["ambient_temp_c", "ambient_pressure_kpa"];

    /// The correction for an output, chosen from its name: speed → N/√θ, thrust → F/δ.
    pub fn for_output(output: &str) -> Result<Self, EffectError> {
        match crate::core::run::Quantity::of(output) {
            Some(crate::core::run::Quantity::ShaftSpeed) => {
                Ok(Self { output_theta_exp: 0.5, output_delta_exp: 0.0 })
            }
            Some(crate::core::run::Quantity::Thrust) => {
                Ok(Self { output_theta_exp: 0.0, output_delta_exp: 1.0 })
            }
            None => Err(EffectError::NotApplicable {
                effect: <Self as super::Block>::ID.name().to_owned(),
                reason: format!("no corrected form is known for output '{output}' (only speed and thrust)"),
            }),
        }
    }

    /// θ and δ of a run from its ambient channels, checked.
    pub fn conditions(run: &Run) -> Result<Conditions, EffectError> {
        let [temp, pressure] = [Self::CHANNELS[0], Self::CHANNELS[1]].map(|name| {
            let channel =
                run.aux(name).or_else(|| run.channel(name)).ok_or_else(|| EffectError::MissingChannel {
                    effect: <Self as super::Block>::ID.name().to_owned(),
                    channel: name.to_owned(),
                    run: run.name.clone(),
                })?;
            if channel.values.len() != run.input.values.len() {
                return Err(EffectError::ChannelLength {
                    channel: name.to_owned(),
                    run: run.name.clone(),
                    found: channel.values.len(),
                    expected: run.input.values.len(),
                });
            }
            Ok(&channel.values)
        });
        let (temp, pressure) = (temp?, pressure?);
        let bad = |name: &str, index: usize, value: f64| EffectError::BadChannelValue {
            channel: name.to_owned(),
            run: run.name.clone(),
            index,
            value,
        };
        let mut theta = Vec::with_capacity(temp.len());
        for (index, t) in temp.iter().enumerate() {
            if !t.is_finite() || *t <= -KELVIN_FROM_CELSIUS {
                return Err(bad(Self::CHANNELS[0], index, *t));
            }
            theta.push((t + KELVIN_FROM_CELSIUS) / T_STD_K);
        }
        let mut delta = Vec::with_capacity(pressure.len());
        for (index, p) in pressure.iter().enumerate() {
            if !p.is_finite() || *p <= 0.0 {
                return Err(bad(Self::CHANNELS[1], index, *p));
            }
            delta.push(p / P_STD_KPA);
        }
        Ok(Conditions { theta, delta })
    }

    /// Corrected fuel flow `u/(δ√θ)`.
    pub fn correct_input(u: &[f64], c: &Conditions) -> Vec<f64> {
        u.iter().zip(&c.theta).zip(&c.delta).map(|((u, th), de)| u / (de * th.sqrt())).collect()
    }

    /// The factor `θ^a δ^b` between the physical and the corrected output.
    pub fn output_factor(&self, c: &Conditions) -> Vec<f64> {
        c.theta
            .iter()
            .zip(&c.delta)
            .map(|(th, de)| th.powf(self.output_theta_exp) * de.powf(self.output_delta_exp))
            .collect()
    }
}

/// Correlation of the percentage residual with each recorded ambient channel, pooled over runs.
/// The correlation is of the residual in output units with the model's output times the channel's
/// deviation from its mean over the runs, `ŷ·(x − x̄)`: inlet conditions scale the engine, so the
/// error they leave grows with the output. Reading it as a percentage of the measurement instead
/// would divide by the output where it is smallest, and at idle thrust the load cell's noise alone
/// is 10–20 % of the reading: the noise would swamp the correlation.
pub(super) fn evidence(traces: &[ResidualTrace]) -> Evidence {
    let best = AmbientCorrection::CHANNELS
        .iter()
        .filter_map(|name| {
            let (mut e, mut x, mut y_hat): (Vec<f64>, Vec<f64>, Vec<f64>) =
                (Vec::new(), Vec::new(), Vec::new());
            for t in traces {
                let channel = t.aux.iter().find(|c| c.name == *name)?;
                let n = t.y.len().min(channel.values.len());
                e.extend(t.residual().into_iter().take(n));
                x.extend(channel.values.iter().take(n));
                y_hat.extend(t.y_hat.iter().take(n));
            }
            let x_mean = x.iter().sum::<f64>() / x.len().max(1) as f64;
            let scaled: Vec<f64> = x.iter().zip(&y_hat).map(|(x, y)| y * (x - x_mean)).collect();
            Some((*name, correlation(&e, &scaled)))
        })
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()));
    let Some((name, r)) = best else { return Evidence::none("no ambient channel recorded") };
    let meaning = if r.abs() > 0.5 {
        "the engine scales with inlet conditions"
    } else if r.abs() > 0.2 {
        "some dependence on inlet conditions"
    } else {
        "little dependence on inlet conditions"
    };
    Evidence {
        sentence: format!("residual tracks the output scaled by {name}, r = {r:.2}: {meaning}"),
        supports: r.abs() > 0.2,
    }
}

block_impl!(
    AmbientCorrection { output_theta_exp, output_delta_exp },
    params: &[ParamSpec::real("output_theta_exp", 0.0, 1.5), ParamSpec::real("output_delta_exp", 0.0, 1.5)],
    physics: "the engine scales with inlet conditions: it runs on corrected fuel u/(δ√θ) and gives \
         corrected speed N/√θ or thrust F/δ",
    evidence: evidence
);

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::core::run::Channel;

    #[test]
    fn standard_day_is_neutral_and_hot_day_corrects() {
        let run = Run {
            name: "r".into(),
            dt_secs: 0.1,
            t_secs: vec![0.0, 0.1],
            input: Channel::new("fuel_flow_gph", vec![5.0, 5.0]),
            outputs: vec![],
            aux: vec![
                Channel::new("ambient_temp_c", vec![15.0, 42.3]),
                Channel::new("ambient_pressure_kpa", vec![101.325, 101.325]),
            ],
        };
        let c = AmbientCorrection::conditions(&run).unwrap();
        let u = AmbientCorrection::correct_input(&run.input.values, &c);
        assert!((u[0] - 5.0).abs() < 1e-12);
        assert!(u[1] < 5.0);
        let speed = AmbientCorrection::for_output("shaft_speed_rpm").unwrap();
        assert!((speed.output_factor(&c)[1] - (315.45f64 / 288.15).sqrt()).abs() < 1e-12);
        assert!(matches!(AmbientCorrection::for_output("egt_c"), Err(EffectError::NotApplicable { .. })));
    }
}
