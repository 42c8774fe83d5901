//! One run against its engine's reference: read as the manifest says, scored per output (RMSE,
//! RMSPE), its health deltas fitted with their intervals, and the stretches where its input sits at
//! its limit measured against what the reference gives there.
use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};

use crate::core::health::{self, Deltas, Estimate, HealthFit};
use crate::core::identification::initial_state::InitialState;
use crate::core::numerics::metrics::metrics;
use crate::core::numerics::stats::significant;
use crate::core::run::Run;
use crate::workflow::runs::{DT_TOLERANCE, load_source};

use super::finding::RunDiagnosis;
use super::manifest::FleetRun;
use super::reference::Reference;

/// Scored runs start from the state that best fits their first seconds: a window cut from a log
/// starts wherever the engine happens to be.
pub(super) const INITIAL: InitialState = InitialState::Estimated;
/// The input must sit at its limit for this many of the reference's slowest time constants before
/// the output is judged: after 3 τ a first-order spool is within 5 % of where the input takes it.
const SETTLE_TIME_CONSTANTS: f64 = 3.0;

/// One output of a run.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct OutputScore {
    pub output: String,
    pub unit: String,
    pub rmse: f64,
    pub rmspe_pct: f64,
    /// The output's range on the run (the map shift is also reported as a share of it).
    pub range: f64,
    pub map_shift: Option<Estimate>,
}

/// The input at its limit over a stretch, and the output there against the reference.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Starved {
    pub output: String,
    pub unit: String,
    pub input: String,
    pub input_unit: String,
    pub limit: f64,
    /// The stretch's first sample.
    pub start: usize,
    pub duration_secs: f64,
    /// The input the reference was asked at: the limit, or the top of its identified range.
    pub probe_input: f64,
    /// The reference's steady output at `probe_input`.
    pub expected: f64,
    /// Mean of (expected − measured) over the stretch after it settled.
    pub shortfall: f64,
}

/// Everything the fleet reports of one run (serialisable, so that a distributed engine's workers
/// can hand it back).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunScore {
    pub outputs: Vec<OutputScore>,
    pub input_gain: Option<Estimate>,
    pub tau_scale: Option<Estimate>,
    pub starved: Vec<Starved>,
    /// Why a delta is missing, what reading the file changed.
    pub notes: Vec<String>,
    pub input_name: String,
    /// The diagnosis of the run against the reference, when the run was screened for one (see
    /// `fleet::diagnosis`).
    #[serde(default)]
    pub diagnosis: Option<RunDiagnosis>,
}

/// Read `run` and score it against `reference`.
pub fn score_run(run: &FleetRun, reference: &Reference) -> Result<RunScore> {
    let mut notes = Vec::new();
    let data = read_run(run, reference, &mut notes)?;
    let present: Vec<usize> =
        (0..reference.models.len()).filter(|&i| data.output(&reference.models[i].output).is_some()).collect();
    if present.is_empty() {
        let names: Vec<&str> = reference.models.iter().map(|m| m.output.as_str()).collect();
        bail!("run '{}' holds none of the reference's outputs ({})", run.name, names.join(", "));
    }
    let models: Vec<_> = present.iter().map(|&i| reference.models[i].clone()).collect();
    let fit = health::fit_deltas(&models, &data, INITIAL)
        .map_err(|e| notes.push(format!("run '{}': no health deltas: {e}", run.name)))
        .ok();
    let mut outputs = Vec::with_capacity(present.len());
    for (k, &i) in present.iter().enumerate() {
        outputs.push(score_output(&data, reference, i, fit.as_ref().map(|f| f.map_shift[k]))?);
    }
    let starved =
        starved_stretches(&data, reference, &present).with_context(|| format!("run '{}'", run.name))?;
    Ok(RunScore {
        outputs,
        input_gain: fit.as_ref().map(|f: &HealthFit| f.input_gain),
        tau_scale: fit.as_ref().map(|f| f.tau_scale),
        starved,
        notes,
        input_name: data.input.name.clone(),
        diagnosis: None,
    })
}

