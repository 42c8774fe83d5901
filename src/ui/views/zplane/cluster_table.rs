//! The cluster table beside the z-plane: each cluster with its members (m of J segments), and the
//! root of the model actually in use that it gave (after the polish, kept inside the circle) with
//! its ωn, ζ and τ; then why the automatic proposal kept or dropped each candidate, its dead time,
//! and the note when the roots were fitted directly.
use egui::{RichText, Sense};

use super::state::ZPlaneViewState;
use crate::core::identification::cluster::{ClusterEval, RootKind};
use crate::core::identification::reduce::RootGroup;
use crate::core::identification::structure::Proposal;
use crate::core::identification::words::root_words;
use crate::ui::derived::LiveView;
use crate::ui::derived::model_cache::Proposed;
use crate::ui::theme;
use crate::ui::widgets::model::{self as model_ui, complex_text, hint};

/// The cluster table, then the free roots of the model (a direct fit), then the proposal's reasons.
pub fn cluster_table_ui(ui: &mut egui::Ui, view: &LiveView<'_>, state: &mut ZPlaneViewState) {
    egui::ScrollArea::vertical().id_salt("cluster_table").auto_shrink([false, true]).show(ui, |ui| {
        clusters_ui(ui, view, state);
        free_roots_ui(ui, view);
        proposal_ui(ui, view);
    });
}

/// The model's root groups (empty without a model).
fn model_roots<'a>(view: &'a LiveView<'_>) -> &'a [RootGroup] {
    view.live.as_ref().map_or(&[], |live| live.model.roots.as_slice())
}

fn dt_secs(view: &LiveView<'_>) -> f64 {
    view.output.fits.as_ref().map_or(1.0, |f| f.dt_secs)
}

fn clusters_ui(ui: &mut egui::Ui, view: &LiveView<'_>, state: &mut ZPlaneViewState) {
    let evals: &[ClusterEval] = match view.evals {
        Ok(evals) => evals,
        Err(err) => {
            model_ui::error_ui(ui, &format!("The clusters could not be evaluated: {err}"));
            return;
        }
    };
    if evals.is_empty() {
        if view.output.proposal.is_running() && view.output.setup.clusters.is_none() {
            hint(ui, "The automatic proposal is being computed.");
        } else if model_roots(view).is_empty() {
            hint(ui, "No clusters. Add one, or accept the automatic proposal.");
        }
        return;
    }
    let roots = model_roots(view);
    let dt = dt_secs(view);
    let segments = view.output.fits.as_ref().map_or(0, |f| f.roots.len());
    egui::Grid::new("cluster_table_grid").striped(true).num_columns(9).spacing([10.0, 4.0]).show(ui, |ui| {
        for title in ["", "members", "radius", "model root", "ωn [rad/s]", "ζ", "τ [s]", "status"] {
            ui.label(RichText::new(title).strong());
        }
        ui.end_row();
        for (i, eval) in evals.iter().enumerate() {
            let kind = if eval.cluster.kind == RootKind::Pole { "p" } else { "z" };
            let colour = if eval.valid { theme::CLUSTER_VALID } else { theme::CLUSTER_INVALID };
            let name = RichText::new(format!("{kind}{}", i + 1)).color(colour).strong();
            if ui.add(egui::Button::selectable(state.selected == Some(i), name)).clicked() {
                state.selected = Some(i);
            }
            ui.label(format!("{} / {segments}", eval.segments_found))
                .on_hover_text(format!("{} needed (the aggregation condition)", eval.segments_needed));
            ui.label(format!("{:.4}", eval.cluster.radius));
            match roots.iter().find(|g| g.cluster == Some(i)) {
                Some(group) => root_cells_ui(ui, group, dt),
                None => {
                    for _ in 0..4 {
                        ui.label(RichText::new("–").color(theme::HINT));
                    }
                }
            }
            let rim = roots.iter().any(|g| g.cluster == Some(i) && g.at_rim());
            let (text, detail, colour) = if rim {
                (
                    "at rim",
                    "Valid, but the polish pushed the model's root to the circle's rim: the data want it further \
                     out. Move or widen the circle to let it go."
                        .to_owned(),
                    theme::WARNING,
                )
            } else {
                (model_ui::status_text(eval), model_ui::status_detail(eval), colour)
            };
            ui.add(egui::Label::new(RichText::new(text).color(colour)).sense(Sense::hover()))
                .on_hover_text(detail);
            ui.end_row();
        }
    });
}

