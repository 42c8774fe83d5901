//! The Bode view: magnitude and phase of every segment's ARX model (thin, coloured by segment) and
//! of the reduced linear block G(z) (thick), against ω in rad/s on a log axis; the chirp run's
//! empirical frequency response on top when the cache has one.
use egui_plot::{Line, MarkerShape, PlotPoints, Points};

use crate::core::numerics::tf::BodePoint;
use crate::ui::derived::{Derived, LiveView};
use crate::ui::theme;
use crate::ui::widgets::model as model_ui;
use crate::ui::widgets::plot as plot_util;
use crate::workflow::products::EmpiricalPoint;

const Y_AXIS_WIDTH: f32 = 64.0;
/// The legend entry of the chirp's measured points.
const EMPIRICAL_NAME: &str = "chirp (measured)";
/// The legend entry of the reduced model.
const REDUCED_NAME: &str = "reduced model G(z)";
/// The legend entry of its band: 2.5 to 97.5 percentiles over models drawn from the parameter
/// covariance.
const BAND_NAME: &str = "G(z): 95 % band (parameters)";
/// The legend entry of the finished model's block when the effects' refit moved it.
const REFITTED_NAME: &str = "G(z) refitted with the effects";
/// Its band's legend entry.
const REFITTED_BAND_NAME: &str = "refitted G(z): 95 % band (parameters)";

#[derive(Default)]
pub struct BodeViewState {
    /// Draw the segment models (they can hide the reduced model at high frequency).
    pub hide_segments: bool,
}

/// The two plots of the view.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Part {
    Magnitude,
    Phase,
}

impl Part {
    fn value(self, p: &BodePoint) -> f64 {
        match self {
            Self::Magnitude => p.mag_db,
            Self::Phase => p.phase_deg,
        }
    }
}

fn curve(points: &[BodePoint], part: Part) -> PlotPoints<'static> {
    points.iter().map(|p| [p.omega_rad_s.log10(), part.value(p)]).collect()
}

pub fn bode_ui(ui: &mut egui::Ui, output: &str, state: &mut BodeViewState, cache: &Derived) {
    let Some(view) = cache.live_view(output) else { return };
    ui.horizontal(|ui| {
        ui.checkbox(&mut state.hide_segments, "Hide segment models");
        model_ui::hint(
            ui,
            "Thin: each segment's ARX model. Thick: the reduced block G(z) (gain fitted so that v is in \
             output units). Diamonds: the chirp, faint where the coherence is low.",
        );
    });
    if !model_ui::model_state_ui(ui, &view) && view.output.segment_bode.is_empty() {
        return;
    }
    legend_ui(ui, &view, state);
    let spacing = ui.spacing().item_spacing.y;
    let height = ((ui.available_height() - spacing) / 2.0).max(120.0);
    let group = egui::Id::unique(("bode_omega_axis", output));
    let unit = &view.output.unit;
    for part in [Part::Magnitude, Part::Phase] {
        let last = part == Part::Phase;
        let mut plot = plot_util::bode_panel(("bode", last, output), group, height, last)
            .y_axis_min_width(Y_AXIS_WIDTH)
            .show_axes([last, true]);
        if last {
            plot = plot.x_axis_label("ω [rad/s]");
        }
        plot.show(ui, |plot_ui| {
            draw_curves(plot_ui, &view, state, part);
            draw_empirical(plot_ui, &view.output.empirical_bode.points, part);
        });
    }
    if unit.is_empty() {
        model_ui::hint(ui, "The output has no unit; magnitudes are in output units per input unit.");
    }
}

