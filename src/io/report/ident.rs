//! What was identified for one output, as report.json keeps it and report.md shows it: segments,
//! the candidate clusters with the proposal's verdicts, the clusters in use with the roots the
//! model actually has in each, the reduced model and the static map.
use std::fmt::Write as _;

use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use crate::core::identification::arx::ArxModel;
use crate::core::identification::cluster::ClusterEval;
use crate::core::identification::dead_time::DeadTimeVerdict;
use crate::core::identification::pipeline::Identified;
use crate::core::identification::reduce::RootGroup;
use crate::core::identification::segment::Segment;
use crate::core::identification::uncertainty::RootInterval;
use crate::core::identification::verdict::CandidateVerdict;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SegmentSummary {
    pub label: String,
    pub start: usize,
    pub step_at: usize,
    pub end: usize,
    pub rank: usize,
    pub cond: f64,
}

/// A cluster in use, with the segments' evidence and the model's root in it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClusterSummary {
    pub kind: String,
    pub centre: Complex64,
    pub radius: f64,
    pub found: usize,
    pub needed: usize,
    pub valid: bool,
    pub status: String,
    /// Mean of the member roots (the evidence of the segment models).
    pub centroid: Complex64,
    pub spread: f64,
    /// Of the centroid.
    pub natural_freq_rad_s: f64,
    pub time_constant_secs: Option<f64>,
    /// The root the model has from this cluster (polished inside the circle), when it is in use.
    #[serde(default)]
    pub model_root: Option<RootSummary>,
}

/// One root (or conjugate pair) of the model's linear block, with its s-plane figures.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RootSummary {
    pub kind: String,
    /// In the upper half-plane for a pair (its conjugate is implied).
    pub root: Complex64,
    pub pair: bool,
    /// Index into `clusters` of the cluster it came from; none for a directly fitted root.
    pub cluster: Option<usize>,
    pub natural_freq_rad_s: f64,
    pub damping: f64,
    pub time_constant_secs: Option<f64>,
    /// 95 % intervals of the three figures from the fit's covariance (see
    /// `core::identification::uncertainty`); absent when the data do not fix the root.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub natural_freq_rad_s_ci95: Option<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping_ci95: Option<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_constant_secs_ci95: Option<[f64; 2]>,
    /// The polish left it on the rim of its cluster: the data pull it further out.
    pub at_rim: bool,
}

/// A candidate cluster of the automatic proposal and what became of it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CandidateSummary {
    pub kind: String,
    pub centre: Complex64,
    pub radius: f64,
    /// Segments holding a root in the circle, of all segments (m/J).
    pub segments_found: usize,
    pub segments_total: usize,
    pub natural_freq_rad_s: f64,
    pub damping: f64,
    pub kept: bool,
    /// Why it was kept or dropped, in one sentence.
    pub reason: String,
    /// Identification RMS error without and with it, output units.
    pub rms_without: Option<f64>,
    pub rms_with: Option<f64>,
    /// Standard errors by which it lowers the held-out error (cross-validation across segments).
    pub standard_errors: Option<f64>,
}

/// The input dead time the automatic proposal tried beside its roots, and why the model carries it
/// or not: the segment models' delay beside the model's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DeadTimeSummary {
    /// Dead time tried or kept, s (samples × sample time).
    pub secs: f64,
    pub samples: usize,
    /// The segment ARX models' input delay, samples.
    pub arx_nk: usize,
    /// Whether the reduced model carries it.
    pub kept: bool,
    /// The proposal's sentence.
    pub reason: String,
}

