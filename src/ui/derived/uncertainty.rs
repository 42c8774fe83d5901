//! What the committed model's parameter covariance gives the views: the covariance (as the batch
//! stores it, `workflow::uncertainty`), models drawn from it, the 95 % band of the noiseless output
//! on every scored run, the band of the linear block's Bode plot and each root's 95 % region.
//! Computed once per committed model, with the finished model (on the worker thread when there is
//! one); a drag preview has none.
use std::sync::Arc;

use num_complex::Complex64;

use crate::core::control::ParameterCovariance;
use crate::core::control::bands::{self, BodeBand, RootRegion};
use crate::core::effects::ExtendedModel;
use crate::core::identification::fits::SegmentFits;
use crate::core::identification::settings::OutputSettings;
use crate::core::numerics::tf::{BodePoint, DiscreteTf};
use crate::core::run::Run;
use crate::workflow::uncertainty::parameter_covariance;

/// Models drawn for the Bode band and the Control view's step-response band (see
/// `core::control::bands::DRAWS` for why this many).
const DRAWS: usize = bands::DRAWS;
/// Seed of the draws: the same model shows the same bands every time.
const SEED: u64 = 0x6A65_7469_6401;

/// The bands of one committed model.
#[derive(Clone, Debug)]
pub struct ModelUncertainty {
    pub covariance: ParameterCovariance,
    /// Models drawn from the covariance around the model.
    pub draws: Vec<ExtendedModel>,
    /// Per scored run, in the order of the live model's runs: the half-width of the 95 % band of
    /// the model's noiseless output (`Err`: why it could not be computed on that run).
    pub run_bands: Vec<Result<Vec<f64>, String>>,
    /// The band of the linear block's Bode plot at the cache's frequency grid.
    pub bode: BodeBand,
    /// The 95 % region of each root (poles, then zeros).
    pub roots: Vec<RootRegion>,
    /// The finished model's linear block, which the bands and regions are drawn around: the
    /// reduced model's block refitted with the effects, when there are any.
    pub block: FinishedBlock,
}

/// The linear block of the finished model.
#[derive(Clone, Debug)]
pub struct FinishedBlock {
    pub tf: DiscreteTf,
    /// Its Bode response at the cache's frequency grid.
    pub bode: Vec<BodePoint>,
    pub poles: Vec<Complex64>,
    pub zeros: Vec<Complex64>,
}

impl ModelUncertainty {
    /// The finished model's linear block when the effects' refit moved it away from `reduced`
    /// (the block the views draw as the reduced model); `None` when the two are the same block.
    pub fn refitted_block(&self, reduced: &DiscreteTf) -> Option<&FinishedBlock> {
        (self.block.tf != *reduced).then_some(&self.block)
    }
}

/// The bands of `model` (identified on `ident` with `fits` and `settings`) on the scored `runs`.
pub fn of(
    model: &ExtendedModel,
    fits: &SegmentFits,
    ident: &Run,
    settings: &OutputSettings,
    runs: &[&Run],
    omegas_rad_s: &[f64],
) -> Result<Arc<ModelUncertainty>, String> {
    let covariance = parameter_covariance(fits, model, ident, settings).map_err(|e| e.to_string())?;
    let draws = covariance.draw_models(model, DRAWS, SEED).map_err(|e| e.to_string())?;
    let run_bands = runs
        .iter()
        .map(|run| bands::output_half_widths(model, &covariance, run).map_err(|e| e.to_string()))
        .collect();
    let roots = bands::root_regions(model, &covariance).map_err(|e| e.to_string())?;
    let bode = bands::bode_band(&draws, omegas_rad_s);
    let tf = model.wiener.linear.tf.clone();
    let block = FinishedBlock {
        bode: tf.bode_response(omegas_rad_s),
        poles: tf.poles().unwrap_or_default(),
        zeros: tf.zeros().unwrap_or_default(),
        tf,
    };
    Ok(Arc::new(ModelUncertainty { covariance, draws, run_bands, bode, roots, block }))
}
