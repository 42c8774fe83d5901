//! The Wiener model extended with effect blocks, and its simulation along the signal path (the
//! stages themselves are in `stages`).
use num_complex::Complex64;

use super::ambient_correction::Conditions;
use super::power_balance::PowerBalance;
use super::rate_limit::StateLimit;
use super::stages::{Through, input_stage, kink, linear_stage, needs_split, output_stage, rate_limit};
use super::{
    AsymmetricDynamics, EffectBlock, EffectError, EffectId, EffectRecord, ReadOffSpeed, SensorDynamics,
    StaticMapOrder,
};
use crate::core::identification::initial_state::{InitialState, fit_free_response};
use crate::core::identification::pipeline::GrayBoxModel;
use crate::core::identification::wiener::WienerModel;
use crate::core::run::Run;

/// The gray-box model of one output with the effects added to it.
///
/// With no effects it simulates exactly like its [`WienerModel`]. Effects are kept in signal-path
/// order (see the module documentation), each id at most once.
#[derive(Clone, Debug, PartialEq)]
pub struct ExtendedModel {
    /// The output modelled.
    pub output: String,
    /// The base model: linear block (gain and offset included) and static map.
    pub wiener: WienerModel,
    /// The effects, in signal-path order.
    pub effects: Vec<EffectBlock>,
}

impl ExtendedModel {
    /// The base model without effects.
    pub fn new(output: &str, wiener: WienerModel) -> Self {
        Self { output: output.to_owned(), wiener, effects: Vec::new() }
    }

    /// The pipeline's gray-box model without effects.
    pub fn from_gray_box(model: &GrayBoxModel) -> Self {
        Self::new(&model.output, model.wiener.clone())
    }

    /// A model restored from its stored parts (e.g. model.json), every record checked.
    pub fn from_records(
        output: &str,
        wiener: WienerModel,
        records: &[EffectRecord],
    ) -> Result<Self, EffectError> {
        let mut model = Self::new(output, wiener);
        for record in records {
            model = model.with_effect(EffectBlock::from_record(record)?)?;
        }
        Ok(model)
    }

    /// The effects' serialisable records, in signal-path order.
    pub fn records(&self) -> Vec<EffectRecord> {
        self.effects.iter().map(EffectBlock::record).collect()
    }

    /// The effect with this id, if applied.
    pub fn effect(&self, id: EffectId) -> Option<&EffectBlock> {
        self.effects.iter().find(|e| e.id() == id)
    }

    /// Ids of the applied effects, in signal-path order.
    pub fn effect_ids(&self) -> Vec<EffectId> {
        self.effects.iter().map(EffectBlock::id).collect()
    }

    /// The model with one more effect block, as given (nothing is refitted; see `apply_effect`).
    pub fn with_effect(&self, block: EffectBlock) -> Result<Self, EffectError> {
        if self.effect(block.id()).is_some() {
            return Err(EffectError::AlreadyApplied { effect: block.id().name().to_owned() });
        }
        if let EffectBlock::SensorDynamics(s) = &block {
            let max = SensorDynamics::max_freq_hz(self.wiener.linear.tf.dt_secs);
            if s.freq_hz > max {
                return Err(EffectError::ParameterOutOfRange {
                    effect: EffectId::SensorDynamics.name().to_owned(),
                    param: "freq_hz".to_owned(),
                    value: s.freq_hz,
                    min: 0.0,
                    max,
                });
            }
        }
        let mut model = self.clone();
        model.effects.push(block);
        model.effects.sort_by_key(EffectBlock::rank);
        Ok(model)
    }

    /// The model without the effect `id`, as it is (nothing is refitted).
    pub fn without_effect(&self, id: EffectId) -> Result<Self, EffectError> {
        if self.effect(id).is_none() {
            return Err(EffectError::NotApplied { effect: id.name().to_owned() });
        }
        let mut model = self.clone();
        model.effects.retain(|e| e.id() != id);
        Ok(model)
    }

