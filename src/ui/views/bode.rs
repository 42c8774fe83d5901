//! The Bode view: magnitude and phase of every segment's ARX model (thin, coloured by segment) and
//! of the reduced linear block G(z) (thick), against ω in rad/s on a log axis; the chirp run's
//! empirical frequency response on top when the cache has one.
use egui_plot::{ColorConflictHandling, Legend, Line, MarkerShape, PlotPoints, Points};

use crate::core::numerics::tf::BodePoint;
use crate::ui::derived::model_cache::EmpiricalPoint;
use crate::ui::derived::{Derived, LiveView};
use crate::ui::theme;
use crate::ui::widgets::model as model_ui;
use crate::ui::widgets::plot as plot_util;

const Y_AXIS_WIDTH: f32 = 64.0;
/// The legend entry of the chirp's measured points.
const EMPIRICAL_NAME: &str = "chirp (measured)";

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
        } else {
            // Bottom-left: a low-pass response runs along the top at low ω and falls to the right,
            // so that corner has no curves. The chirp's points share one entry in the colour of
            // the best-measured point (drawn first), not the grey of mixed colours.
            let legend = Legend::default()
                .position(egui_plot::Corner::LeftBottom)
                .background_alpha(0.85)
                .color_conflict_handling(ColorConflictHandling::PickFirst);
            plot = plot.legend(legend);
        }
        plot.show(ui, |plot_ui| {
            draw_curves(plot_ui, &view, state, part);
            draw_empirical(plot_ui, &view.output.empirical_bode, part);
        });
    }
    if unit.is_empty() {
        model_ui::hint(ui, "The output has no unit; magnitudes are in output units per input unit.");
    }
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
        plot_ui
            .line(Line::new("reduced model G(z)", curve(&live.bode, part)).color(theme::REDUCED).width(3.0));
    }
}

/// The chirp's measured points: (ω, |G| dB, ∠G deg, coherence). Points with low coherence are drawn
/// smaller and fainter; the best-measured point comes first so the legend shows it.
fn draw_empirical(plot_ui: &mut egui_plot::PlotUi<'_>, points: &[EmpiricalPoint], part: Part) {
    let mut sorted: Vec<&EmpiricalPoint> = points.iter().collect();
    sorted.sort_by(|a, b| b.3.total_cmp(&a.3));
    for (omega, mag_db, phase_deg, coherence) in sorted {
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