/// What was identified for one output.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IdentSummary {
    pub arx_orders: [usize; 3],
    pub segments: Vec<SegmentSummary>,
    /// The clusters in use.
    pub clusters: Vec<ClusterSummary>,
    /// The automatic proposal's candidates with their verdicts (empty when clusters were given).
    #[serde(default)]
    pub candidates: Vec<CandidateSummary>,
    /// The model's roots as it uses them.
    #[serde(default)]
    pub roots: Vec<RootSummary>,
    /// What the automatic proposal decided about the input dead time, when it ran.
    #[serde(default)]
    pub dead_time: Option<DeadTimeSummary>,
    /// The proposal's circles that followed their roots out of the segment models' circles, one
    /// sentence each.
    #[serde(default)]
    pub circles_followed: Vec<String>,
    /// Why the linear block was fitted directly instead of built from clusters, when it was.
    #[serde(default)]
    pub direct_fit: Option<String>,
    pub poles: Vec<Complex64>,
    pub zeros: Vec<Complex64>,
    pub dc_gain: Option<f64>,
    pub offset: f64,
    pub static_map_beta: Vec<f64>,
    pub static_order: usize,
    /// (order, leave-one-out RMSE) when the order was chosen from the data.
    pub static_order_loo: Vec<(usize, f64)>,
    pub refined: bool,
    pub diagnostics: Vec<String>,
}

impl IdentSummary {
    /// The summary of an identification.
    pub fn of(identified: &Identified) -> Self {
        let model = &identified.model;
        let tf = &model.wiener.linear.tf;
        let fits = &identified.fits;
        let roots: Vec<RootSummary> = model
            .roots
            .iter()
            .enumerate()
            .map(|(i, g)| RootSummary::of(g, fits.dt_secs, model.root_intervals.get(i)))
            .collect();
        Self {
            arx_orders: fits.models.first().map_or([0; 3], |m| [m.orders.na, m.orders.nb, m.orders.nk]),
            segments: fits.segments.iter().zip(&fits.models).map(|(s, m)| SegmentSummary::of(s, m)).collect(),
            clusters: identified
                .evals
                .iter()
                .enumerate()
                .map(|(i, e)| ClusterSummary::of(i, e, &roots))
                .collect(),
            candidates: identified
                .proposal
                .iter()
                .flat_map(|p| &p.verdicts)
                .map(CandidateSummary::of)
                .collect(),
            roots,
            dead_time: identified.proposal.as_ref().map(|p| DeadTimeSummary::of(&p.dead_time)),
            circles_followed: identified
                .proposal
                .iter()
                .flat_map(|p| &p.followed)
                .map(|f| format!("{}: {f}", f.heading()))
                .collect(),
            direct_fit: model.direct_fit.clone(),
            poles: tf.poles().unwrap_or_default(),
            zeros: tf.zeros().unwrap_or_default(),
            dc_gain: tf.dc_gain().ok(),
            offset: model.wiener.linear.offset,
            static_map_beta: model.wiener.map.beta(),
            static_order: model.wiener.map.order(),
            static_order_loo: model
                .static_suggestion
                .as_ref()
                .map(|s| s.loo_rmse.clone())
                .unwrap_or_default(),
            refined: model.refinement.is_some(),
            diagnostics: fits.diagnostics.clone(),
        }
    }
}

impl SegmentSummary {
    fn of(segment: &Segment, model: &ArxModel) -> Self {
        Self {
            label: segment.label.clone(),
            start: segment.start,
            step_at: segment.step_at,
            end: segment.end,
            rank: model.rank,
            cond: model.cond,
        }
    }
}

impl ClusterSummary {
    /// Cluster `index` in use, with the model's root in it among `roots`.
    fn of(index: usize, e: &ClusterEval, roots: &[RootSummary]) -> Self {
        Self {
            kind: format!("{:?}", e.cluster.kind),
            centre: e.cluster.centre,
            radius: e.cluster.radius,
            found: e.segments_found,
            needed: e.segments_needed,
            valid: e.valid,
            status: format!("{:?}", e.status),
            centroid: e.centroid,
            spread: e.spread,
            natural_freq_rad_s: e.natural_freq_rad_s,
            time_constant_secs: e.time_constant_secs,
            model_root: roots.iter().find(|r| r.cluster == Some(index)).cloned(),
        }
    }
}

impl CandidateSummary {
    fn of(v: &CandidateVerdict) -> Self {
        Self {
            kind: format!("{:?}", v.cluster.kind),
            centre: v.cluster.centre,
            radius: v.cluster.radius,
            segments_found: v.segments_found,
            segments_total: v.segments_total,
            natural_freq_rad_s: v.natural_freq_rad_s,
            damping: v.damping,
            kept: v.kept(),
            reason: v.verdict.to_string(),
            rms_without: v.rms_without,
            rms_with: v.rms_with,
            standard_errors: v.standard_errors,
        }
    }
}

