//! Which roots the reduced model gets: the automatic proposal an engineer would sign.
//!
//! **Candidates.** The cluster proposal (`core::cluster_proposal`) finds every isolated, tight
//! gathering of segment roots, relaxing the aggregation condition step by step from all J segments
//! to a majority; each candidate records the m of J segments it holds.
//!
//! **Choice by simulation error on the identification data** (never the validation runs), by
//! forward selection with cross-validation across segments. The model starts with the pole
//! candidate that alone fits the identification range best (a linear block needs a pole). Then every
//! remaining candidate is tried beside the roots already kept, each trial polished inside its
//! cluster (`core::reduce`); the few that fit all the data best are cross-validated: for each
//! segment, the model is fitted without that segment's step response and simulated through it. The
//! trial that lowers the held-out error most is kept when it passes the parsimony rule below; this
//! repeats until none passes. A zero is only tried while the model has more poles than zeros.
//!
//! **Parsimony rule.** A root enters the model when (1) it lowers the held-out error by more than
//! one standard error of the per-segment improvements — the one-standard-error rule of
//! cross-validated model choice (Breiman et al.; Hastie, Tibshirani & Friedman §7.10): the segments
//! are J separate experiments, and a root that only fits noise in some of them does not predict the
//! others — and (2) it removes at least [`MIN_RELATIVE_REDUCTION`] (10 %) of the held-out model
//! error: the RMS error above the measurement noise (σ read from the data, see
//! [`IdentData::noise_sigma`]), which no structure can remove — on a thrust channel whose noise is
//! most of the error a faint but real pole pair would otherwise never count. Ten percent is the
//! share the diagnosis asks of a physical effect, so that a root and an effect are judged alike;
//! smaller gains come from roots that only shave an error dominated by what a Wiener model cannot
//! do (a speed-dependent time constant), which a controller designer would not want to carry. The
//! held-out error is used rather than the fit to all the data because every extra root lowers the
//! latter.
//!
//! **No dead ends.** When no candidate cluster gives a model (no pole gathers in a majority of the
//! segments), the reduced model is fitted directly: output-error Wiener fit of free roots, grown one
//! real pole or pole pair at a time from a grid of time constants and natural frequencies, under the
//! same parsimony rule, up to [`MAX_DIRECT_POLES`] poles (a low-order model, as the method intends).
//! The proposal says so in words.
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use crate::core::cluster::{
    self, Cluster, ClusterEval, RootKind, SegmentRoots, natural_freq_and_damping,
};
use crate::core::pipeline::{OutputSettings, PipelineError, SegmentFits};
use crate::core::reduce::{IdentData, Polished, RootGroup, assemble_groups, count_of, polish, rms};
use crate::core::run::Run;

/// Smallest share of the held-out RMS error a root must remove to enter the model.
pub const MIN_RELATIVE_REDUCTION: f64 = 0.10;
/// Standard errors by which the held-out improvement must exceed zero (the one-standard-error rule).
pub const MIN_STANDARD_ERRORS: f64 = 1.0;
/// Trials cross-validated per round: the best few by their fit on all the data.
const CROSS_VALIDATED_TRIALS: usize = 3;
/// A trial is cross-validated only when its fit on all the data removes at least this share of
/// [`MIN_RELATIVE_REDUCTION`]: held-out improvements run below in-sample ones.
const SCREEN_SHARE: f64 = 0.5;
/// Most poles the direct fit grows to.
pub const MAX_DIRECT_POLES: usize = 4;
/// Starting points kept after screening a grid, to be polished.
const REFINED_GUESSES: usize = 2;

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
    /// Present when no cluster gave a model and the roots were fitted directly.
    pub direct: Option<DirectFit>,
}

/// Free roots fitted directly by output error, and why they were needed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DirectFit {
    pub groups: Vec<RootGroup>,
    pub note: String,
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
        out.extend(self.direct.as_ref().map(|d| d.note.clone()));
        out
    }
}

/// "pair near 2.31 rad/s (ζ 0.60)" or "real root 0.936 (τ 1.72 s)".
pub fn root_words(z: Complex64, pair: bool, omega_rad_s: f64, zeta: f64) -> String {
    if pair {
        format!("pair near {omega_rad_s:.2} rad/s (ζ {zeta:.2})")
    } else if z.re > 0.0 && z.re < 1.0 && omega_rad_s > 0.0 {
        format!("real root at {:.3} (τ {:.2} s)", z.re, 1.0 / omega_rad_s)
    } else {
        format!("real root at {:.3}", z.re)
    }
}

/// A trial structure against the current one, over the held-out segments of a cross-validation.
struct Gain {
    /// Share of the held-out model error (above the noise) the trial removes.
    reduction: f64,
    /// Held-out errors without and with the trial (output units, pooled over the segments).
    without: f64,
    with: f64,
    /// Segments whose held-out error the trial lowers, and how many segments there are.
    wins: usize,
    folds: usize,
    /// Mean per-segment relative improvement over its standard error.
    standard_errors: f64,
}