/// The key of both plots, in a row above them: inside a plot a legend covers curves somewhere on
/// a Bode plot (every corner has a curve at some ω), and egui_plot's legend draws the chirp's
/// diamonds as a dot.
fn legend_ui(ui: &mut egui::Ui, view: &LiveView<'_>, state: &BodeViewState) {
    ui.horizontal_wrapped(|ui| {
        if !state.hide_segments
            && let Ok(fits) = &view.output.fits
        {
            for (i, segment) in fits.segments.iter().enumerate().take(view.output.segment_bode.len()) {
                plot_util::line_key_ui(
                    ui,
                    theme::segment_colour(i),
                    1.0,
                    false,
                    &format!("segment {}", segment.label),
                );
            }
        }
        if let Ok(live) = view.live {
            plot_util::line_key_ui(ui, theme::REDUCED, 3.0, false, REDUCED_NAME);
            if let Ok(u) = &live.uncertainty {
                let (colour, name) = match u.refitted_block(&live.model.wiener.linear.tf) {
                    Some(_) => {
                        plot_util::line_key_ui(ui, theme::MODEL, 3.0, false, REFITTED_NAME);
                        (theme::MODEL, REFITTED_BAND_NAME)
                    }
                    None => (theme::REDUCED, BAND_NAME),
                };
                plot_util::line_key_ui(ui, colour.gamma_multiply(0.6), 8.0, false, name);
            }
        }
        if !view.output.empirical_bode.points.is_empty() {
            plot_util::diamond_key_ui(ui, theme::EMPIRICAL, EMPIRICAL_NAME);
        }
    });
}

fn draw_curves(plot_ui: &mut egui_plot::PlotUi<'_>, view: &LiveView<'_>, state: &BodeViewState, part: Part) {
    if !state.hide_segments
        && let Ok(fits) = &view.output.fits
    {
        for (i, (points, segment)) in view.output.segment_bode.iter().zip(&fits.segments).enumerate() {
            let name = format!("segment {}", segment.label);
            plot_ui.line(Line::new(name, curve(points, part)).color(theme::segment_colour(i)).width(1.0));
        }
    }
    if let Ok(live) = view.live {
        if let Ok(u) = &live.uncertainty {
            let x: Vec<f64> = u.bode.omega_rad_s.iter().map(|w| w.log10()).collect();
            let pick = |k: usize| -> Vec<f64> {
                let side = |b: &[f64; 2]| b[k];
                match part {
                    Part::Magnitude => u.bode.mag_db.iter().map(side).collect(),
                    Part::Phase => u.bode.phase_deg.iter().map(side).collect(),
                }
            };
            // The band is the finished model's: drawn around its own block, which is the reduced
            // model's unless the effects' refit moved it.
            let refitted = u.refitted_block(&live.model.wiener.linear.tf);
            let (colour, name) = if refitted.is_some() {
                (theme::MODEL, REFITTED_BAND_NAME)
            } else {
                (theme::REDUCED, BAND_NAME)
            };
            if let Some(band) = plot_util::band(name, &x, &pick(0), &pick(1), colour) {
                plot_ui.add(band);
            }
            if let Some(block) = refitted {
                plot_ui
                    .line(Line::new(REFITTED_NAME, curve(&block.bode, part)).color(theme::MODEL).width(3.0));
            }
        }
        plot_ui.line(Line::new(REDUCED_NAME, curve(&live.bode, part)).color(theme::REDUCED).width(3.0));
    }
}

/// The chirp's measured points: (ω, |G| dB, ∠G deg, coherence). Points with low coherence are drawn
/// smaller and fainter.
fn draw_empirical(plot_ui: &mut egui_plot::PlotUi<'_>, points: &[EmpiricalPoint], part: Part) {
    for (omega, mag_db, phase_deg, coherence) in points {
        let y = if part == Part::Magnitude { *mag_db } else { *phase_deg };
        let weight = coherence.clamp(0.15, 1.0) as f32;
        plot_ui.points(
            Points::new(EMPIRICAL_NAME, vec![[omega.log10(), y]])
                .shape(MarkerShape::Diamond)
                .radius(2.0 + 2.5 * weight)
                .color(theme::EMPIRICAL.gamma_multiply(weight)),
        );
    }
}
