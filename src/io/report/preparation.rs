//! How much a preparation choice moves the model, as report.json (`outputs.<name>.preparation`) keeps
//! it and report.md says it (computed by `workflow::preparation`).
use serde::{Deserialize, Serialize};

use crate::core::identification::words::fmt_error;

/// One compared run under both segmentations (plain models, RMSE in output units).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunUnderBoth {
    pub run: String,
    /// With the steps detected on the chosen channel (the model the project uses).
    pub rmse: f64,
    /// With the steps detected on the input instead.
    pub rmse_on_input: f64,
}

/// The segmentation channel as a preparation choice (report.json `outputs.<name>.preparation`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SegmentationChoice {
    /// The channel the steps were detected on.
    pub steps_from: String,
    /// Found in the log (true) or named by the project (false).
    pub found: bool,
    /// Every compared run under both; empty when the input's steps give no model.
    pub runs: Vec<RunUnderBoth>,
    /// Why the input's steps give no model, when they do not.
    pub on_input_fails: Option<String>,
    /// Mean relative change of the runs' RMSE from the chosen segmentation to the input's, %.
    pub moved_pct: Option<f64>,
}

impl SegmentationChoice {
    /// Mean relative change of the RMSE of `runs` from the chosen segmentation to the input's, %
    /// (`None` without a run to compare on).
    pub fn moved_pct_of(runs: &[RunUnderBoth]) -> Option<f64> {
        let changes: Vec<f64> = runs
            .iter()
            .filter(|r| r.rmse > 0.0)
            .map(|r| 100.0 * (r.rmse_on_input - r.rmse) / r.rmse)
            .collect();
        (!changes.is_empty()).then(|| changes.iter().sum::<f64>() / changes.len() as f64)
    }

    /// The sentence report.md and the notes show.
    pub fn sentence(&self, output: &str) -> String {
        let how = if self.found { "found in the log" } else { "named by the project" };
        let head = format!("'{output}': the steps were detected on '{}' ({how})", self.steps_from);
        if let Some(why) = &self.on_input_fails {
            return format!("{head}; on the input's own steps there is no model ({why})");
        }
        let Some(moved) = self.moved_pct else {
            return format!(
                "{head}; no compared run holds the output, so how far the choice moves the model is not known"
            );
        };
        let runs: Vec<String> = self
            .runs
            .iter()
            .map(|r| format!("'{}' RMSE {} against {}", r.run, fmt_error(r.rmse_on_input), fmt_error(r.rmse)))
            .collect();
        format!(
            "{head}. Detected on the input's steps instead, the plain model (before effects) scores {}: the \
             choice of channel moves the plain model's error by {:+.1} % on average",
            runs.join(", "),
            moved
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn choice(runs: Vec<RunUnderBoth>, on_input_fails: Option<String>) -> SegmentationChoice {
        let moved_pct = SegmentationChoice::moved_pct_of(&runs);
        SegmentationChoice { steps_from: "sp".into(), found: true, runs, on_input_fails, moved_pct }
    }

    #[test]
    fn the_sentence_says_how_far_the_model_moves_or_why_it_cannot() {
        let runs = vec![
            RunUnderBoth { run: "a".into(), rmse: 100.0, rmse_on_input: 130.0 },
            RunUnderBoth { run: "b".into(), rmse: 200.0, rmse_on_input: 180.0 },
        ];
        let both = choice(runs, None);
        assert!((both.moved_pct.unwrap_or(f64::NAN) - 10.0).abs() < 1e-12, "{both:?}");
        let words = both.sentence("rpm");
        assert!(words.contains("'a' RMSE 130 against 100") && words.contains("+10.0 %"), "{words}");
        let failed = choice(Vec::new(), Some("no steps in the input".into()));
        assert!(failed.sentence("rpm").contains("no model (no steps in the input)"));
        let unscored = choice(Vec::new(), None);
        assert_eq!(unscored.moved_pct, None);
        assert!(unscored.sentence("rpm").contains("is not known"));
    }
}
