//! One output's model, built the same way for the batch and the app: the segment fits, the given
//! clusters or the automatic proposal, the polished Wiener model ([`identify`], or its steps
//! [`fit_segments`], [`propose`] and [`ModelSource::build`] for the app, which caches each), then
//! the effects added by hand and the missing-physics loop ([`add_effects`]).
use crate::core::diagnose::{self, AutoRound, DiagnoseError, EffectSequence, HistoryStep, SharedBlock};
use crate::core::effects::{EffectId, ExtendedModel};
use crate::core::identification::cluster::Cluster;
use crate::core::identification::error::PipelineError;
use crate::core::identification::fits::SegmentFits;
use crate::core::identification::pipeline::{self, GrayBoxModel, Identified};
use crate::core::identification::segment::Segment;
use crate::core::identification::settings::OutputSettings;
use crate::core::identification::structure::Proposal;
use crate::core::run::{Quantity, Run};
use crate::io::project::Project;

pub use crate::core::identification::pipeline::ModelSource;

use super::runs;

/// The effects of one output's model: added by hand, in order, then the missing-physics loop.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct EffectPlan {
    /// Catalog effects added in this order, each refitted on the identification data.
    pub by_hand: Vec<EffectId>,
    /// Rounds of the missing-physics loop after them (0: none).
    pub auto_rounds: usize,
}

impl EffectPlan {
    /// True when the model gets no effect at all.
    pub fn is_empty(&self) -> bool {
        self.by_hand.is_empty() && self.auto_rounds == 0
    }

    /// "thermal_soak, ambient_correction and the missing-physics loop (3 rounds)".
    pub fn words(&self) -> String {
        let mut parts: Vec<String> = self.by_hand.iter().map(|id| id.name().to_owned()).collect();
        if self.auto_rounds > 0 {
            parts.push(format!("the missing-physics loop ({} rounds)", self.auto_rounds));
        }
        match parts.as_slice() {
            [] => String::new(),
            [one] => one.clone(),
            [rest @ .., last] => format!("{} and {last}", rest.join(", ")),
        }
    }
}

/// What one output's model is built from: its settings, segments, clusters and effects.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputPlan {
    pub output: String,
    pub settings: OutputSettings,
    /// Segments given by the user; `None`: detected on the input or the `steps_from` channel.
    pub segments: Option<Vec<Segment>>,
    /// Channel the steps are detected on instead of the input.
    pub steps_from: Option<String>,
    /// Clusters given by the user; `None`: the automatic proposal.
    pub clusters: Option<Vec<Cluster>>,
    pub effects: EffectPlan,
}

impl OutputPlan {
    /// The plan a project gives `output` (its clusters taken from `clusters_from` already, see
    /// [`super::model_file::take_saved_clusters`]).
    pub fn of_project(project: &Project, output: &str) -> Self {
        Self {
            output: output.to_owned(),
            settings: project.settings_for(output),
            segments: project.segments.get(output).cloned(),
            steps_from: project.steps_from.clone(),
            clusters: project.clusters.get(output).cloned(),
            effects: EffectPlan { by_hand: project.add_effects.clone(), auto_rounds: project.auto_effects },
        }
    }

    /// The plan with its steps detected where [`runs::steps_from`] says (a set-point found in the
    /// log when the project names none).
    pub fn with_steps_from(mut self, steps: &runs::StepsFrom) -> Self {
        self.steps_from = steps.channel().map(str::to_owned);
        self
    }
}

/// The segment fits of `output` (the input dead time estimated first when the settings ask).
pub fn fit_segments(
    ident: &Run,
    output: &str,
    segments: &[Segment],
    settings: &OutputSettings,
) -> Result<SegmentFits, PipelineError> {
    crate::core::identification::fits::fit_segments_for(ident, output, segments, settings)
}

/// The automatic proposal for these fits: which candidate clusters the model keeps, and why.
pub fn propose(
    fits: &SegmentFits,
    ident: &Run,
    settings: &OutputSettings,
) -> Result<Proposal, PipelineError> {
    pipeline::propose(fits, ident, settings)
}

/// Segments → fits → the given clusters or the automatic proposal → the polished model, for the
/// identification run `ident` (several runs joined at `junctions`).
pub fn identify(ident: &Run, junctions: &[usize], plan: &OutputPlan) -> Result<Identified, PipelineError> {
    let segments = runs::segments(ident, junctions, plan.segments.as_deref(), plan.steps_from.as_deref())?;
    pipeline::identify_output(ident, &plan.output, &plan.settings, &segments, plan.clusters.as_deref())
}

/// Fewest step segments that make a dependable model. The proposal keeps a candidate only when it
/// predicts most of the held-out segments better (leave one segment out): with three segments a
/// useless candidate still wins all three by chance one time in eight, and the diagnosis's
/// cross-validation needs six (two per fold). Below four the model is built, and the notes say so.
pub const FEW_SEGMENTS: usize = 4;

