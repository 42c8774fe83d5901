//! A set-point channel found in a log. On closed-loop data (an ECU holding the speed it is told)
//! the fuel command overshoots at every set-point change, so its steps are a poor guide to where
//! the engine's step responses begin; the set-point itself steps cleanly. An engineer would split
//! the run on the set-point; [`find_set_point`] finds such a channel among the auxiliary channels,
//! so the user need not name it (`steps_from`).
//!
//! A channel is taken for a set-point when it is *commanded* (it holds its value exactly between
//! changes, [`MIN_REPEAT_SHARE`]) and the engine *follows* it (across its holds the settled output
//! lies in the same order as the set-point's levels, [`MIN_RANK_CORRELATION`] over at least
//! [`MIN_HOLDS`] holds).
use crate::core::identification::segment::SegmentSettings;
use crate::core::numerics::stats::pearson;
use crate::core::run::{Channel, Run};

/// Share of consecutive samples in which a set-point repeats its value exactly. A set-point is
/// typed or scheduled, not measured: between commands it keeps its value to the bit, and 95 %
/// leaves room for ramps over a twentieth of the log. A measured channel with any sensor noise
/// repeats far less often; a slow, coarsely quantised sensor (an ambient temperature logged in
/// 0.1 °C) can repeat as often, which is why the engine must also follow the channel.
pub const MIN_REPEAT_SHARE: f64 = 0.95;

/// Fewest holds, each ending with the engine settled, that the engine must follow. With `n` holds of an unrelated channel, every ordering of
/// the settled outputs is equally likely; a Spearman correlation of at least 0.9 then happens in
/// 6 of 720 orderings at n = 6 (0.8 %), below the 1 % level the diagnosis tests at, and in
/// fewer beyond (0.3 % at 7); at n = 5 it is 4.2 %.
pub const MIN_HOLDS: usize = 6;

/// Spearman correlation between the set-point's levels and the output settled at the end of each
/// hold (see [`MIN_HOLDS`] for what chance gives). Rank correlation asks only that a higher
/// set-point give a higher output, whatever the units (a speed set-point and a speed, or a thrust
/// demand and a speed).
pub const MIN_RANK_CORRELATION: f64 = 0.9;

/// A set-point channel and the evidence for it.
#[derive(Clone, Debug, PartialEq)]
pub struct SetPoint {
    pub channel: String,
    /// The output that follows it most closely.
    pub output: String,
    /// Holds at least [`SegmentSettings::min_hold_secs`] long at whose end the output had settled.
    pub holds: usize,
    /// Share of consecutive samples with the same value.
    pub repeat_share: f64,
    /// Spearman correlation between the levels of the holds and the settled output.
    pub rank_correlation: f64,
}

impl SetPoint {
    /// "'rpm_setpoint' is a set-point: it holds its value in 99 % of the samples, and over 12 holds
    /// 'rpm' settles in the same order (Spearman 0.98)".
    pub fn words(&self) -> String {
        format!(
            "'{}' is a set-point: it holds its value in {:.0} % of the samples, and over {} holds '{}' settles in the \
             same order (Spearman {:.2})",
            self.channel,
            100.0 * self.repeat_share,
            self.holds,
            self.output,
            self.rank_correlation
        )
    }
}

/// The auxiliary channel of `run` that is a set-point (see the module), the one with the most holds
/// when several are; `junctions` are where joined runs start (no hold crosses one).
pub fn find_set_point(run: &Run, junctions: &[usize]) -> Option<SetPoint> {
    let min_hold = (SegmentSettings::default().min_hold_secs / run.dt_secs).ceil() as usize;
    run.aux
        .iter()
        .filter_map(|channel| judge(run, junctions, channel, min_hold.max(2)))
        .max_by(|a, b| a.holds.cmp(&b.holds).then(a.rank_correlation.total_cmp(&b.rank_correlation)))
}

