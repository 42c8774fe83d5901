//! `scheduled_time_constant`: the spool's time constant follows the operating point it is heading for.
use super::Evidence;
use super::power_balance::PowerBalance;
use super::rate_limit::StateLimit;
use super::spool::{self, SplitShape};
use super::stats::ResidualTrace;
use super::stats::mean;
use super::{AsymmetricDynamics, ParamSpec};
use crate::core::identification::settings::SpoolSchedule;

/// A turbojet's spool is slower at low speed. Its power balance J ω ω̇ = P_t(w) − P_c(N), with
/// compressor power ∝ N^k (k ≈ 3), linearised at speed N gives a time constant τ ∝ N^(2−k); over a
/// large step the rate is set by the power surplus or deficit, Ṅ ∝ (N*^k − N^k)/N with N* the speed
/// the fuel flow is heading for, so a step up from idle runs about as fast as the *top* operating
/// point's time constant says and a step down as slow as the *bottom* one's: decelerations are
/// slower than accelerations between the same two speeds. A Wiener model's linear block cannot
/// follow either. This block lets the slowest real pole (the spool, split off as for
/// [`AsymmetricDynamics`]) run with the time constant the operating point gives it, in one of two
/// forms:
/// - **The power balance** (`load_exponent` k > 0; fitted where the project asks for it,
///   `spool_schedule = "power_balance"`): the spool section runs the
///   balance above read through the model's own static map, `N = f(v)` ([`PowerBalance`]), with
///   the load exponent `k` fitted. Its one number is physical, its large-signal rates are the
///   balance's, and a kink in the map (a bleed valve's load) changes the spool's time constant where
///   it changes the map's slope, as the engine's does.
/// - **The exponential** (`load_exponent` = 0; model files written before the power balance):
///   `τ(r) = τ_ref · exp(−log_ratio · (r − ref_input) / input_span)`, `r` the operating point the
///   spool is heading for. `log_ratio` is the log of how much longer the time constant is at the low
///   end of the identified input range than at its high end.
///
/// In both, `r` is the input the spool part is driven by (after the faster dynamics, in input
/// units: the steady input of that operating point), `τ_ref` the linear block's time constant, at
/// `ref_input`, and `state_log_ratio` lets the time constant also follow the state the spool is at,
/// exponentially (what the balance's form leaves). `ref_input` and `input_span` are the
/// identification data's mean and range, fixed when the block is created. Steady states are
/// unchanged. The diagnosis counts it as a refinement of the model's structure, not as physics
/// added to it: every turbojet has it.
#[derive(Clone, Debug, PartialEq)]
pub struct ScheduledTimeConstant {
    /// ln(τ at ref − span/2 ÷ τ at ref + span/2), by the operating point heading for (the
    /// exponential form only).
    pub log_ratio: f64,
    /// The same by the operating point the spool is at.
    pub state_log_ratio: f64,
    /// Input level at which τ is the linear block's, input units.
    pub ref_input: f64,
    /// Input range the ratio spans, input units.
    pub input_span: f64,
    /// The compressor's load exponent k of the power balance (P_c ∝ N^k); 0 for the exponential form.
    pub load_exponent: f64,
}

/// Largest |log_ratio|: a time constant 20 times longer at one end of the range than at the other.
const MAX_LOG_RATIO: f64 = 3.0;

/// The load exponents the power balance admits. The local time constant goes as N^(2−k): from
/// τ ∝ N (k = 1, a load torque that does not grow with speed, the least a compressor absorbs) to
/// τ ∝ N⁻³ (k = 5, a time constant 8 times longer at half speed): the span [`MAX_LOG_RATIO`] allows
/// the exponential form over the 2:1 speed range of a turbojet's operating line, and more than the
/// fan law's k = 3 that every turbojet sits near.
const LOAD_EXPONENTS: (f64, f64) = (1.0, 5.0);

