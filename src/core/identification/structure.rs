//! Which roots the reduced model gets: the automatic proposal an engineer would sign.
//!
//! **Candidates.** The cluster proposal (`core::identification::cluster_proposal`) finds every isolated, tight
//! gathering of segment roots, relaxing the aggregation condition step by step from all J segments
//! to a majority; each candidate records the m of J segments it holds.
//!
//! **Choice by simulation error on the identification data** (never the validation runs), by
//! forward selection with cross-validation across segments. The model starts with the pole
//! candidate that alone fits the identification range best (a linear block needs a pole). Then every
//! remaining candidate is tried beside the roots already kept, each trial polished inside its
//! cluster (`core::identification::reduce`); the few that fit all the data best are cross-validated: for each
//! segment, the model is fitted without that segment's step response and simulated through it. The
//! trial that lowers the held-out error most is kept when it passes the parsimony rule below; this
//! repeats until none passes. A zero is only tried while the model has more poles than zeros.
//!
//! **Parsimony rule.** A root enters the model only when it beats the simpler model by enough,
//! beyond noise: see `core::identification::parsimony`.
//!
//! **Roots go where the data put them.** When the polish of the kept roots stops on the rim of a
//! circle, the circle follows the root (`core::identification::follow`) and the proposal says so.
//!
//! **No dead ends.** When no candidate cluster gives a model (no pole gathers in a majority of the
//! segments), the reduced model is fitted directly: output-error Wiener fit of free roots, grown one
//! real pole or pole pair at a time from a grid of time constants and natural frequencies, under the
//! same parsimony rule, up to `MAX_DIRECT_POLES` poles (a low-order model, as the method intends;
//! see `core::identification::direct_fit`). The proposal says so in words.
use serde::{Deserialize, Serialize};

use crate::core::identification::cluster::{self, Cluster, RootKind};
use crate::core::identification::cluster_proposal::propose_clusters;
use crate::core::identification::dead_time::DeadTimeVerdict;
use crate::core::identification::direct_fit::{DirectFit, direct_fit};
use crate::core::identification::error::PipelineError;
use crate::core::identification::fits::SegmentFits;
use crate::core::identification::follow::{CircleFollow, follow_roots};
use crate::core::identification::reduce::IdentData;
use crate::core::identification::selection::ForwardSelection;
use crate::core::identification::settings::OutputSettings;
use crate::core::identification::verdict::CandidateVerdict;
use crate::core::identification::words::root_words;
use crate::core::run::Run;

/// The automatic proposal for one output.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Proposal {
    /// The clusters the model is built from (kept candidates), in the candidates' order.
    pub clusters: Vec<Cluster>,
    /// Every candidate with its verdict.
    pub verdicts: Vec<CandidateVerdict>,
    /// The input dead time candidate and its verdict.
    pub dead_time: DeadTimeVerdict,
    /// The circles that followed their roots out of the segment models' circles (`clusters` holds
    /// the grown circles).
    #[serde(default)]
    pub followed: Vec<CircleFollow>,
    /// Present when no cluster gave a model and the roots were fitted directly.
    pub direct: Option<DirectFit>,
}

impl Proposal {
    /// One sentence per candidate, and the direct fit's note.
    pub fn sentences(&self) -> Vec<String> {
        let mut out: Vec<String> = self
            .verdicts
            .iter()
            .map(|v| {
                format!(
                    "{} {} ({}/{} segments): {}",
                    if v.cluster.kind == RootKind::Pole { "pole" } else { "zero" },
                    root_words(v.cluster.centre, !v.cluster.is_real_axis(), v.natural_freq_rad_s, v.damping),
                    v.segments_found,
                    v.segments_total,
                    v.verdict
                )
            })
            .collect();
        out.push(self.dead_time.sentence());
        out.extend(self.followed.iter().map(ToString::to_string));
        out.extend(self.direct.as_ref().map(|d| d.note.clone()));
        out
    }
}

/// The automatic proposal: candidate clusters, the forward selection and, when no cluster gives a
/// model, the direct fit (see the module documentation).
pub fn propose(
    fits: &SegmentFits,
    ident: &Run,
    settings: &OutputSettings,
) -> Result<Proposal, PipelineError> {
    let candidates = propose_clusters(&fits.roots, &settings.cluster, fits.dt_secs)?;
    let evals = cluster::evaluate_clusters(&candidates, &fits.roots, &settings.cluster, fits.dt_secs)?;
    let data = IdentData::new(fits, ident, settings)?;
    let selection = ForwardSelection::run(&data, &evals);
    if selection.kept.is_empty() {
        let direct = direct_fit(&data, &fits.roots)?;
        return Ok(Proposal {
            clusters: Vec::new(),
            verdicts: selection.verdicts,
            dead_time: selection.dead_time,
            followed: Vec::new(),
            direct: Some(direct),
        });
    }
    let followed = follow_roots(&data.with_delay(selection.dead_time.in_model()), &evals, &selection.kept);
    let clusters = evals
        .iter()
        .enumerate()
        .filter(|(i, _)| selection.kept.contains(i))
        .map(|(i, e)| match followed.iter().find(|f| f.candidate == i) {
            Some(f) => Cluster { centre: f.to.centre, radius: f.to.radius, ..e.cluster.clone() },
            None => e.cluster.clone(),
        })
        .collect();
    Ok(Proposal {
        clusters,
        verdicts: selection.verdicts,
        dead_time: selection.dead_time,
        followed,
        direct: None,
    })
}
