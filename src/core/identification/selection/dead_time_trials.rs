//! The input dead time as a trial of the forward selection (`super`): beside the candidates of a
//! round, in place of a root that only stood in for it, for a late start stretched pole pairs
//! imitate, and the roots that stood in for it taken out again.
use crate::core::identification::cross_validation::{cross_validate, fitted};
use crate::core::identification::dead_time::{
    DeadTimeDecision, LATE_START_SAMPLES, apparent_nk, dead_time_guesses, group_delay_secs, with_dead_time,
};
use crate::core::identification::parsimony::{Gain, MIN_RELATIVE_REDUCTION, model_error_reduction, pooled};
use crate::core::identification::reduce::{IdentData, Polished, RootGroup};
use crate::core::identification::verdict::Verdict;

use super::{Best, CROSS_VALIDATED_TRIALS, Current, ForwardSelection, Trial};

/// Dead times for a late start the roots leave that are polished and cross-validated, the best few
/// by their fit on all the data (as many as the trials of a round).
const LATE_START_GUESSES: usize = CROSS_VALIDATED_TRIALS;

/// A root taken out for a dead time: the model with the dead time instead, and the root's own lag.
struct Swap {
    model: Polished,
    delay: usize,
    held_out: Vec<f64>,
    /// Low-frequency group delay of the root taken out, s.
    lag_secs: f64,
}

impl ForwardSelection<'_, '_> {
    /// The dead time competes with the roots for the part of the late start the kept roots do not
    /// explain; roots are preferred (they are the segment models' direct evidence), so the dead time
    /// is kept over the best root only when it also removes a tenth of the model error that root
    /// leaves. The trial to keep: the dead time when it passes so, else `best`.
    pub(super) fn try_dead_time(
        &mut self,
        current: &Current,
        at: &IdentData,
        best: Option<Best>,
    ) -> Option<Best> {
        let arx_nk = self.data.fits.nk();
        let excess = arx_nk.saturating_sub(apparent_nk(at, &current.model.assembled));
        if excess < 1 && self.dead_time.decision == DeadTimeDecision::NotTried {
            self.dead_time.decision = DeadTimeDecision::NotNeeded { arx_nk };
        }
        let tried = (excess >= 1).then(|| with_dead_time(self.data, &current.model.groups, excess)).flatten();
        let (Some((trial, delay)), Some(cur)) = (tried, current.held_out.as_deref()) else { return best };
        self.dead_time.samples = delay;
        let order = trial.assembled.wiener.map.order();
        let Some(cv) = cross_validate(&self.data.with_delay(delay), &trial.groups, order) else {
            self.dead_time.decision = DeadTimeDecision::NoHeldOutModel;
            return best;
        };
        let gain = Gain::of(cur, &cv, self.noise);
        let beats_root = best.as_ref().is_none_or(|b| {
            model_error_reduction(pooled(&b.held_out), pooled(&cv), self.noise) >= MIN_RELATIVE_REDUCTION
        });
        self.dead_time.decision = if gain.passes() && !beats_root {
            DeadTimeDecision::RootPreferred { gain }
        } else {
            DeadTimeDecision::Dropped { gain }
        };
        if gain.passes() && beats_root {
            return Some(Best { trial: Trial::DeadTime, model: trial, delay, held_out: cv, gain });
        }
        best
    }

    /// Parsimony across the two explanations of a late start: a root kept after the first pole may
    /// only stand in for a dead time. If taking it out for the dead time the late start then leaves
    /// unexplained predicts the held-out segments as well, the dead time (one parameter) replaces it
    /// (two parameters for a pair). The last kept root that can be traded is.
    pub(super) fn trade_root_for_dead_time(&mut self, current: Current) -> Current {
        let dt_secs = self.data.fits.dt_secs;
        for i in self.kept.clone().into_iter().skip(1).rev() {
            let Some(cur) = current.held_out.clone() else { break };
            let Some(swap) = self.dead_time_for(&current, i) else { continue };
            // A dead time replaces a root only when it is at least twice the delay that root itself
            // gives (its low-frequency group delay, the time by which it shifts a slow input), less
            // the dead time's own resolution of one sample: a dead time the root's lag could account
            // for is that lag read as a delay, and the root, which the segment models show, is the
            // better explanation.
            let longer = swap.delay.saturating_sub(1) as f64 * dt_secs >= 2.0 * swap.lag_secs;
            if longer && pooled(&swap.held_out) <= pooled(&cur) {
                let gain = Gain::of(&cur, &swap.held_out, self.noise);
                let (held_out_without, held_out_with) = (gain.without, gain.with);
                self.verdicts[i].verdict =
                    Verdict::DroppedForDeadTime { samples: swap.delay, held_out_without, held_out_with };
                self.dead_time.samples = swap.delay;
                self.dead_time.decision = DeadTimeDecision::KeptForRoot { held_out_without, held_out_with };
                self.kept.retain(|k| *k != i);
                return Current { model: swap.model, delay: swap.delay, held_out: Some(swap.held_out) };
            }
        }
        current
    }

