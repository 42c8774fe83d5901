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
use num_complex::Complex64;

use super::model::{ExtendedModel, input_stage, linear_stage, needs_split, output_stage};
use super::static_map_order::fit_map_with_knot;
use super::stats::mean;
use super::{
    AmbientCorrection, AsymmetricDynamics, CalibrationDrift, EffectBlock, EffectError, EffectId,
    ScheduledTimeConstant, SensorDynamics, StaticMapOrder, ThermalSoak, TransportDelay,
};
use crate::core::identification::pipeline::{OutputSettings, SegmentFits};
use crate::core::identification::refine::RootParams;
use crate::core::identification::wiener::{LinearBlock, WienerModel, unit_gain_tf};
use crate::core::numerics::lm::{
    Damping, Jacobian, LeastSquares, LmError, LmSettings, StepSolver, minimise, no_progress,
};
use crate::core::numerics::tf::DiscreteTf;
use crate::core::run::{Channel, Run};

/// Starting points refined by Levenberg–Marquardt after screening.
pub(super) const REFINED_STARTS: usize = 2;
/// Screening rounds for blocks with a discrete choice.
const MAX_SCREENING_ROUNDS: usize = 3;
/// Poles must stay inside this radius.
const MAX_POLE_RADIUS: f64 = 0.999;

/// The identification data a model is fitted on: the run over the segments' range, and the
/// steady-state windows inside it.
#[derive(Clone, Debug, PartialEq)]
pub struct FitData {
    /// The output fitted.
    pub output: String,
    /// Sample time, s.
    pub dt_secs: f64,
    /// The identification run cut to the range of the segments.
    pub run: Run,
    /// The output over `run`.
    pub y: Vec<f64>,
    /// Steady-state windows `(start, end)` in `run`.
    pub steady_windows: Vec<(usize, usize)>,
    /// The longest segment's response after its step, s (the slowest dynamics the data can show).
    pub longest_segment_secs: f64,
    /// Highest static-map order the settings allow.
    pub max_static_order: usize,
}

impl FitData {
    /// The data the pipeline fitted `fits` on, for the output of `fits`.
    pub fn new(ident: &Run, fits: &SegmentFits, settings: &OutputSettings) -> Result<Self, EffectError> {
        let failed = |reason: String| EffectError::FitFailed { run: ident.name.clone(), reason };
        let start = fits.segments.first().map_or(0, |s| s.start);
        let end = fits.segments.last().map_or(0, |s| s.end).min(ident.len());
        if end < start + 10 {
            return Err(failed(format!("the segments span only samples {start}..{end}")));
        }
        let run = slice_run(ident, start, end);
        let y = run
            .output(&fits.output)
            .map(|c| c.values.clone())
            .ok_or_else(|| failed(format!("no output column '{}'", fits.output)))?;
        if y.len() != run.len() || run.input.values.len() != run.len() {
            return Err(failed("input, output and time have different lengths".to_owned()));
        }
        let tail = ((settings.settle_secs / ident.dt_secs).round() as usize).max(3);
        let mut steady_windows = Vec::with_capacity(fits.segments.len() + 1);
        if let Some(first) = fits.segments.first() {
            steady_windows.push((0, first.step_at.saturating_sub(start).max(1)));
        }
        for seg in &fits.segments {
            let (a, b) = seg.settled_tail(tail);
            steady_windows.push((a.saturating_sub(start), b.saturating_sub(start).min(y.len())));
        }
        steady_windows.retain(|(a, b)| a < b);
        let longest_segment_secs =
            fits.segments.iter().map(|s| s.end.saturating_sub(s.step_at)).max().unwrap_or(0) as f64
                * ident.dt_secs;
        Ok(Self {
            output: fits.output.clone(),
            dt_secs: ident.dt_secs,
            run,
            y,
            steady_windows,
            longest_segment_secs,
            max_static_order: settings.max_static_order,
        })
    }
}

