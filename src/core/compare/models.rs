//! Every model of one output that the comparison simulates: the gray-box model, its linear block,
//! the two baselines of the paper and the three simple references, all fitted on the same
//! identification range.
use crate::core::baselines::BaselineError;
use crate::core::baselines::hammerstein_wiener::{HwModel, HwOptions, HwOrders, fit_hammerstein_wiener};
use crate::core::baselines::nnarx::{NnarxModel, NnarxOptions, fit_nnarx};
use crate::core::baselines::references::References;
use crate::core::effects::ExtendedModel;
use crate::core::identification::fits::SegmentFits;
use crate::core::identification::initial_state::InitialState;
use crate::core::identification::pipeline::Identified;
use crate::core::identification::wiener::WienerModel;
use crate::core::run::Run;

use super::ModelKind;

/// Every model of one output that can be simulated from an input sequence.
pub struct OutputModels {
    /// The output modelled.
    pub output: String,
    /// Where every model's simulation of a scored run starts.
    pub initial_state: InitialState,
    pub wiener: WienerModel,
    /// The gray-box model with the applied effects, when there are any: it is what `gray_box` means
    /// on a run (effects may need the run's auxiliary channels); input-only studies (chirp frequency
    /// response, Monte Carlo) use the model without them.
    pub extended: Option<ExtendedModel>,
    pub hw: Option<HwModel>,
    pub nnarx: Option<NnarxModel>,
    pub references: References,
}

impl OutputModels {
    /// (model, simulation of `u` from the steady state of `u[0]`) for every model present.
    pub fn simulate_all(&self, u: &[f64]) -> Vec<(ModelKind, Vec<f64>)> {
        let mut out = vec![
            (ModelKind::GrayBox, self.wiener.simulate(u).1),
            (ModelKind::Linear, self.wiener.linear.simulate(u)),
        ];
        if let Some(hw) = &self.hw {
            out.push((ModelKind::HammersteinWiener, hw.simulate(u)));
        }
        if let Some(nn) = &self.nnarx {
            out.push((ModelKind::Nnarx, nn.simulate(u)));
        }
        out.extend(self.references_simulated(u, None));
        out
    }

    /// The references that were fitted, simulated on `u`; the ARX models start from `measured` when
    /// it is given (the estimated start), else from the steady state of `u[0]`.
    fn references_simulated(&self, u: &[f64], measured: Option<&[f64]>) -> Vec<(ModelKind, Vec<f64>)> {
        let refs = &self.references;
        let arx = |m: &crate::core::baselines::references::PolyArx| {
            measured.map_or_else(|| m.simulate(u), |y| m.simulate_from_measured(u, y))
        };
        let mut out = Vec::with_capacity(3);
        if let Some(m) = &refs.arx {
            out.push((ModelKind::Arx, arx(m)));
        }
        if let Some(m) = &refs.hammerstein_arx {
            out.push((ModelKind::HammersteinArx, arx(m)));
        }
        if let Some(m) = &refs.static_cubic {
            out.push((ModelKind::StaticCubic, m.simulate(u)));
        }
        out
    }

    /// The gray-box model as the runs are scored: with its effects, when it has any.
    pub fn gray_box_model(&self) -> ExtendedModel {
        self.extended.clone().unwrap_or_else(|| ExtendedModel::new(&self.output, self.wiener.clone()))
    }

    /// Every model on a scored run, each started as [`Self::initial_state`] says (from the state that
    /// best fits the first seconds of the measured output, when the run has it): the gray-box model
    /// with its effects (left out when it fails, e.g. for a missing channel), its linear block, and
    /// the baselines.
    pub fn simulate_run(&self, run: &Run) -> Vec<(ModelKind, Vec<f64>)> {
        let u = &run.input.values;
        let measured = run.output(&self.output).map(|c| c.values.as_slice());
        let estimated = measured.filter(|_| self.initial_state == InitialState::Estimated);
        let mut out = Vec::with_capacity(ModelKind::ALL.len());
        if let Ok(y) = self.gray_box_model().simulate_scored(run, self.initial_state) {
            out.push((ModelKind::GrayBox, y));
        }
        let linear = match measured {
            Some(y) => self.wiener.linear.simulate_scored(u, y, self.initial_state),
            None => self.wiener.linear.simulate(u),
        };
        out.push((ModelKind::Linear, linear));
        if let Some(hw) = &self.hw {
            out.push((
                ModelKind::HammersteinWiener,
                estimated.map_or_else(|| hw.simulate(u), |y| hw.simulate_estimated(u, y)),
            ));
        }
        if let Some(nn) = &self.nnarx {
            out.push((
                ModelKind::Nnarx,
                estimated.map_or_else(|| nn.simulate(u), |y| nn.simulate_from_measured(u, y)),
            ));
        }
        out.extend(self.references_simulated(u, estimated));
        out
    }

