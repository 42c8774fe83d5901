//! The Static map view: the fitted f(v) over the steady-state points (v, y) of the identification
//! segments, dashed where it continues past them, the static-map coefficients and the leave-one-out
//! table the order was chosen from.
use egui::RichText;
use egui_plot::{Legend, Line, MarkerShape, Plot, Points};

use crate::core::identification::settings::OutputSettings;
use crate::core::identification::static_map::Beyond;
use crate::ui::derived::Derived;
use crate::ui::state::command::Command;
use crate::ui::theme;
use crate::ui::widgets::model as model_ui;
use crate::ui::widgets::plot as plot_util;

const CURVE_POINTS: usize = 200;
const TABLE_WIDTH: f32 = 330.0;

pub fn static_map_ui(ui: &mut egui::Ui, output: &str, cache: &Derived) -> Vec<Command> {
    let mut commands = Vec::new();
    let Some(view) = cache.live_view(output) else { return commands };
    if !model_ui::model_state_ui(ui, &view) {
        return commands;
    }
    let Ok(live) = view.live else { return commands };
    let model = &live.model;
    let map = &model.wiener.map;
    let unit = &view.output.unit;
    let (v_lo, v_hi) = model
        .steady_points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (v, _)| (lo.min(*v), hi.max(*v)));
    // A third of the range either side shows how the map continues past the holds.
    let pad = 0.35 * (v_hi - v_lo).max(1e-9);
    let curve = |a: f64, b: f64| -> Vec<[f64; 2]> {
        (0..=CURVE_POINTS)
            .map(|k| a + (b - a) * k as f64 / CURVE_POINTS as f64)
            .map(|v| [v, map.eval(v)])
            .collect()
    };
    let (fitted, below, above) = (curve(v_lo, v_hi), curve(v_lo - pad, v_lo), curve(v_hi, v_hi + pad));
    let beyond_name = match map.beyond {
        Beyond::EndTrend => "beyond the holds: the end's trend",
        Beyond::Polynomial => "beyond the holds: the polynomial",
    };
    let steady: Vec<[f64; 2]> = model.steady_points.iter().map(|(v, y)| [*v, *y]).collect();
    let plot_width = (ui.available_width() - TABLE_WIDTH - ui.spacing().item_spacing.x).max(200.0);
    let height = ui.available_height();
    ui.horizontal_top(|ui| {
        ui.allocate_ui(egui::vec2(plot_width, height), |ui| {
            Plot::new(("static_map", output))
                .height(height)
                .x_axis_label(format!("v, linear block output [{unit}]"))
                .y_axis_label(view.output.label())
                .y_axis_min_width(64.0)
                .x_grid_spacer(plot_util::grid_125_x)
                .y_grid_spacer(plot_util::grid_125_y)
                .legend(Legend::default().position(egui_plot::Corner::LeftTop).follow_insertion_order(true))
                .show(ui, |plot_ui| {
                    plot_ui.line(
                        Line::new(format!("f(v), order {}", map.order()), fitted)
                            .color(theme::MODEL)
                            .width(2.0),
                    );
                    for part in [below, above] {
                        plot_ui.line(
                            Line::new(beyond_name, part)
                                .color(theme::MODEL)
                                .width(1.5)
                                .style(egui_plot::LineStyle::dashed_loose()),
                        );
                    }
                    plot_ui.points(
                        Points::new("steady states (segment tails)", steady)
                            .shape(MarkerShape::Circle)
                            .radius(5.0)
                            .color(theme::STEADY_POINT),
                    );
                });
        });
        ui.allocate_ui(egui::vec2(TABLE_WIDTH, height), |ui| {
            ui.vertical(|ui| commands.extend(side_ui(ui, output, &view.output.setup.settings, model)));
        });
    });
    commands
}

fn side_ui(
    ui: &mut egui::Ui,
    output: &str,
    settings: &OutputSettings,
    model: &crate::core::identification::pipeline::GrayBoxModel,
) -> Option<Command> {
    let mut command = None;
    let map = &model.wiener.map;
    ui.label(RichText::new("y = f(v) = β0 + β1 v + β2 v² + …").strong());
    egui::Grid::new("static_beta").num_columns(2).spacing([12.0, 2.0]).show(ui, |ui| {
        for (i, beta) in map.beta().iter().enumerate() {
            ui.label(format!("β{i}"));
            ui.label(RichText::new(format!("{beta:.6e}")).monospace());
            ui.end_row();
        }
    });
    ui.add_space(8.0);
    ui.horizontal(|ui| {
        let label = ui.label("Order:");
        let text = settings.static_order.map_or_else(|| "from the data".to_owned(), |o| o.to_string());
        egui::ComboBox::from_id_salt("static_order")
            .selected_text(text)
            .show_ui(ui, |ui| {
                let choices = std::iter::once(None).chain((1..=settings.max_static_order).map(Some));
                for choice in choices {
                    let name =
                        choice.map_or_else(|| "from the data (leave-one-out)".to_owned(), |o| o.to_string());
                    if ui.selectable_label(settings.static_order == choice, name).clicked()
                        && settings.static_order != choice
                    {
                        let settings = OutputSettings { static_order: choice, ..settings.clone() };
                        command = Some(Command::SetOutputSettings { output: output.to_owned(), settings });
                    }
                }
            })
            .response
            .labelled_by(label.id);
    });
    ui.add_space(4.0);
    match &model.static_suggestion {
        Some(suggestion) => {
            ui.label(RichText::new("Leave-one-out error by order").strong());
            egui::Grid::new("static_loo").striped(true).num_columns(3).spacing([12.0, 2.0]).show(ui, |ui| {
                ui.label("order");
                ui.label("LOO RMSE");
                ui.label("");
                ui.end_row();
                for (order, rmse) in &suggestion.loo_rmse {
                    ui.label(order.to_string());
                    ui.label(RichText::new(format!("{rmse:.4}")).monospace());
                    if *order == suggestion.order {
                        ui.label(RichText::new("chosen").color(theme::OK));
                    } else {
                        ui.label("");
                    }
                    ui.end_row();
                }
            });
        }
        None => model_ui::hint(ui, "The order is set by hand, so no leave-one-out table."),
    }
    ui.add_space(8.0);
    model_ui::hint(
        ui,
        "Points: the mean of v and y over the settled tail of each segment (and before the first step). \
         The linear block's gain is fitted by least squares on the identification run, so v is in output units.",
    );
    if map.beyond == Beyond::EndTrend {
        model_ui::hint(
            ui,
            "The map is held monotone over the points, so every local gain has the engine's sign. Past them \
             (dashed) it continues its end's value, slope and curvature without turning back: an exponential \
             approach where the curvature slows it, a parabola where it speeds it up.",
        );
    }
    command
}
