//! The History view's plots: each health delta of an engine against its runs in date order (the 95 %
//! interval as an error bar, the engine's normal band shaded), and one run's measured outputs against
//! its reference's prediction.
use egui::Color32;
use egui_plot::{Line, LineStyle, Plot, PlotPoints, PlotTransform, Points, Polygon};

use crate::core::health::{Band, Estimate};
use crate::ui::derived::fleet_history::{EngineHistory, RunComparison};
use crate::ui::theme;
use crate::ui::widgets::plot as plot_util;

const BAND_FILL: Color32 = Color32::from_rgba_premultiplied(40, 70, 40, 90);
const BAND_EDGE: Color32 = Color32::from_rgb(90, 150, 90);
const POINT: Color32 = theme::MEASURED;
const Y_AXIS_WIDTH: f32 = 64.0;
/// At most this many runs get a label on a trend's axis.
const LABELLED_RUNS: usize = 10;

/// One delta across an engine's runs.
pub struct TrendPanel {
    pub label: String,
    /// Per run in trend order; `None` where the delta was not fitted.
    pub points: Vec<Option<Estimate>>,
    /// The normal band each run was judged against (it follows the engine's trend), per run.
    pub bands: Vec<Option<Band>>,
}

/// The input gain, the time-constant scale and each output's map shift of `engine`.
pub fn trend_panels(engine: &EngineHistory) -> Vec<TrendPanel> {
    let runs = &engine.runs;
    let mut panels = vec![
        TrendPanel {
            label: "input gain".into(),
            points: runs.iter().map(|r| r.score.input_gain).collect(),
            bands: engine.bands.input_gain.clone(),
        },
        TrendPanel {
            label: "time-constant scale".into(),
            points: runs.iter().map(|r| r.score.tau_scale).collect(),
            bands: engine.bands.tau_scale.clone(),
        },
    ];
    for (output, unit) in engine.outputs() {
        let points = runs
            .iter()
            .map(|r| r.score.outputs.iter().find(|o| o.output == output).and_then(|o| o.map_shift))
            .collect();
        let unit = if unit.is_empty() || unit == "-" { String::new() } else { format!(" [{unit}]") };
        panels.push(TrendPanel {
            label: format!("{output} map shift{unit}"),
            points,
            bands: (0..runs.len()).map(|i| engine.bands.map_shift_of(&output, i).copied()).collect(),
        });
    }
    panels
}

/// Every trend panel of `engine`, stacked, `height` each; returns the run whose point was clicked
/// and the first panel's transform (where its points are on screen, for tests).
pub fn trends_ui(
    ui: &mut egui::Ui,
    engine: &EngineHistory,
    selected: Option<usize>,
    height: f32,
) -> (Option<usize>, Option<PlotTransform>) {
    let labels: Vec<String> = engine.runs.iter().map(|r| r.run.name.clone()).collect();
    let flagged: Vec<bool> = engine.runs.iter().map(|r| r.flagged()).collect();
    let mut clicked = None;
    let mut first = None;
    for panel in trend_panels(engine) {
        ui.label(egui::RichText::new(&panel.label).small());
        let (run, transform) = trend_ui(ui, (&engine.name, &panel), &labels, &flagged, selected, height);
        if run.is_some() {
            clicked = run;
        }
        first = first.or(Some(transform));
    }
    (clicked, first)
}