fn slice_run(run: &Run, start: usize, end: usize) -> Run {
    let cut = |c: &Channel| Channel {
        name: c.name.clone(),
        unit: c.unit.clone(),
        values: c.values.get(start..end).map(<[f64]>::to_vec).unwrap_or_default(),
    };
    Run {
        name: run.name.clone(),
        dt_secs: run.dt_secs,
        t_secs: run.t_secs.get(start..end).map(<[f64]>::to_vec).unwrap_or_default(),
        input: cut(&run.input),
        outputs: run.outputs.iter().map(cut).collect(),
        aux: run.aux.iter().map(cut).collect(),
    }
}

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
    pub(super) fn of(model: &ExtendedModel) -> Result<Self, EffectError> {
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
    let dt = data.dt_secs;
    let unit = unit_gain_tf(&s.poles, &s.zeros, dt).ok()?.with_input_delay(s.delay);
    let (u, conditions) = input_stage(&s.effects, &data.run).ok()?;
    let split = match needs_split(&s.effects) {
        true => Some(AsymmetricDynamics::split(&s.poles, &s.zeros, dt).ok()?),
        false => None,
    };
    let unit_block = LinearBlock { tf: unit.clone(), offset: 0.0 };
    let w = linear_stage(&s.effects, &unit_block, split.as_ref(), &u, dt).ok()?;
    let factor: Option<Vec<f64>> = s.effects.iter().find_map(|e| match (e, &conditions) {
        (EffectBlock::AmbientCorrection(a), Some(c)) => Some(a.output_factor(c)),
        _ => None,
    });
    let y_c: Vec<f64> = match &factor {
        Some(f) => data.y.iter().zip(f).map(|(y, f)| y / f).collect(),
        None => data.y.clone(),
    };
    let w_seen = match s.effects.iter().find_map(|e| match e {
        EffectBlock::SensorDynamics(sd) => Some(sd),
        _ => None,
    }) {
        Some(sensor) => sensor.apply(&w, dt),
        None => w.clone(),
    };
    let (gain, offset) = fit_gain_offset(&w_seen, &y_c)?;
    let v: Vec<f64> = w.iter().map(|wk| gain * wk + offset).collect();
    let (vs, ys): (Vec<f64>, Vec<f64>) = data
        .steady_windows
        .iter()
        .filter_map(|&(a, b)| Some((mean(v.get(a..b)?), mean(y_c.get(a..b)?))))
        .unzip();
    let knot = s.effects.iter().find_map(|e| match e {
        EffectBlock::StaticMapOrder(k) => Some(k.knot_v),
        _ => None,
    });
    let (map, slope_change) = fit_map_with_knot(&vs, &ys, s.map_order, knot)?;
    let mut structure = s.clone();
    for e in &mut structure.effects {
        if let EffectBlock::StaticMapOrder(k) = e {
            k.slope_change = slope_change;
        }
    }
    let num = unit.num_zinv.iter().map(|b| b * gain).collect();
    let tf = DiscreteTf::new(num, unit.den_zinv.clone(), dt).ok()?;
    let y_hat = output_stage(&structure.effects, &map, &v, conditions.as_ref(), dt);
    let residual: Vec<f64> = y_hat.iter().zip(&data.y).map(|(a, b)| a - b).collect();
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

/// The effect fits' Levenberg–Marquardt: few iterations to a loose tolerance (the screening has
/// already chosen the start; a 10⁻⁵ relative gain is far below what the diagnosis can resolve).
const EFFECT_FIT: LmSettings =
    LmSettings { max_iterations: 15, cost_tol: 1e-5, damping: Damping::marquardt(10) };

/// Move roots and continuous effect parameters together from `start`.
pub(super) fn refine(start: &Structure, data: &FitData) -> Option<Assembled> {
    refine_with(start, data, &EFFECT_FIT)
}

fn refine_with(start: &Structure, data: &FitData, settings: &LmSettings) -> Option<Assembled> {
    let (pole_params, theta_p) = PoleParams::from_roots(&start.poles);
    let (zero_params, theta_z) = RootParams::from_roots(&start.zeros);
    let mut theta0: Vec<f64> = theta_p.iter().chain(&theta_z).copied().collect();
    let lens: Vec<usize> = start.effects.iter().map(|e| e.free_params().len()).collect();
    theta0.extend(start.effects.iter().flat_map(EffectBlock::free_params));
    let (np, nz) = (theta_p.len(), theta_z.len());
    let unpack = |theta: &[f64]| -> Option<Structure> {
        let poles = pole_params.roots(theta.get(..np)?);
        if poles.iter().any(|p| p.norm() >= MAX_POLE_RADIUS) {
            return None;
        }
        let zeros = zero_params.roots(theta.get(np..np + nz)?);
        let mut at = np + nz;
        let mut effects = Vec::with_capacity(start.effects.len());
        for (e, len) in start.effects.iter().zip(&lens) {
            effects.push(e.with_free_params(theta.get(at..at + len)?, data.dt_secs)?);
            at += len;
        }
        Some(Structure { poles, zeros, effects, map_order: start.map_order, delay: start.delay })
    };
    let residual = |theta: &[f64]| unpack(theta).and_then(|s| assemble(&s, data)).map(|a| a.residual);
    let mut problem: LeastSquares<_, LmError> =
        LeastSquares::new(residual, Jacobian::default(), StepSolver::QrOnce);
    let fitted = minimise(&mut problem, &theta0, settings, &mut no_progress).ok()?;
    assemble(&unpack(&fitted.theta)?, data)
}

/// Poles as refinement parameters: a real pole is one parameter, a complex pair the two
/// coefficients `(s, p)` of its quadratic `z² − s·z + p`. Unlike (re, im), these let a pair become
/// two real poles when the data want it: a damped pair found on closed-loop data (an ECU that
/// overshoots its command at every set-point change) may be an overdamped spool once the effect
/// that was missing is in the model.
struct PoleParams {
    /// For each root group: true for a quadratic (pair, or two real poles that were one).
    quadratic: Vec<bool>,
}

impl PoleParams {
    fn from_roots(roots: &[Complex64]) -> (Self, Vec<f64>) {
        let mut quadratic = Vec::new();
        let mut theta = Vec::new();
        for r in roots {
            if r.im.abs() <= 1e-12 {
                quadratic.push(false);
                theta.push(r.re);
            } else if r.im > 0.0 {
                quadratic.push(true);
                theta.extend([2.0 * r.re, r.norm_sqr()]);
            }
        }
        (Self { quadratic }, theta)
    }

    fn roots(&self, theta: &[f64]) -> Vec<Complex64> {
        let mut out = Vec::new();
        let mut values = theta.iter().copied();
        for &quadratic in &self.quadratic {
            let first = values.next().unwrap_or(0.0);
            if !quadratic {
                out.push(Complex64::new(first, 0.0));
                continue;
            }
            let (half, product) = (0.5 * first, values.next().unwrap_or(0.0));
            let disc = half * half - product;
            if disc >= 0.0 {
                out.extend([
                    Complex64::new(half + disc.sqrt(), 0.0),
                    Complex64::new(half - disc.sqrt(), 0.0),
                ]);
            } else {
                out.extend([Complex64::new(half, (-disc).sqrt()), Complex64::new(half, -(-disc).sqrt())]);
            }
        }
        out
    }
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

/// Add the effect `id` to `model` and refit on the identification data.
///
/// Starting points for the new block come from the data (see each block's `guesses`) plus, where
/// the block has one, its neutral setting (so the extension is never worse on the identification
/// data than the model it extends). They are screened on the identification error with the current
/// roots; the best [`REFINED_STARTS`] and the neutral start are refined with the roots and the other
/// effects. For a block with a discrete choice (the delay, the kink's position) the screening is
/// repeated around the refined roots while it finds better fits: roots that had absorbed part of a
/// delay only let go of it once the delay is in the model.
pub fn apply_effect(
    model: &ExtendedModel,
    id: EffectId,
    data: &FitData,
) -> Result<ExtendedModel, EffectError> {
    if model.effect(id).is_some() {
        return Err(EffectError::AlreadyApplied { effect: id.name().to_owned() });
    }
    let base = Structure::of(model)?;
    let failed =
        |reason: &str| EffectError::FitFailed { run: data.run.name.clone(), reason: reason.to_owned() };
    let current = assemble(&base, data).ok_or_else(|| failed("the current model cannot be evaluated"))?;
    let guesses = starting_points(id, &base, &current.model, data)?;
    if let Some(first) = guesses.first() {
        check_channels(&base.with(first.clone()), data)?;
    }
    let search = Search { id, guesses: &guesses, data };
    let mut starts: Vec<Structure> = search.screen(&base, &[]);
    starts.extend(neutral_block(id, data).map(|b| base.with(b)));
    if id == EffectId::TransportDelay {
        // Poles may stand in for a dead time (an ARX model cannot hold a long delay, so the segment
        // models put fast roots where it is): the delay is also tried with the fastest one or two pole
        // groups taken out.
        let mut reduced = base.clone();
        for _ in 0..2 {
            let Some(fewer) = without_fastest_pole_group(&reduced) else { break };
            starts.extend(search.screen(&fewer, &[]));
            reduced = fewer;
        }
    }
    let discrete = matches!(id, EffectId::TransportDelay | EffectId::StaticMapOrder);
    let rounds = if discrete { MAX_SCREENING_ROUNDS } else { 1 };
    let best = search.improve(None, starts, rounds);
    best.map(|b| b.model).ok_or_else(|| failed("no admissible starting point"))
}

/// The structure without its fastest pole group (a real pole or a pair, the one of smallest
/// modulus; the slowest pole always stays), and without its fastest zero when that leaves more
/// zeros than poles. `None` when only one pole group is left.
fn without_fastest_pole_group(s: &Structure) -> Option<Structure> {
    let groups: Vec<Complex64> = s.poles.iter().filter(|p| p.im >= 0.0).copied().collect();
    if groups.len() < 2 {
        return None;
    }
    let fastest = groups.iter().min_by(|a, b| a.norm().total_cmp(&b.norm())).copied()?;
    let mut out = s.clone();
    out.poles.retain(|p| (p - fastest).norm() > 1e-12 && (p - fastest.conj()).norm() > 1e-12);
    while out.zeros.len() > out.poles.len() {
        let (i, _) = out.zeros.iter().enumerate().min_by(|a, b| a.1.norm().total_cmp(&b.1.norm()))?;
        out.zeros.remove(i);
    }
    Some(out)
}

/// Screening and refinement of one block's starting points.
struct Search<'a> {
    id: EffectId,
    guesses: &'a [EffectBlock],
    data: &'a FitData,
}

impl Search<'_> {
    /// The best [`REFINED_STARTS`] untried starting points around `around` (its roots and other
    /// effects), by identification error.
    fn screen(&self, around: &Structure, tried: &[EffectBlock]) -> Vec<Structure> {
        let around = Structure {
            effects: around.effects.iter().filter(|e| e.id() != self.id).cloned().collect(),
            ..around.clone()
        };
        let mut scored: Vec<(f64, Structure)> = self
            .guesses
            .iter()
            .filter(|g| !tried.contains(g))
            .filter_map(|g| {
                let s = around.with(g.clone());
                assemble(&s, self.data).map(|a| (a.cost, s))
            })
            .collect();
        scored.sort_by(|a, b| a.0.total_cmp(&b.0));
        scored.into_iter().take(REFINED_STARTS).map(|(_, s)| s).collect()
    }

    /// Refine `starts`, keep the best, and screen again around it for up to `rounds` rounds while
    /// that finds better fits.
    fn improve(
        &self,
        mut best: Option<Assembled>,
        mut starts: Vec<Structure>,
        rounds: usize,
    ) -> Option<Assembled> {
        let mut tried: Vec<EffectBlock> = Vec::new();
        for _ in 0..rounds {
            let mut improved = false;
            for start in starts {
                tried.extend(start.effects.iter().filter(|e| e.id() == self.id).cloned());
                let Some(fitted) = refine(&start, self.data).or_else(|| assemble(&start, self.data)) else {
                    continue;
                };

                if best.as_ref().is_none_or(|b| fitted.cost < b.cost) {
                    best = Some(fitted);
                    improved = true;
                }
            }
            let Some(b) = best.as_ref().filter(|_| improved) else { break };
            starts = self.screen(&b.structure, &tried);
        }
        best
    }
}

