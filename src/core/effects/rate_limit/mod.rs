//! `rate_limit`: the ECU's acceleration/deceleration schedule caps how fast the spool may change.
use super::stats::ResidualTrace;
use super::{Evidence, ParamSpec, StaticMapOrder};
use crate::core::identification::static_map::StaticMap;
use crate::core::run::Quantity;
use evidence::smoothed_rate;

mod evidence;

/// The ECU's acceleration and deceleration schedule: however far the fuel command jumps, the shaft
/// speed may rise by at most `rise_per_s` and fall by at most `fall_per_s`.
///
/// The limit acts where the ECU puts it, on the spool's state: the linear block is split into the
/// spool (its slowest real pole or pair, see `spool::SplitShape`) and the rest ahead of it (the
/// fuel system), and the spool's state may change per sample by at most the limit. The fuel system
/// keeps its own dynamics, and once the limit lets go the spool approaches the fuel's level at its
/// own time constant, as an engine does; a slew limiter on the whole block's output would instead
/// snap onto the unlimited response the moment it meets it. On the family's engines this is what
/// the shape costs: the shaft speed's held-out error after the loop was 3 to 5 times the same
/// engine's without the limit with the limiter on the output, 1.3 to 1.9 times with it on the state.
///
/// The limits are stated in the units of the shaft speed's rate when the model's output is the
/// shaft speed (rpm/s: the state's change is read through the static map's slope, so the limit is
/// the same at idle and at full power, as the schedule's is), and in units of the linear block's
/// output `v` per second for any other output (see [`limits_own_rate`]).
#[derive(Clone, Debug, PartialEq)]
pub struct RateLimit {
    /// Largest rise, per second (see the units above).
    pub rise_per_s: f64,
    /// Largest fall, per second.
    pub fall_per_s: f64,
}

/// Whether a model of `output` states its rate limit in its own output's units: the shaft speed,
/// whose rate is what the ECU's schedule limits. A model of another output (thrust) does not see the
/// speed; its `v`, affine in the fuel at steady state like the speed's own `v`, is the closest it
/// has to the spool's state, and a limit in thrust's own units would vary fivefold from idle to full
/// power (thrust grows as about the fifth power of the speed) where the schedule does not.
pub fn limits_own_rate(output: &str) -> bool {
    Quantity::of(output) == Some(Quantity::ShaftSpeed)
}

/// A [`RateLimit`] as the spool section applies it: per sample, with what turns a change of the
/// unit-gain spool state `x` into the limited quantity (`gain`, `offset`: `v = gain·x + offset`;
/// `through`: the static map and its kink, when the limit is on the output's rate).
#[derive(Clone, Debug, PartialEq)]
pub struct StateLimit {
    pub up: f64,
    pub down: f64,
    pub gain: f64,
    pub offset: f64,
    pub through: Option<(StaticMap, Option<StaticMapOrder>)>,
}

impl StateLimit {
    /// `next` with its change from `x` clamped to the limits.
    pub(super) fn clamp(&self, x: f64, next: f64) -> f64 {
        let v = self.gain * x + self.offset;
        let slope = match &self.through {
            Some((map, kink)) => {
                map.slope(v) + kink.as_ref().map_or(0.0, |k| if v > k.knot_v { k.slope_change } else { 0.0 })
            }
            None => 1.0,
        };
        // One unit of x moves the limited quantity by `rate`; a negative rate swaps the limits.
        let rate = self.gain * slope;
        if !rate.is_finite() || rate.abs() <= f64::MIN_POSITIVE {
            return next;
        }
        let (up, down) = if rate > 0.0 { (self.up, self.down) } else { (self.down, self.up) };
        let r = rate.abs();
        x + (next - x).clamp(-down / r, up / r)
    }
}

/// Smallest admissible limit, output units per second (a limit of zero would freeze the output).
const MIN_LIMIT_PER_S: f64 = 1e-9;
/// Largest admissible limit, output units per second (far above any rate a run can show).
const MAX_LIMIT_PER_S: f64 = 1e12;

/// Shares of the current model's fastest rise (fall) tried as starting limits; above 1 the limit
/// does not bind in that direction (an ECU may limit only acceleration or only deceleration).
const LIMIT_SHARES: [f64; 4] = [0.3, 0.5, 0.7, 1.5];

impl RateLimit {
    /// The limit as the spool section of a model applies it, with samples of `dt_secs`; `gain`,
    /// `offset` and the map (with its kink) are the model's, and `through_map` says whether the
    /// limit is on the map's output (the speed's own rate) or on `v`.
    pub fn on_state(
        &self,
        through_map: bool,
        dt_secs: f64,
        gain: f64,
        offset: f64,
        map: &StaticMap,
        kink: Option<&StaticMapOrder>,
    ) -> StateLimit {
        StateLimit {
            up: self.rise_per_s * dt_secs,
            down: self.fall_per_s * dt_secs,
            gain,
            offset,
            through: through_map.then(|| (map.clone(), kink.cloned())),
        }
    }