fn judge(run: &Run, junctions: &[usize], channel: &Channel, min_hold: usize) -> Option<SetPoint> {
    let v = &channel.values;
    let scale = v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    if v.len() < 2 || !(scale > 0.0 && scale.is_finite()) {
        return None;
    }
    let same = |a: f64, b: f64| (a - b).abs() <= 4.0 * f64::EPSILON * scale;
    let repeats = v.windows(2).filter(|w| same(w[0], w[1])).count();
    let repeat_share = repeats as f64 / (v.len() - 1) as f64;
    if repeat_share < MIN_REPEAT_SHARE {
        return None;
    }
    let holds = holds(v, junctions, min_hold, same);
    if holds.len() < MIN_HOLDS {
        return None;
    }
    run.outputs
        .iter()
        .filter_map(|output| {
            let y = &output.values;
            let range = y.iter().fold(f64::NEG_INFINITY, |m, &x| m.max(x))
                - y.iter().fold(f64::INFINITY, |m, &x| m.min(x));
            let (levels, settled): (Vec<f64>, Vec<f64>) = holds
                .iter()
                .filter_map(|&(start, end)| Some((v[start], settled(y, start, end, range)?)))
                .unzip();
            if levels.len() < MIN_HOLDS {
                return None;
            }
            let rho = spearman(&levels, &settled)?;
            (rho >= MIN_RANK_CORRELATION).then(|| (output.name.clone(), levels.len(), rho))
        })
        .max_by(|a, b| a.1.cmp(&b.1).then(a.2.total_cmp(&b.2)))
        .map(|(output, holds, rank_correlation)| SetPoint {
            channel: channel.name.clone(),
            output,
            holds,
            repeat_share,
            rank_correlation,
        })
}

/// The stretches `[start, end)` of at least `min_hold` samples over which `v` keeps one value, none
/// crossing a junction.
fn holds(
    v: &[f64],
    junctions: &[usize],
    min_hold: usize,
    same: impl Fn(f64, f64) -> bool,
) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = 0;
    for k in 1..=v.len() {
        let breaks = k == v.len() || junctions.contains(&k) || !same(v[k - 1], v[k]);
        if breaks {
            if k - start >= min_hold {
                out.push((start, k));
            }
            start = k;
        }
    }
    out
}

/// How far the output may still move at the end of a hold for the engine to count as settled, as a
/// share of the output's range over the run: between the last two eighths of the hold. An engine
/// still spooling up after a start or down after a fuel cut moves by tens of percent there; sensor
/// noise averaged over an eighth of a hold (at least [`SegmentSettings::min_hold_secs`] / 8, 10
/// samples at 10 Hz) moves it far less than 2 %.
pub const MAX_SETTLING_DRIFT: f64 = 0.02;

/// The output at the end of a hold (the mean of its last quarter) when the engine has settled there
/// ([`MAX_SETTLING_DRIFT`]); `None` while it is still moving (a start, a shutdown).
fn settled(y: &[f64], start: usize, end: usize, range: f64) -> Option<f64> {
    let mean = |from: usize, to: usize| y[from..to].iter().sum::<f64>() / (to - from).max(1) as f64;
    let eighth = ((end - start) / 8).max(1);
    let drift = (mean(end - eighth, end) - mean(end - 2 * eighth, end - eighth)).abs();
    (drift <= MAX_SETTLING_DRIFT * range).then(|| mean(end - 2 * eighth, end))
}

/// Spearman's rank correlation (ties get their mean rank); `None` when either side is constant.
fn spearman(a: &[f64], b: &[f64]) -> Option<f64> {
    pearson(&ranks(a), &ranks(b))
}

