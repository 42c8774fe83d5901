//! The numeric plan of an export: per output, the steps of `ExtendedModel::simulate` in signal-path
//! order with every number they need. Each language renders this plan; whatever needs roots or a
//! transfer-function split is worked out here, so the generated programs only run recursions.
use num_complex::Complex64;

use super::ExportError;
use crate::core::control::covariance::{Layout, ParameterCovariance, parameter_layout, parameters};
use crate::core::effects::{
    AmbientCorrection, AsymmetricDynamics, EffectBlock, EffectError, ExtendedModel, RateLimit, ReadOffSpeed,
    ScheduledTimeConstant, SensorDynamics, StaticMapOrder, ThermalSoak,
};
use crate::core::identification::static_map::StaticMap;
use crate::core::numerics::tf::DiscreteTf;
use crate::io::model_file::{ModelFile, OutputModel};

/// A discrete transfer function in z⁻¹, with the gain its simulation starts from: past inputs equal
/// the first input, past outputs `steady_gain` times it (`DiscreteTf::simulate_from_steady`; zero
/// without a steady state).
#[derive(Clone, Debug, PartialEq)]
pub struct Filter {
    pub num_zinv: Vec<f64>,
    pub den_zinv: Vec<f64>,
    pub steady_gain: f64,
}

impl Filter {
    fn of(tf: &DiscreteTf) -> Self {
        Self {
            num_zinv: tf.num_zinv.clone(),
            den_zinv: tf.den_zinv.clone(),
            steady_gain: tf.dc_gain().unwrap_or(0.0),
        }
    }

    /// The same transfer function in positive powers of z (numerator and denominator of equal
    /// length), as `control.TransferFunction` and MATLAB's `tf` read them.
    pub fn positive_powers(&self) -> (Vec<f64>, Vec<f64>) {
        let len = self.num_zinv.len().max(self.den_zinv.len());
        let pad = |c: &[f64]| {
            let mut out = c.to_vec();
            out.resize(len, 0.0);
            out
        };
        (pad(&self.num_zinv), pad(&self.den_zinv))
    }
}

/// A fractional delay `u(k − d)`, linearly interpolated, the samples before the start equal to the
/// first (`TransportDelay::delay`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Delay {
    pub whole: usize,
    pub frac: f64,
}

impl Delay {
    /// How many past samples the delay line holds (the current one included).
    pub fn line_len(&self) -> usize {
        self.whole + 2
    }
}

/// One step of the input stage, in signal-path order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InputStep {
    /// Fuel-line dead time.
    Delay(Delay),
    /// Corrected fuel flow `u/(δ√θ)` from the run's inlet channels.
    AmbientInput,
}

/// One step after the static map, in signal-path order.
#[derive(Clone, Debug, PartialEq)]
pub enum OutputStep {
    /// The physical output from the corrected one: `· θ^a δ^b`.
    AmbientOutput { theta_exp: f64, delta_exp: f64 },
    /// Sensor lag and resonance (`SensorDynamics::apply`).
    Sensor(SensorDynamics),
}

/// The per-run input offset of `calibration_drift`, found from the run's own steady holds of the
/// measured output (`CalibrationDrift::run_offset`); it needs the whole run, simulated once without
/// the offset, before the first step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Calibration {
    pub hold_s: f64,
    /// G(1) of the linear block: an input offset b moves the linear block's response by `G(1)·b`.
    pub dc_gain: f64,
}

/// The linear block with its spool root split off, for asymmetric or scheduled dynamics
/// (`scheduled_time_constant::respond_each`).
#[derive(Clone, Debug, PartialEq)]
pub struct Spool {
    /// Input dead time of the linear block, samples (`DiscreteTf::input_delay`).
    pub dead_time: usize,
    /// The unit-gain remainder, when the spool is not the only root.
    pub rest: Option<Filter>,
    /// ln of the spool root, as a complex number (re, im).
    pub ln_root: (f64, f64),
    /// Whether the spool is a complex pair.
    pub pair: bool,
    /// G(1) of the linear block, applied after the unit-gain split response.
    pub gain: f64,
    /// Falling over rising time constant (1 without asymmetric dynamics).
    pub decel: f64,
    /// The time-constant schedule, when applied.
    pub schedule: Option<ScheduledTimeConstant>,
}

/// How `v` is made from the (corrected, delayed, calibrated) input.
#[derive(Clone, Debug, PartialEq)]
pub enum Linear {
    /// The linear block simulated from the steady state of the first input.
    Direct(Filter),
    /// The split block of asymmetric or scheduled dynamics.
    Split(Spool),
}