/// Why a model identified from `fits` is weak, when it has fewer than [`FEW_SEGMENTS`] segments.
pub fn few_segments_note(fits: &SegmentFits) -> Option<String> {
    let n = fits.segments.len();
    (n < FEW_SEGMENTS).then(|| {
        format!(
            "'{}' was identified from {n} step segments only: so few make a weak model (each candidate root is \
             judged on {n} held-out steps); record at least {FEW_SEGMENTS} steps across the operating range, each \
             held until the engine settles",
            fits.output
        )
    })
}

/// The effects of a model as [`add_effects`] leaves them.
#[derive(Clone, Debug)]
pub struct Effects {
    /// The model after the last step, its validation error after every step, and the effect that
    /// could not be added (the loop is not run then).
    pub sequence: EffectSequence,
    /// What each round of the missing-physics loop added.
    pub rounds: Vec<AutoRound>,
    /// Why the loop stopped before its rounds were done, when it failed (or was cancelled).
    pub loop_failed: Option<DiagnoseError>,
    /// The spool blocks the shaft speed's model offered this one, and what came of each (see
    /// [`share_spool`]).
    pub shared: Vec<SharedBlock>,
    /// Why no spool block could be offered, when the offer failed.
    pub sharing_failed: Option<String>,
}

/// Why a model's effects could not all be added.
#[derive(Debug, thiserror::Error)]
pub enum EffectsError {
    #[error("adding the effect '{id}' to '{output}': {source}")]
    Add {
        id: EffectId,
        output: String,
        #[source]
        source: Box<DiagnoseError>,
    },
    #[error("the missing-physics loop on '{output}': {source}")]
    Loop {
        output: String,
        #[source]
        source: Box<DiagnoseError>,
    },
}

impl Effects {
    /// The model with every effect that could be added.
    pub fn model(&self) -> &ExtendedModel {
        &self.sequence.model
    }

    /// `Err` when an effect of the plan could not be added or the loop failed: the model is then
    /// not the one the plan asks for.
    pub fn check(&self, output: &str) -> Result<(), EffectsError> {
        if let Some((id, source)) = &self.sequence.failed {
            let (id, output, source) = (*id, output.to_owned(), Box::new(source.clone()));
            return Err(EffectsError::Add { id, output, source });
        }
        match &self.loop_failed {
            Some(source) => {
                Err(EffectsError::Loop { output: output.to_owned(), source: Box::new(source.clone()) })
            }
            None => Ok(()),
        }
    }

    /// What the loop did and which steps have no validation error, in words (the batch's notes,
    /// the app's Diagnosis view).
    pub fn notes(&self, output: &str, plan: &EffectPlan) -> Vec<String> {
        let mut notes = Vec::new();
        let loop_ran = plan.auto_rounds > 0 && self.sequence.failed.is_none() && self.loop_failed.is_none();
        notes.extend(self.sequence.admissibility.iter().map(|r| format!("'{output}': {r}")));
        if loop_ran && self.rounds.len() < plan.auto_rounds {
            notes.push(format!(
                "'{output}': the missing-physics loop stopped after {} of {} rounds: nothing further is significant",
                self.rounds.len(),
                plan.auto_rounds
            ));
        }
        for round in &self.rounds {
            notes.push(format!(
                "'{output}': the loop added {} ({}): {:.3} % → {:.3} %; {}; {}",
                round.added,
                round.kind,
                round.rmspe_before_pct,
                round.rmspe_after_pct,
                round.evidence,
                round.significance
            ));
            notes.extend(round.attribution.iter().map(|a| format!("'{output}': round {}: {a}", round.added)));
            notes.extend(
                round.admissibility.iter().map(|a| format!("'{output}': round {}: {a}", round.added)),
            );
        }
        notes.extend(self.sequence.history_gaps.iter().map(|gap| format!("'{output}': {gap}")));
        notes.extend(self.shared.iter().map(|b| format!("'{output}': {}", b.words())));
        notes.extend(
            self.sharing_failed.iter().map(|e| format!("'{output}': the spool's blocks not shared: {e}")),
        );
        notes
    }
}

/// The output that measures the spool directly, whose model's spool blocks the others share: the
/// shaft speed among `outputs`, when there is exactly one. With two (a gas generator and a free
/// power turbine, N1 and N2) the engine has two spools, and which one another output follows is not
/// known: nothing is shared.
pub fn spool_output(outputs: &[String]) -> Option<&str> {
    let mut speeds =
        outputs.iter().map(String::as_str).filter(|o| Quantity::of(o) == Some(Quantity::ShaftSpeed));
    match (speeds.next(), speeds.next()) {
        (Some(speed), None) => Some(speed),
        _ => None,
    }
}

