//! "Where it fails" of one model, computed once per model (keyed by its id): core's residual
//! analysis of every scored run, with the noise band's σ from the steady run when there is one.
use crate::core::residuals::{ResidualAnalysis, ResidualSettings, analyse_residuals, steady_noise_sigma};
use crate::core::run::RunRole;
use crate::ui::derived::model_cache::LiveModel;
use crate::ui::state::session::Session;
use crate::ui::widgets::at_noise_precision;

/// One scored run's analysis.
pub struct RunAnalysis {
    /// Index of the run in the session.
    pub index: usize,
    pub label: String,
    pub analysis: Result<ResidualAnalysis, String>,
}

/// The analyses of one model.
pub struct Analyses {
    pub model_id: u64,
    /// Where the noise σ of the band comes from, in words.
    pub sigma_note: String,
    pub runs: Vec<RunAnalysis>,
}

/// The measurement-noise σ of `output`: the normal fit (maximum likelihood: the standard
/// deviation) of the first steady run that records it.
fn steady_sigma(session: &Session, output: &str) -> Option<(f64, String)> {
    session.runs.iter().filter(|r| r.role == RunRole::Steady).find_map(|entry| {
        let sigma = steady_noise_sigma(&entry.run, output)?;
        Some((
            sigma,
            format!(
                "σ = {} from the normal fit of the steady run {}",
                at_noise_precision(sigma, sigma, false),
                entry.display_name()
            ),
        ))
    })
}

impl Analyses {
    /// The residual analysis of `live` on every scored run (core's, with the steady run's σ).
    pub fn of(output: &str, session: &Session, live: &LiveModel) -> Self {
        let steady = steady_sigma(session, output);
        let sigma_note = steady.as_ref().map_or_else(
            || {
                "σ estimated from each run's measured output (second differences): there is no steady run \
                 to fit the sensor noise on"
                    .to_owned()
            },
            |(_, note)| note.clone(),
        );
        let settings = ResidualSettings::for_model_channels(&live.current_model().required_channels());
        let runs = live
            .runs
            .iter()
            .map(|scored| {
                let analysis = match session.runs.get(scored.index) {
                    Some(entry) => analyse_residuals(
                        &entry.run,
                        output,
                        &scored.gray_box.y_hat,
                        steady.as_ref().map(|(sigma, _)| *sigma),
                        &settings,
                    )
                    .map_err(|e| e.to_string()),
                    None => Err("the run is no longer in the session".to_owned()),
                };
                RunAnalysis { index: scored.index, label: scored.label(), analysis }
            })
            .collect();
        Analyses { model_id: live.id, sigma_note, runs }
    }
}
