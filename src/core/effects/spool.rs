//! The spool split off a linear block (its slowest real pole, or pair, and the unit-gain rest) and
//! the block's response with the spool's time constant scaled sample by sample: what
//! `asymmetric_dynamics`, `scheduled_time_constant` and `rate_limit` act on.
use num_complex::Complex64;

use super::rate_limit::StateLimit;
use super::{EffectError, EffectId};
use crate::core::identification::wiener::unit_gain_tf;
use crate::core::numerics::tf::DiscreteTf;

/// The unit-gain linear block split into the spool's root and the rest.
#[derive(Clone, Debug, PartialEq)]
pub struct SplitShape {
    /// The spool: a real pole in (0, 1), or the upper root of the slowest complex pair when the
    /// linear block has no real pole there (see `SplitShape::of`).
    pub spool: Complex64,
    /// Unit-gain remainder; `None` when the spool is the only root (group).
    pub rest: Option<DiscreteTf>,
}

impl SplitShape {
    /// Whether the spool is a complex pair rather than a real pole.
    pub fn is_pair(&self) -> bool {
        self.spool.im.abs() > 1e-9
    }

    /// Split off the spool: the slowest real pole in (0, 1); when there is none, the slowest
    /// complex pair. A spool identified from closed-loop data (an ECU that overshoots its fuel
    /// command at every set-point change) or behind a fast actuator often shows as a damped pair
    /// rather than one real pole; its time scale follows the operating point by the same power
    /// balance, so the whole pair is what is scheduled (both its roots' time constants scale
    /// together, `p → p^(1/factor)`, which keeps its damping ratio).
    ///
    /// `effect` is the block that asks, named in the error when there is no spool.
    pub(super) fn of(
        poles: &[Complex64],
        zeros: &[Complex64],
        dt_secs: f64,
        effect: EffectId,
    ) -> Result<Self, EffectError> {
        let not_applicable = |reason: &str| EffectError::NotApplicable {
            effect: effect.name().to_owned(),
            reason: reason.to_owned(),
        };
        let slowest = |pick: &dyn Fn(&Complex64) -> bool| {
            poles.iter().filter(|p| pick(p)).max_by(|a, b| a.norm().total_cmp(&b.norm())).copied()
        };
        let real = slowest(&|p| p.im.abs() <= 1e-9 && p.re > 0.0 && p.re < 1.0);
        let spool = real.or_else(|| slowest(&|p| p.im > 1e-9 && p.norm() < 1.0)).ok_or_else(|| {
            not_applicable("the linear block has neither a real pole between 0 and 1 nor a complex pair")
        })?;
        let is_spool = |p: &Complex64| (p - spool).norm() <= 1e-12 || (p - spool.conj()).norm() <= 1e-12;
        let mut others: Vec<Complex64> = Vec::with_capacity(poles.len());
        let mut taken = 0;
        let group = if real.is_some() { 1 } else { 2 };
        for p in poles {
            if taken < group && is_spool(p) {
                taken += 1;
            } else {
                others.push(*p);
            }
        }
        if zeros.len() > others.len() {
            return Err(not_applicable("the linear block has as many zeros as poles"));
        }
        let rest = if others.is_empty() {
            None
        } else {
            Some(
                unit_gain_tf(&others, zeros, dt_secs)
                    .map_err(|e| EffectError::BadBaseModel { reason: e.to_string() })?,
            )
        };
        Ok(Self { spool, rest })
    }
}

/// Unit-gain response of the split linear block to `u`, from the steady state of `u[0]`, with the
/// spool pole's time constant multiplied at each sample by `schedule(x, r)` (`x` the spool section's
/// output, `r` its input one sample ago) and, while the response falls, by `decel`.
pub(super) fn respond(
    shape: &SplitShape,
    u: &[f64],
    decel: f64,
    schedule: impl Fn(f64, f64) -> f64,
) -> Vec<f64> {
    respond_each(vec![Spool::new(shape, rest_response(shape, u), decel, schedule, None)])
        .pop()
        .unwrap_or_default()
}