impl Gain {
    /// From the per-segment held-out mean squared errors of the two structures; `noise_var` is the
    /// measurement noise's variance, which no structure can remove.
    fn of(without: &[f64], with: &[f64], noise_var: f64) -> Self {
        let d: Vec<f64> = without.iter().zip(with).map(|(a, b)| (a - b) / a.max(f64::MIN_POSITIVE)).collect();
        let n = d.len().max(1) as f64;
        let mean = d.iter().sum::<f64>() / n;
        let sd = (d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt();
        let pooled = |x: &[f64]| x.iter().sum::<f64>() / x.len().max(1) as f64;
        let (without, with) = (pooled(without), pooled(with));
        Self {
            reduction: model_error_reduction(without, with, noise_var),
            without: without.sqrt(),
            with: with.sqrt(),
            wins: d.iter().filter(|x| **x > 0.0).count(),
            folds: d.len(),
            standard_errors: mean / (sd / n.sqrt()).max(f64::MIN_POSITIVE),
        }
    }

    fn passes(&self) -> bool {
        self.reduction >= MIN_RELATIVE_REDUCTION && self.standard_errors >= MIN_STANDARD_ERRORS
    }

    fn words(&self) -> String {
        format!(
            "held-out error {} → {} (model error above noise {:+.0} %), lower on {} of {} segments \
             ({:.1} standard errors); a root must remove {:.0} % of the model error and more than {} \
             standard error",
            fmt_error(self.without),
            fmt_error(self.with),
            -100.0 * self.reduction,
            self.wins,
            self.folds,
            self.standard_errors,
            100.0 * MIN_RELATIVE_REDUCTION,
            MIN_STANDARD_ERRORS
        )
    }
}

fn fmt_error(x: f64) -> String {
    if x.abs() >= 100.0 { format!("{x:.0}") } else { format!("{x:.3}") }
}

/// Share of the model error — the held-out mean squared error above the measurement noise's
/// variance — that a trial removes, as a share of RMS: 1 − √((with − σ²)/(without − σ²)). Zero when
/// the model is already at the noise level (nothing left to remove).
fn model_error_reduction(without_mse: f64, with_mse: f64, noise_var: f64) -> f64 {
    let excess = without_mse - noise_var;
    if excess <= 0.0 {
        return 0.0;
    }
    let left = (with_mse - noise_var).max(0.0);
    1.0 - (left / excess).sqrt()
}

/// Iterations of a cross-validation fold's polish, warm-started from the roots polished on all data.
const FOLD_ITERATIONS: usize = 12;

/// The held-out error of a set of root groups, segment by segment: for each segment the model is
/// fitted (polished from `groups`, the static map of `order` refitted) on the identification range
/// without that segment's response, then simulated through it. Mean squared error per segment.
pub fn cross_validate(data: &IdentData, groups: &[RootGroup], order: usize) -> Option<Vec<f64>> {
    data.fits
        .segments
        .iter()
        .map(|seg| {
            let fold = data.holding_out(seg.step_at, seg.end);
            let residual = if data.settings.refine {
                crate::core::reduce::polish_with(&fold, groups, order, FOLD_ITERATIONS)?.assembled.residual
            } else {
                assemble_groups(&fold, groups, Some(order)).ok()?.residual
            };
            let out = fold.held_out.clone()?;
            let held: Vec<f64> = residual.get(out)?.to_vec();
            Some(rms(&held).powi(2))
        })
        .collect()
}

/// A model of a set of root groups, polished (when the settings ask for it) with the static-map
/// order leave-one-out chooses for its starting roots.
pub fn fitted(data: &IdentData, groups: &[RootGroup]) -> Option<Polished> {
    let start = assemble_groups(data, groups, data.settings.static_order).ok()?;
    let order = start.wiener.map.order();
    if !data.settings.refine {
        let refinement = crate::core::refine::Refinement {
            poles_before: Vec::new(),
            zeros_before: Vec::new(),
            rms_before: start.rms(),
            rms_after: start.rms(),
            iterations: 0,
        };
        return Some(Polished { groups: groups.to_vec(), assembled: start, refinement });
    }
    polish(data, groups, order)
}

/// The automatic proposal: candidate clusters, the forward selection and, when no cluster gives a
/// model, the direct fit (see the module documentation).
pub fn propose(fits: &SegmentFits, ident: &Run, settings: &OutputSettings) -> Result<Proposal, PipelineError> {
    let candidates = cluster::propose_clusters(&fits.roots, &settings.cluster, fits.dt_secs)?;
    let evals = cluster::evaluate_clusters(&candidates, &fits.roots, &settings.cluster, fits.dt_secs)?;
    let data = IdentData::new(fits, ident, settings)?;
    let mut verdicts: Vec<CandidateVerdict> = evals.iter().map(|e| verdict(e, fits.roots.len())).collect();
    let kept = select(&data, &evals, &mut verdicts);
    if kept.is_empty() {
        let direct = direct_fit(&data, &fits.roots)?;
        return Ok(Proposal { clusters: Vec::new(), verdicts, direct: Some(direct) });
    }
    let clusters = evals.iter().enumerate().filter(|(i, _)| kept.contains(i)).map(|(_, e)| e.cluster.clone()).collect();
    Ok(Proposal { clusters, verdicts, direct: None })
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

/// Forward selection over the valid candidates; returns the indices kept and fills the verdicts.
fn select(data: &IdentData, evals: &[ClusterEval], verdicts: &mut [CandidateVerdict]) -> Vec<usize> {
    let groups: Vec<Option<RootGroup>> =
        evals
            .iter()
            .enumerate()
            .map(|(i, e)| e.valid.then(|| RootGroup::of_cluster(i, e).within(data.settings.polish)))
            .collect();
    for (v, g) in verdicts.iter_mut().zip(&groups) {
        if g.is_none() {
            v.reason = "not valid, so not tried".to_owned();
        }
    }
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
    let Some((first_index, mut current)) = first else { return Vec::new() };
    let mut kept = vec![first_index];
    verdicts[first_index].kept = true;
    verdicts[first_index].reason = format!(
        "kept: of the pole candidates it alone fits the identification run best (RMS error {})",
        fmt_error(current.assembled.rms())
    );
    let mut current_cv = cross_validate(data, &current.groups, current.assembled.wiener.map.order());
    let noise_var = data.noise_sigma().powi(2);
    loop {
        let (n_poles, n_zeros) =
            (count_of(&current.groups, RootKind::Pole), count_of(&current.groups, RootKind::Zero));
        // Every remaining candidate beside the kept roots, fitted on the whole identification range.
        let mut trials: Vec<(usize, Polished)> = Vec::new();
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
            match fitted(data, &trial_groups) {
                Some(trial) => trials.push((i, trial)),
                None => verdicts[i].reason = "gives no model beside the kept roots".to_owned(),
            }
        }
        trials.sort_by(|a, b| a.1.assembled.rms().total_cmp(&b.1.assembled.rms()));
        // The most promising few are cross-validated; the rest are judged on their fit alone.
        let mut best: Option<(usize, Polished, Vec<f64>, Gain)> = None;
        for (rank, (i, trial)) in trials.into_iter().enumerate() {
            let without = current.assembled.rms();
            let in_sample = model_error_reduction(without.powi(2), trial.assembled.rms().powi(2), noise_var);
            if std::env::var_os("JETID_TRACE").is_some() { eprintln!("FIT {:?} start {:?} r={:?} fit {:.1}%", trial.groups.last().map(|g| g.root), groups[i].as_ref().map(|g| g.root), groups[i].as_ref().and_then(|g| g.region.map(|r| r.radius)), 100.0*in_sample); }
            let v = &mut verdicts[i];
            v.rms_without = Some(without);
            v.rms_with = Some(trial.assembled.rms());
            let screened_out = rank >= CROSS_VALIDATED_TRIALS || in_sample < SCREEN_SHARE * MIN_RELATIVE_REDUCTION;
            let cv = if screened_out {
                None
            } else {
                cross_validate(data, &trial.groups, trial.assembled.wiener.map.order())
            };
            let (Some(cv), Some(cur)) = (cv, current_cv.as_deref()) else {
                v.reason = format!(
                    "dropped: beside the kept roots it {} the identification error from {} to {} ({:+.0} %), \
                     too little of the error above noise to try it on held-out segments",
                    if in_sample > 0.0 { "lowers" } else { "raises" },
                    fmt_error(without),
                    fmt_error(trial.assembled.rms()),
                    -100.0 * in_sample
                );
                continue;
            };
            let gain = Gain::of(cur, &cv, noise_var);
            if std::env::var_os("JETID_TRACE").is_some() { eprintln!("TRIAL {:?} r={:?} fit {:.1}% cv: {}", groups[i].as_ref().map(|g| g.root), groups[i].as_ref().and_then(|g| g.region.map(|r| r.radius)), 100.0*in_sample, gain.words()); }
            v.standard_errors = Some(gain.standard_errors);
            v.reason = format!("dropped: beside the kept roots, {}", gain.words());
            if best.as_ref().is_none_or(|b| gain.reduction > b.3.reduction) {
                best = Some((i, trial, cv, gain));
            }
        }
        let Some((i, trial, cv, gain)) = best.filter(|b| b.3.passes()) else { break };
        verdicts[i].kept = true;
        verdicts[i].reason = format!("kept: {}", gain.words());
        kept.push(i);
        current = trial;
        current_cv = Some(cv);
    }
    kept.sort_unstable();
    kept
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
fn direct_fit(data: &IdentData, roots: &[SegmentRoots]) -> Result<DirectFit, PipelineError> {
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
        let gain = Gain::of(cur, &cv, data.noise_sigma().powi(2));
        if !gain.passes() {
            break;
        }
        let added = trial.groups.last().map_or("a pole".to_owned(), |g| {
            let (omega, zeta) = natural_freq_and_damping(g.root, data.fits.dt_secs);
            root_words(g.root, g.pair, omega, zeta)
        });
        steps.push(format!("+ {added}: {}", gain.words()));
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
