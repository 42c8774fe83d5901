//! Which roots the reduced model gets: the automatic proposal an engineer would sign.
//!
//! **Candidates.** The cluster proposal (`core::identification::cluster_proposal`) finds every isolated, tight
//! gathering of segment roots, relaxing the aggregation condition step by step from all J segments
//! to a majority; each candidate records the m of J segments it holds.
//!
//! **Choice by simulation error on the identification data** (never the validation runs), by
//! forward selection with cross-validation across segments. The model starts with the pole
//! candidate that alone fits the identification range best (a linear block needs a pole). Then every
//! remaining candidate is tried beside the roots already kept, each trial polished inside its
//! cluster (`core::identification::reduce`); the few that fit all the data best are cross-validated: for each
//! segment, the model is fitted without that segment's step response and simulated through it. The
//! trial that lowers the held-out error most is kept when it passes the parsimony rule below; this
//! repeats until none passes. A zero is only tried while the model has more poles than zeros.
//!
//! **Parsimony rule.** A root enters the model only when it beats the simpler model by enough,
//! beyond noise: see `core::identification::parsimony`.
//!
//! **No dead ends.** When no candidate cluster gives a model (no pole gathers in a majority of the
//! segments), the reduced model is fitted directly: output-error Wiener fit of free roots, grown one
//! real pole or pole pair at a time from a grid of time constants and natural frequencies, under the
//! same parsimony rule, up to `MAX_DIRECT_POLES` poles (a low-order model, as the method intends;
//! see `core::identification::direct_fit`). The proposal says so in words.
use serde::{Deserialize, Serialize};

use crate::core::identification::cluster::{self, Cluster, ClusterEval, RootKind};
use crate::core::identification::cluster_proposal::propose_clusters;
use crate::core::identification::cross_validation::{cross_validate, fitted};
pub use crate::core::identification::dead_time::DeadTimeVerdict;
use crate::core::identification::dead_time::{apparent_nk, group_delay_secs, with_dead_time};
use crate::core::identification::direct_fit::{DirectFit, direct_fit};
use crate::core::identification::error::PipelineError;
use crate::core::identification::fits::SegmentFits;
use crate::core::identification::parsimony::{
    Gain, Noise, model_error_reduction, pooled, too_little_to_cross_validate,
};
pub use crate::core::identification::parsimony::{MIN_RELATIVE_REDUCTION, MIN_STANDARD_ERRORS};
use crate::core::identification::reduce::{IdentData, Polished, RootGroup, count_of};
use crate::core::identification::settings::OutputSettings;
use crate::core::identification::words::fmt_error;
pub use crate::core::identification::words::root_words;
use crate::core::run::Run;

/// Trials cross-validated per round: the best few by their fit on all the data.
const CROSS_VALIDATED_TRIALS: usize = 3;

/// What became of one candidate cluster, in words and numbers.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CandidateVerdict {
    pub cluster: Cluster,
    /// Segments whose models have a root in the circle, and how many segments there are.
    pub segments_found: usize,
    pub segments_total: usize,
    /// Natural frequency (rad/s) and damping of the centroid.
    pub natural_freq_rad_s: f64,
    pub damping: f64,
    pub kept: bool,
    /// Identification RMS error (output units) of the model without and with this root, when tried.
    pub rms_without: Option<f64>,
    pub rms_with: Option<f64>,
    /// Standard errors by which the root lowers the held-out error, when it was cross-validated.
    pub standard_errors: Option<f64>,
    /// Why it was kept or dropped, in one sentence.
    pub reason: String,
}

/// The automatic proposal for one output.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Proposal {
    /// The clusters the model is built from (kept candidates), in the candidates' order.
    pub clusters: Vec<Cluster>,
    /// Every candidate with its verdict.
    pub verdicts: Vec<CandidateVerdict>,
    /// The input dead time candidate and its verdict.
    pub dead_time: DeadTimeVerdict,
    /// Present when no cluster gave a model and the roots were fitted directly.
    pub direct: Option<DirectFit>,
}

impl Proposal {
    /// One sentence per candidate, and the direct fit's note.
    pub fn sentences(&self) -> Vec<String> {
        let mut out: Vec<String> = self
            .verdicts
            .iter()
            .map(|v| {
                format!(
                    "{} {} ({}/{} segments): {}",
                    if v.cluster.kind == RootKind::Pole { "pole" } else { "zero" },
                    root_words(v.cluster.centre, !v.cluster.is_real_axis(), v.natural_freq_rad_s, v.damping),
                    v.segments_found,
                    v.segments_total,
                    v.reason
                )
            })
            .collect();
        out.push(self.dead_time.sentence());
        out.extend(self.direct.as_ref().map(|d| d.note.clone()));
        out
    }
}