    /// One model's simulation.
    pub fn simulate(&self, model: ModelKind, u: &[f64]) -> Option<Vec<f64>> {
        match model {
            ModelKind::GrayBox => Some(self.wiener.simulate(u).1),
            ModelKind::Linear => Some(self.wiener.linear.simulate(u)),
            ModelKind::HammersteinWiener => self.hw.as_ref().map(|m| m.simulate(u)),
            ModelKind::Nnarx => self.nnarx.as_ref().map(|m| m.simulate(u)),
            ModelKind::Arx => self.references.arx.as_ref().map(|m| m.simulate(u)),
            ModelKind::HammersteinArx => self.references.hammerstein_arx.as_ref().map(|m| m.simulate(u)),
            ModelKind::StaticCubic => self.references.static_cubic.as_ref().map(|m| m.simulate(u)),
        }
    }
}

/// Fit both baselines on the identification range the gray-box model was fitted on, reporting the
/// fraction done to `progress`; a baseline that fails is a note, not a failed batch (nor does a
/// `progress` that answers `false` fail it: the models are then the references alone).
pub fn fit_baselines(
    identified: &Identified,
    ident: &Run,
    output: &str,
    notes: &mut Vec<String>,
    progress: &mut dyn FnMut(f64) -> bool,
) -> OutputModels {
    let wiener = &identified.model.wiener;
    fit_baselines_with_progress(&identified.fits, wiener, ident, output, notes, progress).unwrap_or_else(
        |Cancelled| OutputModels {
            output: output.to_owned(),
            initial_state: InitialState::default(),
            wiener: wiener.clone(),
            extended: None,
            hw: None,
            nnarx: None,
            references: References::default(),
        },
    )
}

/// The user stopped a long computation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cancelled;

/// [`fit_baselines`] for the gray-box model `wiener` fitted on `fits`, reporting progress (the
/// Hammerstein–Wiener fit is the first quarter, the NNARX training the rest); `progress` answering
/// `false` stops it with [`Cancelled`].
pub fn fit_baselines_with_progress(
    fits: &SegmentFits,
    wiener: &WienerModel,
    ident: &Run,
    output: &str,
    notes: &mut Vec<String>,
    progress: &mut dyn FnMut(f64) -> bool,
) -> Result<OutputModels, Cancelled> {
    let start = fits.segments.first().map_or(0, |s| s.start);
    let end = fits.segments.last().map_or(ident.len(), |s| s.end);
    let u = ident.input.values.get(start..end).unwrap_or(&[]);
    let y = ident.output(output).and_then(|c| c.values.get(start..end)).unwrap_or(&[]);
    let tf = &wiener.linear.tf;
    let orders = HwOrders {
        input_poly: 2,
        n_poles: tf.den_zinv.len().saturating_sub(1).max(1),
        n_zeros: tf.zeros().map_or(0, |z| z.len()),
        output_poly: 2,
    };
    let hw_options = HwOptions::default();
    let hw = match fit_hammerstein_wiener(
        u,
        y,
        ident.dt_secs,
        orders,
        &hw_options,
        &mut scaled(progress, 0.0, 0.25),
    ) {
        Ok(model) => Some(model),
        Err(BaselineError::Cancelled) => return Err(Cancelled),
        Err(e) => {
            notes.push(format!("Hammerstein–Wiener baseline for '{output}': {e}"));
            None
        }
    };
    let nnarx = match fit_nnarx(u, y, &NnarxOptions::default(), &mut scaled(progress, 0.25, 1.0)) {
        Ok(model) => Some(model),
        Err(BaselineError::Cancelled) => return Err(Cancelled),
        Err(e) => {
            notes.push(format!("NNARX baseline for '{output}': {e}"));
            None
        }
    };
    let references = References::fit(u, y, output, notes);
    Ok(OutputModels {
        output: output.to_owned(),
        initial_state: InitialState::default(),
        wiener: wiener.clone(),
        extended: None,
        hw,
        nnarx,
        references,
    })
}

/// `progress` for a part of the work that spans `lo..=hi` of the whole.
pub fn scaled(progress: &mut dyn FnMut(f64) -> bool, lo: f64, hi: f64) -> impl FnMut(f64) -> bool + '_ {
    // Exactly `lo` at 0 and `hi` at 1, so consecutive parts never step back by a rounding error.
    move |fraction| {
        let f = fraction.clamp(0.0, 1.0);
        progress(lo * (1.0 - f) + hi * f)
    }
}