impl ScheduledTimeConstant {
    /// The block for an input signal, with time constants `ratio` apart over its range (the
    /// exponential form).
    pub fn for_input(u: &[f64], log_ratio: f64) -> Self {
        let (lo, hi) = u.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(*x), b.max(*x)));
        let span = if hi > lo { hi - lo } else { 1.0 };
        Self { log_ratio, state_log_ratio: 0.0, ref_input: mean(u), input_span: span, load_exponent: 0.0 }
    }

    /// The power balance with load exponent `k` for an input signal.
    pub fn power_balance(u: &[f64], k: f64) -> Self {
        Self { load_exponent: k, ..Self::for_input(u, 0.0) }
    }

    /// Whether the spool runs the power balance through the static map (else the exponential form).
    pub fn is_power_balance(&self) -> bool {
        self.load_exponent > 0.0
    }

    /// Time-constant factor τ/τ_ref at state `x` heading for the operating point `r`: the power
    /// balance's (`through` the model's map) or the exponential's. Without the map, which a fit's
    /// first pass lacks, the power balance's share is 1 (its steady states are the same).
    pub fn factor_through(&self, x: f64, r: f64, through: Option<&PowerBalance>) -> f64 {
        match (self.is_power_balance(), through) {
            (true, Some(balance)) => balance.factor(x, r) * self.state_factor(x),
            (true, None) => self.state_factor(x),
            (false, _) => self.factor(x, r),
        }
    }

    /// The state's share of the factor.
    fn state_factor(&self, x: f64) -> f64 {
        (-self.state_log_ratio * (x - self.ref_input) / self.input_span).exp()
    }

    /// Time-constant factor τ/τ_ref at state `x` heading for the operating point of input `r`.
    pub fn factor(&self, x: f64, r: f64) -> f64 {
        (-(self.log_ratio * (r - self.ref_input) + self.state_log_ratio * (x - self.ref_input))
            / self.input_span)
            .exp()
    }

    pub(super) fn free_params(&self) -> Vec<f64> {
        match self.is_power_balance() {
            true => vec![self.load_exponent, self.state_log_ratio],
            false => vec![self.log_ratio, self.state_log_ratio],
        }
    }

    pub(super) fn with_free_params(&self, theta: &[f64]) -> Option<Self> {
        let (first, state_log_ratio) = (*theta.first()?, *theta.get(1)?);
        if state_log_ratio.abs() > MAX_LOG_RATIO {
            return None;
        }
        if self.is_power_balance() {
            let (lo, hi) = LOAD_EXPONENTS;
            (lo..=hi).contains(&first).then_some(Self {
                load_exponent: first,
                state_log_ratio,
                ..self.clone()
            })
        } else {
            (first.abs() <= MAX_LOG_RATIO).then_some(Self {
                log_ratio: first,
                state_log_ratio,
                ..self.clone()
            })
        }
    }

    /// Whether the spool split off the linear block runs the power balance when `form` asks for
    /// it: a real pole, the first-order lag the balance linearises to. A spool that shows as a
    /// complex pair is a spool inside a loop (an ECU closing the speed loop on a closed-loop log,
    /// see `SplitShape::of`), whose pair is the loop's, not the balance's; it keeps the
    /// exponential form.
    fn balance_applies(form: SpoolSchedule, split: &SplitShape) -> bool {
        form == SpoolSchedule::PowerBalance && !split.is_pair()
    }

    /// Starting points. For a spool that runs the power balance, its load exponents: the fan
    /// law's k = 3 (τ ∝ 1/N) and around it time constants that fall faster or slower with speed,
    /// τ ∝ N^(2−k) for k from 1.3 to 4.8. Otherwise the exponential form's ratios: time constants
    /// 1.4, 2, 3, 5, 9 and 16 times longer at the low end (τ ∝ 1/N alone gives the ratio of the
    /// top to the bottom speed, 3 on a turbojet from idle to full power; scheduling on the speed
    /// heading for, over a range the spool crosses slowly, gives more), and 1.4 and 2 times
    /// shorter.
    pub(super) fn guesses(u: &[f64], form: SpoolSchedule, split: &SplitShape) -> Vec<Self> {
        match Self::balance_applies(form, split) {
            true => [2.35, 2.7, 3.1, 3.6, 4.2, 4.8, 1.65, 1.3]
                .iter()
                .map(|&k| Self::power_balance(u, k))
                .collect(),
            false => {
                [0.35, 0.7, 1.1, 1.6, 2.2, 2.8, -0.35, -0.7].iter().map(|&r| Self::for_input(u, r)).collect()
            }
        }
    }

    /// The start nearest to no schedule. For the exponential form, no schedule at all. For the
    /// power balance, k = 2: the same local time constant at every operating point; over a large
    /// step the balance still moves at the rate of the power surplus, so this start is not quite
    /// the linear block, and the fit's guarantee of never ending worse than the model it extends
    /// holds for the exponential form only.
    pub(super) fn neutral(u: &[f64], form: SpoolSchedule, split: &SplitShape) -> Self {
        match Self::balance_applies(form, split) {
            true => Self::power_balance(u, 2.0),
            false => Self::for_input(u, 0.0),
        }
    }
}

