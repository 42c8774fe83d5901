//! The Diagnosis view's left part: the error history after each step, the effects in the model
//! (added by hand, each with Remove), the missing-physics loop (its rounds, what it added, its
//! progress while it runs, with Stop) and the fitted parameters.
use egui::RichText;
use egui_plot::{Bar, BarChart, Plot, Text};

use crate::core::diagnose::HistoryStep;
use crate::ui::derived::model_cache::{LiveModel, OutputCache};
use crate::ui::state::command::Command;
use crate::ui::theme;
use crate::ui::widgets::model::hint;

/// Most rounds the loop can be set to from the view: each round diagnoses every candidate (seconds
/// on long runs), and more than a handful of effects on one engine is a sign the structure is wrong.
const MAX_ROUNDS: usize = 5;

/// The error history beside the effects in the model and the loop; `shared_with`: what the other
/// outputs' models took of this one's spool blocks, in words.
pub(super) fn effects_panel_ui(
    ui: &mut egui::Ui,
    output: &str,
    cache: &OutputCache,
    live: &LiveModel,
    shared_with: &[String],
) -> Vec<Command> {
    let mut commands = Vec::new();
    ui.horizontal_top(|ui| {
        ui.vertical(|ui| {
            ui.set_width(460.0);
            ui.label(RichText::new("Error history (mean validation RMSPE)").strong());
            history_chart_ui(ui, output, &live.effects.history);
        });
        ui.vertical(|ui| {
            commands.extend(effects_list_ui(ui, output, live));
            commands.extend(loop_ui(ui, output, cache, live));
            shared_ui(ui, live);
            if !shared_with.is_empty() {
                ui.label(RichText::new("Its spool blocks, shared").strong()).on_hover_text(
                    "The other outputs' models took these blocks of this model with its parameters: the \
                     spool is measured here",
                );
                for words in shared_with {
                    hint(ui, words);
                }
            }
            if let Some(model) = &live.effects.model {
                for effect in &model.effects {
                    let params: Vec<String> =
                        effect.params().iter().map(|(name, value)| format!("{name} = {value:.4}")).collect();
                    hint(ui, &format!("{}: {}", effect.id(), params.join(", ")));
                }
            }
        });
    });
    commands
}

/// The effects added by hand, each with Remove.
fn effects_list_ui(ui: &mut egui::Ui, output: &str, live: &LiveModel) -> Vec<Command> {
    let mut commands = Vec::new();
    ui.label(RichText::new("Effects in the model").strong());
    let requested = &live.effects.requested;
    if requested.is_empty() && !live.effects.shared.iter().any(|b| b.taken) {
        hint(ui, "None yet: the model is the paper's gray-box Wiener model.");
    }
    for &id in &requested.by_hand {
        ui.horizontal(|ui| {
            ui.label(RichText::new(id.name()).monospace());
            if ui.button("Remove").on_hover_text("Take the effect out (undo: Ctrl+Z)").clicked() {
                commands.push(Command::RemoveEffect { output: output.to_owned(), effect: id });
            }
        });
    }
    commands
}

/// The missing-physics loop: its rounds (changed here, undoable), what each round added, and its
/// progress with Stop while it runs.
fn loop_ui(ui: &mut egui::Ui, output: &str, cache: &OutputCache, live: &LiveModel) -> Vec<Command> {
    let mut commands = Vec::new();
    let rounds = live.effects.requested.auto_rounds;
    ui.horizontal(|ui| {
        ui.label("Missing-physics loop:");
        let mut wanted = rounds;
        let edit = egui::DragValue::new(&mut wanted).range(0..=MAX_ROUNDS).suffix(" rounds");
        let response = ui.add(edit).on_hover_text(
            "Each round diagnoses the model and adds the top significant effect or refinement, refitted \
             (a project's auto_effects; the batch runs the same loop)",
        );
        if response.changed() && wanted != rounds {
            commands.push(Command::SetAutoEffects { output: output.to_owned(), rounds: wanted });
        }
    });
    if let Some(job) = cache.finishing_job().filter(|_| rounds > 0)
        && super::progress_ui(ui, job)
    {
        commands.push(Command::SetAutoEffects { output: output.to_owned(), rounds: 0 });
    }
    for round in &live.effects.rounds {
        ui.label(
            RichText::new(format!(
                "+{} ({}): {:.3} % → {:.3} %",
                round.added, round.kind, round.rmspe_before_pct, round.rmspe_after_pct
            ))
            .monospace()
            .color(theme::OK),
        );
        hint(ui, &format!("{}; {}", round.evidence, round.significance));
        for words in round.attribution.iter().chain(&round.admissibility) {
            hint(ui, &format!("{words}."));
        }
    }
    for note in live.effects.notes.iter().filter(|n| n.contains("stopped after")) {
        hint(ui, note);
    }
    for words in &live.effects.admissibility {
        hint(ui, &format!("{words}."));
    }
    commands
}

