//! Fitting effect blocks on the identification data.
//!
//! Every fit uses the pipeline's own construction, so a model and its extension are compared on
//! equal terms: for given poles, zeros and effect parameters the unit-gain response `w` is
//! simulated, gain and offset come from least squares of the (corrected) output on `w`, and the
//! static map of the model's order is fitted to the steady-state points (pre-step baseline and
//! settled tail of every segment). Levenberg–Marquardt then moves the poles, zeros and the effects'
//! continuous parameters together to minimise the simulation error on the identification range
//! (variable projection, as `core::identification::refine` does for the base model). Discrete choices — the delay
//! in samples, the starting point of every other parameter — are screened on that same error first.
//! [`refine`] holds the Levenberg–Marquardt step, [`search`] the screening when one block is added.
use std::borrow::Cow;

use num_complex::Complex64;

use super::model::ExtendedModel;
use super::stages::{
    StageInput, input_stage, linear_stage, linear_stages, needs_split, output_stage, rate_limit,
};
use super::static_map_order::fit_map_with_knot;
use super::stats::mean;
use super::{AsymmetricDynamics, EffectBlock, EffectError, SensorDynamics, limits_own_rate};
use crate::core::identification::wiener::{LinearBlock, WienerModel, unit_gain_tf};
use crate::core::numerics::tf::{DiscreteTf, alternates_sign};

mod data;
mod memo;
mod refine;
mod search;

pub use data::{FOLDS, FitData, MIN_HELD_OUT_SEGMENTS};
pub(super) use refine::refine;
use refine::{has_negative_real_pole, refine_admissible};
pub use search::apply_effect;

/// Starting points refined by Levenberg–Marquardt after screening.
pub(super) const REFINED_STARTS: usize = 2;

/// What the fit moves: roots, effects (with their current parameters) and the map order.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Structure {
    pub(super) poles: Vec<Complex64>,
    pub(super) zeros: Vec<Complex64>,
    pub(super) effects: Vec<EffectBlock>,
    pub(super) map_order: usize,
    /// Input dead time of the linear block beyond what its roots give, samples (kept as it is).
    pub(super) delay: usize,
}

/// A fitted model with its residual on the identification data.
pub(super) struct Assembled {
    pub(super) model: ExtendedModel,
    pub(super) structure: Structure,
    pub(super) residual: Vec<f64>,
    pub(super) cost: f64,
}

impl Structure {
    /// The structure of `model`, to be fitted on its output's data. A model read off the shaft
    /// speed's model is the speed's, fitted where the speed is measured: it is refused.
    pub(super) fn of(model: &ExtendedModel) -> Result<Self, EffectError> {
        if model.read_off().is_some() {
            return Err(EffectError::NotApplicable {
                effect: super::EffectId::ReadOffSpeed.name().to_owned(),
                reason: format!(
                    "'{}' is read off the shaft speed's model, whose blocks are fitted on the speed: it \
                     changes with the speed's model",
                    model.output
                ),
            });
        }
        let (poles, zeros) = model.roots()?;
        Ok(Self {
            poles,
            zeros,
            effects: model.effects.clone(),
            map_order: model.wiener.map.order().max(1),
            delay: model.wiener.linear.tf.input_delay(),
        })
    }

    fn with(&self, block: EffectBlock) -> Self {
        let mut s = self.clone();
        s.effects.retain(|e| e.id() != block.id());
        s.effects.push(block);
        s.effects.sort_by_key(EffectBlock::rank);
        s
    }
}

/// Gain, offset and static map for a structure; its simulation error on the data.
pub(super) fn assemble(s: &Structure, data: &FitData) -> Option<Assembled> {
    assemble_from(s, data, &linear_part(s, data)?)
}

/// What a structure's simulation gives before its output stage: the unit-gain linear block (its
/// roots and dead time), the ambient conditions, and `w`, the response of the blocks that act on
/// the input and the spool ([`EffectBlock::shapes_linear_part`]) to the data's input. Two
/// structures that differ only in their other blocks' parameters share it (see `fit::memo`).
pub(super) struct LinearPart {
    unit: DiscreteTf,
    conditions: Option<super::ambient_correction::Conditions>,
    w: Vec<f64>,
}

pub(super) fn linear_part(s: &Structure, data: &FitData) -> Option<LinearPart> {
    linear_parts(&[s], data).pop().flatten()
}

