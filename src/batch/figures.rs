//! The pictures `jetid --batch` writes beside its reports (z-plane clusters, Bode comparison,
//! static-map fit, validation traces). A picture that cannot be drawn is a note, not a failure.
use std::path::Path;

use std::collections::BTreeMap;

use crate::core::compare::{FrequencyComparison, ModelKind, OutputModels};
use crate::core::identification::pipeline::Identified;
use crate::core::monte_carlo::MonteCarloResult;
use crate::core::numerics::metrics::BoxStats;
use crate::core::numerics::tf::{BodePoint, log_space};
use crate::core::run::Run;
use crate::io::figures::{self, BodeCurve, EmpiricalBode};

/// Draw the figures of one output into `dir`; returns the file names written and notes on failures.
pub fn output_figures(
    dir: &Path,
    output: &str,
    identified: &Identified,
    models: &OutputModels,
    validation: &[&Run],
    freq: Option<&FrequencyComparison>,
    boxes: &BTreeMap<String, BTreeMap<String, BoxStats>>,
) -> (Vec<String>, Vec<String>) {
    let (mut written, mut notes) = (Vec::new(), Vec::new());
    let mut keep = |name: String, result: Result<(), figures::FigureError>| match result {
        Ok(()) => written.push(name),
        Err(e) => notes.push(format!("figure {name}: {e}")),
    };
    let fits = &identified.fits;
    let model = &identified.model;
    let name = format!("{output}_zplane.png");
    keep(
        name.clone(),
        figures::zplane_png(
            &dir.join(&name),
            &format!("{output}: segment poles/zeros and clusters"),
            &fits.roots,
            &identified.evals,
            fits.dt_secs,
        ),
    );

    let omegas = log_space(0.05, std::f64::consts::PI / fits.dt_secs, 256);
    let mut curves: Vec<BodeCurve> = fits
        .models
        .iter()
        .zip(&fits.segments)
        .map(|(m, s)| BodeCurve {
            name: format!("segment {}", s.label),
            points: m.bode_response(&omegas),
            emphasis: false,
        })
        .collect();
    // Segment models are in deviation units; scale the reduced model's curve to compare shapes.
    curves.push(BodeCurve {
        name: "reduced model".into(),
        points: model.wiener.linear.tf.bode_response(&omegas),
        emphasis: true,
    });
    let name = format!("{output}_bode.png");
    keep(
        name.clone(),
        figures::bode_png(
            &dir.join(&name),
            &format!("{output}: segment models and the reduced model"),
            &curves,
            None,
        ),
    );

    let (lo, hi) = model
        .steady_points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), (v, _)| (a.min(*v), b.max(*v)));
    let curve: Vec<(f64, f64)> =
        (0..=100).map(|i| lo + (hi - lo) * i as f64 / 100.0).map(|v| (v, model.wiener.map.eval(v))).collect();
    let name = format!("{output}_static_map.png");
    keep(
        name.clone(),
        figures::static_map_png(
            &dir.join(&name),
            &format!("{output}: static map f(v)"),
            &model.steady_points,
            &curve,
            "v (linear block output)",
            output,
        ),
    );

    for run in validation {
        let Some(y) = run.output(output) else { continue };
        let traces: Vec<(String, Vec<f64>)> =
            models.simulate_run(run).into_iter().map(|(kind, y)| (kind.label().to_owned(), y)).collect();
        let name = format!("{output}_traces_{}.png", run.name);
        keep(
            name.clone(),
            figures::traces_png(
                &dir.join(&name),
                &format!("{output} on '{}': every model from the input alone", run.name),
                &run.t_secs,
                &y.values,
                &traces,
                &figures::with_unit(output, &y.unit),
            ),
        );
    }

    if let Some(freq) = freq
        && let Some(measured) = freq.responses.get("measured")
    {
        let curves: Vec<BodeCurve> = freq
            .responses
            .iter()
            .filter(|(name, _)| name.as_str() != "measured")
            .map(|(name, r)| BodeCurve {
                name: model_label(name).to_owned(),
                points: r
                    .omega_rad_s
                    .iter()
                    .zip(&r.mag_db)
                    .zip(&r.phase_deg)
                    .map(|((w, m), p)| BodePoint { omega_rad_s: *w, mag_db: *m, phase_deg: *p })
                    .collect(),
                emphasis: name.as_str() == ModelKind::GrayBox.report_name(),
            })
            .collect();
        let empirical = EmpiricalBode {
            omega_rad_s: measured.omega_rad_s.clone(),
            mag_db: measured.mag_db.clone(),
            phase_deg: measured.phase_deg.clone(),
            coherence: measured.coherence.clone(),
        };
        let name = format!("{output}_bode_compare.png");
        keep(
            name.clone(),
            figures::bode_png(
                &dir.join(&name),
                &format!("{output}: chirp '{}' measured vs every model (same Welch estimate)", freq.run),
                &curves,
                Some(&empirical),
            ),
        );
    }

    let box_list: Vec<(String, BoxStats)> = boxes
        .iter()
        .flat_map(|(model, runs)| {
            runs.iter().map(move |(run, b)| (format!("{} / {run}", model_label(model)), *b))
        })
        .collect();
    if !box_list.is_empty() {
        let name = format!("{output}_error_boxes.png");
        keep(
            name.clone(),
            figures::boxplot_png(
                &dir.join(&name),
                &format!("{output}: percentage error 100·(y − ŷ)/y per model and run"),
                &box_list,
                "error (%)",
            ),
        );
    }
    (written, notes)
}

/// The name people read for a model keyed by its report name.
fn model_label(name: &str) -> &str {
    ModelKind::from_report_name(name).map_or(name, |kind| kind.label())
}

/// One histogram per model of the Monte Carlo differences, with the fitted normal.
pub fn monte_carlo_figures(
    dir: &Path,
    output: &str,
    results: &BTreeMap<String, MonteCarloResult>,
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
                model_label(model),
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
