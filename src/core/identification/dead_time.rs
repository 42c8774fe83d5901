//! The input dead time as a candidate of the proposal (`core::identification::structure`): its
//! verdict, the screening of whole delays beside the kept roots, and how late a model itself starts.
use std::fmt;

use serde::{Deserialize, Serialize};

use crate::core::identification::arx;
use crate::core::identification::cluster::RootKind;
use crate::core::identification::cross_validation::{REFINED_GUESSES, fitted};
use crate::core::identification::fits::MAX_DEAD_TIME_SECS;
use crate::core::identification::parsimony::Gain;
use crate::core::identification::reduce::{Assembled, IdentData, Polished, RootGroup, assemble_groups};
use crate::core::identification::words::fmt_error;
use crate::core::numerics::stats::mean;

/// What the forward selection decided about the input dead time.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum DeadTimeDecision {
    /// The selection never came to it.
    NotTried,
    /// The settings give the dead time; the selection keeps it without searching (shown as "not
    /// tried").
    Given,
    /// The kept roots already explain the responses' late start.
    NotNeeded {
        /// The segment ARX models' input delay, samples.
        arx_nk: usize,
    },
    /// The model with it cannot be fitted on held-out segments.
    NoHeldOutModel,
    /// Cross-validated beside the kept roots, and it fails the parsimony rule.
    Dropped { gain: Gain },
    /// It passes the parsimony rule, but a root of the segment models does as well and roots are
    /// preferred.
    RootPreferred { gain: Gain },
    /// Kept by the forward selection.
    Kept { gain: Gain },
    /// Kept beside the roots for the late start they leave: the model without it starts
    /// [`LATE_START_SAMPLES`] or more before the segment models say the responses start, its roots
    /// have stretched towards a slower rise to cover the gap, and the model without it does not
    /// predict the held-out segments better.
    KeptForLateStart {
        /// How late the model without it starts (the segment models' estimator on its own responses), samples.
        model_nk: usize,
        /// Held-out errors without and with it, output units.
        held_out_without: f64,
        held_out_with: f64,
    },
    /// Kept in place of a root that only stood in for it.
    KeptForRoot {
        /// Held-out errors with that root and with the dead time instead, output units.
        held_out_without: f64,
        held_out_with: f64,
    },
}

impl DeadTimeDecision {
    /// Whether the model carries the dead time.
    pub fn kept(&self) -> bool {
        matches!(
            self,
            Self::Given | Self::Kept { .. } | Self::KeptForRoot { .. } | Self::KeptForLateStart { .. }
        )
    }
}

/// The sentence the report and the app show.
impl fmt::Display for DeadTimeDecision {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NotTried | Self::Given => write!(f, "not tried"),
            Self::NotNeeded { arx_nk } => write!(
                f,
                "not needed: the kept roots already explain the responses' late start (their own \
                 simulation fits best {arx_nk} samples late)"
            ),
            Self::NoHeldOutModel => write!(f, "gives no model on held-out segments"),
            Self::Dropped { gain } => write!(f, "dropped: beside the kept roots, {gain}"),
            Self::RootPreferred { gain } => {
                write!(
                    f,
                    "dropped: {gain}, but a root of the segment models does as well (roots are preferred)"
                )
            }
            Self::Kept { gain } => write!(f, "kept: {gain}"),
            Self::KeptForLateStart { model_nk, held_out_without, held_out_with } => write!(
                f,
                "kept for the late start: without it the model's own responses start {model_nk} samples \
                 late, earlier than the segments', and its pole pairs stretch to cover the gap; the held-out \
                 segments cannot tell the two apart or prefer the dead time: error from {} to {} with it",
                fmt_error(*held_out_without),
                fmt_error(*held_out_with)
            ),
            Self::KeptForRoot { held_out_without, held_out_with } => write!(
                f,
                "kept in place of a root that only stood in for it: held-out error from {} to {} with \
                 fewer parameters",
                fmt_error(*held_out_without),
                fmt_error(*held_out_with)
            ),
        }
    }
}

