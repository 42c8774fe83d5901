//! Pieces the model views share: the output selector, error and hint lines, number formats, the
//! cluster status in words and the metrics table.
pub use super::hint;
use egui::RichText;
use num_complex::Complex64;

use crate::core::identification::cluster::{ClusterEval, ClusterStatus};
use crate::core::numerics::metrics::Metrics;
use crate::ui::derived::model_cache::ScoredRun;
use crate::ui::derived::{Derived, LiveView};
use crate::ui::state::command::Command;
use crate::ui::theme;

/// "Output: [shaft_speed_rpm] [thrust_n]"; each output has its own segments fits and clusters.
pub fn output_bar_ui(ui: &mut egui::Ui, cache: &Derived, selected: &str) -> Option<Command> {
    let mut command = None;
    ui.horizontal(|ui| {
        ui.label("Output:");
        for name in cache.output_names() {
            let label = cache.output(name).map_or_else(|| name.to_owned(), |o| o.label());
            if ui.selectable_label(name == selected, label).clicked() && name != selected {
                command = Some(Command::SelectOutput(name.to_owned()));
            }
        }
    });
    command
}

pub fn error_ui(ui: &mut egui::Ui, text: &str) {
    ui.add(egui::Label::new(RichText::new(text).color(theme::ERROR)).wrap());
}

/// The model's state in one line above a view: an error instead of a model, or a preview note.
/// Returns false when there is no model to draw.
pub fn model_state_ui(ui: &mut egui::Ui, view: &LiveView<'_>) -> bool {
    match view.live {
        Err(err) => {
            error_ui(ui, &format!("No model for {}: {err}", view.output.name));
            false
        }
        Ok(live) if view.is_preview || live.finishing => {
            // The effects a drag preview or a model being finished leaves out, when it does.
            let effects = live.effects.left_out_for_preview.then(|| live.effects.requested.words());
            let text = if view.is_preview {
                let left_out = effects.map(|e| format!("; without the effects {e}, fitted again on release"));
                format!(
                    "Preview while a cluster is dragged (centroids not polished{})",
                    left_out.unwrap_or_default()
                )
            } else {
                let refit = effects.map(|e| format!(" and refitting the effects: {e}"));
                let done = view.output.finishing_job().map(|job| {
                    format!(" ({:.0} % after {:.1} s)", 100.0 * job.progress(), job.elapsed().as_secs_f64())
                });
                format!(
                    "Polishing the centroids{}{}…; meanwhile the model without them is shown",
                    refit.unwrap_or_default(),
                    done.unwrap_or_default()
                )
            };
            ui.label(RichText::new(text).color(theme::WARNING));
            true
        }
        Ok(live) => {
            for problem in &live.effects.problems {
                error_ui(ui, &format!("Effects: {problem}"));
            }
            true
        }
    }
}

/// `0.9369` or `0.8404±0.1982i` (conjugate pairs once).
/// `name` cut to `max_chars` characters, the last one an ellipsis, for a column or panel too
/// narrow for a long run name (show the whole name on hover); unchanged when it fits.
pub fn clipped(name: &str, max_chars: usize) -> String {
    if name.chars().count() <= max_chars {
        return name.to_owned();
    }
    let mut cut: String = name.chars().take(max_chars.saturating_sub(1)).collect();
    cut.push('…');
    cut
}

pub fn complex_text(z: Complex64) -> String {
    if z.im.abs() < 5e-5 { format!("{:.4}", z.re) } else { format!("{:.4}{:+.4}i", z.re, z.im) }
}

/// Roots with conjugate pairs shown once as `a±bi`; `–` when there are none.
pub fn roots_text(roots: &[Complex64]) -> String {
    let shown: Vec<String> = roots
        .iter()
        .filter(|z| z.im >= -5e-5)
        .map(|z| if z.im.abs() < 5e-5 { format!("{:.4}", z.re) } else { format!("{:.4}±{:.4}i", z.re, z.im) })
        .collect();
    if shown.is_empty() { "–".to_owned() } else { shown.join(", ") }
}

