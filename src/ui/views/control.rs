//! The Control view: what a controller designer schedules on. The gain schedule (local gain and
//! −3 dB bandwidth against the operating point), the local step responses overlaid and normalised,
//! the Bode of the local model at a chosen point, and the table of every point. Computed from the
//! model the other views show (with its effects), so it follows every change of the model.
use crate::core::run::RunRole;
use egui::RichText;
use egui_plot::{Legend, Line, MarkerShape, Plot, Points};

use crate::core::control::{OperatingPoint, PointSource, bands, identified_range, operating_points};
use crate::core::effects::ExtendedModel;
use crate::core::numerics::stats::mean;
use crate::core::numerics::tf::log_space;
use crate::ui::derived::Derived;
use crate::ui::derived::uncertainty::ModelUncertainty;
use crate::ui::state::session::Session;
use crate::ui::theme;
use crate::ui::widgets::model as model_ui;
use crate::ui::widgets::plot as plot_util;

/// The most the table takes of the view's height; beyond it the table scrolls.
const MAX_TABLE_SHARE: f32 = 0.4;
/// Space between the table's rows, points.
const ROW_SPACING: f32 = 3.0;
/// The least height of a plot row, points.
const MIN_PLOT_HEIGHT: f32 = 140.0;
const Y_AXIS_WIDTH: f32 = 64.0;
/// Bode points of the local model.
const BODE_POINTS: usize = 300;

pub struct ControlViewState {
    /// Index of the point whose Bode is shown.
    pub selected: usize,
    /// The points of the model last drawn: (output, model id, points or why there are none).
    cache: Option<(String, u64, Result<Vec<OperatingPoint>, String>)>,
    /// Their uncertainty: the 95 % band of each point's normalised step response (over the step
    /// plot's horizon), or why there are no intervals.
    bands: Result<StepBands, String>,
}

/// The 95 % bands of the points' normalised step responses, from models drawn from the parameter
/// covariance.
#[derive(Default)]
struct StepBands {
    /// Per point: (low, high) at each sample of the horizon.
    per_point: Vec<Option<(Vec<f64>, Vec<f64>)>>,
}

impl Default for ControlViewState {
    fn default() -> Self {
        Self { selected: 0, cache: None, bands: Err(String::new()) }
    }
}

/// The step plot's horizon: one and a half times the slowest settling time, at least 1.5 s.
fn step_horizon(points: &[OperatingPoint]) -> f64 {
    points.iter().filter_map(|p| p.step.settling_s).fold(0.0, f64::max).max(1.0) * 1.5
}

/// Fill the points' intervals from the model's parameter uncertainty and compute their step bands.
fn with_uncertainty(
    points: &mut [OperatingPoint],
    model: &ExtendedModel,
    uncertainty: &ModelUncertainty,
    range: (f64, f64),
    plateaus: &[(String, f64)],
) -> Result<StepBands, String> {
    bands::with_intervals(points, model, &uncertainty.covariance, range, plateaus)
        .map_err(|e| e.to_string())?;
    let horizon_s = step_horizon(points);
    // The same horizon and sample count as the step plot draws the responses over.
    let per_point = points
        .iter()
        .map(|p| {
            let n = ((horizon_s / p.local.dt_secs).ceil() as usize).clamp(2, 100_000);
            bands::step_band(&uncertainty.draws, p.u, n)
        })
        .collect();
    Ok(StepBands { per_point })
}

impl ControlViewState {
    /// The operating points last drawn, when they could be computed.
    pub fn points(&self) -> Option<&[OperatingPoint]> {
        self.cache.as_ref().and_then(|(_, _, p)| p.as_deref().ok())
    }
}