/// Everything needed to simulate one output.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputPlan {
    /// The output's name (a column of the run file).
    pub name: String,
    /// The name as an identifier of the generated languages.
    pub ident: String,
    pub unit: String,
    /// The linear block G(z) as identified (for the transfer-function objects and the local model).
    pub tf: Filter,
    /// Added to the linear block's output.
    pub offset: f64,
    pub map: StaticMap,
    pub kink: Option<StaticMapOrder>,
    pub calibration: Option<Calibration>,
    pub input_steps: Vec<InputStep>,
    pub linear: Linear,
    pub soak: Option<ThermalSoak>,
    /// The rate limit on the spool's state, inside the split block (see [`RateLimit`]); always
    /// with a split.
    pub rate_limit: Option<RateLimit>,
    /// Whether the rate limit is on the output's own rate, read through the static map's slope
    /// (the shaft speed), or on `v`'s (see `core::effects::limits_own_rate`).
    pub rate_limit_through_map: bool,
    pub output_steps: Vec<OutputStep>,
    /// The output read off the shaft speed: `P(y)` after the output steps, `y` being the speed
    /// (see `core::effects::ReadOffSpeed`).
    pub read_off: Option<ReadOffSpeed>,
    /// The effects' linear dynamics every local model shares (dead time, soak, sensor; unit steady
    /// gain), as `core::control::effect_dynamics` builds them.
    pub effect_dynamics: Filter,
    /// Names of the applied effects, in signal-path order (for the generated file's header).
    pub effects: Vec<&'static str>,
    /// The parameter covariance the model file holds, checked against the model.
    pub uncertainty: Option<Uncertainty>,
}

/// A model's parameter covariance and where its parameters sit (see `core::control::covariance`).
#[derive(Clone, Debug, PartialEq)]
pub struct Uncertainty {
    pub covariance: ParameterCovariance,
    pub layout: Layout,
}

/// The model file's covariance of `out`, when it holds one that describes `model`'s parameters:
/// as many names and values as the model has parameters, a square symmetric matrix of finite
/// numbers with no negative variance.
fn uncertainty(out: &OutputModel, model: &ExtendedModel) -> Result<Option<Uncertainty>, ExportError> {
    let Some(cov) = &out.covariance else { return Ok(None) };
    let bad = |reason: String| ExportError::BadCovariance { output: out.name.clone(), reason };
    let layout = parameter_layout(model).map_err(|e| bad(e.to_string()))?;
    let (names, _) = parameters(model).map_err(|e| bad(e.to_string()))?;
    let n = names.len();
    if cov.names.len() != n || cov.values.len() != n {
        return Err(bad(format!(
            "it lists {} parameters with {} values, the model has {n} ({})",
            cov.names.len(),
            cov.values.len(),
            names.join(", ")
        )));
    }
    if cov.matrix.len() != n || cov.matrix.iter().any(|row| row.len() != n) {
        return Err(bad(format!("its matrix is not {n} × {n}")));
    }
    let finite = cov.values.iter().chain(cov.matrix.iter().flatten()).all(|v| v.is_finite());
    let symmetric = (0..n).all(|i| {
        (0..n).all(|j| {
            (cov.matrix[i][j] - cov.matrix[j][i]).abs() <= 1e-9 * (cov.matrix[i][i] * cov.matrix[j][j]).sqrt()
        })
    });
    if !finite || !symmetric || (0..n).any(|i| cov.matrix[i][i] < 0.0) {
        return Err(bad(
            "its matrix is not a covariance (finite, symmetric, no negative variance)".to_owned()
        ));
    }
    Ok(Some(Uncertainty { covariance: cov.clone(), layout }))
}

impl OutputPlan {
    /// Whether the output reads the run's inlet channels.
    pub fn needs_ambient(&self) -> bool {
        self.input_steps.contains(&InputStep::AmbientInput)
    }
}

/// The whole model, ready to render.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// The model file it was made from, for the generated file's header.
    pub source: String,
    pub dt_secs: f64,
    /// The input column.
    pub input: String,
    pub outputs: Vec<OutputPlan>,
}