/// [`linear_part`] of several structures, their simulations stepped side by side
/// ([`linear_stages`]); each the one [`linear_part`] gives alone, bit for bit.
pub(super) fn linear_parts(structures: &[&Structure], data: &FitData) -> Vec<Option<LinearPart>> {
    let dt = data.dt_secs;
    let prepared: Vec<Option<Prepared>> = structures.iter().map(|s| Prepared::of(s, data)).collect();
    let stages: Vec<StageInput> = structures
        .iter()
        .zip(&prepared)
        .filter_map(|(s, p)| {
            let p = p.as_ref()?;
            Some(StageInput {
                effects: &s.effects,
                linear: &p.block,
                split: p.split.as_ref(),
                u: &p.u,
                limit: None,
                through: None,
            })
        })
        .collect();
    let mut ws = linear_stages(&stages, dt).into_iter();
    prepared
        .into_iter()
        .map(|p| {
            let p = p?;
            let w = ws.next()?.ok()?;
            Some(LinearPart { unit: p.block.tf, conditions: p.conditions, w })
        })
        .collect()
}

/// A structure's unit-gain block, its input after the input stage, and its spool split.
struct Prepared {
    block: LinearBlock,
    u: Vec<f64>,
    conditions: Option<super::ambient_correction::Conditions>,
    split: Option<super::spool::SplitShape>,
}

impl Prepared {
    fn of(s: &Structure, data: &FitData) -> Option<Self> {
        let dt = data.dt_secs;
        let unit = unit_gain_tf(&s.poles, &s.zeros, dt).ok()?.with_input_delay(s.delay);
        let (u, conditions) = input_stage(&s.effects, &data.run).ok()?;
        let split = match needs_split(&s.effects) {
            true => Some(AsymmetricDynamics::split(&s.poles, &s.zeros, dt).ok()?),
            false => None,
        };
        Some(Self { block: LinearBlock { tf: unit, offset: 0.0 }, u, conditions, split })
    }
}

/// The measured output as the static map gives it, before the blocks after the map: the inlet
/// conditions' factor divided out, and a soak on the output's power undone (the gain, offset and
/// map read `v`, which carries neither).
fn what_the_map_gives<'y>(
    s: &Structure,
    data: &'y FitData,
    conditions: Option<&super::ambient_correction::Conditions>,
) -> Cow<'y, [f64]> {
    let factor: Option<Vec<f64>> = s.effects.iter().find_map(|e| match (e, conditions) {
        (EffectBlock::AmbientCorrection(a), Some(c)) => Some(a.output_factor(c)),
        _ => None,
    });
    let y_c: Cow<[f64]> = match &factor {
        Some(f) => data.y.iter().zip(f).map(|(y, f)| y / f).collect(),
        None => Cow::Borrowed(&data.y),
    };
    let soak = s.effects.iter().find_map(|e| match e {
        EffectBlock::ThermalSoak(soak) if soak.on_output() => Some(soak),
        _ => None,
    });
    match soak {
        Some(soak) => Cow::Owned(soak.undo_on_power(&y_c, data.dt_secs)),
        None => y_c,
    }
}