pub fn control_ui(
    ui: &mut egui::Ui,
    output: &str,
    state: &mut ControlViewState,
    session: &Session,
    cache: &Derived,
) {
    let Some(view) = cache.live_view(output) else { return };
    if !model_ui::model_state_ui(ui, &view) {
        return;
    }
    let Ok(live) = view.live else { return };
    let Some(ident) = cache.ident.as_ref() else { return };
    let fresh = state.cache.as_ref().is_some_and(|(o, id, _)| o == output && *id == live.id);
    if !fresh {
        let model = live.current_model();
        let u = &ident.run.input.values;
        let range = identified_range(u);
        let plateaus: Vec<(String, f64)> = session
            .runs
            .iter()
            .filter(|r| r.role == RunRole::Steady)
            .map(|r| (r.run.name.clone(), mean(&r.run.input.values)))
            .collect();
        let mut points = operating_points(&model, range, &plateaus).map_err(|e| e.to_string());
        state.bands = match (&mut points, &live.uncertainty) {
            (Ok(points), Ok(u)) => with_uncertainty(points, &model, u, range, &plateaus),
            (_, Err(why)) => Err(why.clone()),
            (Err(_), _) => Err(String::new()),
        };
        state.cache = Some((output.to_owned(), live.id, points));
    }
    let Some((_, _, points)) = &state.cache else { return };
    let points = match points {
        Ok(p) if !p.is_empty() => p,
        Ok(_) => return model_ui::hint(ui, "No operating points."),
        Err(e) => {
            ui.colored_label(theme::ERROR, format!("No operating points: {e}"));
            return;
        }
    };
    state.selected = state.selected.min(points.len() - 1);
    model_ui::hint(
        ui,
        "Local model at each point: K·G(z)/G(1), K = dy/du there, effects linearised where they act. \
         Nine points across the identified input range, plus each steady run's plateau. Click a row for its Bode. \
         x −a/+b: the 95 % interval from x − a to x + b, over models drawn from the parameter covariance.",
    );
    let unit = &view.output.unit;
    let input = &ident.run.input;
    let width = ui.available_width();
    // The table shows every row (the steady-run plateaus come last) and the plots share the rest.
    let table_height = table_height(ui, points.len());
    let plot_height = ((ui.available_height() - table_height) / 2.0 - 8.0).max(MIN_PLOT_HEIGHT);
    let half = (width - ui.spacing().item_spacing.x) / 2.0;
    ui.horizontal_top(|ui| {
        ui.allocate_ui(egui::vec2(half, plot_height), |ui| {
            schedule_plot(
                ui,
                output,
                points,
                &format!("u*: {}", crate::core::run::name_with_unit(&input.name, &input.unit)),
                &crate::io::report::markdown::gain_unit(unit, &input.unit),
            )
        });
        let bands = state.bands.as_ref().ok();
        ui.allocate_ui(egui::vec2(half, plot_height), |ui| {
            step_plot(ui, output, points, state.selected, bands)
        });
    });
    bode_plots(ui, output, &points[state.selected], plot_height, unit, &input.unit);
    table_ui(ui, points, &mut state.selected, table_height, unit, &input.unit);
}

/// The height of the table with a header and `rows` rows, at most [`MAX_TABLE_SHARE`] of the view.
fn table_height(ui: &egui::Ui, rows: usize) -> f32 {
    let row = ui.spacing().interact_size.y.max(ui.text_style_height(&egui::TextStyle::Body)) + ROW_SPACING;
    ((rows + 1) as f32 * row + ROW_SPACING).min(MAX_TABLE_SHARE * ui.available_height())
}

/// The schedule plot's legend entry of the local gain, with the largest gain in `gain_unit`.
pub fn gain_legend(max_gain: f64, gain_unit: &str) -> String {
    format!("local gain dy/du (largest {max_gain:.4e} {gain_unit})")
}

/// Local gain and bandwidth against u*, each relative to its largest value (named in the legend,
/// the gain in `gain_unit`): the shape of the schedule at a glance, the numbers in the table.
fn schedule_plot(
    ui: &mut egui::Ui,
    output: &str,
    points: &[OperatingPoint],
    input_label: &str,
    gain_unit: &str,
) {
    let grid: Vec<&OperatingPoint> = points.iter().filter(|p| p.source == PointSource::Grid).collect();
    let steady: Vec<&OperatingPoint> = points.iter().filter(|p| p.source != PointSource::Grid).collect();
    let max_gain = points.iter().map(|p| p.gain.abs()).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
    let max_bw = points.iter().filter_map(|p| p.bandwidth_rad_s).fold(0.0, f64::max);
    let gain_of =
        |ps: &[&OperatingPoint]| -> Vec<[f64; 2]> { ps.iter().map(|p| [p.u, p.gain / max_gain]).collect() };
    let bw_of = |ps: &[&OperatingPoint]| -> Vec<[f64; 2]> {
        ps.iter().filter_map(|p| Some([p.u, p.bandwidth_rad_s? / max_bw])).collect()
    };
    Plot::new(("control_schedule", output))
        .height(ui.available_height())
        .x_axis_label(input_label.to_owned())
        .y_axis_label("relative to the largest")
        .y_axis_min_width(Y_AXIS_WIDTH)
        .x_grid_spacer(plot_util::grid_125_x)
        .y_grid_spacer(plot_util::grid_125_y)
        .include_y(0.0)
        .include_y(1.05)
        .legend(Legend::default().position(egui_plot::Corner::LeftBottom).follow_insertion_order(true))
        .show(ui, |plot_ui| {
            let gain_name = gain_legend(max_gain, gain_unit);
            let with_ci: Vec<(f64, [f64; 2])> =
                grid.iter().filter_map(|p| Some((p.u, p.gain_ci95?))).collect();
            if with_ci.len() == grid.len() {
                let x: Vec<f64> = with_ci.iter().map(|(u, _)| *u).collect();
                let lo: Vec<f64> = with_ci.iter().map(|(_, ci)| ci[0] / max_gain).collect();
                let hi: Vec<f64> = with_ci.iter().map(|(_, ci)| ci[1] / max_gain).collect();
                if let Some(band) =
                    plot_util::band("local gain: 95 % band (parameters)", &x, &lo, &hi, theme::MODEL)
                {
                    plot_ui.add(band);
                }
            }
            plot_ui.line(Line::new(gain_name.clone(), gain_of(&grid)).color(theme::MODEL).width(2.0));
            plot_ui.points(
                Points::new(gain_name, gain_of(&grid))
                    .shape(MarkerShape::Circle)
                    .radius(3.5)
                    .color(theme::MODEL),
            );
            if max_bw > 0.0 {
                let bw_name = format!("−3 dB bandwidth (largest {max_bw:.3} rad/s)");
                plot_ui.line(
                    Line::new(bw_name.clone(), bw_of(&grid))
                        .color(theme::LINEAR)
                        .width(2.0)
                        .style(egui_plot::LineStyle::dashed_loose()),
                );
                plot_ui.points(
                    Points::new(bw_name, bw_of(&grid))
                        .shape(MarkerShape::Square)
                        .radius(3.5)
                        .color(theme::LINEAR),
                );
            }
            if !steady.is_empty() {
                let mut marks = gain_of(&steady);
                marks.extend(bw_of(&steady));
                plot_ui.points(
                    Points::new("steady-run plateaus", marks)
                        .shape(MarkerShape::Diamond)
                        .radius(6.0)
                        .color(theme::STEADY_POINT),
                );
            }
        });
}