    /// Channels every run must carry for this model, besides its input and output.
    pub fn required_channels(&self) -> Vec<&'static str> {
        self.effects.iter().flat_map(|e| e.required_channels().iter().copied()).collect()
    }

    /// Poles and zeros of the linear block.
    pub fn roots(&self) -> Result<(Vec<Complex64>, Vec<Complex64>), EffectError> {
        let tf = &self.wiener.linear.tf;
        let bad =
            |e: crate::core::numerics::poly::PolyError| EffectError::BadBaseModel { reason: e.to_string() };
        Ok((tf.poles().map_err(bad)?, tf.zeros().map_err(bad)?))
    }

    /// Simulate the output from the run's input (and the channels the effects need) alone.
    pub fn simulate(&self, run: &Run) -> Result<Vec<f64>, EffectError> {
        Ok(self.simulate_with_v(run)?.1)
    }

    /// Simulate a run to score it: from the steady state of its first input, or with the linear
    /// block's free response that best fits the first seconds of the measured output (see
    /// `core::identification::initial_state`). A run without the model's output is simulated from the steady state.
    pub fn simulate_scored(&self, run: &Run, initial: InitialState) -> Result<Vec<f64>, EffectError> {
        let measured = run.output(&self.output).map(|c| c.values.as_slice());
        let (InitialState::Estimated, Some(y)) = (initial, measured) else { return self.simulate(run) };
        let (_, conditions) = input_stage(&self.effects, run)?;
        let (v, _) = self.simulate_with_v(run)?;
        let (poles, _) = self.roots()?;
        let dt = run.dt_secs;
        let output = |v: &[f64]| output_stage(&self.effects, &self.wiener.map, v, conditions.as_ref(), dt);
        let v = fit_free_response(&poles, &v, y, output);
        Ok(output(&v))
    }

    /// Simulate and also return the linear block's output `v` (what the static map reads).
    pub fn simulate_with_v(&self, run: &Run) -> Result<(Vec<f64>, Vec<f64>), EffectError> {
        let (mut u, conditions) = input_stage(&self.effects, run)?;
        let split = if needs_split(&self.effects) {
            let (poles, zeros) = self.roots()?;
            Some(AsymmetricDynamics::split(&poles, &zeros, run.dt_secs)?)
        } else {
            None
        };
        let limit = self.state_limit(run.dt_secs)?;
        // The map is cloned for the power balance only, which reads the spool through it.
        let balance = matches!(
            self.effect(EffectId::ScheduledTimeConstant),
            Some(EffectBlock::ScheduledTimeConstant(s)) if s.is_power_balance()
        );
        let through = balance.then(|| self.through());
        let linear = |u: &[f64]| {
            let stage = &self.wiener.linear;
            linear_stage(
                &self.effects,
                stage,
                split.as_ref(),
                u,
                limit.clone(),
                through.as_ref(),
                run.dt_secs,
            )
        };
        let mut v = linear(&u)?;
        let offset = self.calibration_offset(run, &u, &v, conditions.as_ref());
        if offset != 0.0 {
            u.iter_mut().for_each(|x| *x += offset);
            v = linear(&u)?;
        }
        let y = output_stage(&self.effects, &self.wiener.map, &v, conditions.as_ref(), run.dt_secs);
        Ok((v, y))
    }
}

impl ExtendedModel {
    /// The model's rate limit as its spool section applies it, with samples of `dt_secs`.
    fn state_limit(&self, dt_secs: f64) -> Result<Option<StateLimit>, EffectError> {
        let Some(limit) = rate_limit(&self.effects) else { return Ok(None) };
        let linear = &self.wiener.linear;
        let gain = linear.tf.dc_gain().map_err(|e| EffectError::BadBaseModel { reason: e.to_string() })?;
        let through_map = self.limits_own_rate();
        Ok(Some(limit.on_state(through_map, dt_secs, gain, linear.offset, &self.wiener.map, self.kink())))
    }

    /// The linear block's way to the static map, which the power balance reads the spool through.
    fn through(&self) -> Through {
        Through {
            gain: 1.0,
            offset: self.wiener.linear.offset,
            map: self.wiener.map.clone(),
            kink: self.kink().cloned(),
        }
    }