/// The block's setting that leaves the model unchanged, where there is one.
fn neutral_block(id: EffectId, data: &FitData) -> Option<EffectBlock> {
    match id {
        EffectId::ThermalSoak => Some(EffectBlock::ThermalSoak(ThermalSoak { gain: 0.0, tau_s: 20.0 })),
        EffectId::AsymmetricDynamics => {
            Some(EffectBlock::AsymmetricDynamics(AsymmetricDynamics { decel_factor: 1.0 }))
        }
        EffectId::ScheduledTimeConstant => Some(EffectBlock::ScheduledTimeConstant(
            ScheduledTimeConstant::for_input(&data.run.input.values, 0.0),
        )),
        EffectId::SensorDynamics => Some(EffectBlock::SensorDynamics(SensorDynamics {
            freq_hz: 0.9 * SensorDynamics::max_freq_hz(data.dt_secs),
            zeta: 0.7,
            lag_s: 0.01,
        })),
        EffectId::TransportDelay
        | EffectId::AmbientCorrection
        | EffectId::StaticMapOrder
        | EffectId::CalibrationDrift => None,
    }
}

/// Starting points for the new block, from the data and the current model.
fn starting_points(
    id: EffectId,
    base: &Structure,
    current: &ExtendedModel,
    data: &FitData,
) -> Result<Vec<EffectBlock>, EffectError> {
    Ok(match id {
        EffectId::TransportDelay => {
            TransportDelay::guesses(data.dt_secs).into_iter().map(EffectBlock::TransportDelay).collect()
        }
        EffectId::ThermalSoak => ThermalSoak::guesses().into_iter().map(EffectBlock::ThermalSoak).collect(),
        EffectId::AmbientCorrection => {
            vec![EffectBlock::AmbientCorrection(AmbientCorrection::for_output(&data.output)?)]
        }
        EffectId::AsymmetricDynamics => {
            AsymmetricDynamics::split(&base.poles, &base.zeros, data.dt_secs)?;
            AsymmetricDynamics::guesses().into_iter().map(EffectBlock::AsymmetricDynamics).collect()
        }
        EffectId::ScheduledTimeConstant => {
            AsymmetricDynamics::split(&base.poles, &base.zeros, data.dt_secs)?;
            ScheduledTimeConstant::guesses(&data.run.input.values)
                .into_iter()
                .map(EffectBlock::ScheduledTimeConstant)
                .collect()
        }
        EffectId::CalibrationDrift => {
            // The slowest root's time constant sets how long a hold must last to count as steady.
            let slowest = base.poles.iter().map(|p| p.norm()).fold(0.0, f64::max);
            let tau_s = if slowest > 0.0 && slowest < 1.0 { -data.dt_secs / slowest.ln() } else { 1.0 };
            vec![EffectBlock::CalibrationDrift(CalibrationDrift::for_time_constant(tau_s))]
        }
        EffectId::SensorDynamics => {
            let y_hat = current.simulate(&data.run)?;
            let e: Vec<f64> = data.y.iter().zip(&y_hat).map(|(y, yh)| y - yh).collect();
            SensorDynamics::guesses(&e, data.dt_secs).into_iter().map(EffectBlock::SensorDynamics).collect()
        }
        EffectId::StaticMapOrder => {
            let (v, _) = current.simulate_with_v(&data.run)?;
            let steady_v: Vec<f64> =
                data.steady_windows.iter().filter_map(|&(a, b)| v.get(a..b).map(mean)).collect();
            StaticMapOrder::guesses(&steady_v).into_iter().map(EffectBlock::StaticMapOrder).collect()
        }
    })
}