    fn admissible(&self) -> bool {
        let ok = |x: f64| x.is_finite() && (MIN_LIMIT_PER_S..=MAX_LIMIT_PER_S).contains(&x);
        ok(self.rise_per_s) && ok(self.fall_per_s)
    }

    pub(super) fn free_params(&self) -> Vec<f64> {
        vec![self.rise_per_s.ln(), self.fall_per_s.ln()]
    }

    pub(super) fn with_free_params(&self, theta: &[f64]) -> Option<Self> {
        let b = Self { rise_per_s: theta.first()?.exp(), fall_per_s: theta.get(1)?.exp() };
        b.admissible().then_some(b)
    }

    /// Starting limits: shares of the fastest rise and fall of what the current model's limit
    /// would limit (see `ExtendedModel::rate_limited_quantity`) on the identification data (a limit
    /// only matters where it is below what the linear block does).
    pub(super) fn guesses(v: &[f64], dt_secs: f64) -> Vec<Self> {
        let (rise, fall) = peak_rates(v, dt_secs);
        if rise <= 0.0 && fall <= 0.0 {
            return Vec::new();
        }
        let (rise, fall) = (rise.max(fall * 1e-3), fall.max(rise * 1e-3));
        LIMIT_SHARES
            .iter()
            .flat_map(|&a| LIMIT_SHARES.iter().map(move |&b| (a, b)))
            .filter(|(a, b)| a.min(*b) < 1.0)
            .map(|(a, b)| Self { rise_per_s: a * rise, fall_per_s: b * fall })
            .filter(Self::admissible)
            .collect()
    }

    /// A starting limit read off the measurement itself: its fastest rise and fall, each averaged
    /// over a few samples (see [`RATE_HALF_SPAN`]). Where the schedule binds, the measured output
    /// ramps at the limit, so this is the limit itself plus the little the noise adds; the shares of
    /// the model's rates above miss it when the current model's roots have already slowed to follow
    /// the limited responses. Only for a limit on the measured output's own rate.
    pub(super) fn measured_guess(y: &[f64], dt_secs: f64) -> Option<Self> {
        let rate = smoothed_rate(y, dt_secs);
        let rise = rate.iter().copied().fold(0.0, f64::max);
        let fall = rate.iter().map(|r| -r).fold(0.0, f64::max);
        let b = Self { rise_per_s: rise, fall_per_s: fall };
        b.admissible().then_some(b)
    }

    /// A limiter that does not bind on the current model (twice its fastest rise and fall).
    pub(super) fn neutral(v: &[f64], dt_secs: f64) -> Option<Self> {
        let (rise, fall) = peak_rates(v, dt_secs);
        let b = Self { rise_per_s: 2.0 * rise, fall_per_s: 2.0 * fall };
        b.admissible().then_some(b)
    }
}

/// A limit binds on the identification data when the unlimited response exceeds it on at least this
/// many samples: a rate is read off a ramp, and a ramp of fewer than three samples (two intervals) is
/// not told apart from the rounding the linear block's own poles give a step.
const MIN_BINDING_SAMPLES: usize = 3;

impl RateLimit {
    /// The block with a limit the data never reach lifted: `v_free` is what the limit limits (the
    /// speed, or `v`; see `ExtendedModel::rate_limited_quantity`) in the model without the
    /// limiter on the identification data; where the limit in one direction binds on fewer than
    /// [`MIN_BINDING_SAMPLES`] samples, the data say nothing about it (any value above their fastest
    /// change fits them alike), so the model does not impose one there (the limit becomes the
    /// largest admissible). A limit fitted just above the fastest fall of data that hold only small
    /// falls would otherwise cap every larger fall of the runs it predicts.
    pub(super) fn lifted_where_unreached(&self, v_free: &[f64], dt_secs: f64) -> Self {
        let (mut up, mut down) = (0usize, 0usize);
        for w in v_free.windows(2) {
            let r = (w[1] - w[0]) / dt_secs;
            up += usize::from(r > self.rise_per_s);
            down += usize::from(-r > self.fall_per_s);
        }
        let lift = |count: usize, x: f64| if count < MIN_BINDING_SAMPLES { MAX_LIMIT_PER_S } else { x };
        Self { rise_per_s: lift(up, self.rise_per_s), fall_per_s: lift(down, self.fall_per_s) }
    }
}

/// Fastest one-sample rise and fall of `v`, per second (both ≥ 0).
fn peak_rates(v: &[f64], dt_secs: f64) -> (f64, f64) {
    v.windows(2).fold((0.0_f64, 0.0_f64), |(up, down), w| {
        let r = (w[1] - w[0]) / dt_secs;
        (up.max(r), down.max(-r))
    })
}