/// [`assemble`] from the structure's [`LinearPart`] (which must be `s`'s own, or that of a
/// structure with the same roots, dead time and blocks that shape it).
pub(super) fn assemble_from(s: &Structure, data: &FitData, part: &LinearPart) -> Option<Assembled> {
    let dt = data.dt_secs;
    let (unit, conditions) = (&part.unit, &part.conditions);
    let y_c = what_the_map_gives(s, data, conditions.as_ref());
    let sensor = s.effects.iter().find_map(|e| match e {
        EffectBlock::SensorDynamics(sd) => Some(sd),
        _ => None,
    });
    // What the sensor sees of `w`: `w` itself without the stand's dynamics.
    fn seen<'w>(sensor: Option<&SensorDynamics>, w: &'w [f64], dt: f64) -> Cow<'w, [f64]> {
        match sensor {
            Some(sensor) => Cow::Owned(sensor.apply(w, dt)),
            None => Cow::Borrowed(w),
        }
    }
    let mut w = Cow::Borrowed(part.w.as_slice());
    let (gain, offset) = data.fit_gain_offset(&seen(sensor, &w, dt), &y_c)?;
    let knot = super::stages::kink(&s.effects).map(|k| k.knot_v);
    let steady = |v: &[f64]| -> (Vec<f64>, Vec<f64>) {
        data.steady_windows
            .iter()
            .filter_map(|&(a, b)| Some((mean(v.get(a..b)?), mean(y_c.get(a..b)?))))
            .unzip()
    };
    let power =
        s.effects.iter().any(|e| matches!(e, EffectBlock::ScheduledTimeConstant(s) if s.is_power_balance()));
    if power || rate_limit(&s.effects).is_some() {
        // The limit is on the spool's state in units the gain and the map give (see
        // `RateLimit::on_state`), and the power balance reads the spool's speed through the map
        // (see `PowerBalance`): both from the response without them first (a limit binds on the
        // transients, and a schedule changes only them, so the settled values the map is fitted on
        // are the same with them), then the response again with them in the spool. Gain and offset
        // are not refitted after: the map's refit below takes up any affine change of `v`.
        let v: Vec<f64> = w.iter().map(|wk| gain * wk + offset).collect();
        let (vs, ys) = steady(&v);
        let (map, slope_change) = fit_map_with_knot(&vs, &ys, s.map_order, knot)?;
        let kink = knot.map(|knot_v| super::StaticMapOrder { knot_v, slope_change });
        let state = rate_limit(&s.effects).map(|limit| {
            limit.on_state(limits_own_rate(&data.output), dt, gain, offset, &map, kink.as_ref())
        });
        let through = super::stages::Through { gain, offset, map, kink };
        w = Cow::Owned(second_pass_response(s, data, state, power.then_some(&through))?);
    }
    let v: Vec<f64> = w.iter().map(|wk| gain * wk + offset).collect();
    let (vs, ys) = steady(&v);
    let mut structure = s.clone();
    let (map, slope_change) = fit_map_with_knot(&vs, &ys, s.map_order, knot)?;
    for e in &mut structure.effects {
        if let EffectBlock::StaticMapOrder(k) = e {
            k.slope_change = slope_change;
        }
    }
    let num = unit.num_zinv.iter().map(|b| b * gain).collect();
    let tf = DiscreteTf::new(num, unit.den_zinv.clone(), dt).ok()?;
    let y_hat = output_stage(&structure.effects, &map, &v, conditions.as_ref(), dt);
    let mut residual: Vec<f64> = y_hat.iter().zip(&data.y).map(|(a, b)| a - b).collect();
    let n = residual.len();
    for &(a, b) in &data.held_out {
        residual.get_mut(a.min(n)..b.min(n)).into_iter().flatten().for_each(|r| *r = 0.0);
    }
    let cost: f64 = residual.iter().map(|r| r * r).sum();
    if !cost.is_finite() {
        return None;
    }
    let model = ExtendedModel {
        output: data.output.clone(),
        wiener: WienerModel { linear: LinearBlock { tf, offset }, map },
        effects: structure.effects.clone(),
    };
    Some(Assembled { model, structure, residual, cost })
}

/// The unit-gain response of `s` with its spool's state limited by `limit` and its power balance
/// read `through` the first pass's map (see [`linear_parts`], whose first pass has neither).
fn second_pass_response(
    s: &Structure,
    data: &FitData,
    limit: Option<super::rate_limit::StateLimit>,
    through: Option<&super::stages::Through>,
) -> Option<Vec<f64>> {
    let p = Prepared::of(s, data)?;
    linear_stage(&s.effects, &p.block, p.split.as_ref(), &p.u, limit, through, data.dt_secs).ok()
}

impl FitData {
    /// [`fit_gain_offset`] over the fitted samples only.
    fn fit_gain_offset(&self, w: &[f64], y: &[f64]) -> Option<(f64, f64)> {
        if self.held_out.is_empty() {
            return fit_gain_offset(w, y);
        }
        let (w, y): (Vec<f64>, Vec<f64>) = w
            .iter()
            .zip(y)
            .enumerate()
            .filter(|(k, _)| self.is_fitted(*k))
            .map(|(_, (a, b))| (*a, *b))
            .unzip();
        fit_gain_offset(&w, &y)
    }
}

/// Least squares of `y ≈ gain·w + offset`: one Gram–Schmidt step of the QR factorisation of
/// `[1, w]` (centre, then project), so no normal equations are formed. `None` when `w` is constant.
fn fit_gain_offset(w: &[f64], y: &[f64]) -> Option<(f64, f64)> {
    let (mw, my) = (mean(w), mean(y));
    let (mut sww, mut swy) = (0.0, 0.0);
    for (wk, yk) in w.iter().zip(y) {
        sww += (wk - mw) * (wk - mw);
        swy += (wk - mw) * (yk - my);
    }
    let scale = w.iter().map(|x| x * x).sum::<f64>();
    if sww <= f64::EPSILON * scale.max(f64::MIN_POSITIVE) * w.len() as f64 {
        return None;
    }
    let gain = swy / sww;
    Some((gain, my - gain * mw))
}

