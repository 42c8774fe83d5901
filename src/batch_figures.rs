//! The pictures `jetid --batch` writes beside its reports (z-plane clusters, Bode comparison,
//! static-map fit, validation traces). A picture that cannot be drawn is a note, not a failure.
use std::path::Path;

use crate::core::pipeline::{Identified, predict_linear, predict_wiener};
use crate::core::run::Run;
use crate::core::tf::log_space;
use crate::io::figures::{self, BodeCurve};

/// Draw the figures of one output into `dir`; returns the file names written and notes on failures.
pub fn output_figures(
    dir: &Path,
    output: &str,
    identified: &Identified,
    validation: Option<&Run>,
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

    if let Some(run) = validation
        && let (Some(y), Ok(gray), Ok(lin)) = (
            run.output(output),
            predict_wiener(&model.wiener, run, output),
            predict_linear(&model.wiener.linear, run, output),
        )
    {
        let name = format!("{output}_traces_{}.png", run.name);
        keep(
            name.clone(),
            figures::traces_png(
                &dir.join(&name),
                &format!("{output} on '{}'", run.name),
                &run.t_secs,
                &y.values,
                &[("gray-box".into(), gray.y_hat), ("linear".into(), lin.y_hat)],
                output,
            ),
        );
    }
    (written, notes)
}
