//! Where each output's final model fails, for `jetid --batch`: the residual analysis of every
//! scored run (report.json `residuals`, report.md "Where it fails") and one picture per run.
use std::path::Path;

use crate::core::compare::OutputModels;
use crate::core::effects::ExtendedModel;
use crate::core::residuals::{ResidualSettings, SigmaSource, analyse_residuals, summary};
use crate::core::run::Run;
use crate::io::report::ResidualReport;

/// The residual analysis of the final gray-box model (with its effects) on every run; the figures go
/// to `out_dir` and their file names are returned with the reports. A run that cannot be analysed
/// is a note.
pub fn residual_reports(
    out_dir: &Path,
    output: &str,
    models: &OutputModels,
    runs: &[&Run],
    sigma: Option<f64>,
    notes: &mut Vec<String>,
) -> (Vec<ResidualReport>, Vec<String>) {
    let channels = models.extended.as_ref().map(ExtendedModel::required_channels).unwrap_or_default();
    let settings = ResidualSettings::for_model_channels(&channels);
    let mut reports = Vec::new();
    let mut figures = Vec::new();
    for run in runs.iter().filter(|r| r.output(output).is_some()) {
        // The gray-box model as `OutputModels::simulate_run` has it, without simulating the others.
        let y_hat =
            models.gray_box_model().simulate_scored(run, models.initial_state).map_err(|e| e.to_string());
        let y_hat = match y_hat {
            Ok(y) => y,
            Err(e) => {
                notes.push(format!(
                    "residuals of '{output}' on '{}': the model cannot simulate it: {e}",
                    run.name
                ));
                continue;
            }
        };
        let analysis = match analyse_residuals(run, output, &y_hat, sigma, &settings) {
            Ok(a) => a,
            Err(e) => {
                notes.push(format!("residuals of '{output}' on '{}': {e}", run.name));
                continue;
            }
        };
        let file = format!("{output}_residuals_{}.png", run.name);
        let title = format!("{output} on {}: where the model fails", run.name);
        let figure =
            match crate::io::figures::residuals_png(&out_dir.join(&file), &title, &run.t_secs, &analysis) {
                Ok(()) => {
                    figures.push(file.clone());
                    Some(file)
                }
                Err(e) => {
                    notes.push(e.to_string());
                    None
                }
            };
        let peak =
            analysis.input_xcorr.as_ref().map(|x| (x.peak_lag_secs, x.peak_value, x.peak_exceeds_bound));
        reports.push(ResidualReport {
            run: run.name.clone(),
            summary: summary(&analysis),
            noise_sigma: analysis.band.sigma,
            noise_sigma_source: match analysis.band.sigma_source {
                SigmaSource::Supplied => "normal fit of the steady run".to_owned(),
                SigmaSource::EstimatedFromSecondDifferences => {
                    "run's second differences (no steady run)".to_owned()
                }
            },
            outside_band_pct: 100.0 * analysis.band.outside_fraction,
            noise_band_applies: analysis.band.applies(),
            regimes: analysis.regimes.rows.clone(),
            acf_lags_beyond_99_secs: analysis
                .autocorrelation
                .exceeding_lags_samples
                .iter()
                .map(|l| *l as f64 * analysis.dt_secs)
                .collect(),
            input_xcorr_peak: peak,
            spectrum_peak_hz: analysis.spectrum.peak_freq_hz,
            spectrum_peak_prominence: analysis.spectrum.peak_prominence,
            channels: analysis.channels.channels.clone(),
            worst_stretches: analysis.worst_stretches.clone(),
            figure,
        });
    }
    (reports, figures)
}
