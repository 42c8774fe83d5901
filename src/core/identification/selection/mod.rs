//! The forward selection of the automatic proposal (see `core::identification::structure`): which
//! candidate clusters and whether the input dead time the reduced model keeps, judged by
//! cross-validation across segments under the parsimony rule, each decision recorded as a
//! [`Verdict`] or a [`DeadTimeDecision`].
use crate::core::identification::cluster::{ClusterEval, RootKind};
use crate::core::identification::cross_validation::{cross_validate, fitted};
use crate::core::identification::dead_time::{DeadTimeDecision, DeadTimeVerdict};
use crate::core::identification::parsimony::{
    Gain, Noise, model_error_reduction, too_little_to_cross_validate,
};
use crate::core::identification::reduce::{IdentData, Polished, RootGroup, count_of};
use crate::core::identification::verdict::{CandidateVerdict, Verdict};
use crate::core::parallel::on_two_threads;

mod dead_time_trials;

/// Trials cross-validated per round: the best few by their fit on all the data.
const CROSS_VALIDATED_TRIALS: usize = 3;

/// What the forward selection kept: candidate indices (sorted) and the dead time, with every
/// candidate's verdict.
pub(super) struct Selection {
    pub(super) kept: Vec<usize>,
    pub(super) verdicts: Vec<CandidateVerdict>,
    pub(super) dead_time: DeadTimeVerdict,
}

/// A trial the selection can keep: a cluster candidate (its index) or the dead time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Trial {
    Cluster(usize),
    DeadTime,
}

/// The model the selection has reached.
struct Current {
    model: Polished,
    /// Input dead time of the model, samples.
    delay: usize,
    /// Held-out mean squared error per segment; `None` when the model cannot be cross-validated.
    held_out: Option<Vec<f64>>,
}

/// The trial of a round that lowers the held-out error most.
struct Best {
    trial: Trial,
    model: Polished,
    delay: usize,
    held_out: Vec<f64>,
    gain: Gain,
}

impl Best {
    fn into_current(self) -> Current {
        Current { model: self.model, delay: self.delay, held_out: Some(self.held_out) }
    }
}

/// Forward selection over the valid candidates and the dead time: the first pole, then rounds that
/// each keep the trial that lowers the held-out error most while it passes the parsimony rule, then
/// the trade of a root that only stood in for a dead time.
pub(super) struct ForwardSelection<'d, 'a> {
    data: &'d IdentData<'a>,
    noise: Noise,
    /// Each candidate's root group; `None` for a cluster that is not valid.
    groups: Vec<Option<RootGroup>>,
    verdicts: Vec<CandidateVerdict>,
    dead_time: DeadTimeVerdict,
    /// Candidates kept, in the order they were kept.
    kept: Vec<usize>,
}

impl<'d, 'a> ForwardSelection<'d, 'a> {
    /// Run the selection over the candidates `evals` on `data`.
    pub(super) fn run(data: &'d IdentData<'a>, evals: &[ClusterEval]) -> Selection {
        let mut selection = Self::new(data, evals);
        let Some(mut current) = selection.first_pole() else { return selection.finish() };
        while let Some(best) = selection.round(&current) {
            current = selection.keep(best);
        }
        if !selection.dead_time.kept() {
            current = selection.trade_root_for_dead_time(current);
        }
        if !selection.dead_time.kept() {
            current = selection.dead_time_for_late_start(current);
        }
        if selection.dead_time.kept() {
            selection.drop_stand_ins(current);
        }
        selection.finish()
    }

    fn new(data: &'d IdentData<'a>, evals: &[ClusterEval]) -> Self {
        let groups: Vec<Option<RootGroup>> = evals
            .iter()
            .enumerate()
            .map(|(i, e)| e.valid.then(|| RootGroup::of_cluster(i, e).within(data.settings.polish)))
            .collect();
        let mut verdicts: Vec<CandidateVerdict> =
            evals.iter().map(|e| CandidateVerdict::untried(e, data.fits.roots.len())).collect();
        for (v, g) in verdicts.iter_mut().zip(&groups) {
            if g.is_none() {
                v.verdict = Verdict::NotValid;
            }
        }
        Self {
            data,
            noise: Noise::of(data),
            groups,
            verdicts,
            dead_time: DeadTimeVerdict::before_selection(data),
            kept: Vec::new(),
        }
    }

    fn finish(mut self) -> Selection {
        self.kept.sort_unstable();
        Selection { kept: self.kept, verdicts: self.verdicts, dead_time: self.dead_time }
    }