impl DeadTimeSummary {
    fn of(d: &DeadTimeVerdict) -> Self {
        Self {
            secs: d.samples as f64 * d.dt_secs,
            samples: d.samples,
            arx_nk: d.arx_nk,
            kept: d.kept(),
            reason: d.sentence(),
        }
    }
}

impl RootSummary {
    /// A root of the model with its s-plane figures and, when known, their 95 % intervals.
    pub fn of(g: &RootGroup, dt_secs: f64, interval: Option<&RootInterval>) -> Self {
        let (natural_freq_rad_s, damping, time_constant_secs) = g.s_plane(dt_secs);
        Self {
            natural_freq_rad_s_ci95: interval.and_then(|i| i.natural_freq_rad_s),
            damping_ci95: interval.and_then(|i| i.damping),
            time_constant_secs_ci95: interval.and_then(|i| i.time_constant_secs),
            kind: format!("{:?}", g.kind),
            root: g.root,
            pair: g.pair,
            cluster: g.cluster,
            natural_freq_rad_s,
            damping,
            time_constant_secs,
            at_rim: g.at_rim(),
        }
    }
}

pub(super) fn fmt_complex(z: &Complex64) -> String {
    if z.im.abs() < 1e-12 {
        format!("{:.4}", z.re)
    } else {
        format!("{:.4} {} {:.4}j", z.re, if z.im < 0.0 { "−" } else { "+" }, z.im.abs())
    }
}

/// "0.8043 ± 0.2288j" for a pair, "0.9346" for a real root.
fn fmt_root(r: &RootSummary) -> String {
    if r.pair { format!("{:.4} ± {:.4}j", r.root.re, r.root.im.abs()) } else { format!("{:.4}", r.root.re) }
}

/// A figure with the half-width of its 95 % interval (`value ± half`; the interval is symmetric).
fn fmt_with_ci(value: f64, ci95: Option<[f64; 2]>) -> String {
    match ci95 {
        Some([lo, hi]) => format!("{value:.3} ± {:.3}", 0.5 * (hi - lo)),
        None => format!("{value:.3}"),
    }
}

pub(super) fn ident_section(out: &mut String, id: &IdentSummary, unit: &str) {
    let [na, nb, nk] = id.arx_orders;
    let _ = writeln!(
        out,
        "Segment ARX models: {na} poles, {nb} zeros, delay {nk}; {} segments.\n",
        id.segments.len()
    );
    if !id.candidates.is_empty() {
        candidates_table(out, &id.candidates);
    }
    if let Some(d) = &id.dead_time {
        let _ = writeln!(out, "Dead time: {}.\n", d.reason);
    }
    if let Some(note) = &id.direct_fit {
        let _ = writeln!(out, "**Fitted directly:** {note}\n");
    }
    if !id.clusters.is_empty() {
        clusters_table(out, &id.clusters);
    }
    for sentence in &id.circles_followed {
        let _ = writeln!(out, "- {sentence}.");
    }
    fitted_roots_table(out, &id.roots);
    let poles: Vec<String> = id.poles.iter().map(fmt_complex).collect();
    let zeros: Vec<String> = id.zeros.iter().map(fmt_complex).collect();
    let _ = writeln!(
        out,
        "\nReduced model{}: poles {}; zeros {}; steady-state gain {} {unit} per input unit, offset {:.4}.",
        if id.refined { " (roots polished by simulation error)" } else { "" },
        poles.join(", "),
        if zeros.is_empty() { "none".to_owned() } else { zeros.join(", ") },
        id.dc_gain.map_or("–".to_owned(), |g| format!("{g:.5}")),
        id.offset
    );
    let beta: Vec<String> =
        id.static_map_beta.iter().enumerate().map(|(i, b)| format!("{b:.6e}·v^{i}")).collect();
    let _ = writeln!(out, "Static map (order {}): f(v) = {}.", id.static_order, beta.join(" + "));
    if !id.static_order_loo.is_empty() {
        let loo: Vec<String> =
            id.static_order_loo.iter().map(|(o, e)| format!("order {o}: {e:.4}")).collect();
        let _ = writeln!(out, "Leave-one-out RMSE on the steady points: {}.", loo.join(", "));
    }
    for d in &id.diagnostics {
        let _ = writeln!(out, "- note: {d}");
    }
}