/// The automatic proposal: candidate clusters, the forward selection and, when no cluster gives a
/// model, the direct fit (see the module documentation).
pub fn propose(
    fits: &SegmentFits,
    ident: &Run,
    settings: &OutputSettings,
) -> Result<Proposal, PipelineError> {
    let candidates = propose_clusters(&fits.roots, &settings.cluster, fits.dt_secs)?;
    let evals = cluster::evaluate_clusters(&candidates, &fits.roots, &settings.cluster, fits.dt_secs)?;
    let data = IdentData::new(fits, ident, settings)?;
    let mut verdicts: Vec<CandidateVerdict> = evals.iter().map(|e| verdict(e, fits.roots.len())).collect();
    let selection = select(&data, &evals, &mut verdicts);
    if selection.kept.is_empty() {
        let direct = direct_fit(&data, &fits.roots)?;
        return Ok(Proposal {
            clusters: Vec::new(),
            verdicts,
            dead_time: selection.dead_time,
            direct: Some(direct),
        });
    }
    let clusters = evals
        .iter()
        .enumerate()
        .filter(|(i, _)| selection.kept.contains(i))
        .map(|(_, e)| e.cluster.clone())
        .collect();
    Ok(Proposal { clusters, verdicts, dead_time: selection.dead_time, direct: None })
}

fn verdict(e: &ClusterEval, segments_total: usize) -> CandidateVerdict {
    CandidateVerdict {
        cluster: e.cluster.clone(),
        segments_found: e.segments_found,
        segments_total,
        natural_freq_rad_s: e.natural_freq_rad_s,
        damping: e.damping,
        kept: false,
        rms_without: None,
        rms_with: None,
        standard_errors: None,
        reason: "not tried".to_owned(),
    }
}

/// What the forward selection kept: candidate indices and the dead time, with every verdict.
struct Selection {
    kept: Vec<usize>,
    dead_time: DeadTimeVerdict,
}

/// A trial of the forward selection: a cluster candidate (its index) or the dead time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Trial {
    Cluster(usize),
    DeadTime,
}