fn ranks(x: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..x.len()).collect();
    order.sort_by(|&i, &j| x[i].total_cmp(&x[j]));
    let mut rank = vec![0.0; x.len()];
    let mut i = 0;
    while i < order.len() {
        let mut j = i;
        while j + 1 < order.len() && x[order[j + 1]].total_cmp(&x[order[i]]).is_eq() {
            j += 1;
        }
        let mean = (i + j) as f64 / 2.0;
        for &k in &order[i..=j] {
            rank[k] = mean;
        }
        i = j + 1;
    }
    rank
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::run::Channel;

    /// A closed-loop log: a set-point stepping through `levels` (each held 20 s at 10 Hz), the
    /// speed following it through a first-order lag, the fuel command overshooting, and a noisy
    /// temperature.
    fn closed_loop(levels: &[f64]) -> Run {
        let per = 200;
        let sp: Vec<f64> = levels.iter().flat_map(|&l| std::iter::repeat_n(l, per)).collect();
        let mut y = vec![sp[0]; sp.len()];
        for k in 1..sp.len() {
            y[k] = y[k - 1] + 0.1 * (sp[k] - y[k - 1]);
        }
        let u: Vec<f64> = sp.iter().zip(&y).map(|(s, y)| s / 20000.0 + (s - y) / 5000.0).collect();
        let temp: Vec<f64> = (0..sp.len()).map(|k| 500.0 + ((k * 7919) % 13) as f64 * 0.1).collect();
        Run {
            name: "closed".into(),
            dt_secs: 0.1,
            t_secs: (0..sp.len()).map(|k| k as f64 * 0.1).collect(),
            input: Channel::new("pump_V", u),
            outputs: vec![Channel::new("rpm", y)],
            aux: vec![Channel::new("egt_C", temp), Channel::new("rpm_setpoint", sp)],
        }
    }

    #[test]
    fn a_set_point_the_engine_follows_is_found_among_noisy_channels() {
        let run = closed_loop(&[60e3, 100e3, 75e3, 50e3, 90e3, 60e3, 80e3]);
        let Some(found) = find_set_point(&run, &[]) else { panic!("no set-point found") };
        assert_eq!(found.channel, "rpm_setpoint");
        assert_eq!(found.output, "rpm");
        assert_eq!(found.holds, 7);
        assert!(found.rank_correlation > 0.99, "{found:?}");
        assert!(found.words().contains("7 holds"), "{}", found.words());
    }

    #[test]
    fn a_held_channel_the_engine_does_not_follow_is_not_a_set_point() {
        let mut run = closed_loop(&[60e3, 100e3, 75e3, 50e3, 90e3, 60e3, 80e3]);
        // The same holds, but levels in an order the speed does not take (a mode switch, a gear).
        let per = 200;
        let mode: Vec<f64> =
            [3.0, 1.0, 4.0, 2.0, 1.0, 5.0, 2.0].iter().flat_map(|&l| std::iter::repeat_n(l, per)).collect();
        run.aux[1] = Channel::new("mode", mode);
        assert_eq!(find_set_point(&run, &[]), None);
    }

    #[test]
    fn holds_where_the_engine_is_still_moving_do_not_count() {
        // A fuel cut during the last hold: the set-point stays, the speed runs down.
        let mut run = closed_loop(&[60e3, 100e3, 75e3, 50e3, 90e3, 60e3, 80e3, 100e3]);
        let n = run.len();
        for (k, y) in run.outputs[0].values[n - 200..].iter_mut().enumerate() {
            *y = 100e3 * (-(k as f64) / 80.0).exp();
        }
        let Some(found) = find_set_point(&run, &[]) else { panic!("no set-point found") };
        assert_eq!(found.holds, 7, "the run-down hold left out: {found:?}");
        assert!(found.rank_correlation > 0.99, "{found:?}");
    }

    #[test]
    fn too_few_holds_prove_nothing() {
        let run = closed_loop(&[60e3, 100e3, 75e3, 50e3, 90e3]);
        assert_eq!(find_set_point(&run, &[]), None);
    }

    #[test]
    fn a_hold_does_not_cross_a_junction() {
        let v = [1.0; 10];
        assert_eq!(holds(&v, &[4], 3, |a: f64, b: f64| a.total_cmp(&b).is_eq()), vec![(0, 4), (4, 10)]);
    }

    #[test]
    fn ties_share_their_mean_rank() {
        assert_eq!(ranks(&[2.0, 1.0, 2.0, 3.0]), vec![1.5, 0.0, 1.5, 3.0]);
        assert_eq!(spearman(&[1.0, 1.0], &[1.0, 2.0]), None);
    }
}