    /// The first pole: the candidate that alone fits best. `None` when no pole candidate gives a
    /// model.
    fn first_pole(&mut self) -> Option<Current> {
        let mut first: Option<(usize, Polished)> = None;
        let poles: Vec<(usize, &RootGroup)> = (self.groups.iter().enumerate())
            .filter_map(|(i, g)| Some((i, g.as_ref().filter(|g| g.kind == RootKind::Pole)?)))
            .collect();
        let data = self.data;
        let fits = on_two_threads(&poles, |(_, g)| fitted(data, std::slice::from_ref(*g)));
        for (&(i, _), fit) in poles.iter().zip(fits) {
            match fit {
                Some(p) => {
                    self.verdicts[i].rms_with = Some(p.assembled.rms());
                    if first.as_ref().is_none_or(|(_, b)| p.assembled.rms() < b.assembled.rms()) {
                        first = Some((i, p));
                    }
                }
                None => self.verdicts[i].verdict = Verdict::NoModelAlone,
            }
        }
        let (index, model) = first?;
        self.kept.push(index);
        self.verdicts[index].verdict = Verdict::KeptFirst { rms: model.assembled.rms() };
        let held_out = cross_validate(self.data, &model.groups, model.assembled.wiener.map.order());
        Some(Current { model, delay: self.data.delay, held_out })
    }

    /// One round: every remaining candidate beside the kept roots, then the dead time. The trial to
    /// keep, if one passes the parsimony rule.
    fn round(&mut self, current: &Current) -> Option<Best> {
        let at = self.data.with_delay(current.delay);
        let trials = self.trials(current, &at);
        let best = self.judge(current, &at, trials).filter(|b| b.gain.passes());
        if self.dead_time.kept() {
            return best;
        }
        self.try_dead_time(current, &at, best)
    }

    /// Every remaining candidate beside the kept roots, fitted on the whole identification range,
    /// best fit first.
    fn trials(&mut self, current: &Current, at: &IdentData) -> Vec<(usize, Polished)> {
        let groups = &current.model.groups;
        let (n_poles, n_zeros) = (count_of(groups, RootKind::Pole), count_of(groups, RootKind::Zero));
        let mut tried: Vec<(usize, Vec<RootGroup>)> = Vec::new();
        for (i, g) in self.groups.iter().enumerate() {
            let Some(g) = g.as_ref().filter(|_| !self.kept.contains(&i)) else { continue };
            if g.kind == RootKind::Zero && n_zeros + g.count() > n_poles {
                self.verdicts[i].verdict = Verdict::ZeroWithoutPole { poles: n_poles, zeros: n_zeros };
                continue;
            }
            let mut trial_groups = groups.clone();
            trial_groups.push(g.clone());
            tried.push((i, trial_groups));
        }
        // Each candidate's fit is independent of the others': fitted on two threads, gathered in order.
        let fits = on_two_threads(&tried, |(_, trial_groups)| fitted(at, trial_groups));
        let mut trials: Vec<(usize, Polished)> = Vec::new();
        for ((i, _), fit) in tried.iter().zip(fits) {
            match fit {
                Some(trial) => trials.push((*i, trial)),
                None => self.verdicts[*i].verdict = Verdict::NoModelBeside,
            }
        }
        trials.sort_by(|a, b| a.1.assembled.rms().total_cmp(&b.1.assembled.rms()));
        trials
    }