/// Why a cluster is (in)valid, in a word or two: the last, narrow column of the cluster table
/// (the members column beside it has the counts, [`status_detail`] the numbers).
pub fn status_text(eval: &ClusterEval) -> &'static str {
    match &eval.status {
        ClusterStatus::Valid => "valid",
        ClusterStatus::TooFewMembers { .. } => "too few",
        ClusterStatus::NearOrigin { .. } => "near 0",
        ClusterStatus::NearNyquist { .. } => "excluded",
        ClusterStatus::Unstable { .. } => "unstable",
    }
}

/// The same, with the numbers.
pub fn status_detail(eval: &ClusterEval) -> String {
    match &eval.status {
        ClusterStatus::Valid => "Holds a root from enough segment models: it gives the reduced model a root \
                                 (a conjugate pair off the real axis)."
            .to_owned(),
        ClusterStatus::TooFewMembers { found, needed } => format!(
            "Holds roots from {found} segment models, {needed} needed (the aggregation condition): \
             not in the reduced model"
        ),
        ClusterStatus::NearOrigin { modulus, min_modulus } => {
            format!("Centroid modulus {modulus:.4} is below {min_modulus:.4}: ARX noise roots gather there")
        }
        ClusterStatus::NearNyquist { angle_rad, limit_rad } => {
            format!(
                "Centroid angle {angle_rad:.4} rad is beyond the exclusion angle {limit_rad:.4} rad \
                 (too near Nyquist): not in the reduced model"
            )
        }
        ClusterStatus::Unstable { modulus } => {
            format!("Pole centroid modulus {modulus:.4} is on or outside the unit circle")
        }
    }
}

const METRIC_COLUMNS: [(&str, &str); 6] = [
    ("RMSPE [%]", "Root-mean-square percentage error"),
    ("MAPE [%]", "Mean absolute percentage error"),
    ("SE", "Standard error of the residual"),
    ("fit [%]", "Normalised fit: 100 (1 − ‖y − ŷ‖ / ‖y − mean y‖)"),
    ("RMSE", "Root-mean-square error (output units)"),
    ("max |e|", "Largest absolute error (output units)"),
];

fn metric_values(m: &Metrics) -> [String; 6] {
    [
        format!("{:.4}", m.rmspe_pct),
        format!("{:.4}", m.mape_pct),
        format!("{:.4}", m.se),
        format!("{:.2}", m.fit_pct),
        format!("{:.4}", m.rmse),
        format!("{:.4}", m.max_abs_error),
    ]
}

/// Gray-box and linear metrics of every scored run, one row per run and model.
pub fn metrics_table_ui(ui: &mut egui::Ui, id: &str, runs: &[ScoredRun]) {
    egui::Grid::new(id).striped(true).num_columns(8).spacing([14.0, 3.0]).show(ui, |ui| {
        ui.label(RichText::new("run").strong());
        ui.label(RichText::new("model").strong());
        for (title, tip) in METRIC_COLUMNS {
            ui.label(RichText::new(title).strong()).on_hover_text(tip);
        }
        ui.end_row();
        for run in runs {
            let model = if run.without_effects.is_some() { "gray-box + effects" } else { "gray-box" };
            let rows =
                [(model, Ok(&run.gray_box), theme::MODEL), ("linear", run.linear.as_ref(), theme::LINEAR)];
            for (model, prediction, colour) in rows {
                ui.label(run.label());
                ui.label(RichText::new(model).color(colour));
                match prediction {
                    Ok(p) => {
                        for value in metric_values(&p.metrics) {
                            ui.label(RichText::new(value).monospace());
                        }
                    }
                    Err(err) => {
                        ui.label(RichText::new(err.to_string()).color(theme::ERROR));
                    }
                }
                ui.end_row();
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::clipped;

    #[test]
    fn a_long_name_is_cut_to_its_width_with_an_ellipsis_and_a_short_one_kept() {
        let name = "runA_2023-01-09_steps60k-34k-100k";
        let cut = clipped(name, 14);
        assert_eq!(cut.chars().count(), 14);
        assert_eq!(cut, "runA_2023-01-…");
        assert_eq!(clipped("validation", 14), "validation");
        assert_eq!(clipped("exactly_14_chr", 14), "exactly_14_chr");
        // Characters, not bytes: a multi-byte name is cut on a character boundary.
        assert_eq!(clipped("Prüfstand_Lauf_Nr_12", 10), "Prüfstand…");
    }
}