/// Forward selection over the valid candidates and the dead time (see the module documentation);
/// fills the clusters' verdicts.
fn select(data: &IdentData, evals: &[ClusterEval], verdicts: &mut [CandidateVerdict]) -> Selection {
    let groups: Vec<Option<RootGroup>> = evals
        .iter()
        .enumerate()
        .map(|(i, e)| e.valid.then(|| RootGroup::of_cluster(i, e).within(data.settings.polish)))
        .collect();
    for (v, g) in verdicts.iter_mut().zip(&groups) {
        if g.is_none() {
            v.reason = "not valid, so not tried".to_owned();
        }
    }
    let mut dead_time = DeadTimeVerdict::untried(data);
    // The first pole: the candidate that alone fits best.
    let mut first: Option<(usize, Polished)> = None;
    for (i, g) in groups.iter().enumerate() {
        let Some(g) = g.as_ref().filter(|g| g.kind == RootKind::Pole) else { continue };
        match fitted(data, std::slice::from_ref(g)) {
            Some(p) => {
                verdicts[i].rms_with = Some(p.assembled.rms());
                if first.as_ref().is_none_or(|(_, b)| p.assembled.rms() < b.assembled.rms()) {
                    first = Some((i, p));
                }
            }
            None => verdicts[i].reason = "gives no model on its own (its gain cannot be fitted)".to_owned(),
        }
    }
    let Some((first_index, mut current)) = first else { return Selection { kept: Vec::new(), dead_time } };
    let mut kept = vec![first_index];
    verdicts[first_index].kept = true;
    verdicts[first_index].reason = format!(
        "kept: of the pole candidates it alone fits the identification run best (RMS error {})",
        fmt_error(current.assembled.rms())
    );
    let mut delay = data.delay;
    let mut current_cv = cross_validate(data, &current.groups, current.assembled.wiener.map.order());
    let noise_var = Noise::of(data);
    loop {
        let at = data.with_delay(delay);
        let (n_poles, n_zeros) =
            (count_of(&current.groups, RootKind::Pole), count_of(&current.groups, RootKind::Zero));
        // Every remaining candidate beside the kept roots, fitted on the whole identification range.
        let mut trials: Vec<(Trial, Polished, usize)> = Vec::new();
        for (i, g) in groups.iter().enumerate() {
            let Some(g) = g.as_ref().filter(|_| !kept.contains(&i)) else { continue };
            if g.kind == RootKind::Zero && n_zeros + g.count() > n_poles {
                verdicts[i].reason = format!(
                    "not tried: the model has {n_poles} poles and {n_zeros} zeros, and a zero needs a pole beside it"
                );
                continue;
            }
            let mut trial_groups = current.groups.clone();
            trial_groups.push(g.clone());
            match fitted(&at, &trial_groups) {
                Some(trial) => trials.push((Trial::Cluster(i), trial, delay)),
                None => verdicts[i].reason = "gives no model beside the kept roots".to_owned(),
            }
        }
        trials.sort_by(|a, b| a.1.assembled.rms().total_cmp(&b.1.assembled.rms()));
        // The most promising few are cross-validated; the rest are judged on their fit alone.
        let mut best: Option<(Trial, Polished, usize, Vec<f64>, Gain)> = None;
        for (rank, (which, trial, d)) in trials.into_iter().enumerate() {
            let without = current.assembled.rms();
            let in_sample = model_error_reduction(without.powi(2), trial.assembled.rms().powi(2), noise_var);
            let screened_out = rank >= CROSS_VALIDATED_TRIALS || too_little_to_cross_validate(in_sample);
            let cv = if screened_out {
                None
            } else {
                cross_validate(&data.with_delay(d), &trial.groups, trial.assembled.wiener.map.order())
            };
            let reason = match (cv.as_deref(), current_cv.as_deref()) {
                (Some(cv), Some(cur)) => {
                    let gain = Gain::of(cur, cv, noise_var);
                    let words = format!("dropped: beside the kept roots, {gain}");
                    if best.as_ref().is_none_or(|b| gain.reduction > b.4.reduction) {
                        best = Some((which, trial.clone(), d, cv.to_vec(), gain));
                    }
                    words
                }
                _ => format!(
                    "dropped: beside the kept roots it {} the identification error from {} to {} ({:+.0} %), \
                     too little of the error above noise to try it on held-out segments",
                    if in_sample > 0.0 { "lowers" } else { "raises" },
                    fmt_error(without),
                    fmt_error(trial.assembled.rms()),
                    -100.0 * in_sample
                ),
            };
            match which {
                Trial::Cluster(i) => {
                    let v = &mut verdicts[i];
                    v.rms_without = Some(without);
                    v.rms_with = Some(trial.assembled.rms());
                    v.reason = reason;
                }
                Trial::DeadTime => {
                    dead_time.samples = d;
                    dead_time.reason = reason;
                }
            }
        }
        // The dead time competes with the roots for the part of the late start the kept roots do
        // not explain; roots are preferred (they are the segment models' direct evidence), so the dead
        // time is kept over the best root only when it also removes a tenth of the model error that
        // root leaves.
        let mut best = best.filter(|b| b.4.passes());
        if !dead_time.kept {
            let excess = data.fits.nk().saturating_sub(apparent_nk(&at, &current.assembled));
            if excess < 1 && dead_time.reason == "not tried" {
                dead_time.reason = format!(
                    "not needed: the kept roots already explain the responses' late start (their own \
                     simulation fits best {} samples late)",
                    data.fits.nk()
                );
            }
            let tried = (excess >= 1).then(|| with_dead_time(data, &current.groups, excess)).flatten();
            if let (Some((trial, d)), Some(cur)) = (tried, current_cv.as_deref()) {
                dead_time.samples = d;
                match cross_validate(&data.with_delay(d), &trial.groups, trial.assembled.wiener.map.order()) {
                    Some(cv) => {
                        let gain = Gain::of(cur, &cv, noise_var);
                        let beats_root = best.as_ref().is_none_or(|b| {
                            model_error_reduction(pooled(&b.3), pooled(&cv), noise_var)
                                >= MIN_RELATIVE_REDUCTION
                        });
                        dead_time.reason = if gain.passes() && !beats_root {
                            format!(
                                "dropped: {gain}, but a root of the segment models does as well (roots are preferred)"
                            )
                        } else {
                            format!("dropped: beside the kept roots, {gain}")
                        };
                        if gain.passes() && beats_root {
                            best = Some((Trial::DeadTime, trial, d, cv, gain));
                        }
                    }
                    None => dead_time.reason = "gives no model on held-out segments".to_owned(),
                }
            }
        }
        let Some((which, trial, d, cv, gain)) = best else { break };
        let words = format!("kept: {gain}");
        match which {
            Trial::Cluster(i) => {
                verdicts[i].kept = true;
                verdicts[i].standard_errors = Some(gain.standard_errors);
                verdicts[i].reason = words;
                kept.push(i);
            }
            Trial::DeadTime => {
                dead_time.kept = true;
                dead_time.samples = d;
                dead_time.reason = words;
            }
        }
        delay = d;
        current = trial;
        current_cv = Some(cv);
    }
    if !dead_time.kept {
        // Parsimony across the two explanations of a late start: a root kept after the first pole may
        // only stand in for a dead time. If taking it out for the dead time the late start then leaves
        // unexplained predicts the held-out segments as well, the dead time (one parameter) replaces
        // it (two parameters for a pair).
        for i in kept.clone().into_iter().skip(1).rev() {
            let Some(cur) = current_cv.clone() else { break };
            let Some(index) = current.groups.iter().position(|g| g.cluster == Some(i)) else { continue };
            let mut fewer = current.groups.clone();
            fewer.remove(index);
            let at = data.with_delay(delay);
            let Some(reduced) = fitted(&at, &fewer) else { continue };
            let excess = data.fits.nk().saturating_sub(apparent_nk(&at, &reduced.assembled));
            let Some((swapped, d)) = (excess >= 1).then(|| with_dead_time(data, &fewer, excess)).flatten()
            else {
                continue;
            };
            let Some(cv) =
                cross_validate(&data.with_delay(d), &swapped.groups, swapped.assembled.wiener.map.order())
            else {
                continue;
            };
            // A dead time replaces a root only when it is at least twice the delay that root itself
            // gives (its low-frequency group delay, the time by which it shifts a slow input), less
            // the dead time's own resolution of one sample: a dead time the root's lag could account
            // for is that lag read as a delay, and the root, which the segment models show, is the
            // better explanation.
            let removed = &current.groups[index];
            let lag_secs = group_delay_secs(removed, data.fits.dt_secs);
            let longer = d.saturating_sub(1) as f64 * data.fits.dt_secs >= 2.0 * lag_secs;
            if longer && pooled(&cv) <= pooled(&cur) {
                let gain = Gain::of(&cur, &cv, noise_var);
                verdicts[i].kept = false;
                verdicts[i].reason = format!(
                    "dropped: a dead time of {d} samples predicts the held-out segments as well with fewer \
                     parameters (held-out error from {} to {}); the root only stood in for it",
                    fmt_error(gain.without),
                    fmt_error(gain.with)
                );
                dead_time.kept = true;
                dead_time.samples = d;
                dead_time.reason = format!(
                    "kept in place of a root that only stood in for it: held-out error from {} to {} with \
                     fewer parameters",
                    fmt_error(gain.without),
                    fmt_error(gain.with)
                );
                kept.retain(|k| *k != i);
                delay = d;
                current = swapped;
                current_cv = Some(cv);
                break;
            }
        }
    }
    if dead_time.kept {
        // Roots kept before the dead time may only have stood in for it: each is taken out again
        // unless the model with the dead time still needs it by the same rule.
        let at = data.with_delay(delay);
        for i in kept.clone().into_iter().skip(1).rev() {
            let Some(cur) = current_cv.clone() else { break };
            let Some(index) = current.groups.iter().position(|g| g.cluster == Some(i)) else { continue };
            let mut fewer = current.groups.clone();
            fewer.remove(index);
            let Some(without) = fitted(&at, &fewer) else { continue };
            let Some(cv) = cross_validate(&at, &without.groups, without.assembled.wiener.map.order()) else {
                continue;
            };
            let gain = Gain::of(&cv, &cur, noise_var);
            if !gain.passes() {
                verdicts[i].kept = false;
                verdicts[i].reason = format!(
                    "dropped once the dead time was kept: it only stood in for it; with the dead time, {gain}"
                );
                kept.retain(|k| *k != i);
                current = without;
                current_cv = Some(cv);
            }
        }
    }
    kept.sort_unstable();
    Selection { kept, dead_time }
}