/// The shaft speed's spool blocks offered to this output's model: each with the validation error
/// without and with it, shared or not, and why.
fn shared_ui(ui: &mut egui::Ui, live: &LiveModel) {
    let Some(first) = live.effects.shared.first() else { return };
    ui.label(RichText::new(format!("Spool blocks from {}", first.from)).strong()).on_hover_text(
        "The spool's time-constant schedule, asymmetry and soak are the same numbers on every output; they \
         are fitted on the shaft speed, which measures the spool, and shared unless this output's own \
         validation runs show the model worse with them beyond noise",
    );
    for block in &live.effects.shared {
        let (mark, color) = if block.taken { ("shared", theme::OK) } else { ("not shared", theme::HINT) };
        ui.label(
            RichText::new(format!(
                "{} ({mark}): {:.3} % → {:.3} %",
                block.id, block.rmspe_before_pct, block.rmspe_after_pct
            ))
            .monospace()
            .color(color),
        );
        hint(ui, &format!("{}.", block.words()));
    }
}

/// Bars of the validation RMSPE after each step, each labelled with its value.
fn history_chart_ui(ui: &mut egui::Ui, output: &str, history: &[HistoryStep]) {
    if history.is_empty() {
        hint(ui, "No validation run: give a run the role validation to see the error.");
        return;
    }
    let steps = history.len();
    let top = history.iter().map(|s| s.rmspe_pct).fold(0.0, f64::max);
    let bars: Vec<Bar> = history
        .iter()
        .enumerate()
        .map(|(i, s)| Bar::new(i as f64, s.rmspe_pct).width(0.6).name(&s.step))
        .collect();
    Plot::new(("diagnosis_history", output))
        .height(170.0)
        .allow_drag(false)
        .allow_zoom(false)
        .allow_scroll(false)
        .allow_boxed_zoom(false)
        .show_x(false)
        .include_y(0.0)
        .include_y(top * 1.25)
        .include_x(-0.6)
        .include_x(history.len() as f64 - 0.4)
        .y_axis_label("RMSPE [%]")
        .show_grid([false, true])
        // The steps are numbered on the axis and named below the chart: egui_plot drops tick labels
        // that would overlap, and step names ("+scheduled_time_constant (auto)") are long.
        .x_axis_formatter(move |mark, _| {
            let i = mark.value.round();
            if (mark.value - i).abs() > 1e-6 || i < 0.0 || i as usize >= steps {
                return String::new();
            }
            format!("{}", i as usize + 1)
        })
        .show(ui, |plot_ui| {
            plot_ui.bar_chart(BarChart::new("validation RMSPE", bars).color(theme::MODEL));
            for (i, step) in history.iter().enumerate() {
                let at = egui_plot::PlotPoint::new(i as f64, step.rmspe_pct + top * 0.04);
                let label = Text::new(
                    "value",
                    at,
                    RichText::new(format!("{:.3} %", step.rmspe_pct)).size(14.0).strong(),
                )
                .anchor(egui::Align2::CENTER_BOTTOM);
                plot_ui.text(label);
            }
        });
    let names: Vec<String> =
        history.iter().enumerate().map(|(i, s)| format!("{} {}", i + 1, s.step)).collect();
    hint(ui, &names.join("    "));
}