/// Step responses of every local model, normalised by their final values; the selected one thick,
/// with its 95 % band from the parameter uncertainty when there is one.
fn step_plot(
    ui: &mut egui::Ui,
    output: &str,
    points: &[OperatingPoint],
    selected: usize,
    bands: Option<&StepBands>,
) {
    let horizon = step_horizon(points);
    Plot::new(("control_steps", output))
        .height(ui.available_height())
        .x_axis_label("time after the step [s]")
        .y_axis_label("normalised response")
        .y_axis_min_width(Y_AXIS_WIDTH)
        .x_grid_spacer(plot_util::grid_125_x)
        .y_grid_spacer(plot_util::grid_125_y)
        .legend(Legend::default().position(egui_plot::Corner::RightBottom).follow_insertion_order(true))
        .show(ui, |plot_ui| {
            let selected_band = bands.and_then(|b| b.per_point.get(selected)?.as_ref());
            if let (Some((lo, hi)), Some(p)) = (selected_band, points.get(selected)) {
                let t: Vec<f64> = (0..lo.len()).map(|j| j as f64 * p.local.dt_secs).collect();
                let colour = theme::ramp(if points.len() > 1 {
                    selected as f32 / (points.len() - 1) as f32
                } else {
                    0.0
                });
                if let Some(band) = plot_util::band("selected: 95 % band (parameters)", &t, lo, hi, colour) {
                    plot_ui.add(band);
                }
            }
            for (i, p) in points.iter().enumerate() {
                let dt = p.local.dt_secs;
                let n = ((horizon / dt).ceil() as usize).clamp(2, 100_000);
                let y = p.local.simulate_with_history(&vec![1.0; n], 0.0, 0.0);
                let k = if p.gain.abs() > f64::MIN_POSITIVE { p.gain } else { 1.0 };
                let curve: Vec<[f64; 2]> =
                    y.iter().enumerate().map(|(j, v)| [j as f64 * dt, v / k]).collect();
                let t = if points.len() > 1 { i as f32 / (points.len() - 1) as f32 } else { 0.0 };
                let color = theme::ramp(t);
                // One legend entry for all the others (blue at the bottom of the range, red at the top).
                let name = if i == selected {
                    format!("u* = {:.4} (selected)", p.u)
                } else {
                    "other points (blue: low u*, red: high)".to_owned()
                };
                let line = Line::new(name, curve).color(color).width(if i == selected { 3.0 } else { 1.2 });
                plot_ui.line(line);
            }
            plot_ui.line(
                Line::new("±2 % band", vec![[0.0, 1.02], [horizon, 1.02]])
                    .color(theme::HINT)
                    .style(egui_plot::LineStyle::dotted_dense()),
            );
            plot_ui.line(
                Line::new("", vec![[0.0, 0.98], [horizon, 0.98]])
                    .color(theme::HINT)
                    .style(egui_plot::LineStyle::dotted_dense()),
            );
        });
}

