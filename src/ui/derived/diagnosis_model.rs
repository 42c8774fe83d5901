//! What a diagnosis of one output's current model needs, owned so that it can run on a worker
//! thread (the Diagnosis view's job).
use std::sync::Arc;

use crate::core::diagnose;
use crate::core::effects::ExtendedModel;
use crate::core::identification::fits::SegmentFits;
use crate::core::identification::settings::OutputSettings;
use crate::core::run::Run;
use crate::ui::derived::live_model::ModelKey;

/// What a diagnosis of one output's current model needs (owned, for a worker thread).
#[derive(Clone)]
pub struct DiagnosisInput {
    /// The model the diagnosis is for.
    pub model: ModelKey,
    pub output: String,
    /// The model as the views show it (with its effects).
    pub current: ExtendedModel,
    pub ident: Arc<Run>,
    pub fits: Arc<SegmentFits>,
    pub validation: Vec<Arc<Run>>,
    pub settings: OutputSettings,
}

impl DiagnosisInput {
    /// Rank the catalog's effects on this model, as the batch does (see [`diagnose::diagnose_admissible`]).
    pub fn run(
        &self,
        progress: &mut dyn FnMut(f64) -> bool,
    ) -> Result<diagnose::DiagnosisReport, diagnose::DiagnoseError> {
        let validation: Vec<&Run> = self.validation.iter().map(AsRef::as_ref).collect();
        diagnose::diagnose_admissible(
            &self.current,
            &self.ident,
            &self.fits,
            &validation,
            &self.settings,
            progress,
        )
    }
}
