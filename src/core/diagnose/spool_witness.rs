//! The spool as a witness for every output that follows it.
//!
//! Effects that act before the spool (see [`EffectId::acts_before_spool`]) show their signature on
//! the spool: a rate limit caps its acceleration, a soak makes it creep, a drift moves its steady
//! states. Thrust sees all of them only through its static map, which bends the slopes a rate
//! limit makes constant, and through a load cell whose noise at idle is a good part of the value:
//! read on thrust, the signatures are blurred or invented by the map's curvature.
//!
//! So when the runs also measure the shaft speed, a model of another output (thrust) is read as
//! one spool model with a static map per output: its linear block (with its effects) is the spool,
//! `v`, and the shaft speed is a second static map of the same `v`, fitted by least squares on the
//! identification run. The residual of the measured shaft speed against that map, `N − h(v)`, is
//! where the evidence of an effect that acts before the spool is read. The trial itself is still
//! judged on the output's own data: the evidence says *which* physics, the output's test says
//! whether it helps there.
use super::{DiagnoseError, measured};
use crate::core::effects::stats::ResidualTrace;
use crate::core::effects::{EffectId, ExtendedModel};
use crate::core::identification::static_map::fit_static_map;
use crate::core::run::{Quantity, Run};

/// Order of the speed map `h(v)`: speed and the spool state are close to proportional, and a cubic
/// takes up the curvature of a corrected-speed law without following noise between the holds.
const SPEED_MAP_ORDER: usize = 3;

/// The shaft speed read through `current`'s spool on `runs` (the identification run first), with
/// the name of the speed column; `None` when `current` models the speed itself, when no run
/// measures it, or when the map cannot be fitted.
pub(super) fn spool_traces(
    current: &ExtendedModel,
    runs: &[&Run],
) -> Result<Option<(String, Vec<ResidualTrace>)>, DiagnoseError> {
    if Quantity::of(&current.output) == Some(Quantity::ShaftSpeed) {
        return Ok(None);
    }
    let Some(first) = runs.first() else { return Ok(None) };
    let Some(speed) = first
        .outputs
        .iter()
        .map(|c| c.name.clone())
        .find(|name| *name != current.output && Quantity::of(name) == Some(Quantity::ShaftSpeed))
    else {
        return Ok(None);
    };
    if runs.iter().any(|run| run.output(&speed).is_none()) {
        return Ok(None);
    }
    let spool = |run: &Run| {
        current
            .simulate_with_v(run)
            .map(|(v, _)| v)
            .map_err(|source| DiagnoseError::CurrentModel { run: run.name.clone(), source })
    };
    let v_ident = spool(first)?;
    let Ok(map) = fit_static_map(&v_ident, measured(first, &speed)?, SPEED_MAP_ORDER) else {
        return Ok(None);
    };
    let traces = runs
        .iter()
        .map(|run| {
            let v = if std::ptr::eq(*run, *first) { v_ident.clone() } else { spool(run)? };
            Ok(ResidualTrace {
                run: run.name.clone(),
                dt_secs: run.dt_secs,
                u: run.input.values.clone(),
                y: measured(run, &speed)?.to_vec(),
                y_hat: v.iter().map(|x| map.eval(*x)).collect(),
                aux: run.aux.clone(),
            })
        })
        .collect::<Result<Vec<_>, DiagnoseError>>()?;
    Ok(Some((speed, traces)))
}

/// The evidence for `id`: on the spool's traces when the effect acts before the spool and they
/// exist (saying so), on the output's own otherwise.
pub(super) fn evidence(
    id: EffectId,
    own: &[ResidualTrace],
    spool: Option<&(String, Vec<ResidualTrace>)>,
) -> crate::core::effects::Evidence {
    match spool.filter(|_| id.acts_before_spool()) {
        Some((speed, traces)) => {
            let read = id.evidence(traces);
            crate::core::effects::Evidence {
                sentence: format!("read on {speed} through this model's spool: {}", read.sentence),
                supports: read.supports,
            }
        }
        None => id.evidence(own),
    }
}