impl Plan {
    /// The plan of a model file; errors name the output and what cannot be exported.
    pub fn new(model: &ModelFile, source: &str) -> Result<Self, ExportError> {
        check_name("input", &model.input.name)?;
        if model.outputs.is_empty() {
            return Err(ExportError::NoOutputs);
        }
        let mut outputs: Vec<OutputPlan> = Vec::with_capacity(model.outputs.len());
        for out in &model.outputs {
            let plan = output_plan(out)?;
            if let Some(other) = outputs.iter().find(|o| o.ident == plan.ident) {
                return Err(ExportError::NameClash {
                    first: other.name.clone(),
                    second: plan.name.clone(),
                    ident: plan.ident.clone(),
                });
            }
            outputs.push(plan);
        }
        Ok(Self {
            source: source.to_owned(),
            dt_secs: model.dt_secs,
            input: model.input.name.clone(),
            outputs,
        })
    }

    /// Whether any output reads the run's inlet channels.
    pub fn needs_ambient(&self) -> bool {
        self.outputs.iter().any(OutputPlan::needs_ambient)
    }

    /// Longest delay line any output needs (at least that of a zero delay, which the runtime can
    /// always reach).
    pub fn max_delay_line(&self) -> usize {
        self.outputs
            .iter()
            .flat_map(|o| {
                let input = o.input_steps.iter().filter_map(|s| match s {
                    InputStep::Delay(d) => Some(d.line_len()),
                    InputStep::AmbientInput => None,
                });
                let dead = match &o.linear {
                    Linear::Split(s) => Some(Delay { whole: s.dead_time, frac: 0.0 }.line_len()),
                    Linear::Direct(_) => None,
                };
                input.chain(dead)
            })
            .fold(Delay { whole: 0, frac: 0.0 }.line_len(), usize::max)
    }

    /// Longest numerator or denominator of any filter.
    pub fn max_filter_len(&self) -> usize {
        self.outputs
            .iter()
            .flat_map(|o| {
                let rest = match &o.linear {
                    Linear::Split(s) => s.rest.as_ref(),
                    Linear::Direct(_) => None,
                };
                [Some(&o.tf), rest].into_iter().flatten()
            })
            .map(|f| f.num_zinv.len().max(f.den_zinv.len()))
            .max()
            .unwrap_or(1)
    }
}

/// Names become string literals and CSV header cells in every language: they must not need
/// quoting there.
fn check_name(what: &'static str, name: &str) -> Result<(), ExportError> {
    let bad = name.chars().find(|c| c.is_control() || matches!(c, '"' | '\'' | '\\' | ',' | '%'));
    match (name.trim().is_empty() || name.trim() != name, bad) {
        (false, None) => Ok(()),
        (_, bad) => Err(ExportError::UnsupportedName {
            what,
            name: name.to_owned(),
            reason: match bad {
                Some(c) => {
                    format!("it holds the character {c:?}, which the generated CSV reader cannot read")
                }
                None => "it is empty or starts or ends with white space".to_owned(),
            },
        }),
    }
}

/// An identifier for the generated languages: letters, digits and `_`, not starting with a digit.
fn identifier(name: &str) -> String {
    let mut ident: String = name.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
    if !ident.starts_with(|c: char| c.is_ascii_alphabetic()) {
        ident.insert_str(0, "y_");
    }
    ident
}

fn output_plan(out: &OutputModel) -> Result<OutputPlan, ExportError> {
    check_name("output", &out.name)?;
    let model = ExtendedModel::from_records(&out.name, out.wiener.clone(), &out.effects)
        .map_err(|source| effect_error(out, source))?;
    let tf = &model.wiener.linear.tf;
    let (poles, zeros) = model.roots().map_err(|e| bad_linear(out, e.to_string()))?;
    check_stable(out, &poles)?;
    let mut plan = direct_plan(out, &model);
    let mut split = SplitEffects::default();
    for effect in &model.effects {
        add_effect(&mut plan, &mut split, effect, tf);
    }
    if split.needed() {
        plan.linear = Linear::Split(spool(out, tf, &poles, &zeros, split)?);
    }
    plan.uncertainty = uncertainty(out, &model)?;
    Ok(plan)
}

fn effect_error(out: &OutputModel, source: EffectError) -> ExportError {
    ExportError::Effect { output: out.name.clone(), source }
}

fn bad_linear(out: &OutputModel, reason: String) -> ExportError {
    ExportError::BadLinearBlock { output: out.name.clone(), reason }
}

/// A pole on or outside the unit circle (or not a number) makes the model unstable: refused.
fn check_stable(out: &OutputModel, poles: &[Complex64]) -> Result<(), ExportError> {
    let margin = crate::core::numerics::tf::STABILITY_MARGIN;
    match poles.iter().find(|p| p.norm().is_nan() || p.norm() >= 1.0 - margin) {
        Some(p) => Err(bad_linear(
            out,
            format!(
                "a pole at {:.4}{:+.4}i (|z| = {:.4}) is on or outside the unit circle: the model is unstable and \
                 `jetid predict` refuses it too",
                p.re,
                p.im,
                p.norm()
            ),
        )),
        None => Ok(()),
    }
}

