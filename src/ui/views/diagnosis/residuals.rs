//! "Where it fails": the residual `y − ŷ` of the model (with its effects) on the scored runs, taken
//! apart by [`crate::core::residuals`]: the residual with the measurement-noise band, the error by
//! regime, the residual autocorrelation and residual–input cross-correlation with their 99 %
//! bounds, the residual spectrum, the residual against every recorded channel the model does not
//! use, and the worst stretches (a click shows one in the Traces view).
//!
//! The analyses are computed once per model (keyed by the live model's id), for every scored run.
use egui::RichText;
use egui_plot::{Bar, BarChart, HLine, Line, LineStyle, Plot, PlotPoints, Points, Span};

use crate::core::residuals::{ChannelCorrelation, Regime, RegimeRow, ResidualAnalysis, summary_sentences};
use crate::core::run::Run;
use crate::ui::derived::model_cache::LiveModel;
pub use crate::ui::derived::residuals::{Analyses, RunAnalysis};
use crate::ui::state::command::Command;
use crate::ui::state::session::Session;
use crate::ui::theme;
use crate::ui::widgets::at_noise_precision;
use crate::ui::widgets::model::{error_ui, hint};
use crate::ui::widgets::plot as plot_util;

/// Most points drawn in one channel scatter (every k-th sample beyond that).
const MAX_SCATTER_POINTS: usize = 1500;

/// The pictures of "Where it fails", one at a time.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Picture {
    #[default]
    Residual,
    Regimes,
    Correlation,
    Spectrum,
    Channels,
}

impl Picture {
    const ALL: [Self; 5] = [Self::Residual, Self::Regimes, Self::Correlation, Self::Spectrum, Self::Channels];

    fn label(self) -> &'static str {
        match self {
            Self::Residual => "Residual & worst stretches",
            Self::Regimes => "By regime",
            Self::Correlation => "Correlations",
            Self::Spectrum => "Spectrum",
            Self::Channels => "Unused channels",
        }
    }
}

#[derive(Default)]
pub struct ResidualsState {
    /// The scored run shown (its index in the session).
    pub run: Option<usize>,
    pub picture: Picture,
    analyses: Option<Analyses>,
}

impl ResidualsState {
    /// The analyses last computed (for the model they name).
    pub fn current(&self) -> Option<&Analyses> {
        self.analyses.as_ref()
    }

    /// The analyses of `live`, computed now if they are for another model.
    pub fn analyses(&mut self, output: &str, session: &Session, live: &LiveModel) -> &Analyses {
        let stale = self.analyses.as_ref().is_none_or(|a| a.model_id != live.id);
        if stale {
            self.analyses = None;
        }
        self.analyses.get_or_insert_with(|| Analyses::of(output, session, live))
    }
}

pub fn where_it_fails_ui(
    ui: &mut egui::Ui,
    output: &str,
    state: &mut ResidualsState,
    session: &Session,
    live: &LiveModel,
) -> Vec<Command> {
    let mut commands = Vec::new();
    if live.runs.is_empty() {
        hint(ui, "Give a run the role validation or chirp to see where the model fails on it.");
        return commands;
    }
    state.analyses(output, session, live);
    let ResidualsState { run: chosen_run, picture, analyses } = state;
    let chosen = *chosen_run;
    let Some(analyses) = analyses.as_ref() else { return commands };
    let shown = chosen.and_then(|i| analyses.runs.iter().find(|r| r.index == i)).or(analyses.runs.first());
    let Some(shown) = shown else { return commands };
    let mut new_run = None;
    ui.horizontal(|ui| {
        let label = ui.label("Run:");
        egui::ComboBox::from_id_salt("diagnosis_residual_run")
            .selected_text(&shown.label)
            .show_ui(ui, |ui| {
                for run in &analyses.runs {
                    if ui.selectable_label(run.index == shown.index, &run.label).clicked() {
                        new_run = Some(run.index);
                    }
                }
            })
            .response
            .labelled_by(label.id);
        hint(ui, &format!("Noise band: {}.", analyses.sigma_note));
    });
    let analysis = match &shown.analysis {
        Ok(a) => a,
        Err(err) => {
            error_ui(ui, &format!("No residual analysis on {}: {err}", shown.label));
            *chosen_run = new_run.or(chosen);
            return commands;
        }
    };
    for sentence in summary_sentences(analysis) {
        ui.label(sentence);
    }
    ui.horizontal(|ui| {
        for p in Picture::ALL {
            if ui.selectable_label(*picture == p, p.label()).clicked() {
                *picture = p;
            }
        }
    });
    ui.separator();
    let run = session.runs.get(shown.index).map(|r| r.run.as_ref());
    match (*picture, run) {
        (_, None) => {}
        (Picture::Residual, Some(run)) => commands.extend(residual_ui(ui, analysis, run, shown.index)),
        (Picture::Regimes, Some(_)) => regimes_ui(ui, analysis, analyses),
        (Picture::Correlation, Some(_)) => correlation_ui(ui, analysis),
        (Picture::Spectrum, Some(_)) => spectrum_ui(ui, analysis),
        (Picture::Channels, Some(run)) => channels_ui(ui, analysis, run),
    }
    *chosen_run = new_run.or(chosen);
    commands
}