/// Unit-gain response of the split linear block to `u`, from the steady state of `u[0]`, with the
/// spool pole's time constant scaled by the operating point it is heading for (`scheduled`) and by
/// the direction of motion (`asymmetric`, its decel factor while falling). The model simulates
/// through [`respond_each`].
#[cfg(test)]
fn respond(
    shape: &SplitShape,
    u: &[f64],
    asymmetric: Option<&AsymmetricDynamics>,
    scheduled: Option<&ScheduledTimeConstant>,
) -> Vec<f64> {
    respond_each(vec![Section {
        shape,
        r: spool::rest_response(shape, u),
        asymmetric,
        scheduled,
        limit: None,
        power: None,
    }])
    .pop()
    .unwrap_or_default()
}

/// One spool for [`respond_each`]: the split, the section's input `r` (the rest's response,
/// [`spool::rest_response`]) and the blocks that act on the spool.
pub(super) struct Section<'a> {
    pub shape: &'a SplitShape,
    pub r: Vec<f64>,
    pub asymmetric: Option<&'a AsymmetricDynamics>,
    pub scheduled: Option<&'a ScheduledTimeConstant>,
    pub limit: Option<StateLimit>,
    /// The power balance through the map, when the schedule is the physical one.
    pub power: Option<PowerBalance>,
}

/// [`respond`] for several spools at once, stepped side by side ([`spool::respond_each`]).
pub(super) fn respond_each(sections: Vec<Section>) -> Vec<Vec<f64>> {
    let spools = sections
        .into_iter()
        .map(|Section { shape, r, asymmetric, scheduled, limit, power }| {
            let decel = asymmetric.map_or(1.0, |a| a.decel_factor);
            let schedule =
                move |x: f64, r: f64| scheduled.map_or(1.0, |s| s.factor_through(x, r, power.as_ref()));
            spool::Spool::new(shape, r, decel, schedule, limit)
        })
        .collect();
    spool::respond_each(spools)
}