/// The clusters in use, with the root the model has in each.
fn clusters_table(out: &mut String, clusters: &[ClusterSummary]) {
    let _ = writeln!(
        out,
        "Clusters in use, with the root the model has in each (polished inside the circle); ± is the half-width \
         of the 95 % interval the identification data give the figure (report.json: `*_ci95`):\n\n\
         | cluster | centre | radius | members | valid | centroid | model root | ωn (rad/s) | ζ | τ (s) |\n\
         |---|---|---|---|---|---|---|---|---|---|"
    );
    for (i, c) in clusters.iter().enumerate() {
        let (root, omega, zeta, tau) = match &c.model_root {
            Some(r) => (
                format!("{}{}", fmt_root(r), if r.at_rim { " (on the rim)" } else { "" }),
                fmt_with_ci(r.natural_freq_rad_s, r.natural_freq_rad_s_ci95),
                fmt_with_ci(r.damping, r.damping_ci95),
                r.time_constant_secs.map_or("–".to_owned(), |t| fmt_with_ci(t, r.time_constant_secs_ci95)),
            ),
            None => ("not in the model".to_owned(), "–".to_owned(), "–".to_owned(), "–".to_owned()),
        };
        let valid = if c.valid { "yes".to_owned() } else { c.status.clone() };
        let cells = [
            format!("{} {}", c.kind, i + 1),
            fmt_complex(&c.centre),
            format!("{:.4}", c.radius),
            format!("{}/{}", c.found, c.needed),
            valid,
            fmt_complex(&c.centroid),
        ];
        table_row(out, cells.into_iter().chain([root, omega, zeta, tau]));
    }
}

/// The roots fitted directly (in no cluster), when there are any.
fn fitted_roots_table(out: &mut String, roots: &[RootSummary]) {
    let free: Vec<&RootSummary> = roots.iter().filter(|r| r.cluster.is_none()).collect();
    if !free.is_empty() {
        let _ = writeln!(
            out,
            "\nRoots fitted directly; ± is the half-width of the 95 % interval:\n\n| fitted root | ωn (rad/s) | ζ | τ (s) |\n|---|---|---|---|"
        );
        for r in free {
            let cells = [
                format!("{} {}", r.kind, fmt_root(r)),
                fmt_with_ci(r.natural_freq_rad_s, r.natural_freq_rad_s_ci95),
                fmt_with_ci(r.damping, r.damping_ci95),
                r.time_constant_secs.map_or("–".to_owned(), |t| fmt_with_ci(t, r.time_constant_secs_ci95)),
            ];
            table_row(out, cells);
        }
    }
}

/// The automatic proposal: every candidate, kept or dropped, and why.
fn candidates_table(out: &mut String, candidates: &[CandidateSummary]) {
    let _ = writeln!(
        out,
        "Automatic proposal: candidate clusters (held by m of J segment models) and why each was kept \
         or dropped, judged by the simulation error on the identification run (never on the validation \
         runs):\n\n| candidate | centre | m/J | ωn (rad/s) | ζ | verdict |\n|---|---|---|---|---|---|"
    );
    for (i, c) in candidates.iter().enumerate() {
        let cells = [
            format!("{} {}", c.kind, i + 1),
            fmt_complex(&c.centre),
            format!("{}/{}", c.segments_found, c.segments_total),
            format!("{:.3}", c.natural_freq_rad_s),
            format!("{:.3}", c.damping),
            c.reason.clone(),
        ];
        table_row(out, cells);
    }
    let _ = writeln!(out);
}

/// One row of a report.md table: `| a | b | … |`.
fn table_row(out: &mut String, cells: impl IntoIterator<Item = String>) {
    let cells: Vec<String> = cells.into_iter().collect();
    let _ = writeln!(out, "| {} |", cells.join(" | "));
}