/// The residual with the noise band, the worst stretches shaded, and the list of them.
fn residual_ui(ui: &mut egui::Ui, a: &ResidualAnalysis, run: &Run, index: usize) -> Vec<Command> {
    let mut commands = Vec::new();
    let band = &a.band;
    match band.why_not(&a.unit) {
        None => hint(
            ui,
            &format!(
                "Noise band ±{}σ = ±{} {} (dashed green): {:.1} % of the samples lie outside it (noise \
                 alone: {:.1} %).",
                band.band_sigmas,
                at_noise_precision(band.half_width, band.sigma, false),
                a.unit,
                100.0 * band.outside_fraction,
                100.0 * band.expected_outside_fraction
            ),
        ),
        Some(why) => {
            // The summary above says why in full; the hover repeats it here.
            ui.label(
                RichText::new(
                    "No noise band drawn: the noise σ estimated from the run does not apply to this \
                     residual (see above).",
                )
                .color(theme::WARNING),
            )
            .on_hover_text(why);
        }
    }
    let height = (ui.available_height() - 190.0).max(200.0);
    Plot::new(("diagnosis_residual", &a.run, &a.output))
        .height(height)
        .x_axis_label("time [s]")
        .y_axis_label(format!("residual y − ŷ{}", crate::core::run::bracketed_unit(&a.unit)))
        .x_grid_spacer(plot_util::grid_125_x)
        .y_grid_spacer(plot_util::grid_125_y)
        // No legend: it covered the residual in one corner or another; the band is named above,
        // the stretches below.
        .show(ui, |plot_ui| {
            stretches_ui(plot_ui, &a.worst_stretches, numbers_height(&a.residual));
            let points: PlotPoints = run.t_secs.iter().zip(&a.residual).map(|(t, r)| [*t, *r]).collect();
            plot_ui.line(Line::new("residual", points).color(theme::MODEL).width(1.0));
            if band.applies() {
                for y in [band.half_width, -band.half_width] {
                    plot_ui.hline(
                        HLine::new(format!("noise band ±{}σ", band.band_sigmas), y)
                            .color(theme::OK)
                            .style(LineStyle::Dashed { length: 6.0 }),
                    );
                }
            }
        });
    ui.label(
        RichText::new(
            "Worst stretches, shaded and numbered in the plot (click one to see it in the Traces view)",
        )
        .strong(),
    );
    egui::Grid::new("diagnosis_stretches").striped(true).num_columns(4).show(ui, |ui| {
        for (i, s) in a.worst_stretches.iter().enumerate() {
            let text = format!("{}. {:.1}–{:.1} s", i + 1, s.start_secs, s.end_secs);
            if ui.link(text).on_hover_text("Show this window in the Traces view").clicked() {
                commands.push(Command::FocusTraces {
                    run: index,
                    t0_secs: s.start_secs,
                    t1_secs: s.end_secs,
                });
            }
            let rms = at_noise_precision(s.rms, band.sigma, false);
            let mean = at_noise_precision(s.mean_error, band.sigma, true);
            ui.label(RichText::new(format!("RMS {rms} {}", a.unit)).monospace());
            ui.label(RichText::new(format!("mean {mean} {}", a.unit)).monospace());
            ui.label(format!("{:?}", s.motion).to_lowercase());
            ui.end_row();
        }
    });
    commands
}