    /// The spool's time-constant factor in steady state at input `u` (state and target both at
    /// `u`): 1 without a scheduled time constant. What the local models at operating points use.
    pub fn steady_spool_factor(&self, u: f64) -> f64 {
        let Some(EffectBlock::ScheduledTimeConstant(s)) = self.effect(EffectId::ScheduledTimeConstant) else {
            return 1.0;
        };
        let balance = self.wiener.linear.tf.dc_gain().ok().filter(|_| s.is_power_balance()).map(|gain| {
            let t = self.through();
            PowerBalance::new(gain, t.offset, t.map, t.kink, s.load_exponent, s.ref_input)
        });
        s.factor_through(u, u, balance.as_ref())
    }

    /// Whether the model's rate limit is read through its static map (a limit on the shaft speed's
    /// own rate, [`super::rate_limit::limits_own_rate`]): a speed model's, and the speed model's
    /// path that an output read off the speed holds.
    pub fn limits_own_rate(&self) -> bool {
        super::rate_limit::limits_own_rate(&self.output) || self.read_off().is_some()
    }

    /// The output at the steady state of a constant input `u` (as the input stage leaves it): the
    /// static map and its kink at the linear block's steady `v`, read off the speed where the model
    /// is; `None` without a steady state.
    pub fn steady_output(&self, u: f64) -> Option<f64> {
        let linear = &self.wiener.linear;
        Some(self.static_output(linear.tf.dc_gain().ok()? * u + linear.offset))
    }

    /// The static map and its kink, when the model has one, at `v` (for a model read off the speed,
    /// the speed).
    pub fn map_with_kink(&self, v: f64) -> f64 {
        self.wiener.map.eval(v) + self.kink().map_or(0.0, |k| k.eval(v))
    }

    /// The output in steady state at `v`: [`Self::map_with_kink`], then read off the speed where the
    /// model is.
    pub fn static_output(&self, v: f64) -> f64 {
        let y = self.map_with_kink(v);
        self.read_off().map_or(y, |r| r.eval(y))
    }

    /// d[`Self::static_output`]/dv at `v`: the map's slope with its kink's, times the read-off's
    /// slope at the steady speed where the model is read off the speed (the chain rule).
    pub fn static_slope(&self, v: f64) -> f64 {
        let kink = self.kink().map_or(0.0, |k| if v > k.knot_v { k.slope_change } else { 0.0 });
        let slope = self.wiener.map.slope(v) + kink;
        self.read_off().map_or(slope, |r| slope * r.slope(self.map_with_kink(v)))
    }

    /// The read-off of the speed, when the output is read off the shaft speed's model.
    pub fn read_off(&self) -> Option<&ReadOffSpeed> {
        self.effects.iter().find_map(|e| match e {
            EffectBlock::ReadOffSpeed(r) => Some(r),
            _ => None,
        })
    }

    /// The inputs (as the input stage leaves them) whose steady states span the range the static
    /// map was identified on, lowest first; `None` for a map without one or no steady state.
    pub fn identified_inputs(&self) -> Option<(f64, f64)> {
        let (lo, hi) = self.wiener.map.identified_range()?;
        let linear = &self.wiener.linear;
        let gain = linear.tf.dc_gain().ok().filter(|g| g.is_finite() && *g != 0.0)?;
        let (a, b) = ((lo - linear.offset) / gain, (hi - linear.offset) / gain);
        Some((a.min(b), a.max(b)))
    }

    /// The static map's kink, when the model has one.
    fn kink(&self) -> Option<&StaticMapOrder> {
        kink(&self.effects)
    }

    /// What the rate limit of a model of this output limits, over a simulation's `v`: the output's
    /// static map (with its kink) for the shaft speed, `v` itself otherwise (see
    /// [`super::rate_limit::limits_own_rate`]).
    pub(super) fn rate_limited_quantity(&self, v: &[f64]) -> Vec<f64> {
        if !self.limits_own_rate() {
            return v.to_vec();
        }
        v.iter().map(|x| self.map_with_kink(*x)).collect()
    }