/// The plan of the model without its effects: the linear block simulated directly, no steps.
fn direct_plan(out: &OutputModel, model: &ExtendedModel) -> OutputPlan {
    let tf = &model.wiener.linear.tf;
    OutputPlan {
        name: out.name.clone(),
        ident: identifier(&out.name),
        unit: out.unit.clone(),
        tf: Filter::of(tf),
        offset: model.wiener.linear.offset,
        map: model.wiener.map.clone(),
        kink: None,
        calibration: None,
        input_steps: Vec::new(),
        linear: Linear::Direct(Filter::of(tf)),
        soak: None,
        rate_limit: None,
        rate_limit_through_map: model.limits_own_rate(),
        output_steps: Vec::new(),
        read_off: None,
        effect_dynamics: {
            let (num_zinv, den_zinv) = crate::core::control::effect_dynamics(model);
            Filter { num_zinv, den_zinv, steady_gain: 1.0 }
        },
        effects: model.effects.iter().map(|e| e.id().name()).collect(),
        uncertainty: None,
    }
}

/// What asymmetric and scheduled dynamics and a rate limit ask of the linear block, which each
/// splits.
#[derive(Default)]
struct SplitEffects {
    decel: Option<f64>,
    schedule: Option<ScheduledTimeConstant>,
    /// A rate limit acts on the spool's state.
    limited: bool,
}

impl SplitEffects {
    fn needed(&self) -> bool {
        self.decel.is_some() || self.schedule.is_some() || self.limited
    }
}

/// Puts `effect` into its place in `plan` (or, for the split's effects, into `split`).
fn add_effect(plan: &mut OutputPlan, split: &mut SplitEffects, effect: &EffectBlock, tf: &DiscreteTf) {
    match effect {
        EffectBlock::CalibrationDrift(c) => {
            plan.calibration = tf.dc_gain().ok().map(|dc_gain| Calibration { hold_s: c.hold_s, dc_gain });
        }
        EffectBlock::TransportDelay(d) => {
            let whole = d.delay_samples.floor();
            plan.input_steps
                .push(InputStep::Delay(Delay { whole: whole as usize, frac: d.delay_samples - whole }));
        }
        EffectBlock::ThermalSoak(s) => plan.soak = Some(s.clone()),
        EffectBlock::RateLimit(r) => {
            plan.rate_limit = Some(r.clone());
            split.limited = true;
        }
        EffectBlock::AmbientCorrection(AmbientCorrection { output_theta_exp, output_delta_exp }) => {
            plan.input_steps.push(InputStep::AmbientInput);
            plan.output_steps.push(OutputStep::AmbientOutput {
                theta_exp: *output_theta_exp,
                delta_exp: *output_delta_exp,
            });
        }
        EffectBlock::AsymmetricDynamics(a) => split.decel = Some(a.decel_factor),
        EffectBlock::ScheduledTimeConstant(s) => split.schedule = Some(s.clone()),
        EffectBlock::SensorDynamics(s) => plan.output_steps.push(OutputStep::Sensor(s.clone())),
        EffectBlock::StaticMapOrder(k) => plan.kink = Some(k.clone()),
        EffectBlock::ReadOffSpeed(r) => plan.read_off = Some(r.clone()),
    }
}

/// The linear block with its spool root split off, for `split`'s effects.
fn spool(
    out: &OutputModel,
    tf: &DiscreteTf,
    poles: &[Complex64],
    zeros: &[Complex64],
    split: SplitEffects,
) -> Result<Spool, ExportError> {
    let shape =
        AsymmetricDynamics::split(poles, zeros, tf.dt_secs).map_err(|source| effect_error(out, source))?;
    let gain = tf.dc_gain().map_err(|e| bad_linear(out, e.to_string()))?;
    let ln_root: Complex64 =
        Complex64::new(shape.spool.norm().max(f64::MIN_POSITIVE).ln(), shape.spool.arg());
    Ok(Spool {
        dead_time: tf.input_delay(),
        rest: shape.rest.as_ref().map(Filter::of),
        ln_root: (ln_root.re, ln_root.im),
        pair: shape.is_pair(),
        gain,
        decel: split.decel.unwrap_or(1.0),
        schedule: split.schedule,
    })
}
