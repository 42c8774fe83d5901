//! The Z-plane view: every segment model's poles and zeros, the clusters (drag a centre to move one,
//! its rim to resize it), the cluster table and a live strip of the reduced model and its errors.
pub mod cluster_table;
pub mod plot;
mod state;

pub use state::{ClusterDrag, Handle, ZPlaneViewState, ZoomView, fit_view};

use egui::{RichText, Sense};
use num_complex::Complex64;

use crate::core::identification::cluster::{Cluster, RootKind};
use crate::ui::derived::model_cache::Proposed;
use crate::ui::derived::{Derived, LiveView};
use crate::ui::state::command::Command;
use crate::ui::state::setup::History;
use crate::ui::theme;
use crate::ui::views::zplane::cluster_table as cluster_table_ui;
use crate::ui::views::zplane::plot as zplane_plot;
use crate::ui::widgets::model::{self as model_ui, roots_text};

/// Width of the column beside the plot (overview, live strip, cluster table).
const SIDE_WIDTH: f32 = 560.0;
const OVERVIEW_SIDE: f32 = 210.0;

pub fn zplane_ui(
    ui: &mut egui::Ui,
    output: &str,
    history: &History,
    state: &mut ZPlaneViewState,
    cache: &Derived,
) -> Vec<Command> {
    let mut commands = Vec::new();
    let Some(view) = cache.live_view(output) else { return commands };
    if state.selected.is_some_and(|i| i >= view.clusters.len()) {
        state.selected = None;
    }
    commands.extend(toolbar_ui(ui, output, &view, history, state));
    if let Err(err) = &view.output.fits {
        model_ui::error_ui(ui, &format!("No segment models, so nothing to cluster: {err}"));
        return commands;
    }
    let side_width = SIDE_WIDTH.min(ui.available_width() * 0.45);
    let plot_width = ui.available_width() - side_width - ui.spacing().item_spacing.x;
    let height = ui.available_height();
    ui.horizontal_top(|ui| {
        ui.allocate_ui(egui::vec2(plot_width, height), |ui| {
            ui.vertical(|ui| commands.extend(zplane_plot::main_plot_ui(ui, &view, state, height)));
        });
        ui.allocate_ui(egui::vec2(side_width, height), |ui| {
            ui.vertical(|ui| {
                ui.horizontal_top(|ui| {
                    zplane_plot::overview_ui(ui, &view, state, OVERVIEW_SIDE);
                    ui.vertical(|ui| live_strip_ui(ui, &view));
                });
                ui.separator();
                legend_ui(ui, &view);
                ui.separator();
                cluster_table_ui::cluster_table_ui(ui, &view, state);
            });
        });
    });
    commands
}

fn toolbar_ui(
    ui: &mut egui::Ui,
    output: &str,
    view: &LiveView<'_>,
    history: &History,
    state: &mut ZPlaneViewState,
) -> Vec<Command> {
    let mut commands = Vec::new();
    ui.horizontal_wrapped(|ui| {
        commands.extend(cluster_buttons_ui(ui, output, view, state));
        ui.separator();
        if ui.add_enabled(history.can_undo(), egui::Button::new("Undo")).on_hover_text("Ctrl+Z").clicked() {
            commands.push(Command::Undo);
        }
        if ui
            .add_enabled(history.can_redo(), egui::Button::new("Redo"))
            .on_hover_text("Ctrl+Shift+Z")
            .clicked()
        {
            commands.push(Command::Redo);
        }
        ui.separator();
        if ui.button("Fit clusters").clicked() {
            state.zoom.insert(output.to_owned(), fit_view(view));
        }
        if ui.button("Whole circle").clicked() {
            state.zoom.insert(output.to_owned(), ZoomView::WHOLE);
        }
        ui.separator();
        commands.extend(polish_checkbox_ui(ui, output, view));
    });
    ui.horizontal_wrapped(|ui| {
        let source = if view.output.setup.clusters.is_none() { "automatic proposal" } else { "edited" };
        ui.label(RichText::new(format!("Clusters: {source}")).strong());
        model_ui::hint(
            ui,
            "× pole, o zero of each segment's ARX model · drag a circle's centre to move it, its rim to \
             resize it (Esc cancels) · drag empty space to pan, wheel to zoom",
        );
    });
    commands
}