/// Refit every parameter of the model's structure (roots, effect parameters, gain, offset, static
/// map) on the identification data; discrete choices (the delay) stay as they are. Never worse on
/// the identification data than the model itself, refitted statically.
pub fn refit(model: &ExtendedModel, data: &FitData) -> Result<ExtendedModel, EffectError> {
    let start = Structure::of(model)?;
    check_channels(&start, data)?;
    let failed =
        || EffectError::FitFailed { run: data.run.name.clone(), reason: "no admissible fit".to_owned() };
    let best = [refine(&start, data), assemble(&start, data)]
        .into_iter()
        .flatten()
        .min_by(|a, b| a.cost.total_cmp(&b.cost))
        .ok_or_else(failed)?;
    Ok(best.model)
}

/// Share of the identification error a sample-alternating pole must remove, against the admissible
/// fit, to be kept: the share the parsimony rule asks of a root
/// (`identification::parsimony::MIN_RELATIVE_REDUCTION`), but of the whole RMS error, noise
/// included, so it asks more: the pole costs the controller designer the continuous-time model,
/// which an extra root does not.
pub const ALTERNATING_POLE_SHARE: f64 = 0.10;

/// What [`admissible`] did with a model's sample-alternating poles.
#[derive(Clone, Debug)]
pub enum Alternating {
    /// The admissible fit replaced the model; the alternating poles it had.
    Replaced { model: ExtendedModel, poles: Vec<f64> },
    /// The model keeps its alternating poles: the admissible fit leaves `more_error` times its RMS
    /// identification error (at least `1/(1 − ALTERNATING_POLE_SHARE)`), or none could be had.
    Kept { poles: Vec<f64>, more_error: Option<f64> },
}

/// `model` with no real pole on the negative real axis, when it has one (`None` when it has none).
///
/// Such a pole alternates sign every sample, which no engine sampled behind a zero-order hold
/// does: the local models a controller is designed on zig-zag and have no continuous-time form.
/// The effect fits may grow one (a pole pair that splits into two real poles), because what it does
/// for the fit is a phase lead of a fraction of a sample. The admissible fit gives that lead with a
/// zero instead and keeps real poles positive (see `refine::refine_admissible`). It replaces the
/// model unless the alternating pole removes [`ALTERNATING_POLE_SHARE`] of the RMS error the
/// admissible fit leaves: then the data can only be reached with it, and it is kept and named.
pub fn admissible(model: &ExtendedModel, data: &FitData) -> Result<Option<Alternating>, EffectError> {
    let start = Structure::of(model)?;
    if !has_negative_real_pole(&start.poles) {
        return Ok(None);
    }
    check_channels(&start, data)?;
    let poles: Vec<f64> = start.poles.iter().filter(|p| alternates_sign(**p)).map(|p| p.re).collect();
    let Some(as_is) = assemble(&start, data) else {
        return Ok(Some(Alternating::Kept { poles, more_error: None }));
    };
    Ok(Some(match refine_admissible(&start, data) {
        Some(fit) => {
            let more_error = (fit.cost / as_is.cost.max(f64::MIN_POSITIVE)).sqrt();
            if 1.0 - 1.0 / more_error >= ALTERNATING_POLE_SHARE {
                Alternating::Kept { poles, more_error: Some(more_error) }
            } else {
                Alternating::Replaced { model: fit.model, poles }
            }
        }
        None => Alternating::Kept { poles, more_error: None },
    }))
}

/// Refit gain, offset and static map (and a kink's slope) for the model's dynamics as they are:
/// what changes when the same linear block is used for another output or after a manual edit.
pub fn refit_static(model: &ExtendedModel, data: &FitData) -> Result<ExtendedModel, EffectError> {
    let start = Structure::of(model)?;
    check_channels(&start, data)?;
    assemble(&start, data).map(|a| a.model).ok_or_else(|| EffectError::FitFailed {
        run: data.run.name.clone(),
        reason: "the static map cannot be fitted for these dynamics".to_owned(),
    })
}

/// Fail early, with the run's name, when the data lack a channel the effects need.
fn check_channels(s: &Structure, data: &FitData) -> Result<(), EffectError> {
    input_stage(&s.effects, &data.run).map(|_| ())
}
