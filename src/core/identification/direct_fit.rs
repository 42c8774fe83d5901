//! Free roots fitted directly by output error: the fallback when no cluster gives a model, the
//! grids a free real pole or pair is started from, and the direct fit of a given order that the
//! engine-family study uses as a yardstick.
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use crate::core::identification::cluster::{RootKind, SegmentRoots, natural_freq_and_damping};
use crate::core::identification::cross_validation::{REFINED_GUESSES, cross_validate, fitted};
use crate::core::identification::error::PipelineError;
use crate::core::identification::fits::SegmentFits;
use crate::core::identification::parsimony::{Gain, Noise};
use crate::core::identification::reduce::{IdentData, Polished, RootGroup, assemble_groups, count_of};
use crate::core::identification::words::{fmt_error, root_words};

/// Most poles the direct fit grows to.
pub const MAX_DIRECT_POLES: usize = 4;

/// Free roots fitted directly by output error, and why they were needed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DirectFit {
    pub groups: Vec<RootGroup>,
    pub note: String,
}

/// Time constants (s) a free real pole is started from: geometric from two samples to half the
/// longest segment, the range a step response of these segments can show.
pub fn real_pole_guesses(dt_secs: f64, span_secs: f64) -> Vec<Complex64> {
    geometric(2.0 * dt_secs, (0.5 * span_secs).max(4.0 * dt_secs), 10)
        .into_iter()
        .map(|tau| Complex64::new((-dt_secs / tau).exp(), 0.0))
        .collect()
}

/// Pole pairs a free pair is started from: natural frequencies geometric from the slowest a segment
/// shows to the π/2 rad/sample limit the cluster analysis keeps (above it ARX noise roots ring), each
/// at light, medium and heavy damping.
pub fn pair_guesses(dt_secs: f64, span_secs: f64) -> Vec<Complex64> {
    let lo = 4.0 / span_secs.max(4.0 * dt_secs);
    let hi = 0.9 * std::f64::consts::FRAC_PI_2 / dt_secs;
    let mut out = Vec::new();
    for omega in geometric(lo.min(0.5 * hi), hi, 8) {
        for zeta in [0.3, 0.6, 0.9] {
            let s = Complex64::new(-zeta * omega, omega * (1.0 - zeta * zeta).sqrt());
            out.push((s * dt_secs).exp());
        }
    }
    out
}

fn geometric(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    let ratio = (hi / lo).max(1.0).powf(1.0 / (n.max(2) - 1) as f64);
    (0..n).map(|k| lo * ratio.powi(k as i32)).collect()
}

/// Longest segment after its step, s.
fn longest_segment_secs(fits: &SegmentFits) -> f64 {
    fits.segments.iter().map(|s| s.end.saturating_sub(s.step_at)).max().unwrap_or(0) as f64 * fits.dt_secs
}

/// The best model with one more free real pole or pole pair beside `groups`: every guess screened
/// on the identification error with the current roots as they are, the best few polished.
pub fn add_free_pole(data: &IdentData, groups: &[RootGroup], max_poles: usize) -> Option<Polished> {
    let span = longest_segment_secs(data.fits);
    let dt = data.fits.dt_secs;
    let room = max_poles.saturating_sub(count_of(groups, RootKind::Pole));
    let reals = real_pole_guesses(dt, span).into_iter().map(|z| RootGroup::free_real(RootKind::Pole, z.re));
    let pairs = pair_guesses(dt, span).into_iter().map(|z| RootGroup::free_pair(RootKind::Pole, z));
    let guesses = reals.chain(pairs).filter(|g| g.count() <= room);
    let mut screened: Vec<(f64, Vec<RootGroup>)> = guesses
        .filter_map(|g| {
            let mut trial = groups.to_vec();
            trial.push(g);
            assemble_groups(data, &trial, data.settings.static_order).ok().map(|a| (a.rms(), trial))
        })
        .collect();
    screened.sort_by(|a, b| a.0.total_cmp(&b.0));
    screened
        .into_iter()
        .take(REFINED_GUESSES)
        .filter_map(|(_, trial)| fitted(data, &trial))
        .min_by(|a, b| a.assembled.rms().total_cmp(&b.assembled.rms()))
}

/// The direct output-error fit of free roots when no cluster gives a model.
pub(super) fn direct_fit(data: &IdentData, roots: &[SegmentRoots]) -> Result<DirectFit, PipelineError> {
    let candidates = roots.len();
    let Some(mut current) = add_free_pole(data, &[], 1) else {
        return Err(PipelineError::NoModel {
            reason: "not even a single real pole can be fitted to the identification run: check that \
                     the output responds to the input (column mapping) and that the run holds steps"
                .to_owned(),
        });
    };
    let mut steps = vec![format!("1 real pole (RMS error {})", fmt_error(current.assembled.rms()))];
    let cv_of = |p: &Polished| cross_validate(data, &p.groups, p.assembled.wiener.map.order());
    let mut current_cv = cv_of(&current);
    while count_of(&current.groups, RootKind::Pole) < MAX_DIRECT_POLES {
        let Some(trial) = add_free_pole(data, &current.groups, MAX_DIRECT_POLES) else { break };
        let (Some(cur), Some(cv)) = (current_cv.as_deref(), cv_of(&trial)) else { break };
        let gain = Gain::of(cur, &cv, Noise::of(data));
        if !gain.passes() {
            break;
        }
        let added = trial.groups.last().map_or("a pole".to_owned(), |g| {
            let (omega, zeta) = natural_freq_and_damping(g.root, data.fits.dt_secs);
            root_words(g.root, g.pair, omega, zeta)
        });
        steps.push(format!("+ {added}: {gain}"));
        current = trial;
        current_cv = Some(cv);
    }
    let note = format!(
        "no pole gathers in a majority of the {candidates} segment models, so the cluster method has nothing \
         to build on; the linear block was fitted directly by output error instead: {}. Look at the \
         z-plane: the segment models disagree (closed-loop data, steps too small to excite the \
         dynamics, or ARX orders that do not suit this engine).",
        steps.join(", ")
    );
    Ok(DirectFit { groups: current.groups, note })
}

/// The best free-root output-error fit with exactly `n_poles` poles: grown greedily from the grids
/// (one real pole or pair at a time, each step's best polished), and from each of `starts` with its
/// roots freed. A yardstick for the cluster-based model, which cannot beat it on the identification
/// data with the same roots.
pub fn direct_fit_of_order(data: &IdentData, n_poles: usize, starts: &[Vec<RootGroup>]) -> Option<Polished> {
    let mut results: Vec<Polished> = Vec::new();
    let mut grown: Vec<RootGroup> = Vec::new();
    while count_of(&grown, RootKind::Pole) < n_poles {
        let Some(next) = add_free_pole(data, &grown, n_poles) else { break };
        grown = next.groups.clone();
        if count_of(&grown, RootKind::Pole) == n_poles {
            results.push(next);
        }
    }
    for start in starts {
        let freed: Vec<RootGroup> =
            start.iter().map(|g| RootGroup { region: None, cluster: None, ..g.clone() }).collect();
        results.extend(fitted(data, &freed));
    }
    results.into_iter().min_by(|a, b| a.assembled.rms().total_cmp(&b.assembled.rms()))
}