    /// The most promising few trials are cross-validated, the rest judged on their fit alone; every
    /// trial gets its verdict. The cross-validated trial that removes the most held-out model error.
    fn judge(&mut self, current: &Current, at: &IdentData, trials: Vec<(usize, Polished)>) -> Option<Best> {
        let mut best: Option<Best> = None;
        for (rank, (i, trial)) in trials.into_iter().enumerate() {
            let without = current.model.assembled.rms();
            let with = trial.assembled.rms();
            let in_sample = model_error_reduction(without.powi(2), with.powi(2), self.noise);
            let screened_out = rank >= CROSS_VALIDATED_TRIALS || too_little_to_cross_validate(in_sample);
            let cv = if screened_out {
                None
            } else {
                cross_validate(at, &trial.groups, trial.assembled.wiener.map.order())
            };
            let verdict = match (cv, current.held_out.as_deref()) {
                (Some(cv), Some(cur)) => {
                    let gain = Gain::of(cur, &cv, self.noise);
                    if best.as_ref().is_none_or(|b| gain.reduction > b.gain.reduction) {
                        let (which, delay) = (Trial::Cluster(i), current.delay);
                        best = Some(Best { trial: which, model: trial, delay, held_out: cv, gain });
                    }
                    Verdict::DroppedHeldOut { gain }
                }
                _ => Verdict::DroppedInSample { rms_without: without, rms_with: with, reduction: in_sample },
            };
            let v = &mut self.verdicts[i];
            v.rms_without = Some(without);
            v.rms_with = Some(with);
            v.verdict = verdict;
        }
        best
    }
    /// Keep the round's best trial; the model it gives.
    fn keep(&mut self, best: Best) -> Current {
        let gain = best.gain;
        match best.trial {
            Trial::Cluster(i) => {
                let v = &mut self.verdicts[i];
                v.verdict = Verdict::Kept { gain };
                v.standard_errors = Some(gain.standard_errors);
                self.kept.push(i);
            }
            Trial::DeadTime => {
                self.dead_time.decision = DeadTimeDecision::Kept { gain };
                self.dead_time.samples = best.delay;
            }
        }
        best.into_current()
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use num_complex::Complex64;

    use super::*;
    use crate::core::identification::cluster::ClusterEval;
    use crate::core::identification::parsimony::too_little_to_cross_validate;
    use crate::core::identification::test_system::TestSystem;

    fn pole(re: f64) -> Complex64 {
        Complex64::new(re, 0.0)
    }

    /// The pair of noise-model roots an ARX fitted to noisy data puts in every segment, on the left
    /// half of the z-plane: a candidate the segment models agree on that is not the system's.
    fn noise_pair(sys: &TestSystem) -> ClusterEval {
        let roots: Vec<Complex64> = sys
            .fits
            .roots
            .iter()
            .flat_map(|r| r.poles.iter().filter(|p| p.im > 1e-9 && p.re < 0.0))
            .copied()
            .collect();
        let centre = roots.iter().sum::<Complex64>() / roots.len() as f64;
        let radius = roots.iter().map(|p| (p - centre).norm()).fold(0.0, f64::max) + 0.02;
        sys.candidate(RootKind::Pole, centre, radius)
    }

    #[test]
    fn forward_selection_keeps_the_systems_poles_and_drops_a_spurious_pair() {
        let mut sys = TestSystem::new(&[0.9, 0.7], 0, 0.02, 7);
        // Let the noise pair through the cluster condition, as a candidate.
        sys.settings.cluster.nyquist_exclusion_rad = std::f64::consts::PI;
        let evals = [
            sys.candidate(RootKind::Pole, pole(0.9), 0.03),
            sys.candidate(RootKind::Pole, pole(0.7), 0.08),
            noise_pair(&sys),
        ];
        assert!(evals.iter().all(|e| e.valid), "{evals:#?}");
        let data = IdentData::new(&sys.fits, &sys.run, &sys.settings).unwrap();
        let selection = ForwardSelection::run(&data, &evals);
        let [slow, fast, spurious] = &selection.verdicts[..] else { panic!("three verdicts") };
        assert_eq!(selection.kept, [0, 1], "{:?}", selection.verdicts);
        // The slow pole alone fits best; the fast one beside it lowers the held-out error on every segment.
        assert!(matches!(slow.verdict, Verdict::KeptFirst { .. }), "{}", slow.verdict);
        let Verdict::Kept { gain } = fast.verdict else { panic!("{}", fast.verdict) };
        assert!(gain.passes() && gain.wins == gain.folds && gain.with < gain.without, "{gain:?}");
        assert_eq!(fast.standard_errors, Some(gain.standard_errors));
        // The noise pair is dropped, and its verdict says by how little it helps.
        assert!(!spurious.kept());
        match spurious.verdict {
            Verdict::DroppedInSample { reduction, .. } => assert!(too_little_to_cross_validate(reduction)),
            Verdict::DroppedHeldOut { gain } => assert!(!gain.passes(), "{gain:?}"),
            ref other => panic!("{other}"),
        }
        assert!(spurious.rms_without.is_some() && spurious.rms_with.is_some());
        assert!(!selection.dead_time.kept(), "{}", selection.dead_time.sentence());
    }

    #[test]
    fn forward_selection_keeps_a_known_dead_time_and_none_where_there_is_none() {
        let sys = TestSystem::new(&[0.9], 5, 0.02, 9);
        let evals = [sys.candidate(RootKind::Pole, pole(0.9), 0.03)];
        let data = IdentData::new(&sys.fits, &sys.run, &sys.settings).unwrap();
        let dead_time = ForwardSelection::run(&data, &evals).dead_time;
        let DeadTimeDecision::Kept { gain } = dead_time.decision else { panic!("{}", dead_time.sentence()) };
        assert!(gain.passes() && gain.wins == gain.folds, "{gain:?}");
        // The dead time is searched beside the first pole as polished without one, which has taken up
        // part of the late start: on this system the model settles one sample short of the truth.
        assert!(dead_time.in_model().abs_diff(5) <= 1, "{}", dead_time.sentence());

        let clean = TestSystem::new(&[0.9], 0, 0.02, 9);
        let evals = [clean.candidate(RootKind::Pole, pole(0.9), 0.03)];
        let data = IdentData::new(&clean.fits, &clean.run, &clean.settings).unwrap();
        let dead_time = ForwardSelection::run(&data, &evals).dead_time;
        assert_eq!(dead_time.decision, DeadTimeDecision::NotNeeded { arx_nk: 1 }, "{}", dead_time.sentence());
        assert_eq!(dead_time.in_model(), 0);
    }
}