/// What drives the spool section: the unit-gain rest's response to `u`, or `u` itself.
pub(super) fn rest_response(shape: &SplitShape, u: &[f64]) -> Vec<f64> {
    match &shape.rest {
        Some(tf) => tf.simulate_from_steady(u),
        None => u.to_vec(),
    }
}

/// The spool section of one response (see [`respond`]), stepped a sample at a time.
pub(super) struct Spool<S> {
    /// The section's input: the rest's response ([`rest_response`]).
    r: Vec<f64>,
    /// The spool's root as a continuous-time rate: scaling the time constant by `factor` divides it.
    ln_root: Complex64,
    pair: bool,
    decel: f64,
    schedule: S,
    /// The rate limit on the section's output, when the model has one.
    limit: Option<StateLimit>,
    /// The section's output now and one sample ago; its input one and two samples ago.
    x: f64,
    x_old: f64,
    prev: f64,
    prev_old: f64,
}

impl<S: Fn(f64, f64) -> f64> Spool<S> {
    /// The section of `shape` driven by `r`, from the steady state of `r[0]`, its output's changes
    /// clamped by `limit`.
    pub(super) fn new(
        shape: &SplitShape,
        r: Vec<f64>,
        decel: f64,
        schedule: S,
        limit: Option<StateLimit>,
    ) -> Self {
        let ln_root = Complex64::new(shape.spool.norm().max(f64::MIN_POSITIVE).ln(), shape.spool.arg());
        let start = r.first().copied().unwrap_or(0.0);
        Self {
            r,
            ln_root,
            pair: shape.is_pair(),
            decel,
            schedule,
            limit,
            x: start,
            x_old: start,
            prev: start,
            prev_old: start,
        }
    }

    /// The section's output after the input `rk` is taken in.
    fn step(&mut self, rk: f64) -> f64 {
        let (x, prev) = (self.x, self.prev);
        let mut factor = (self.schedule)(x, prev);
        if prev < x {
            factor *= self.decel;
        }
        let factor = factor.max(f64::MIN_POSITIVE);
        let next = if self.pair {
            let root = (self.ln_root / factor).exp();
            // Unit-gain pair (1 − a₁ + a₂) z⁻² / (1 − a₁ z⁻¹ + a₂ z⁻²), as `unit_gain_tf` builds it.
            let (a1, a2) = (2.0 * root.re, root.norm_sqr());
            a1 * x - a2 * self.x_old + (1.0 - a1 + a2) * self.prev_old
        } else {
            // A real root's rate has no imaginary part: its exponential is real (the complex
            // one's cosine of zero, sine of zero and their products are skipped, the same number).
            let root = (self.ln_root.re / factor).exp();
            root * x + (1.0 - root) * prev
        };
        let next = match &self.limit {
            Some(limit) => limit.clamp(x, next),
            None => next,
        };
        (self.x_old, self.x) = (x, next);
        (self.prev_old, self.prev) = (prev, rk);
        next
    }
}

/// The responses of several spool sections, stepped together sample by sample. Each section's
/// samples form one chain of dependent exponentials, whose latency, not the processor's throughput,
/// sets its pace; independent chains stepped side by side overlap their latencies (what a
/// finite-difference Jacobian's columns are). Each response is the one [`respond`] gives alone, bit
/// for bit: every section does the same arithmetic in the same order.
pub(super) fn respond_each<S: Fn(f64, f64) -> f64>(mut spools: Vec<Spool<S>>) -> Vec<Vec<f64>> {
    let longest = spools.iter().map(|s| s.r.len()).max().unwrap_or(0);
    let mut out: Vec<Vec<f64>> = spools.iter().map(|s| Vec::with_capacity(s.r.len())).collect();
    for k in 0..longest {
        for (spool, y) in spools.iter_mut().zip(&mut out) {
            if let Some(&rk) = spool.r.get(k) {
                y.push(spool.step(rk));
            }
        }
    }
    out
}