/// The worst stretches shaded, each numbered as in the list below the plot (a name would not fit a
/// stretch a few seconds wide).
fn stretches_ui(
    plot_ui: &mut egui_plot::PlotUi<'_>,
    stretches: &[crate::core::residuals::Stretch],
    top: f64,
) {
    let fill = theme::WARNING.gamma_multiply(0.15);
    for (i, stretch) in stretches.iter().enumerate() {
        // Unnamed: egui_plot writes a span's name inside it, cut to "worst stre…" on a few seconds.
        plot_ui.span(Span::new("", stretch.start_secs..=stretch.end_secs).fill(fill).border_width(0.0));
        if top.is_finite() {
            let at = egui_plot::PlotPoint::new(0.5 * (stretch.start_secs + stretch.end_secs), top);
            let number = RichText::new(format!("{}", i + 1))
                .text_style(egui::TextStyle::Body)
                .strong()
                .color(theme::WARNING);
            plot_ui.text(egui_plot::Text::new("", at, number).anchor(egui::Align2::CENTER_CENTER));
        }
    }
}

/// Where the stretch numbers sit: a little above the highest residual, so the plot's fitted bounds
/// take them in (the plot's own last bounds would feed back and grow every frame).
fn numbers_height(residual: &[f64]) -> f64 {
    let (lo, hi) = residual
        .iter()
        .filter(|r| r.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), r| (lo.min(*r), hi.max(*r)));
    if lo.is_finite() { hi + 0.06 * (hi - lo).max(f64::MIN_POSITIVE) } else { f64::NAN }
}

/// The regime table, a bar picture of its RMSPE column, and the whole-run error of every run.
fn regimes_ui(ui: &mut egui::Ui, a: &ResidualAnalysis, all: &Analyses) {
    ui.horizontal_top(|ui| {
        ui.vertical(|ui| {
            regime_table_ui(ui, &a.regimes.rows);
            ui.add_space(8.0);
            ui.label(RichText::new("Per run (whole run)").strong());
            runs_table_ui(ui, all);
        });
        regime_bars_ui(ui, &a.run, &a.regimes.rows);
    });
}

/// The error of one run by regime.
fn regime_table_ui(ui: &mut egui::Ui, rows: &[RegimeRow]) {
    egui::Grid::new("diagnosis_regimes").striped(true).num_columns(6).show(ui, |ui| {
        for title in ["regime", "samples", "RMSE", "RMSPE [%]", "mean error", "share of e² [%]"] {
            ui.label(RichText::new(title).strong());
        }
        ui.end_row();
        let opt = |v: Option<f64>, d: usize| v.map_or_else(|| "–".to_owned(), |v| format!("{v:.d$}"));
        for row in rows {
            ui.label(row.regime.label());
            ui.label(format!("{} ({:.0} %)", row.samples, row.share_of_samples_pct));
            ui.label(RichText::new(opt(row.rmse, 3)).monospace());
            ui.label(RichText::new(opt(row.rmspe_pct, 3)).monospace());
            ui.label(RichText::new(opt(row.mean_error, 3)).monospace());
            ui.label(RichText::new(format!("{:.1}", row.share_of_squared_error_pct)).monospace());
            ui.end_row();
        }
    });
}

/// The whole-run error of every run and its share outside the noise band.
fn runs_table_ui(ui: &mut egui::Ui, all: &Analyses) {
    egui::Grid::new("diagnosis_regimes_runs").striped(true).num_columns(3).show(ui, |ui| {
        for title in ["run", "RMSPE [%]", "outside the noise band [%]"] {
            ui.label(RichText::new(title).strong());
        }
        ui.end_row();
        for run in &all.runs {
            let Ok(analysis) = &run.analysis else { continue };
            let whole = analysis.regimes.row(Regime::Run).and_then(|r| r.rmspe_pct);
            ui.label(&run.label);
            ui.label(RichText::new(whole.map_or("–".into(), |v| format!("{v:.3}"))).monospace());
            if analysis.band.applies() {
                ui.label(RichText::new(format!("{:.1}", 100.0 * analysis.band.outside_fraction)).monospace());
            } else {
                ui.label(RichText::new("–").monospace()).on_hover_text(
                    "The noise σ estimated from the run does not apply to this residual: no band",
                );
            }
            ui.end_row();
        }
    });
}

