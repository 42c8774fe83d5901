//! The MATLAB/Octave rendering of a [`Plan`].
use super::ExportError;
use super::plan::Plan;

pub(super) fn render(plan: &Plan, name: &str) -> Result<String, ExportError> {
    let _ = plan;
    Err(ExportError::BadMatlabName { name: name.to_owned() })
}