/// The least late start, samples, that the roots must leave unexplained before a dead time is kept for
/// it without lowering the held-out error ([`DeadTimeDecision::KeptForLateStart`]). The data's delay
/// and the model's are read by the same estimator ([`apparent_nk`]), which picks a whole number of
/// samples: a true start between two samples reads as either neighbour, so each reading is good to
/// one sample and their difference to two. Three or more samples is a start the model reaches by a
/// slower rise instead of a wait.
pub const LATE_START_SAMPLES: usize = 3;

/// The input dead time the reduced model may carry (a fuel line and valve delay), as a candidate of
/// the proposal like a root: what the segment ARX models say, and what the cross-validation said.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DeadTimeVerdict {
    /// Dead time tried (or kept), samples.
    pub samples: usize,
    pub dt_secs: f64,
    /// The segment ARX models' input delay, samples (1: none beyond the sampling).
    pub arx_nk: usize,
    pub decision: DeadTimeDecision,
}

impl DeadTimeVerdict {
    /// The dead time before the selection: the one the settings give (kept), or none, not tried.
    pub(super) fn before_selection(data: &IdentData) -> Self {
        Self {
            samples: data.delay,
            dt_secs: data.fits.dt_secs,
            arx_nk: data.fits.nk(),
            decision: if data.delay > 0 { DeadTimeDecision::Given } else { DeadTimeDecision::NotTried },
        }
    }

    /// Whether the model carries the dead time.
    pub fn kept(&self) -> bool {
        self.decision.kept()
    }

    /// The dead time the model carries, samples (0 when none was kept).
    pub fn in_model(&self) -> usize {
        if self.kept() { self.samples } else { 0 }
    }

    /// The sentence the report and the app show.
    pub fn sentence(&self) -> String {
        format!(
            "input dead time {:.2} s ({} samples; the segment ARX models fit best with the input {} samples late): {}",
            self.samples as f64 * self.dt_secs,
            self.samples,
            self.arx_nk,
            self.decision
        )
    }
}

/// The dead time candidate beside `groups`, around `excess` samples (the late start the roots do not
/// explain): the whole delays next to it screened on the identification error with the roots as they
/// are, the best few polished with the roots.
pub(super) fn with_dead_time(
    data: &IdentData,
    groups: &[RootGroup],
    excess: usize,
) -> Option<(Polished, usize)> {
    dead_time_guesses(data, groups, excess.saturating_sub(1)..=excess + 1, REFINED_GUESSES)
        .into_iter()
        .min_by(|a, b| a.0.assembled.rms().total_cmp(&b.0.assembled.rms()))
}

/// The whole delays in `delays` (at least one sample, at most [`MAX_DEAD_TIME_SECS`]), screened on
/// the identification error with `groups` as they are; the best `guesses` polished with the roots.
pub(super) fn dead_time_guesses(
    data: &IdentData,
    groups: &[RootGroup],
    delays: std::ops::RangeInclusive<usize>,
    guesses: usize,
) -> Vec<(Polished, usize)> {
    let max = ((MAX_DEAD_TIME_SECS / data.fits.dt_secs).round() as usize).max(1);
    let mut screened: Vec<(f64, usize)> = ((*delays.start()).max(1)..=(*delays.end()).min(max))
        .filter_map(|d| {
            assemble_groups(&data.with_delay(d), groups, data.settings.static_order)
                .ok()
                .map(|a| (a.rms(), d))
        })
        .collect();
    screened.sort_by(|a, b| a.0.total_cmp(&b.0));
    screened
        .into_iter()
        .take(guesses)
        .filter_map(|(_, d)| fitted(&data.with_delay(d), groups).map(|p| (p, d)))
        .collect()
}

/// Low-frequency group delay of a root group, s: τ for a real pole, 2ζ/ωn for a pair (the slope of
/// its phase at ω → 0); zero for a zero or a root that is not a stable pole.
pub(super) fn group_delay_secs(g: &RootGroup, dt_secs: f64) -> f64 {
    if g.kind != RootKind::Pole {
        return 0.0;
    }
    let (omega, zeta, tau) = g.s_plane(dt_secs);
    match (g.pair, tau) {
        (false, Some(tau)) => tau,
        (true, _) if omega > 0.0 => 2.0 * zeta / omega,
        _ => 0.0,
    }
}