/// Bars of the RMSPE by regime, each labelled with its value.
fn regime_bars_ui(ui: &mut egui::Ui, run: &str, rows: &[RegimeRow]) {
    let labels: Vec<&'static str> = rows.iter().map(|r| short_label(r.regime)).collect();
    let values: Vec<(f64, f64)> =
        rows.iter().enumerate().filter_map(|(i, r)| Some((i as f64, r.rmspe_pct?))).collect();
    let top = values.iter().map(|(_, v)| *v).fold(0.0, f64::max);
    let bars: Vec<Bar> = rows
        .iter()
        .enumerate()
        .filter_map(|(i, r)| Some(Bar::new(i as f64, r.rmspe_pct?).width(0.7).name(r.regime.label())))
        .collect();
    Plot::new(("diagnosis_regime_bars", run))
        .height(300.0)
        .width(ui.available_width().max(300.0))
        .allow_drag(false)
        .allow_zoom(false)
        .allow_scroll(false)
        .include_y(0.0)
        .include_y(top * 1.15)
        .show_grid([false, true])
        .y_axis_label("RMSPE [%]")
        .x_grid_spacer(|input| {
            let (lo, hi) = input.bounds;
            let first = lo.ceil().max(0.0) as usize;
            let last = hi.floor().max(0.0) as usize;
            (first..=last).map(|i| egui_plot::GridMark { value: i as f64, step_size: 1.0 }).collect()
        })
        .x_axis_formatter(move |mark, _| {
            let i = mark.value.round();
            if (mark.value - i).abs() > 1e-6 || i < 0.0 {
                return String::new();
            }
            labels.get(i as usize).map(|l| (*l).to_owned()).unwrap_or_default()
        })
        .show(ui, |plot_ui| {
            plot_ui.bar_chart(BarChart::new("RMSPE by regime", bars).color(theme::MODEL));
            for (x, v) in values {
                let at = egui_plot::PlotPoint::new(x, v + 0.02 * top);
                let text = egui_plot::Text::new("value", at, RichText::new(format!("{v:.2}")).strong())
                    .anchor(egui::Align2::CENTER_BOTTOM);
                plot_ui.text(text);
            }
        });
}

/// A regime in a word, for the bar picture's axis.
fn short_label(regime: Regime) -> &'static str {
    match regime {
        Regime::Run => "run",
        Regime::Steady => "steady",
        Regime::Transient => "transient",
        Regime::Accelerating => "accel.",
        Regime::Decelerating => "decel.",
        Regime::Low => "low",
        Regime::Mid => "mid",
        Regime::High => "high",
    }
}

/// A correlogram as stems with its ±99 % bounds.
fn correlogram_plot(
    ui: &mut egui::Ui,
    id: &str,
    title: &str,
    lags: &[i64],
    values: &[f64],
    bound: f64,
    dt: f64,
) {
    ui.label(RichText::new(title).strong());
    let bars: Vec<Bar> =
        lags.iter().zip(values).map(|(lag, v)| Bar::new(*lag as f64 * dt, *v).width(0.6 * dt)).collect();
    Plot::new(id)
        .height(ui.available_height().clamp(180.0, 320.0))
        .width(ui.available_width())
        .x_axis_label("lag [s]")
        .include_y(1.0)
        .include_y(-1.0)
        .show(ui, |plot_ui| {
            plot_ui.bar_chart(BarChart::new(title, bars).color(theme::MEASURED));
            for y in [bound, -bound] {
                plot_ui.hline(
                    HLine::new("99 % bound", y)
                        .color(theme::WARNING)
                        .style(LineStyle::Dashed { length: 6.0 }),
                );
            }
        });
}

fn correlation_ui(ui: &mut egui::Ui, a: &ResidualAnalysis) {
    let dt = a.dt_secs;
    ui.columns(2, |columns| {
        let acf = &a.autocorrelation;
        let [left, right] = columns else { return };
        correlogram_plot(
            left,
            "diagnosis_acf",
            "Residual autocorrelation",
            &acf.lags_samples,
            &acf.values,
            acf.bound_99,
            dt,
        );
        hint(left, &format!("{} lags outside the 99 % bounds ±{:.3}.", acf.exceeding_lags_samples.len(), acf.bound_99));
        match &a.input_xcorr {
            Some(x) => {
                let c = &x.correlogram;
                let title = format!("Residual–{} cross-correlation", x.input);
                correlogram_plot(right, "diagnosis_ccf", &title, &c.lags_samples, &c.values, c.bound_99, dt);
                hint(
                    right,
                    &format!(
                        "Peak {:+.3} at lag {:+.2} s ({}; positive: the input leads){}; input prewhitened (AR {}).",
                        x.peak_value,
                        x.peak_lag_secs,
                        if x.peak_exceeds_bound { "outside the bounds" } else { "inside the bounds" },
                        if x.input_leads { "" } else { ", the residual leads" },
                        x.prewhitening_order
                    ),
                );
            }
            None => hint(right, "The input does not vary on this run: no cross-correlation."),
        }
    });
}