    /// The input offset a [`CalibrationDrift`](super::CalibrationDrift) block gives this run (from the run's own steady
    /// holds of the measured output); zero without the block, the output or a usable linear block.
    /// `u` is the input as the linear block sees it and `v` the linear block's response to it.
    pub fn calibration_offset(
        &self,
        run: &Run,
        u: &[f64],
        v: &[f64],
        conditions: Option<&Conditions>,
    ) -> f64 {
        let Some(EffectBlock::CalibrationDrift(block)) = self.effect(EffectId::CalibrationDrift) else {
            return 0.0;
        };
        let (Some(y), Ok(dc)) = (run.output(&self.output), self.wiener.linear.tf.dc_gain()) else {
            return 0.0;
        };
        let response = |b: f64| {
            let shifted: Vec<f64> = v.iter().map(|x| x + dc * b).collect();
            output_stage(&self.effects, &self.wiener.map, &shifted, conditions, run.dt_secs)
        };
        block.run_offset(u, &y.values, run.dt_secs, response)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::core::effects::{AmbientCorrection, ThermalSoak, TransportDelay};
    use crate::core::identification::static_map::StaticMap;
    use crate::core::identification::wiener::LinearBlock;
    use crate::core::identification::wiener::unit_gain_tf;
    use crate::core::run::Channel;

    fn model() -> ExtendedModel {
        let tf = unit_gain_tf(&[Complex64::new(0.9, 0.0)], &[], 0.1).unwrap();
        let map = StaticMap { coeffs_scaled: vec![1.0, 2.0], ..StaticMap::identity() };
        ExtendedModel::new("thrust_n", WienerModel { linear: LinearBlock { tf, offset: 0.5 }, map })
    }

    fn run(n: usize) -> Run {
        Run {
            name: "bench".into(),
            dt_secs: 0.1,
            t_secs: (0..n).map(|k| k as f64 * 0.1).collect(),
            input: Channel::new("fuel_flow_gph", (0..n).map(|k| if k < 20 { 3.0 } else { 5.0 }).collect()),
            outputs: vec![],
            aux: vec![],
        }
    }

    #[test]
    fn no_effect_simulates_like_the_wiener_model_and_effects_compose() {
        let m = model();
        let r = run(100);
        let plain = m.simulate(&r).unwrap();
        assert_eq!(plain, m.wiener.simulate(&r.input.values).1);
        let soaked = m
            .with_effect(EffectBlock::ThermalSoak(ThermalSoak { gain: 0.2, tau_s: 5.0, power_exponent: 0.0 }))
            .unwrap();
        let both =
            soaked.with_effect(EffectBlock::TransportDelay(TransportDelay { delay_samples: 3.0 })).unwrap();
        assert_eq!(both.effect_ids(), vec![EffectId::CATALOG[0], EffectId::CATALOG[1]]);
        let y = both.simulate(&r).unwrap();
        assert!((y[22] - plain[0]).abs() < 1e-12, "the delay holds the start");
        assert!(y[60] < plain[60], "the soak slows the rise");
        let back = ExtendedModel::from_records("thrust_n", m.wiener.clone(), &both.records()).unwrap();
        assert_eq!(back, both);
    }

    #[test]
    fn misuse_is_an_error_with_data() {
        let m =
            model().with_effect(EffectBlock::TransportDelay(TransportDelay { delay_samples: 1.0 })).unwrap();
        assert_eq!(
            m.with_effect(EffectBlock::TransportDelay(TransportDelay { delay_samples: 2.0 })),
            Err(EffectError::AlreadyApplied { effect: EffectId::TransportDelay.name().into() })
        );
        assert_eq!(
            m.without_effect(EffectId::ThermalSoak),
            Err(EffectError::NotApplied { effect: EffectId::ThermalSoak.name().into() })
        );
        assert!(
            matches!("warp".parse::<EffectId>(), Err(EffectError::UnknownEffect { known, .. }) if known.len() == EffectId::ALL.len())
        );
        let ambient = model().with_effect(EffectBlock::AmbientCorrection(AmbientCorrection {
            output_theta_exp: 0.0,
            output_delta_exp: 1.0,
        }));
        assert_eq!(ambient.as_ref().unwrap().required_channels(), AmbientCorrection::CHANNELS.to_vec());
        assert_eq!(
            ambient.unwrap().simulate(&run(10)),
            Err(EffectError::MissingChannel {
                effect: EffectId::AmbientCorrection.name().into(),
                channel: "ambient_temp_c".into(),
                run: "bench".into()
            })
        );
        let too_fast = EffectBlock::SensorDynamics(SensorDynamics { freq_hz: 6.0, zeta: 0.1, lag_s: 0.0 });
        assert!(matches!(model().with_effect(too_fast), Err(EffectError::ParameterOutOfRange { .. })));
    }
}
