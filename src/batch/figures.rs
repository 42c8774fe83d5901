//! The pictures `jetid --batch` writes beside its reports (z-plane clusters, Bode comparison,
//! static-map fit, validation traces). A picture that cannot be drawn is a note, not a failure.
use std::path::Path;

use std::collections::BTreeMap;

use crate::core::compare::{Curve, FrequencyComparison, ModelKind, OutputModels};
use crate::core::control::{ParameterCovariance, bands};
use crate::core::effects::ExtendedModel;
use crate::core::identification::pipeline::{GrayBoxModel, Identified};
use crate::core::monte_carlo::MonteCarloResult;
use crate::core::numerics::metrics::BoxStats;
use crate::core::numerics::tf::BodePoint;
use crate::core::run::{Channel, Run};
use crate::io::figures::{self, BodeCurve, EmpiricalBode};
use crate::workflow::products::bode_grid;

/// What one output's figures show, computed before anything is drawn: the segment roots and
/// clusters, every Bode curve, the static map over its steady points, each model's traces on the
/// compared runs and the chirp's responses.
pub struct OutputCurves<'a> {
    identified: &'a Identified,
    /// Every segment model's Bode curve and the reduced model's (emphasised).
    bode: Vec<BodeCurve>,
    /// f(v) over the range of the steady points.
    static_map: Vec<(f64, f64)>,
    /// Per compared run that records the output: the run, its measurement, each model's simulation.
    traces: Vec<RunTraces<'a>>,
    /// Each model's response to the chirp and the measured one, when there is a chirp run.
    chirp: Option<ChirpCurves>,
    /// What could not be drawn, one sentence each.
    notes: Vec<String>,
    /// The band of the final model's linear block from its parameter uncertainty.
    bode_band: Option<bands::BodeBand>,
    /// The 95 % region of each of its roots, as outlines in z.
    regions: Vec<Vec<[f64; 2]>>,
    /// The final model's poles and zeros (the regions are drawn around them).
    model_roots: (Vec<num_complex::Complex64>, Vec<num_complex::Complex64>),
}

/// Points on each root region's outline.
const REGION_POINTS: usize = 72;
/// Seed of the models drawn for the Bode band (the figure comes out the same on every run).
const BAND_SEED: u64 = 0x6A65_7469_6402;

/// A compared run with every model's simulation of it.
struct RunTraces<'a> {
    run: &'a Run,
    measured: &'a Channel,
    models: Vec<(String, Vec<f64>)>,
    /// Half-width of the 95 % band of the gray-box's noiseless output from its parameter
    /// uncertainty, when the covariance could be carried to this run.
    band: Option<Vec<f64>>,
}

/// The chirp's measured response and every model's, by the same Welch estimate.
struct ChirpCurves {
    run: String,
    curves: Vec<BodeCurve>,
    measured: EmpiricalBode,
}

