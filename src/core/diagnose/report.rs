//! What a diagnosis hands back: the trials, ranked, with their tests and evidence.
use std::fmt;

use super::Comparison;
use super::{FOLDS, MIN_HELD_OUT_SEGMENTS};
use crate::core::effects::{EffectId, ExtendedModel, StructuralChange};

/// What a diagnosis trial adds to the model: a refinement of its own structure, or an effect of the
/// catalog. Shown by its id (`extra_pole_pair`, `thermal_soak`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TrialId {
    Structure(StructuralChange),
    Effect(EffectId),
}

impl TrialId {
    /// The id the reports and the app list it under.
    pub fn name(self) -> &'static str {
        match self {
            Self::Structure(change) => change.id(),
            Self::Effect(id) => id.name(),
        }
    }

    /// Physics or structure.
    pub fn kind(self) -> DiagnosisKind {
        match self {
            Self::Structure(_) => DiagnosisKind::Structure,
            Self::Effect(_) => DiagnosisKind::Physics,
        }
    }

    /// The catalog effect that adds this as a block, when one does: every effect, and the
    /// scheduled spool time constant, a refinement that is also a block. The other refinements
    /// change the linear block or the map themselves (the clusters, the map's order).
    pub fn as_effect(self) -> Option<EffectId> {
        match self {
            Self::Effect(id) => Some(id),
            Self::Structure(StructuralChange::ScheduledTimeConstant) => Some(EffectId::ScheduledTimeConstant),
            Self::Structure(_) => None,
        }
    }
}

impl TrialId {
    /// The bench experiment that shows this trial's signature and not another's, in words.
    pub fn separating_test(self) -> &'static str {
        match self {
            Self::Effect(EffectId::ThermalSoak) => "a 60 s hold after a large step (a soak keeps creeping)",
            Self::Effect(EffectId::TransportDelay) => {
                "a small fast step (a dead time shifts the whole response late, a lag starts on time)"
            }
            Self::Effect(EffectId::RateLimit) => {
                "steps of several sizes (a rate limit caps the slope of the large ones only)"
            }
            Self::Effect(EffectId::AsymmetricDynamics) => {
                "equal steps up and down at one operating point (only asymmetry makes them differ)"
            }
            Self::Effect(EffectId::CalibrationDrift) => {
                "the same steady point on both test days (a drift moves it, dynamics do not)"
            }
            Self::Effect(EffectId::AmbientCorrection) => "runs on days of different ambient temperature",
            Self::Effect(EffectId::SensorDynamics) => "a tap or chirp test of the stand alone",
            Self::Effect(EffectId::StaticMapOrder) | Self::Structure(StructuralChange::MapOrder) => {
                "a staircase of long holds across the range (the map's shape shows in the settled values)"
            }
            Self::Effect(EffectId::ScheduledTimeConstant)
            | Self::Structure(StructuralChange::ScheduledTimeConstant) => {
                "equal small steps at low and high power (a scheduled spool is slower at the low end)"
            }
            Self::Structure(_) => "a chirp across the model's band (a missing root shows at one frequency)",
            Self::Effect(EffectId::ReadOffSpeed) => {
                "fast steps of several sizes with speed and thrust logged (thrust follows the speed it is read off)"
            }
        }
    }
}

impl fmt::Display for TrialId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl serde::Serialize for TrialId {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.name())
    }
}

/// Whether a trial adds physics (an effect of the catalog) or refines the model's own structure.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DiagnosisKind {
    /// An effect of the catalog.
    Physics,
    /// One more real pole, pole pair or zero, or a higher static-map order (see
    /// [`StructuralChange`](crate::core::effects::StructuralChange)).
    Structure,
}

impl DiagnosisKind {
    /// "physics" or "structure".
    pub fn label(self) -> &'static str {
        match self {
            Self::Physics => "physics",
            Self::Structure => "structure",
        }
    }
}

impl fmt::Display for DiagnosisKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.label())
    }
}

/// One trial: the fitted extension, its validation score and the evidence.
#[derive(Clone, Debug, PartialEq)]
pub struct Diagnosis {
    /// The effect of the catalog or the structural refinement tried.
    pub effect: TrialId,
    /// Physics or structure.
    pub kind: DiagnosisKind,
    /// What the effect means physically.
    pub physics: String,
    /// Beyond what noise gives and large enough to matter (see the module documentation).
    pub significant: bool,
    /// Validation error of the current model (RMSPE averaged over the validation runs), %.
    pub rmspe_before_pct: f64,
    /// Validation error with the effect added and refitted, %.
    pub rmspe_after_pct: f64,
    /// The same two errors beyond the measurement noise, in units of the noise: each validation
    /// run's `√(mean((y − ŷ)/σ)² − 1)`, an estimate of the RMS error against the noiseless truth,
    /// averaged over the runs. The decision and the ranking read these (see `loss`); RMSPE is what
    /// the user compares.
    pub beyond_noise_before: f64,
    pub beyond_noise_after: f64,
    /// The test of "the extension is no better than the refitted current model", on the validation
    /// runs and the held-out identification data.
    pub test: Comparison,
    /// One sentence from the current model's residuals, in an engine engineer's words.
    pub evidence: String,
    /// The current model with the effect added and refitted on the identification data.
    pub model: ExtendedModel,
    /// Why a physical effect that beats the current model is still not counted, when the test's
    /// words do not say it: its own evidence does not show its signature.
    pub why_not: Option<String>,
}

