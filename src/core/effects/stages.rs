//! The signal path of an [`ExtendedModel`](super::ExtendedModel), stage by stage: the input stage
//! (inlet correction, dead time), the linear stage (the linear block, or the spool split off it
//! with its asymmetry, schedule and rate limit, and the soak branch) and the output stage (the
//! static map and its kink, the soak on the output's power, the inlet factor, the sensor, the
//! read-off of the speed). The model and the fits both run them.
use super::ambient_correction::Conditions;
use super::power_balance::PowerBalance;
use super::rate_limit::StateLimit;
use super::scheduled_time_constant::{ScheduledTimeConstant, Section};
use super::spool::SplitShape;
use super::{
    AmbientCorrection, AsymmetricDynamics, EffectBlock, EffectError, RateLimit, StaticMapOrder,
    TransportDelay,
};
use crate::core::identification::static_map::StaticMap;
use crate::core::identification::wiener::LinearBlock;
use crate::core::numerics::tf::DiscreteTf;
use crate::core::run::Run;

/// The input as the linear block sees it: corrected for inlet conditions, then delayed. Also
/// returns the conditions when the model is corrected.
pub(super) fn input_stage(
    effects: &[EffectBlock],
    run: &Run,
) -> Result<(Vec<f64>, Option<Conditions>), EffectError> {
    let mut u = run.input.values.clone();
    let mut conditions = None;
    for effect in effects {
        match effect {
            EffectBlock::AmbientCorrection(_) => {
                let c = AmbientCorrection::conditions(run)?;
                u = AmbientCorrection::correct_input(&u, &c);
                conditions = Some(c);
            }
            EffectBlock::TransportDelay(d) => u = d.delay(&u),
            _ => {}
        }
    }
    Ok((u, conditions))
}

/// Whether the blocks act on the spool pole split off the linear block (asymmetric dynamics, a
/// scheduled time constant, a rate limit).
pub(super) fn needs_split(effects: &[EffectBlock]) -> bool {
    effects.iter().any(|e| {
        matches!(
            e,
            EffectBlock::AsymmetricDynamics(_)
                | EffectBlock::ScheduledTimeConstant(_)
                | EffectBlock::RateLimit(_)
        )
    })
}

/// `v`: the linear block (with rise/fall time constants when asymmetric, the spool time constant
/// following the operating point when scheduled, the spool's state rate-limited by `limit`) and the
/// soak branch. `split` must be given when [`needs_split`].
pub(super) fn linear_stage(
    effects: &[EffectBlock],
    linear: &LinearBlock,
    split: Option<&SplitShape>,
    u: &[f64],
    limit: Option<StateLimit>,
    through: Option<&Through>,
    dt_secs: f64,
) -> Result<Vec<f64>, EffectError> {
    let stage = StageInput { effects, linear, split, u, limit, through };
    linear_stages(&[stage], dt_secs).pop().unwrap_or_else(|| Ok(Vec::new()))
}

/// What [`linear_stage`] takes, for [`linear_stages`].
pub(super) struct StageInput<'a> {
    pub effects: &'a [EffectBlock],
    pub linear: &'a LinearBlock,
    pub split: Option<&'a SplitShape>,
    pub u: &'a [f64],
    /// The rate limit on the spool's state (the fit's first pass, which finds the gain and the map
    /// the limit is read through, has none).
    pub limit: Option<StateLimit>,
    /// The gain, offset and map the spool's power balance is read through, when the schedule is
    /// the physical one (the fit's first pass has none).
    pub through: Option<&'a Through>,
}

/// The linear stage's way to the output: `N = f(gain·w + offset)` with the map's kink, `w` the
/// stage's response before its offset.
#[derive(Clone, Debug)]
pub(super) struct Through {
    pub gain: f64,
    pub offset: f64,
    pub map: StaticMap,
    pub kink: Option<StaticMapOrder>,
}

/// How one [`StageInput`] is simulated: its whole linear block, or the spool split off it (with the
/// block's gain, and the input delayed by the block's dead time, which the split's roots lack).
enum Path<'a> {
    Block,
    Spool {
        split: &'a SplitShape,
        gain: f64,
        delayed: Vec<f64>,
        asymmetric: Option<&'a AsymmetricDynamics>,
        scheduled: Option<&'a ScheduledTimeConstant>,
        limit: Option<StateLimit>,
        power: Option<Box<PowerBalance>>,
    },
}