/// Add a pole or zero cluster, delete the selected one, accept the automatic proposal.
fn cluster_buttons_ui(
    ui: &mut egui::Ui,
    output: &str,
    view: &LiveView<'_>,
    state: &mut ZPlaneViewState,
) -> Vec<Command> {
    let mut commands = Vec::new();
    let set =
        |clusters: Vec<Cluster>| Command::SetClusters { output: output.to_owned(), clusters: Some(clusters) };
    let zoom = *state.zoom.entry(output.to_owned()).or_insert_with(|| fit_view(view));
    for (label, kind) in [("+ Pole cluster", RootKind::Pole), ("+ Zero cluster", RootKind::Zero)] {
        if ui.button(label).on_hover_text("Add a cluster in the middle of the view").clicked() {
            let mut clusters = view.clusters.to_vec();
            let centre = Complex64::new(zoom.centre[0], zoom.centre[1]);
            clusters.push(Cluster::new(kind, centre, 0.08 * zoom.half_width));
            state.selected = Some(clusters.len() - 1);
            commands.push(set(clusters));
        }
    }
    let delete_key = ui.input(|i| i.key_pressed(egui::Key::Delete)) && !ui.ctx().egui_wants_keyboard_input();
    let delete = ui
        .add_enabled(state.selected.is_some(), egui::Button::new("Delete"))
        .on_hover_text("Delete the selected cluster (Del)");
    if (delete.clicked() || delete_key)
        && let Some(i) = state.selected.filter(|i| *i < view.clusters.len())
    {
        let mut clusters = view.clusters.to_vec();
        clusters.remove(i);
        state.selected = None;
        commands.push(set(clusters));
    }
    let automatic = view.output.setup.clusters.is_none();
    let accept = ui
        .add_enabled(!automatic, egui::Button::new("Accept automatic proposal"))
        .on_hover_text(proposal_hint(&view.output.proposal));
    if accept.clicked() {
        state.selected = None;
        commands.push(Command::SetClusters { output: output.to_owned(), clusters: None });
    }
    commands
}

/// What accepting the automatic proposal would do, in words.
fn proposal_hint(proposal: &Proposed) -> String {
    match proposal {
        Proposed::Ready(proposal) if proposal.direct.is_some() => {
            "Replace the clusters by the automatic proposal: roots fitted directly (no cluster \
             met the aggregation condition)"
                .to_owned()
        }
        Proposed::Ready(proposal) => format!(
            "Replace the clusters by the {} proposed from the segment roots, with the proposal's \
             dead time",
            proposal.clusters.len()
        ),
        Proposed::Running(_) => "The automatic proposal is being computed".to_owned(),
        Proposed::Failed(err) => format!("The proposal failed: {err}"),
    }
}

/// Polish the centroids after a change, or not.
fn polish_checkbox_ui(ui: &mut egui::Ui, output: &str, view: &LiveView<'_>) -> Option<Command> {
    let mut refine = view.output.setup.settings.refine;
    let polish = ui.checkbox(&mut refine, "Polish centroids").on_hover_text(
        "After a change, move the reduced roots to lower the simulation error on the identification run \
         (not while dragging)",
    );
    polish.changed().then(|| {
        let settings = crate::core::identification::settings::OutputSettings {
            refine,
            ..view.output.setup.settings.clone()
        };
        Command::SetOutputSettings { output: output.to_owned(), settings }
    })
}

/// What the marks on the z-plane are.
#[derive(Clone, Copy)]
enum Mark {
    PoleAndZero,
    Circle { dashed: bool },
}

fn mark_ui(ui: &mut egui::Ui, mark: Mark, colour: egui::Color32, text: &str) {
    let (rect, _) = ui.allocate_exact_size(egui::vec2(26.0, 14.0), Sense::hover());
    let painter = ui.painter();
    let stroke = egui::Stroke::new(1.6, colour);
    match mark {
        Mark::PoleAndZero => {
            let c = rect.left_center() + egui::vec2(6.0, 0.0);
            let d = 4.0;
            painter.line_segment([c + egui::vec2(-d, -d), c + egui::vec2(d, d)], stroke);
            painter.line_segment([c + egui::vec2(-d, d), c + egui::vec2(d, -d)], stroke);
            painter.circle_stroke(rect.left_center() + egui::vec2(19.0, 0.0), 4.0, stroke);
        }
        Mark::Circle { dashed } => {
            if dashed {
                let pts = [rect.left_center(), rect.right_center()];
                painter.extend(egui::Shape::dashed_line(&pts, stroke, 4.0, 3.0));
            } else {
                painter.circle_stroke(rect.center(), 6.0, stroke);
            }
        }
    }
    ui.label(RichText::new(text).color(colour));
}