block_impl!(
    RateLimit { rise_per_s, fall_per_s },
    params: &[
        ParamSpec::real("rise_per_s", MIN_LIMIT_PER_S, MAX_LIMIT_PER_S),
        ParamSpec::real("fall_per_s", MIN_LIMIT_PER_S, MAX_LIMIT_PER_S),
    ],
    physics: "the ECU's acceleration/deceleration schedule limits how fast speed may change: the spool's \
         state rises and falls at most at fitted rates while the fuel system ahead of it keeps its dynamics",
    evidence: evidence::evidence
);

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn the_state_limit_clamps_changes_in_the_limited_quantity() {
        let r = RateLimit { rise_per_s: 10.0, fall_per_s: 5.0 };
        let map = StaticMap { coeffs_scaled: vec![0.0, 1.0], ..StaticMap::identity() };
        // On v (a thrust model): v = 2x, so x may rise by 10·0.1/2 a sample.
        let on_v = r.on_state(false, 0.1, 2.0, 0.0, &map, None);
        assert!((on_v.clamp(0.0, 3.0) - 0.5).abs() < 1e-12 && (on_v.clamp(0.0, -3.0) + 0.25).abs() < 1e-12);
        assert!((on_v.clamp(0.0, 0.1) - 0.1).abs() < 1e-15, "a small change is untouched");
        // A negative gain turns a rise of x into a fall of v: the fall's limit applies.
        let negative = r.on_state(false, 0.1, -2.0, 0.0, &map, None);
        assert!((negative.clamp(0.0, 3.0) - 0.25).abs() < 1e-12);
        // On the speed's own rate, through the map's slope (here 4 per unit of v).
        let steep = StaticMap { coeffs_scaled: vec![0.0, 4.0], ..StaticMap::identity() };
        let on_speed = r.on_state(true, 0.1, 2.0, 0.0, &steep, None);
        assert!((on_speed.clamp(0.0, 3.0) - 0.125).abs() < 1e-12);
        assert!(r.with_free_params(&r.free_params()).is_some_and(|b| (b.rise_per_s - 10.0).abs() < 1e-9));
        assert!(r.with_free_params(&[f64::NAN, 0.0]).is_none());
    }

    /// A large step through a model of the shaft speed whose spool (pole 0.9) follows a fuel pole
    /// (0.3): the speed ramps at the limit until the spool's own free change falls below it, where
    /// the gap to the final value is about `rise·dt / (1 − 0.9)`, and from there closes by the spool's
    /// pole each sample, as an engine's speed does once the schedule lets go. A slew limiter on the
    /// whole block's output would ramp on until it met the unlimited response, nearly at the end.
    #[test]
    fn a_limited_spool_ramps_then_settles_at_its_own_time_constant() {
        use crate::core::effects::{EffectBlock, ExtendedModel};
        use crate::core::identification::wiener::{LinearBlock, WienerModel, unit_gain_tf};
        use crate::core::run::{Channel, Run};
        use num_complex::Complex64;
        let dt = 0.1;
        let poles = [Complex64::new(0.9, 0.0), Complex64::new(0.3, 0.0)];
        let tf = unit_gain_tf(&poles, &[], dt).unwrap();
        let wiener = WienerModel { linear: LinearBlock { tf, offset: 0.0 }, map: StaticMap::identity() };
        let limit = RateLimit { rise_per_s: 2.0, fall_per_s: 2.0 };
        let model =
            ExtendedModel::new("shaft_speed_rpm", wiener).with_effect(EffectBlock::RateLimit(limit)).unwrap();
        let n = 400;
        let run = Run {
            name: "step".into(),
            dt_secs: dt,
            t_secs: (0..n).map(|k| k as f64 * dt).collect(),
            input: Channel::new("fuel_flow_gph", (0..n).map(|k| if k < 5 { 0.0 } else { 10.0 }).collect()),
            outputs: vec![],
            aux: vec![],
        };
        let y = model.simulate(&run).unwrap();
        let rates: Vec<f64> = y.windows(2).map(|w| (w[1] - w[0]) / dt).collect();
        assert!(rates.iter().all(|r| *r <= 2.0 + 1e-9), "never faster than the limit");
        let ramp_end = rates.iter().rposition(|r| (r - 2.0).abs() < 1e-9).unwrap();
        // The last limited step starts at a gap of at least rise·dt/(1 − 0.9) = 2 and takes 0.2 off.
        let gap = 10.0 - y[ramp_end + 1];
        assert!((1.8 - 1e-9..2.0).contains(&gap), "the ramp ends 1.8 to 2 short of the end: {gap}");
        for k in ramp_end + 5..ramp_end + 40 {
            let ratio = (10.0 - y[k + 1]) / (10.0 - y[k]);
            assert!((ratio - 0.9).abs() < 1e-3, "sample {k}: the gap closes by {ratio}");
        }
    }
}