fn trend_ui(
    ui: &mut egui::Ui,
    (engine, panel): (&str, &TrendPanel),
    labels: &[String],
    flagged: &[bool],
    selected: Option<usize>,
    height: f32,
) -> (Option<usize>, PlotTransform) {
    let n = panel.points.len();
    let last = n.saturating_sub(1) as f64;
    let formatter = |mark: egui_plot::GridMark, _: &std::ops::RangeInclusive<f64>| {
        let i = mark.value.round();
        if (mark.value - i).abs() > 1e-9 || i < 0.0 {
            return String::new();
        }
        labels.get(i as usize).cloned().unwrap_or_default()
    };
    let response = Plot::new(("history_trend", engine, &panel.label))
        .height(height)
        .y_axis_min_width(Y_AXIS_WIDTH)
        .include_x(-0.5)
        .include_x(last + 0.5)
        .x_axis_formatter(formatter)
        .x_grid_spacer(move |_| {
            // A labelled mark on every run, or every k-th one when there are many (egui_plot paints a
            // label when its step spans 60 points: twice the run spacing does at ten runs per plot).
            let every = n.div_ceil(LABELLED_RUNS).max(1);
            let step_size = 2.0 * every as f64;
            (0..n).step_by(every).map(|i| egui_plot::GridMark { value: i as f64, step_size }).collect()
        })
        .y_grid_spacer(plot_util::grid_125_y)
        .y_axis_formatter(plot_util::range_label)
        .allow_drag(false)
        .allow_zoom(false)
        .allow_scroll(false)
        .allow_boxed_zoom(false)
        .allow_double_click_reset(false)
        .show(ui, |plot_ui| {
            // Each run's band, a run wide: the band follows the engine's trend, and is wider for a
            // run whose own estimate is noisier than the typical run's (what it was judged against).
            for (i, band) in panel.bands.iter().enumerate() {
                let Some(band) = band else { continue };
                let ci95 = panel.points.get(i).copied().flatten().and_then(|e| e.ci95);
                let [lo, hi] = band.limits_for(ci95);
                let (x0, x1) = (i as f64 - 0.45, i as f64 + 0.45);
                plot_ui.polygon(
                    Polygon::new(
                        "normal band",
                        PlotPoints::from(vec![[x0, lo], [x1, lo], [x1, hi], [x0, hi]]),
                    )
                    .fill_color(BAND_FILL)
                    .stroke(egui::Stroke::new(0.5, BAND_EDGE)),
                );
                plot_ui.line(
                    Line::new("band centre", vec![[x0, band.centre], [x1, band.centre]])
                        .color(BAND_EDGE)
                        .style(LineStyle::Dashed { length: 6.0 }),
                );
            }
            for (i, estimate) in panel.points.iter().enumerate() {
                let Some(estimate) = estimate else { continue };
                let x = i as f64;
                let bad = flagged.get(i).copied().unwrap_or(false);
                let colour = if bad { theme::ERROR } else { POINT };
                if let Some([lo, hi]) = estimate.ci95 {
                    plot_ui.line(Line::new("95 % interval", vec![[x, lo], [x, hi]]).color(colour).width(1.5));
                }
                let radius = if Some(i) == selected { 6.0 } else { 3.5 };
                plot_ui.points(Points::new("delta", vec![[x, estimate.value]]).color(colour).radius(radius));
            }
            let clicked = plot_ui.response().clicked();
            clicked
                .then(|| plot_ui.pointer_coordinate())
                .flatten()
                .map(|p| p.x.round().clamp(0.0, last) as usize)
        });
    (response.inner.filter(|_| n > 0), response.transform)
}

/// One run's measured outputs and the reference's prediction, one plot per output, `height` each.
pub fn comparison_ui(ui: &mut egui::Ui, comparison: &RunComparison, height: f32) {
    for (k, trace) in comparison.outputs.iter().enumerate() {
        let unit = if trace.unit.is_empty() || trace.unit == "-" {
            String::new()
        } else {
            format!(" [{}]", trace.unit)
        };
        ui.label(format!(
            "{}{unit}: measured and the reference's prediction (RMSE {})",
            trace.output,
            crate::fleet::flags::plain(trace.rmse, 3)
        ));
        let series =
            |y: &[f64]| -> Vec<[f64; 2]> { comparison.t_secs.iter().zip(y).map(|(t, v)| [*t, *v]).collect() };
        Plot::new(("history_comparison", &comparison.run, &trace.output))
            .height(height)
            .x_axis_label("time [s]")
            .y_axis_min_width(Y_AXIS_WIDTH)
            .x_grid_spacer(plot_util::grid_125_x)
            .y_grid_spacer(plot_util::grid_125_y)
            .legend(egui_plot::Legend::default())
            .show(ui, |plot_ui| {
                // The model wide underneath, the measurement thin on top: both stay visible where
                // they agree.
                plot_ui.line(
                    Line::new("reference model", series(&trace.predicted))
                        .color(theme::output_colour(k + 1))
                        .width(3.0),
                );
                plot_ui
                    .line(Line::new("measured", series(&trace.measured)).color(theme::MEASURED).width(1.0));
            });
    }
}