impl<'a> OutputCurves<'a> {
    /// The curves of `identified`'s output and of every model in `models` on the runs `compared`.
    pub fn of(
        identified: &'a Identified,
        models: &OutputModels,
        uncertain: Option<(&ExtendedModel, &ParameterCovariance)>,
        compared: &[&'a Run],
        freq: Option<&FrequencyComparison>,
    ) -> Self {
        let output = &identified.model.output;
        let notes = std::cell::RefCell::new(Vec::new());
        let traces = compared
            .iter()
            .filter_map(|run| {
                let measured = run.output(output)?;
                let models = models
                    .simulate_run(run)
                    .into_iter()
                    .map(|(kind, y)| (kind.label().to_owned(), y))
                    .collect();
                let band = uncertain.and_then(|(model, cov)| {
                    bands::output_half_widths(model, cov, run)
                        .map_err(|e| {
                            notes.borrow_mut().push(format!("uncertainty band on '{}': {e}", run.name))
                        })
                        .ok()
                });
                Some(RunTraces { run, measured, models, band })
            })
            .collect();
        Self {
            identified,
            bode: bode_curves(identified, uncertain.map(|(model, _)| model)),
            static_map: static_map_curve(&identified.model),
            traces,
            chirp: freq.and_then(chirp_curves),
            notes: notes.into_inner(),
            bode_band: uncertain.and_then(|(model, cov)| {
                let draws = cov.draw_models(model, bands::DRAWS, BAND_SEED).ok()?;
                Some(bands::bode_band(&draws, &bode_grid(identified.fits.dt_secs)))
            }),
            regions: uncertain
                .and_then(|(model, cov)| bands::root_regions(model, cov).ok())
                .map(|rs| rs.iter().map(|r| r.outline(REGION_POINTS)).collect())
                .unwrap_or_default(),
            model_roots: uncertain
                .and_then(|(model, _)| model.roots().ok())
                .or_else(|| {
                    let tf = &identified.model.wiener.linear.tf;
                    Some((tf.poles().ok()?, tf.zeros().ok()?))
                })
                .unwrap_or_default(),
        }
    }
}

/// Segment models are in deviation units; the reduced model's curve is drawn beside them to compare
/// shapes, and the final model's block when its effects' refit moved it (the band is of that block).
fn bode_curves(identified: &Identified, finished: Option<&ExtendedModel>) -> Vec<BodeCurve> {
    let fits = &identified.fits;
    let omegas = bode_grid(fits.dt_secs);
    let mut curves: Vec<BodeCurve> = fits
        .models
        .iter()
        .zip(&fits.segments)
        .map(|(m, s)| BodeCurve {
            name: format!("segment {}", s.label),
            points: m.bode_response(&omegas),
            emphasis: false,
            colour: None,
            dashed: false,
        })
        .collect();
    curves.push(BodeCurve {
        name: "reduced model".into(),
        points: identified.model.wiener.linear.tf.bode_response(&omegas),
        emphasis: true,
        colour: Some(figures::palette::REDUCED),
        dashed: false,
    });
    if let Some(finished) = finished.filter(|m| m.wiener.linear.tf != identified.model.wiener.linear.tf) {
        // An output read off the speed's model holds the speed's block, in the speed's units.
        let name = if finished.read_off().is_some() { READ_OFF_NAME } else { REFITTED_NAME };
        let block = &finished.wiener.linear.tf;
        curves.push(BodeCurve {
            name: name.into(),
            points: block.bode_response(&omegas),
            emphasis: true,
            colour: Some(figures::palette::model(ModelKind::GrayBox)),
            dashed: false,
        });
    }
    curves
}

/// The name of the final model's block when the effects' refit moved it from the reduced model's.
const REFITTED_NAME: &str = "model with effects";
/// The name of the final model's block when the output is read off the shaft speed's model (in
/// the speed's units: its level is not thrust's).
const READ_OFF_NAME: &str = "speed's block";

/// f(v) at 101 points over the range of the steady points.
fn static_map_curve(model: &GrayBoxModel) -> Vec<(f64, f64)> {
    let (lo, hi) = model
        .steady_points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), (v, _)| (a.min(*v), b.max(*v)));
    (0..=100).map(|i| lo + (hi - lo) * i as f64 / 100.0).map(|v| (v, model.wiener.map.eval(v))).collect()
}

/// The chirp's curves, when the measured response is among them.
fn chirp_curves(freq: &FrequencyComparison) -> Option<ChirpCurves> {
    let measured = freq.responses.get(&Curve::Measured)?;
    let curves = freq
        .responses
        .iter()
        .filter_map(|(curve, r)| match curve {
            Curve::Measured => None,
            Curve::Model(kind) => Some((*kind, r)),
        })
        .map(|(kind, r)| BodeCurve {
            name: kind.label().to_owned(),
            points: r
                .omega_rad_s
                .iter()
                .zip(&r.mag_db)
                .zip(&r.phase_deg)
                .map(|((w, m), p)| BodePoint { omega_rad_s: *w, mag_db: *m, phase_deg: *p })
                .collect(),
            emphasis: kind == ModelKind::GrayBox,
            colour: Some(figures::palette::model(kind)),
            dashed: kind == ModelKind::Linear || kind.is_reference(),
        })
        .collect();
    let measured = EmpiricalBode {
        omega_rad_s: measured.omega_rad_s.clone(),
        mag_db: measured.mag_db.clone(),
        phase_deg: measured.phase_deg.clone(),
        coherence: measured.coherence.clone(),
    };
    Some(ChirpCurves { run: freq.run.clone(), curves, measured })
}