fn spectrum_ui(ui: &mut egui::Ui, a: &ResidualAnalysis) {
    let s = &a.spectrum;
    hint(
        ui,
        &format!(
            "Welch, Hann window, {} segments of {} samples. Largest peak at {:.3} Hz ({:.2} rad/s), {:.1}× its surroundings.",
            s.segments, s.segment_len, s.peak_freq_hz, s.peak_omega_rad_s, s.peak_prominence
        ),
    );
    let points: PlotPoints = s
        .freq_hz
        .iter()
        .zip(&s.psd_per_hz)
        .filter(|(_, p)| **p > 0.0)
        .map(|(f, p)| [*f, p.log10()])
        .collect();
    Plot::new(("diagnosis_spectrum", &a.run))
        .height(ui.available_height().max(200.0))
        .x_axis_label("frequency [Hz]")
        .y_axis_label(format!("log₁₀ PSD [{}²/Hz]", a.unit))
        .show(ui, |plot_ui| {
            plot_ui.line(Line::new("residual PSD", points).color(theme::MODEL).width(1.2));
            plot_ui.vline(
                egui_plot::VLine::new("peak", s.peak_freq_hz)
                    .color(theme::WARNING)
                    .style(LineStyle::Dashed { length: 6.0 }),
            );
        });
}

/// The residual against every recorded channel the model does not use, one scatter each.
fn channels_ui(ui: &mut egui::Ui, a: &ResidualAnalysis, run: &Run) {
    let scan = &a.channels;
    if scan.channels.is_empty() {
        hint(ui, "The run records no channel the model does not use.");
    }
    for excluded in &scan.excluded {
        hint(ui, &format!("{} left out: {:?}", excluded.channel, excluded.reason));
    }
    let step = (a.residual.len() / MAX_SCATTER_POINTS).max(1);
    let per_row = ((ui.available_width() / 340.0).floor() as usize).max(1);
    egui::ScrollArea::vertical().auto_shrink([false, false]).show(ui, |ui| {
        for row in scan.channels.chunks(per_row) {
            ui.horizontal_top(|ui| {
                for c in row {
                    channel_scatter_ui(ui, a, run, c, step);
                }
            });
        }
    });
}

/// The residual against one channel, with its correlation.
fn channel_scatter_ui(
    ui: &mut egui::Ui,
    a: &ResidualAnalysis,
    run: &Run,
    c: &ChannelCorrelation,
    step: usize,
) {
    let Some(channel) = run.channel(&c.channel) else { return };
    ui.vertical(|ui| {
        ui.set_width(330.0);
        let verdict = if c.significant { "significant" } else { "not significant" };
        let colour = if c.significant { theme::WARNING } else { theme::HINT };
        ui.label(RichText::new(&c.channel).strong());
        ui.label(
            RichText::new(format!("r = {:+.3}, slow r = {:+.3}, {verdict}", c.r, c.r_slow)).color(colour),
        );
        let points: PlotPoints =
            channel.values.iter().zip(&a.residual).step_by(step).map(|(x, r)| [*x, *r]).collect();
        let unit = crate::core::run::bracketed_unit(&c.unit);
        Plot::new(("diagnosis_channel", &c.channel))
            .width(320.0)
            .height(220.0)
            .x_grid_spacer(plot_util::grid_125_x)
            .y_grid_spacer(plot_util::grid_125_y)
            .x_axis_label(format!("{}{unit}", c.channel))
            .y_axis_label(format!("residual{}", crate::core::run::bracketed_unit(&a.unit)))
            .show(ui, |plot_ui| {
                plot_ui.points(Points::new(&c.channel, points).radius(1.2).color(theme::MEASURED));
            });
    });
}