/// What of the shaft speed's finished `model` the other outputs can share: all of it, since besides
/// its spool blocks ([`diagnose::SHARED_SPOOL_BLOCKS`]) another output may be read off the whole
/// model ([`share_spool`]). `None` for a model read off another (nothing of its own to share). A
/// cache keyed on it rebuilds another output when the speed's model changes.
pub fn spool_part(model: &ExtendedModel) -> Option<ExtendedModel> {
    model.read_off().is_none().then(|| model.clone())
}

/// `effects` (of an output other than the shaft speed) with the spool blocks of `spool`, the
/// shaft speed's finished model, shared where this output's validation runs do not refuse them
/// ([`diagnose::share_spool_dynamics`]): the model, one history step per block kept, and what was
/// offered (the notes say it). The loop's last diagnosis no longer describes the model when a block
/// is kept, and is dropped. Nothing happens to a speed model or to effects that failed.
pub fn share_spool(
    effects: &mut Effects,
    spool: &ExtendedModel,
    settings: &OutputSettings,
    ident: &Run,
    validation: &[&Run],
) {
    let model = effects.model();
    if model.output == spool.output || effects.check(&model.output).is_err() {
        return;
    }
    match diagnose::share_spool_dynamics(model, spool, ident, validation, settings.initial_state) {
        Ok((shared_model, offered)) => {
            // One step per set taken: a set's blocks name each other in `with`.
            let taken: Vec<&SharedBlock> = offered.iter().filter(|b| b.taken).collect();
            for (i, block) in taken.iter().enumerate() {
                if taken[..i].iter().any(|earlier| earlier.with.contains(&block.id)) {
                    continue;
                }
                let names: Vec<&str> =
                    std::iter::once(block.id.name()).chain(block.with.iter().map(|id| id.name())).collect();
                effects.sequence.history.push(HistoryStep {
                    step: format!("+{} (from {})", names.join(", "), block.from),
                    rmspe_pct: block.rmspe_after_pct,
                });
            }
            if offered.iter().any(|b| b.taken) {
                effects.sequence.model = shared_model;
                effects.sequence.final_diagnosis = None;
            }
            effects.shared = offered;
        }
        Err(err) => effects.sharing_failed = Some(err.to_string()),
    }
}

/// [`add_effects`] for an output of a project whose runs are loaded: its identified model and
/// fits, the plan's effects, chosen on the output's validation runs (the batch and a fleet's
/// reference project build a model alike).
pub fn add_project_effects(
    plan: &OutputPlan,
    runs: &runs::Runs,
    identified: &Identified,
    progress: &mut dyn FnMut(f64) -> bool,
) -> Effects {
    let validation = runs.validation_of(&plan.output);
    let (model, fits) = (&identified.model, &identified.fits);
    add_effects(model, &plan.effects, &runs.ident, fits, &plan.settings, &validation, progress)
}

/// The gray-box `model` with the effects of `plan`: each effect added by hand refitted on the
/// identification data (`ident`, `fits`) in turn, then the missing-physics loop, every choice made
/// on `validation`; the validation error after each step. `progress` gets the fraction of the
/// loop done; when it returns false the loop stops (cancelled).
pub fn add_effects(
    model: &GrayBoxModel,
    plan: &EffectPlan,
    ident: &Run,
    fits: &SegmentFits,
    settings: &OutputSettings,
    validation: &[&Run],
    progress: &mut dyn FnMut(f64) -> bool,
) -> Effects {
    let base = ExtendedModel::from_gray_box(model);
    let mut sequence = diagnose::apply_in_order(&base, &plan.by_hand, ident, fits, settings, validation);
    let (mut rounds, mut loop_failed) = (Vec::new(), None);
    if plan.auto_rounds > 0 && sequence.failed.is_none() {
        match diagnose::auto_effects(
            &mut sequence,
            plan.auto_rounds,
            ident,
            fits,
            settings,
            validation,
            progress,
        ) {
            Ok(taken) => rounds = taken,
            Err(err) => loop_failed = Some(err),
        }
    }
    Effects { sequence, rounds, loop_failed, shared: Vec::new(), sharing_failed: None }
}

#[cfg(test)]
mod tests {
    use super::spool_output;

    #[test]
    fn the_spool_is_the_one_shaft_speed_and_two_speeds_share_nothing() {
        let names = |n: &[&str]| n.iter().map(|s| (*s).to_owned()).collect::<Vec<_>>();
        assert_eq!(spool_output(&names(&["thrust_n", "shaft_speed_rpm"])), Some("shaft_speed_rpm"));
        assert_eq!(spool_output(&names(&["N1_krpm", "N2_krpm", "power_kW"])), None);
        assert_eq!(spool_output(&names(&["thrust_n", "egt_c"])), None);
    }
}