/// Magnitude and phase of the selected point's local model, ω in rad/s, up to Nyquist.
fn bode_plots(
    ui: &mut egui::Ui,
    output: &str,
    p: &OperatingPoint,
    height: f32,
    unit: &str,
    input_unit: &str,
) {
    let nyquist = std::f64::consts::PI / p.local.dt_secs;
    let slowest = p.poles.iter().filter_map(|r| r.wn_rad_s).fold(f64::INFINITY, f64::min);
    let lo = (slowest.min(nyquist) * 1e-2).max(nyquist * 1e-6);
    let bode = p.local.bode_response(&log_space(lo, nyquist * 0.999, BODE_POINTS));
    let group = egui::Id::unique(("control_bode_axis", output));
    let half = (ui.available_width() - ui.spacing().item_spacing.x) / 2.0;
    let title = format!("local model at u* = {:.4}", p.u);
    ui.horizontal_top(|ui| {
        for phase in [false, true] {
            let points: Vec<[f64; 2]> = bode
                .iter()
                .map(|b| [b.omega_rad_s.log10(), if phase { b.phase_deg } else { b.mag_db }])
                .collect();
            ui.allocate_ui(egui::vec2(half, height), |ui| {
                plot_util::bode_panel(("control_bode", output, phase), group, height, phase)
                    .x_axis_label("ω [rad/s]")
                    .y_axis_min_width(Y_AXIS_WIDTH)
                    .legend(Legend::default().position(egui_plot::Corner::LeftBottom))
                    .show(ui, |plot_ui| {
                        let name = if phase {
                            title.clone()
                        } else {
                            format!(
                                "{title} [dB of {}]",
                                crate::io::report::markdown::gain_unit(unit, input_unit)
                            )
                        };
                        plot_ui.line(Line::new(name, points).color(theme::MODEL).width(2.0));
                        if let (false, Some(bw)) = (phase, p.bandwidth_rad_s) {
                            let top = bode.first().map_or(0.0, |b| b.mag_db);
                            plot_ui.points(
                                Points::new(format!("−3 dB at {bw:.3} rad/s"), vec![[bw.log10(), top - 3.0]])
                                    .shape(MarkerShape::Diamond)
                                    .radius(6.0)
                                    .color(theme::LINEAR),
                            );
                        }
                    });
            });
        }
    });
}

fn table_ui(
    ui: &mut egui::Ui,
    points: &[OperatingPoint],
    selected: &mut usize,
    height: f32,
    unit: &str,
    input_unit: &str,
) {
    use crate::io::report::markdown::{pole_with_interval, with_interval};
    let opt = |x: Option<f64>, ci: Option<[f64; 2]>| x.map_or("–".to_owned(), |v| with_interval(v, ci, 3));
    let gain = |p: &OperatingPoint| match p.gain_ci95 {
        Some([lo, hi]) => {
            format!("{:.4e} −{:.2e}/+{:.2e}", p.gain, (p.gain - lo).max(0.0), (hi - p.gain).max(0.0))
        }
        None => format!("{:.4e}", p.gain),
    };
    egui::ScrollArea::vertical().max_height(height).show(ui, |ui| {
        let grid = egui::Grid::new("control_table").striped(true).num_columns(9).spacing([14.0, ROW_SPACING]);
        grid.show(ui, |ui| {
            for head in [
                "point".to_owned(),
                format!("u*{}", crate::core::run::bracketed_unit(input_unit)),
                format!("y*{}", crate::core::run::bracketed_unit(unit)),
                format!("dy/du [{}]", crate::io::report::markdown::gain_unit(unit, input_unit)),
                "poles".to_owned(),
                "bandwidth [rad/s]".to_owned(),
                "rise 10–90 % [s]".to_owned(),
                "settling 2 % [s]".to_owned(),
                "overshoot %".to_owned(),
            ] {
                ui.label(RichText::new(head).strong());
            }
            ui.end_row();
            for (i, p) in points.iter().enumerate() {
                let source = match &p.source {
                    PointSource::Grid => format!("grid {}", i + 1),
                    PointSource::SteadyRun(run) => format!("steady: {run}"),
                };
                if ui.selectable_label(*selected == i, source).clicked() {
                    *selected = i;
                }
                ui.label(RichText::new(format!("{:.4}", p.u)).monospace());
                ui.label(RichText::new(format!("{:.1}", p.y)).monospace());
                ui.label(RichText::new(gain(p)).monospace());
                let poles: Vec<String> = p.poles.iter().map(pole_with_interval).collect();
                ui.label(poles.join("; "));
                ui.label(RichText::new(opt(p.bandwidth_rad_s, p.bandwidth_rad_s_ci95)).monospace());
                ui.label(RichText::new(opt(p.step.rise_s, p.step.rise_s_ci95)).monospace());
                ui.label(RichText::new(opt(p.step.settling_s, p.step.settling_s_ci95)).monospace());
                ui.label(RichText::new(format!("{:.1}", p.step.overshoot_pct)).monospace());
                ui.end_row();
            }
        });
    });
}