    /// The segment models time the responses' start directly (their input delay); roots that reach
    /// a late start by a slower rise contradict that timing while fitting the held-out segments just
    /// as well, because a few samples of wait and a stretched pole pair look alike under the noise. When
    /// the kept pole pairs have stretched (as polished they delay a slow input by a sample or more
    /// beyond where the segment models put them), a dead time for the late start they still leave
    /// ([`LATE_START_SAMPLES`] or more) is kept
    /// unless the model without it predicts the held-out segments better by the rule that keeps a
    /// root (when the held-out segments cannot tell the two apart, the timing the segment models
    /// measured directly decides): the roots then return to where the
    /// segment models put them, and the continuous-time model a controller is designed on carries
    /// the wait instead of a pole pair slowed to imitate it.
    pub(super) fn dead_time_for_late_start(&mut self, current: Current) -> Current {
        let Some(cur) = current.held_out.as_deref() else { return current };
        let at = self.data.with_delay(current.delay);
        let model_nk = apparent_nk(&at, &current.model.assembled);
        let excess = self.data.fits.nk().saturating_sub(model_nk);
        // The roots stretch to cover the gap when, as polished, their pole pairs delay a slow input by
        // at least a sample more than where the segment models put them (their low-frequency group
        // delay). A real pole is not counted: the spool's time constant follows the operating point,
        // so its polished pole is slower or faster than the segments' average for that reason alone.
        let as_segments_show: Vec<RootGroup> =
            self.kept.iter().filter_map(|&i| self.groups[i].clone()).collect();
        let dt_secs = self.data.fits.dt_secs;
        let lag = |groups: &[RootGroup]| {
            groups.iter().filter(|g| g.pair).map(|g| group_delay_secs(g, dt_secs)).sum::<f64>()
        };
        let stretched = lag(&current.model.groups) - lag(&as_segments_show) >= dt_secs;
        if excess < LATE_START_SAMPLES || !stretched {
            return current;
        }
        // The late start is the most the wait can be (the roots, returned to where the segment models
        // put them, take up part of it), so every whole delay up to it is screened; the wait is one
        // parameter chosen among the best few by the held-out segments, as the decision itself is.
        // The delays are screened with the kept roots where the segment models put them (their
        // clusters' centroids), not as polished without a wait: those have stretched to imitate it
        // and would favour the shortest wait.
        let delays = 1..=excess + 1;
        let best = dead_time_guesses(self.data, &as_segments_show, delays, LATE_START_GUESSES)
            .into_iter()
            .filter_map(|(model, delay)| {
                let order = model.assembled.wiener.map.order();
                let held_out = cross_validate(&self.data.with_delay(delay), &model.groups, order)?;
                Some((model, delay, held_out))
            })
            .min_by(|a, b| pooled(&a.2).total_cmp(&pooled(&b.2)));
        let Some((model, delay, held_out)) = best else { return current };
        // The model without the dead time must not be the better one by the rule that keeps a root.
        if Gain::of(&held_out, cur, self.noise).passes() {
            return current;
        }
        let gain = Gain::of(cur, &held_out, self.noise);
        self.dead_time.samples = delay;
        self.dead_time.decision = DeadTimeDecision::KeptForLateStart {
            model_nk,
            held_out_without: gain.without,
            held_out_with: gain.with,
        };
        Current { model, delay, held_out: Some(held_out) }
    }

    /// The model with candidate `i` taken out and a dead time for the late start that leaves, with
    /// its held-out errors. `None` when `i` is not in the model, the model without it leaves no late
    /// start, or a model cannot be fitted.
    fn dead_time_for(&self, current: &Current, i: usize) -> Option<Swap> {
        let index = current.model.groups.iter().position(|g| g.cluster == Some(i))?;
        let mut fewer = current.model.groups.clone();
        let removed = fewer.remove(index);
        let at = self.data.with_delay(current.delay);
        let reduced = fitted(&at, &fewer)?;
        let excess = self.data.fits.nk().saturating_sub(apparent_nk(&at, &reduced.assembled));
        let (model, delay) = (excess >= 1).then(|| with_dead_time(self.data, &fewer, excess)).flatten()?;
        let order = model.assembled.wiener.map.order();
        let held_out = cross_validate(&self.data.with_delay(delay), &model.groups, order)?;
        let lag_secs = group_delay_secs(&removed, self.data.fits.dt_secs);
        Some(Swap { model, delay, held_out, lag_secs })
    }

    /// Roots kept before the dead time may only have stood in for it: each is taken out again unless
    /// the model with the dead time still needs it by the same rule.
    pub(super) fn drop_stand_ins(&mut self, mut current: Current) {
        let at = self.data.with_delay(current.delay);
        for i in self.kept.clone().into_iter().skip(1).rev() {
            let Some(cur) = current.held_out.clone() else { break };
            let Some(index) = current.model.groups.iter().position(|g| g.cluster == Some(i)) else {
                continue;
            };
            let mut fewer = current.model.groups.clone();
            fewer.remove(index);
            let Some(without) = fitted(&at, &fewer) else { continue };
            let Some(cv) = cross_validate(&at, &without.groups, without.assembled.wiener.map.order()) else {
                continue;
            };
            let gain = Gain::of(&cv, &cur, self.noise);
            if !gain.passes() {
                self.verdicts[i].verdict = Verdict::DroppedStoodIn { gain };
                self.kept.retain(|k| *k != i);
                current = Current { model: without, delay: current.delay, held_out: Some(cv) };
            }
        }
    }
}