/// Segment colours (× pole, o zero) and the cluster and model marks.
fn legend_ui(ui: &mut egui::Ui, view: &LiveView<'_>) {
    ui.horizontal_wrapped(|ui| {
        ui.spacing_mut().item_spacing.x = 4.0;
        if let Ok(fits) = &view.output.fits {
            ui.label("segments:");
            for (i, roots) in fits.roots.iter().enumerate() {
                mark_ui(ui, Mark::PoleAndZero, theme::segment_colour(i), &roots.label);
                ui.add_space(6.0);
            }
        }
    });
    ui.horizontal_wrapped(|ui| {
        ui.spacing_mut().item_spacing.x = 4.0;
        mark_ui(ui, Mark::Circle { dashed: false }, theme::CLUSTER_VALID, "valid cluster");
        ui.add_space(8.0);
        mark_ui(ui, Mark::Circle { dashed: true }, theme::CLUSTER_INVALID, "invalid cluster");
        ui.add_space(8.0);
        mark_ui(ui, Mark::PoleAndZero, theme::REDUCED, "reduced model");
        if let Ok(live) = view.live
            && let Ok(u) = &live.uncertainty
        {
            ui.add_space(8.0);
            if u.refitted_block(&live.model.wiener.linear.tf).is_some() {
                mark_ui(ui, Mark::PoleAndZero, theme::MODEL, zplane_plot::REFITTED_NAME);
                ui.add_space(8.0);
                mark_ui(ui, Mark::Circle { dashed: false }, theme::MODEL, "their 95 % regions (parameters)");
            } else {
                mark_ui(ui, Mark::Circle { dashed: false }, theme::REDUCED, "its 95 % regions (parameters)");
            }
        }
    });
}

/// Characters of a run's name in the live strip: the side column is as wide as the overview, and a
/// longer name (the JetCat's are 34 characters) pushed the fit column out of the view.
const RUN_NAME_CHARS: usize = 24;

/// The reduced model and its validation errors, live while dragging.
fn live_strip_ui(ui: &mut egui::Ui, view: &LiveView<'_>) {
    ui.label(RichText::new("Reduced model").strong());
    if view.is_preview {
        ui.label(
            RichText::new("preview while dragging: centroids not polished").color(theme::WARNING).small(),
        );
    }
    let live = match view.live {
        Ok(live) => live,
        Err(err) => {
            model_ui::error_ui(ui, &format!("No model: {err}"));
            return;
        }
    };
    if live.finishing {
        ui.label(RichText::new("polishing the centroids…").color(theme::WARNING).small());
    } else if !view.is_preview && live.polish_requested {
        let text = if live.model.refinement.is_some() {
            "centroids polished"
        } else {
            "centroids (polish did not help)"
        };
        ui.label(RichText::new(text).color(theme::HINT).small());
    }
    let tf = &live.model.wiener.linear.tf;
    ui.label(format!("poles: {}", roots_text(&tf.poles().unwrap_or_default())));
    ui.label(format!("zeros: {}", roots_text(&tf.zeros().unwrap_or_default())));
    ui.label(format!("static map: order {}", live.model.wiener.map.order()));
    ui.add_space(4.0);
    egui::Grid::new("live_strip_metrics").num_columns(3).spacing([10.0, 2.0]).show(ui, |ui| {
        ui.label(RichText::new("run").small());
        ui.label(RichText::new("RMSPE").small());
        ui.label(RichText::new("fit").small());
        ui.end_row();
        for run in &live.runs {
            ui.label(model_ui::clipped(&run.name, RUN_NAME_CHARS)).on_hover_text(format!(
                "{} ({})",
                run.name,
                run.role.label()
            ));
            ui.label(RichText::new(format!("{:.3} %", run.gray_box.metrics.rmspe_pct)).monospace().strong());
            ui.label(RichText::new(format!("{:.1} %", run.gray_box.metrics.fit_pct)).monospace());
            ui.end_row();
        }
    });
    if live.runs.is_empty() {
        model_ui::hint(ui, "No validation or chirp run to score the model on.");
    }
}