/// [`linear_stage`] of several inputs, their simulations stepped side by side
/// ([`DiscreteTf::simulate_each_from_steady`], [`super::scheduled_time_constant::respond_each`]):
/// what a finite-difference Jacobian's columns ask for. Each result is the one [`linear_stage`]
/// gives alone, bit for bit.
pub(super) fn linear_stages(stages: &[StageInput], dt_secs: f64) -> Vec<Result<Vec<f64>, EffectError>> {
    let paths: Vec<Result<Path, EffectError>> = stages.iter().map(path).collect();
    // The linear simulations first: each whole block, or each spool's rest.
    let blocks: Vec<(&DiscreteTf, &[f64])> = stages
        .iter()
        .zip(&paths)
        .filter_map(|(stage, path)| match path {
            Ok(Path::Block) => Some((&stage.linear.tf, stage.u)),
            Ok(Path::Spool { split, delayed, .. }) => Some((split.rest.as_ref()?, delayed.as_slice())),
            Err(_) => None,
        })
        .collect();
    let mut simulated = DiscreteTf::simulate_each_from_steady(&blocks).into_iter();
    let mut responses: Vec<Option<Vec<f64>>> = Vec::with_capacity(stages.len());
    let mut sections = Vec::new();
    for path in &paths {
        match path {
            Ok(Path::Block) => responses.push(simulated.next()),
            Ok(Path::Spool { split, delayed, asymmetric, scheduled, limit, power, .. }) => {
                let r = match split.rest {
                    Some(_) => simulated.next().unwrap_or_default(),
                    None => delayed.clone(),
                };
                sections.push(Section {
                    shape: split,
                    r,
                    asymmetric: *asymmetric,
                    scheduled: *scheduled,
                    limit: limit.clone(),
                    power: power.as_deref().cloned(),
                });
                responses.push(None);
            }
            Err(_) => responses.push(None),
        }
    }
    let mut spooled = super::scheduled_time_constant::respond_each(sections).into_iter();
    stages
        .iter()
        .zip(paths)
        .zip(responses)
        .map(|((stage, path), response)| {
            let mut v = match path? {
                Path::Block => response.unwrap_or_default(),
                Path::Spool { gain, .. } => {
                    spooled.next().unwrap_or_default().iter().map(|w| gain * w).collect()
                }
            };
            for effect in stage.effects {
                if let EffectBlock::ThermalSoak(soak) = effect
                    && !soak.on_output()
                {
                    v = soak.apply(&v, dt_secs);
                }
            }
            for x in &mut v {
                *x += stage.linear.offset;
            }
            Ok(v)
        })
        .collect()
}

/// How `stage` is simulated: through the spool when it is split and an effect acts on the spool.
fn path<'a>(stage: &StageInput<'a>) -> Result<Path<'a>, EffectError> {
    let asymmetric = stage.effects.iter().find_map(|e| match e {
        EffectBlock::AsymmetricDynamics(a) => Some(a),
        _ => None,
    });
    let scheduled = stage.effects.iter().find_map(|e| match e {
        EffectBlock::ScheduledTimeConstant(s) => Some(s),
        _ => None,
    });
    match stage.split.filter(|_| asymmetric.is_some() || scheduled.is_some() || stage.limit.is_some()) {
        Some(split) => {
            let gain =
                stage.linear.tf.dc_gain().map_err(|e| EffectError::BadBaseModel { reason: e.to_string() })?;
            // The split is built from the roots alone; the block's dead time delays its input.
            let delay_samples = stage.linear.tf.input_delay() as f64;
            let delayed = TransportDelay { delay_samples }.delay(stage.u);
            let power = scheduled.filter(|s| s.is_power_balance()).zip(stage.through).map(|(s, t)| {
                PowerBalance::new(
                    t.gain * gain,
                    t.offset,
                    t.map.clone(),
                    t.kink.clone(),
                    s.load_exponent,
                    s.ref_input,
                )
            });
            let power = power.map(Box::new);
            Ok(Path::Spool { split, gain, delayed, asymmetric, scheduled, limit: stage.limit.clone(), power })
        }
        None => Ok(Path::Block),
    }
}

/// The rate limit among the blocks, if any. It acts on the spool's state in units that need the
/// gain and the map (see [`RateLimit::on_state`]), so the fit finds those first without it.
pub(super) fn rate_limit(effects: &[EffectBlock]) -> Option<&RateLimit> {
    effects.iter().find_map(|e| match e {
        EffectBlock::RateLimit(r) => Some(r),
        _ => None,
    })
}

/// The ambient correction among the blocks, if any.
fn ambient(effects: &[EffectBlock]) -> Option<&AmbientCorrection> {
    effects.iter().find_map(|e| match e {
        EffectBlock::AmbientCorrection(a) => Some(a),
        _ => None,
    })
}

/// The static map's kink among the blocks, if any.
pub(super) fn kink(effects: &[EffectBlock]) -> Option<&StaticMapOrder> {
    effects.iter().find_map(|e| match e {
        EffectBlock::StaticMapOrder(k) => Some(k),
        _ => None,
    })
}

/// `y`: the static map (with its kink), back to physical units, through the sensor (and read off
/// the speed, for a model that is).
pub(super) fn output_stage(
    effects: &[EffectBlock],
    map: &StaticMap,
    v: &[f64],
    conditions: Option<&Conditions>,
    dt_secs: f64,
) -> Vec<f64> {
    let kink = kink(effects);
    let mut y: Vec<f64> = v.iter().map(|vk| map.eval(*vk) + kink.map_or(0.0, |k| k.eval(*vk))).collect();
    for effect in effects {
        match (effect, conditions) {
            (EffectBlock::ThermalSoak(soak), _) if soak.on_output() => y = soak.apply_to_power(&y, dt_secs),
            (EffectBlock::AmbientCorrection(a), Some(c)) => {
                for (yk, f) in y.iter_mut().zip(a.output_factor(c)) {
                    *yk *= f;
                }
            }
            (EffectBlock::SensorDynamics(s), _) => y = s.apply(&y, dt_secs),
            (EffectBlock::ReadOffSpeed(r), c) => r.apply(&mut y, ambient(effects).zip(c)),
            _ => {}
        }
    }
    y
}