block_impl!(
    ScheduledTimeConstant { log_ratio, state_log_ratio, ref_input, input_span, load_exponent },
    params: &[
        ParamSpec::real("log_ratio", -MAX_LOG_RATIO, MAX_LOG_RATIO),
        ParamSpec::real("state_log_ratio", -MAX_LOG_RATIO, MAX_LOG_RATIO),
        ParamSpec::real("ref_input", -1e12, 1e12),
        ParamSpec::real("input_span", 1e-12, 1e12),
        ParamSpec::added_later("load_exponent", 0.0, LOAD_EXPONENTS.1, 0.0),
    ],
    physics: "the spool time constant changes with the operating point (slower at low speed): the \
         slowest pole is scheduled on the operating point",
    evidence: super::asymmetric_dynamics::level_evidence
);

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::core::identification::wiener::unit_gain_tf;
    use num_complex::Complex64;

    #[test]
    fn no_schedule_is_the_linear_block_and_a_schedule_slows_the_low_end() {
        let poles = [Complex64::new(0.9, 0.0), Complex64::new(0.5, 0.2), Complex64::new(0.5, -0.2)];
        let tf = unit_gain_tf(&poles, &[], 0.1).unwrap();
        let u: Vec<f64> = (0..600).map(|k| if (k / 150) % 2 == 0 { 1.0 } else { 3.0 }).collect();
        let split = AsymmetricDynamics::split(&poles, &[], 0.1).unwrap();
        let flat = ScheduledTimeConstant::for_input(&u, 0.0);
        let same = respond(&split, &u, None, Some(&flat));
        for (a, b) in same.iter().zip(tf.simulate_from_steady(&u)) {
            assert!((a - b).abs() < 1e-9, "{a} vs {b}");
        }
        // Slower when heading for the low end: the fall towards 1.0 (from sample 300) lags the linear
        // block; the settled values agree.
        let sched = ScheduledTimeConstant::for_input(&u, 1.0);
        let slow = respond(&split, &u, None, Some(&sched));
        assert!(slow[310] > same[310] + 0.05, "{} vs {}", slow[310], same[310]);
        assert!((slow[449] - same[449]).abs() < 1e-3, "{} vs {}", slow[449], same[449]);
        assert!(ScheduledTimeConstant { log_ratio: 9.0, ..sched }.with_free_params(&[9.0]).is_none());
    }

    /// Spools stepped side by side give each the response it gives alone, bit for bit: a pair
    /// spool with a rest and a schedule, a real spool alone with asymmetric dynamics, inputs of
    /// different lengths.
    #[test]
    fn spools_stepped_together_respond_as_each_alone() {
        let pair = [
            Complex64::new(0.8, 0.3),
            Complex64::new(0.8, -0.3),
            Complex64::new(0.3, 0.2),
            Complex64::new(0.3, -0.2),
        ];
        let real = [Complex64::new(0.93, 0.0)];
        let u: Vec<f64> = (0..500).map(|k| 1.0 + (k / 60 % 3) as f64 + 0.01 * (k as f64).sin()).collect();
        let short = &u[..321];
        let (pair_split, real_split) = (
            AsymmetricDynamics::split(&pair, &[], 0.05).unwrap(),
            AsymmetricDynamics::split(&real, &[], 0.05).unwrap(),
        );
        assert!(pair_split.is_pair() && pair_split.rest.is_some());
        assert!(!real_split.is_pair() && real_split.rest.is_none());
        let sched =
            ScheduledTimeConstant { state_log_ratio: -0.4, ..ScheduledTimeConstant::for_input(&u, 1.3) };
        let asym = AsymmetricDynamics { decel_factor: 2.5 };
        let alone = [
            respond(&pair_split, &u, Some(&asym), Some(&sched)),
            respond(&real_split, short, Some(&asym), None),
            respond(&real_split, &u, None, Some(&sched)),
        ];
        let together = respond_each(vec![
            Section {
                shape: &pair_split,
                r: spool::rest_response(&pair_split, &u),
                asymmetric: Some(&asym),
                scheduled: Some(&sched),
                limit: None,
                power: None,
            },
            Section {
                shape: &real_split,
                r: spool::rest_response(&real_split, short),
                asymmetric: Some(&asym),
                scheduled: None,
                limit: None,
                power: None,
            },
            Section {
                shape: &real_split,
                r: spool::rest_response(&real_split, &u),
                asymmetric: None,
                scheduled: Some(&sched),
                limit: None,
                power: None,
            },
        ]);
        assert_eq!(together.len(), 3);
        for (a, b) in alone.iter().zip(&together) {
            assert_eq!(a.len(), b.len());
            assert!(a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits()));
        }
        // The schedule and the asymmetry change the responses (the check above compares something).
        assert!(alone[0].iter().zip(&alone[2]).any(|(x, y)| (x - y).abs() > 1e-3));
    }
}