/// Draw the figures of one output (recorded in `unit`) into `dir`; returns the file names written
/// and notes on failures.
pub fn output_figures(
    dir: &Path,
    output: &str,
    unit: &str,
    curves: &OutputCurves<'_>,
    boxes: &BTreeMap<ModelKind, BTreeMap<String, BoxStats>>,
) -> (Vec<String>, Vec<String>) {
    let (mut written, mut notes) = (Vec::new(), curves.notes.clone());
    let mut keep = |name: String, result: Result<(), figures::FigureError>| match result {
        Ok(()) => written.push(name),
        Err(e) => notes.push(format!("figure {name}: {e}")),
    };
    let (fits, model) = (&curves.identified.fits, &curves.identified.model);
    let name = format!("{output}_zplane.png");
    let title = format!("{output}: segment poles/zeros and clusters");
    keep(
        name.clone(),
        figures::zplane_with_regions_png(
            &dir.join(&name),
            &title,
            &fits.roots,
            &curves.identified.evals,
            fits.dt_secs,
            &figures::ModelRoots {
                poles: &curves.model_roots.0,
                zeros: &curves.model_roots.1,
                regions: &curves.regions,
            },
        ),
    );
    let name = format!("{output}_bode.png");
    let title = format!("{output}: segment models and the reduced model");
    keep(
        name.clone(),
        figures::bode_with_band_png(&dir.join(&name), &title, &curves.bode, None, curves.bode_band.as_ref()),
    );
    let name = format!("{output}_static_map.png");
    let title = format!("{output}: static map f(v)");
    let v_label = "v (linear block output)";
    let drawn = figures::static_map_png(
        &dir.join(&name),
        &title,
        &model.steady_points,
        &curves.static_map,
        v_label,
        &figures::with_unit(output, unit),
    );
    keep(name, drawn);
    for traces in &curves.traces {
        let run = traces.run;
        let name = format!("{output}_traces_{}.png", run.name);
        let title = format!("{output} on '{}': every model from the input alone", run.name);
        let y_label = figures::with_unit(output, &traces.measured.unit);
        let drawn = figures::traces_with_band_png(
            &dir.join(&name),
            &title,
            &run.t_secs,
            &traces.measured.values,
            &traces.models,
            traces.band.as_deref(),
            &y_label,
        );
        keep(name, drawn);
    }
    if let Some(chirp) = &curves.chirp {
        let name = format!("{output}_bode_compare.png");
        let title = format!("{output}: chirp '{}' measured vs every model (same Welch estimate)", chirp.run);
        keep(name.clone(), figures::bode_png(&dir.join(&name), &title, &chirp.curves, Some(&chirp.measured)));
    }
    if let Some((name, drawn)) = error_boxes_figure(dir, output, boxes) {
        keep(name, drawn);
    }
    (written, notes)
}

/// The box plot of every model's percentage error on every run, when there are any.
fn error_boxes_figure(
    dir: &Path,
    output: &str,
    boxes: &BTreeMap<ModelKind, BTreeMap<String, BoxStats>>,
) -> Option<(String, Result<(), figures::FigureError>)> {
    let box_list: Vec<(String, BoxStats)> = boxes
        .iter()
        .flat_map(|(model, runs)| runs.iter().map(move |(run, b)| (format!("{} / {run}", model.label()), *b)))
        .collect();
    if box_list.is_empty() {
        return None;
    }
    let name = format!("{output}_error_boxes.png");
    let title = format!("{output}: percentage error 100·(y − ŷ)/y per model and run");
    let drawn = figures::boxplot_png(&dir.join(&name), &title, &box_list, "error (%)");
    Some((name, drawn))
}

/// One histogram per model of the Monte Carlo differences, with the fitted normal.
pub fn monte_carlo_figures(
    dir: &Path,
    output: &str,
    results: &BTreeMap<ModelKind, MonteCarloResult>,
) -> (Vec<String>, Vec<String>) {
    let (mut written, mut notes) = (Vec::new(), Vec::new());
    for (model, r) in results {
        let name = format!("{output}_monte_carlo_{model}.png");
        let (mean, std) = match r.normal_fit {
            crate::core::numerics::noise_fit::Distribution::Normal { mean, std } => (mean, std),
            _ => (r.mean_difference, r.std_difference),
        };
        let result = figures::histogram_png(
            &dir.join(&name),
            &format!(
                "{output}, {}: noisy − nominal over {} runs (std {:.4})",
                model.label(),
                r.std_per_run.len(),
                r.std_difference
            ),
            &r.differences,
            40,
            Some((mean, std)),
            &format!("{output} difference"),
        );
        match result {
            Ok(()) => written.push(name),
            Err(e) => notes.push(format!("figure {name}: {e}")),
        }
    }
    (written, notes)
}