/// The input delay at which short-B ARX models fit a model's own simulated step responses best (the
/// same estimator that timed the data, [`arx::estimate_dead_time`]): how late the model itself starts.
pub(super) fn apparent_nk(data: &IdentData, assembled: &Assembled) -> usize {
    let simulated: Vec<f64> = data.y.iter().zip(&assembled.residual).map(|(y, r)| y + r).collect();
    let deviations: Vec<(Vec<f64>, Vec<f64>)> = data
        .fits
        .segments
        .iter()
        .filter_map(|seg| {
            let (a, s, b) = (
                seg.start.checked_sub(data.start)?,
                seg.step_at.checked_sub(data.start)?,
                seg.end.checked_sub(data.start)?,
            );
            let (u, y) = (data.u.get(a..b)?, simulated.get(a..b)?);
            let (u0, y0) = (mean(data.u.get(a..s)?), mean(simulated.get(a..s)?));
            Some((u.iter().map(|x| x - u0).collect(), y.iter().map(|x| x - y0).collect()))
        })
        .collect();
    let max = ((MAX_DEAD_TIME_SECS / data.fits.dt_secs).round() as usize).clamp(1, 50);
    arx::estimate_dead_time(&deviations, data.settings.orders.na, max).map_or(1, |d| d.nk)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use num_complex::Complex64;

    use super::*;
    use crate::core::identification::test_system::TestSystem;

    /// The model of the system's pole as the segment models show it, without dead time, and the late
    /// start it leaves unexplained: the segment models' delay less the model's own.
    fn late_start(sys: &TestSystem) -> (IdentData<'_>, RootGroup, Polished, usize) {
        let eval = sys.candidate(RootKind::Pole, Complex64::new(0.9, 0.0), 0.03);
        assert!(eval.valid, "{eval:?}");
        let data = IdentData::new(&sys.fits, &sys.run, &sys.settings).unwrap();
        let group = RootGroup::of_cluster(0, &eval);
        let without = fitted(&data, std::slice::from_ref(&group)).unwrap();
        let excess = sys.fits.nk().saturating_sub(apparent_nk(&data, &without.assembled));
        (data, group, without, excess)
    }

    #[test]
    fn the_dead_time_step_finds_a_known_input_delay() {
        let sys = TestSystem::new(&[0.9], 5, 0.02, 9);
        let (data, group, without, excess) = late_start(&sys);
        assert!(excess >= 1, "segment models {} samples late", sys.fits.nk());
        let (with, samples) = with_dead_time(&data, std::slice::from_ref(&group), excess).unwrap();
        assert_eq!(samples, 5);
        assert!(with.assembled.rms() < 0.5 * without.assembled.rms());
        // How late the model itself starts: its own lag (one sample for a first-order block) and the
        // dead time on top.
        let own = apparent_nk(&data, &without.assembled);
        assert_eq!(apparent_nk(&data.with_delay(samples), &with.assembled), own + samples);
    }

    #[test]
    fn no_dead_time_is_found_on_a_system_without_one() {
        let sys = TestSystem::new(&[0.9], 0, 0.02, 9);
        let (_, _, _, excess) = late_start(&sys);
        assert_eq!(excess, 0, "segment models {} samples late", sys.fits.nk());
    }

    #[test]
    fn a_pole_pair_delays_by_twice_its_damping_over_its_frequency() {
        let dt = 0.1;
        let s = Complex64::new(-0.6 * 2.0, 2.0 * (1.0 - 0.36_f64).sqrt());
        let pair = RootGroup::free_pair(RootKind::Pole, (s * dt).exp());
        assert!((group_delay_secs(&pair, dt) - 2.0 * 0.6 / 2.0).abs() < 1e-9);
        let real = RootGroup::free_real(RootKind::Pole, (-dt / 1.5_f64).exp());
        assert!((group_delay_secs(&real, dt) - 1.5).abs() < 1e-9);
        assert!(group_delay_secs(&RootGroup::free_real(RootKind::Zero, 0.5), dt).abs() < 1e-15);
    }
}