/// Read `run` as the manifest says, named as it names it and on the reference's sample time; what
/// reading changed goes into `notes`.
pub fn read_run(run: &FleetRun, reference: &Reference, notes: &mut Vec<String>) -> Result<Run> {
    let mut data = load_source(&run.source, notes)?;
    data.name = run.name.clone();
    if data.input.name != reference.input {
        bail!(
            "run '{}' ({}) gives '{}' as its input but the reference was identified from '{}' (map it with \
             map = [\"input=COLUMN\"] in [engine.load])",
            run.name,
            run.source.path.display(),
            data.input.name,
            reference.input
        );
    }
    if (data.dt_secs / reference.dt_secs - 1.0).abs() > DT_TOLERANCE {
        if !run.source.load.resample {
            bail!(
                "run '{}' is sampled every {} s but the reference every {} s; the model is discrete-time: add \
                 resample = true to [engine.load]",
                run.name,
                significant(data.dt_secs, 5),
                significant(reference.dt_secs, 5)
            );
        }
        data = data.resampled(reference.dt_secs);
        notes.push(format!(
            "run '{}': resampled onto the reference's {} s grid",
            run.name,
            significant(reference.dt_secs, 5)
        ));
    }
    Ok(data)
}

fn score_output(
    data: &Run,
    reference: &Reference,
    i: usize,
    map_shift: Option<Estimate>,
) -> Result<OutputScore> {
    let model = &reference.models[i];
    let y = data.output(&model.output).map(|c| c.values.as_slice()).unwrap_or_default();
    let none = Deltas::none(1);
    let simulated = health::simulate_with(model, data, &none, 0.0, INITIAL)?;
    let scored = metrics(y, &simulated)
        .with_context(|| format!("scoring '{}' on run '{}'", model.output, data.name))?;
    let (lo, hi) = y.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
    Ok(OutputScore {
        output: model.output.clone(),
        unit: reference.units.get(i).cloned().unwrap_or_default(),
        rmse: scored.rmse,
        rmspe_pct: scored.rmspe_pct,
        range: hi - lo,
        map_shift,
    })
}

/// The slowest continuous time constant of a model's linear block, s.
fn slowest_time_constant(model: &crate::core::effects::ExtendedModel) -> f64 {
    let tf = &model.wiener.linear.tf;
    tf.poles()
        .unwrap_or_default()
        .iter()
        .filter(|p| p.norm() > 0.0 && p.norm() < 1.0)
        .map(|p| -tf.dt_secs / p.norm().ln())
        .fold(tf.dt_secs, f64::max)
}

/// Every stretch with the input at its limit, long enough for the spool to settle, with each
/// output's mean shortfall against the reference's steady output there.
fn starved_stretches(data: &Run, reference: &Reference, present: &[usize]) -> Result<Vec<Starved>> {
    let mut found = Vec::new();
    for &i in present {
        let model = &reference.models[i];
        let settle = (SETTLE_TIME_CONSTANTS * slowest_time_constant(model) / data.dt_secs).ceil() as usize;
        let Some(y) = data.output(&model.output) else { continue };
        for pinned in health::pinned_stretches(&data.input.values, 2 * settle.max(2)) {
            // The engine gives at least the reference's top output with more input than the top of
            // the identified range: the map is not extrapolated.
            let top = reference.input_range.map_or(pinned.limit, |[_, hi]| hi);
            let probe_input = pinned.limit.min(top);
            let mut probe = data.clone();
            probe.input.values.iter_mut().for_each(|u| *u = probe_input);
            let steady = health::simulate_with(model, &probe, &Deltas::none(1), 0.0, InitialState::Steady)?;
            let Some(&expected) = steady.last() else { continue };
            let settled = &y.values[pinned.start + settle..pinned.end()];
            let shortfall = settled.iter().map(|v| expected - v).sum::<f64>() / settled.len().max(1) as f64;
            found.push(Starved {
                output: model.output.clone(),
                unit: reference.units.get(i).cloned().unwrap_or_default(),
                input: data.input.name.clone(),
                input_unit: data.input.unit.clone(),
                limit: pinned.limit,
                start: pinned.start,
                duration_secs: pinned.len as f64 * data.dt_secs,
                probe_input,
                expected,
                shortfall,
            });
        }
    }
    Ok(found)
}