/// The root, ωn, ζ and τ cells of one root group.
fn root_cells_ui(ui: &mut egui::Ui, group: &RootGroup, dt_secs: f64) {
    let (omega, zeta, tau) = group.s_plane(dt_secs);
    let root = if group.pair {
        format!("{:.4}±{:.4}i", group.root.re, group.root.im.abs())
    } else {
        complex_text(group.root)
    };
    ui.label(RichText::new(root).monospace());
    ui.label(format!("{omega:.3}"));
    ui.label(if group.pair { format!("{zeta:.3}") } else { "–".to_owned() });
    ui.label(tau.map_or_else(|| "–".to_owned(), |t| format!("{t:.3}")));
}

/// Roots of the model that no cluster gave (the direct fit's), with their ωn, ζ and τ.
fn free_roots_ui(ui: &mut egui::Ui, view: &LiveView<'_>) {
    let free: Vec<&RootGroup> = model_roots(view).iter().filter(|g| g.cluster.is_none()).collect();
    if free.is_empty() {
        return;
    }
    ui.add_space(6.0);
    ui.label(RichText::new("Roots fitted directly (no cluster)").strong());
    let dt = dt_secs(view);
    egui::Grid::new("free_roots_grid").striped(true).num_columns(5).spacing([10.0, 4.0]).show(ui, |ui| {
        for title in ["", "model root", "ωn [rad/s]", "ζ", "τ [s]"] {
            ui.label(RichText::new(title).strong());
        }
        ui.end_row();
        for (i, group) in free.iter().enumerate() {
            let kind = if group.kind == RootKind::Pole { "pole" } else { "zero" };
            ui.label(format!("{kind} {}", i + 1));
            root_cells_ui(ui, group, dt);
            ui.end_row();
        }
    });
}

/// Why the automatic proposal kept or dropped each candidate, its dead time and its direct fit.
fn proposal_ui(ui: &mut egui::Ui, view: &LiveView<'_>) {
    ui.add_space(6.0);
    let proposal = match &view.output.proposal {
        Proposed::Ready(proposal) => proposal,
        Proposed::Running(job) => {
            ui.horizontal(|ui| {
                ui.spinner();
                hint(ui, &format!("{} … {:.1} s", job.label(), job.elapsed().as_secs_f64()));
            });
            return;
        }
        Proposed::Failed(err) => {
            model_ui::error_ui(ui, &format!("The automatic proposal failed: {err}"));
            return;
        }
    };
    let title = if view.output.setup.clusters.is_some() {
        "The automatic proposal (not in use: the clusters were edited)"
    } else {
        "Why the automatic proposal chose these"
    };
    egui::CollapsingHeader::new(RichText::new(title).strong())
        .id_salt("proposal_reasons")
        .default_open(true)
        .show(ui, |ui| reasons_ui(ui, proposal));
}

fn reasons_ui(ui: &mut egui::Ui, proposal: &Proposal) {
    for verdict in &proposal.verdicts {
        let kind = if verdict.cluster.kind == RootKind::Pole { "pole" } else { "zero" };
        let what = root_words(
            verdict.cluster.centre,
            !verdict.cluster.is_real_axis(),
            verdict.natural_freq_rad_s,
            verdict.damping,
        );
        let what = format!("{kind} {what}, {}/{} segments", verdict.segments_found, verdict.segments_total);
        reason_ui(ui, verdict.kept(), &what, &verdict.verdict.to_string());
    }
    let dead_time = &proposal.dead_time;
    let what = format!(
        "input dead time {:.2} s ({} samples)",
        dead_time.samples as f64 * dead_time.dt_secs,
        dead_time.samples
    );
    reason_ui(ui, dead_time.kept(), &what, &dead_time.decision.to_string());
    for follow in &proposal.followed {
        let mut words = format!("{}: {follow}", follow.heading());
        words[..1].make_ascii_uppercase();
        ui.add(egui::Label::new(RichText::new(words).color(theme::WARNING)).wrap());
    }
    if let Some(direct) = &proposal.direct {
        ui.add(egui::Label::new(RichText::new(&direct.note).color(theme::WARNING)).wrap());
    }
}

/// One candidate: kept or dropped and what it is on one line, why below it.
fn reason_ui(ui: &mut egui::Ui, kept: bool, what: &str, reason: &str) {
    let (word, colour) = if kept { ("kept", theme::CLUSTER_VALID) } else { ("dropped", theme::HINT) };
    ui.horizontal(|ui| {
        ui.label(RichText::new(word).color(colour).strong());
        ui.label(what);
    });
    ui.indent(what, |ui| {
        ui.add(egui::Label::new(RichText::new(reason).color(theme::HINT).small()).wrap());
    });
}