impl Diagnosis {
    /// What the witnesses say, and why the trial is not counted when they alone do not explain it.
    pub fn significance_words(&self) -> String {
        match &self.why_not {
            Some(why) => format!("{}; {why}", self.test.words()),
            None => self.test.words(),
        }
    }
}

/// An effect that was not tried, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct SkippedEffect {
    /// The effect or refinement not tried.
    pub effect: TrialId,
    /// Why it was not tried, in words.
    pub reason: String,
}

/// The diagnosis of one output: tried effects best first, and the ones that were skipped.
#[derive(Clone, Debug, PartialEq)]
pub struct DiagnosisReport {
    /// The output diagnosed.
    pub output: String,
    /// Validation error of the current model (RMSPE averaged over the runs), %.
    pub rmspe_current_pct: f64,
    /// Validation error of the current model refitted without a new block (the test's yardstick), %.
    pub rmspe_refit_pct: f64,
    /// Error of that refit on the identification data held out by the cross-validation, %, when
    /// the data have enough segments for one.
    pub held_out_refit_pct: Option<f64>,
    /// Segments the cross-validation holds out (0: none, the trials are judged on the validation
    /// runs alone).
    pub held_out_segments: usize,
    /// The effects tried, lowest validation error first.
    pub entries: Vec<Diagnosis>,
    /// The effects not tried, with the reason.
    pub skipped: Vec<SkippedEffect>,
    /// When a structural refinement is significant: what the linear block or the map needs, in
    /// words that follow the ranking ("structure is the missing piece: the linear block needs a pole
    /// pair near 2.31 rad/s (ζ 0.60)", or "below the physics ranked first, the structure may also
    /// improve: …" when a physical effect ranks above it).
    pub structure_note: Option<String>,
    /// When the two best significant trials cannot be told apart: both, with the numbers, which
    /// one was put first and why, and the experiment that would separate them.
    pub attribution_note: Option<String>,
}

impl DiagnosisReport {
    /// `structure_note` from the entries as they stand: the words follow the ranking, structure is
    /// "the missing piece" only when no physics ranks above it (the table and the loop take the top
    /// significant entry).
    pub(super) fn note_structure(&mut self) {
        let top_is_physics = self.top_is_physics();
        self.structure_note =
            self.entries.iter().find(|d| d.kind == DiagnosisKind::Structure && d.significant).map(|d| {
                if top_is_physics {
                    format!("below the physics ranked first, the structure may also improve: {}", d.evidence)
                } else {
                    format!("structure is the missing piece: {}", d.evidence)
                }
            });
    }

    /// Entry `index` no longer counts, for the reason `why` (the loop refused it: its fit needs a
    /// sample-alternating pole). When it was the first significant entry, the note that explained
    /// its place goes with it.
    pub(super) fn refuse(&mut self, index: usize, why: String) {
        let was_first = self.entries.iter().position(|d| d.significant) == Some(index);
        if let Some(entry) = self.entries.get_mut(index) {
            entry.significant = false;
            entry.why_not = Some(why);
        }
        if was_first {
            self.attribution_note = None;
        }
        self.note_structure();
    }
}

impl DiagnosisReport {
    /// Whether the top significant entry (the one the loop would take) is a physical effect.
    pub fn top_is_physics(&self) -> bool {
        self.entries.iter().find(|d| d.significant).is_some_and(|d| d.kind == DiagnosisKind::Physics)
    }

    /// What the trials were judged on besides the validation runs, in one sentence.
    pub fn held_out_words(&self) -> String {
        match self.held_out_refit_pct {
            Some(refit) => format!(
                "the trials were also judged on {} segment responses of the identification data, each held \
                 out by one of {FOLDS} cross-validation folds (the refitted current model's error there: \
                 {refit:.3} %)",
                self.held_out_segments
            ),
            None if self.held_out_segments > 0 => format!(
                "the current model could not be refitted on the cross-validation folds of its {} segment \
                 responses: the trials were judged on the validation runs alone",
                self.held_out_segments
            ),
            None => format!(
                "the identification data have fewer than {} segments, too few for a cross-validation: the \
                 trials were judged on the validation runs alone",
                FOLDS * MIN_HELD_OUT_SEGMENTS
            ),
        }
    }

    /// The best-ranked effect, if any was tried.
    pub fn best(&self) -> Option<&Diagnosis> {
        self.entries.first()
    }
}
