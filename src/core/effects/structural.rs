//! Structure before physics: refinements of the Wiener model itself, which the diagnosis tries
//! before it credits any physical effect.
//!
//! A model that lacks a pole (the automatic proposal dropped it, or the engineer never drew it)
//! leaves a residual that a lag block, a dead time or a sensor filter can partly absorb; without
//! these candidates such an effect would be reported as missing physics when the missing piece is
//! the linear block's structure. The refinements are one more real pole, one more pole pair, one
//! more zero, one more order of the static map, and a spool time constant that follows the
//! operating point ([`ScheduledTimeConstant`]: every turbojet's spool is slower at low speed, which
//! no Wiener model follows, and which a rise/fall asymmetry or a soak would otherwise stand in for). Each is fitted like an effect: starting points
//! from a grid (time constants, natural frequencies and dampings, zero positions) screened on the
//! identification error with the current roots, the best few refined with every root and the
//! effects' parameters free (see `fit`).
use num_complex::Complex64;

use super::fit::{Assembled, REFINED_STARTS, Structure, assemble, refine};
use super::{EffectBlock, EffectError, EffectId, ExtendedModel, FitData, apply_effect};
use crate::core::identification::cluster::natural_freq_and_damping;
use crate::core::identification::direct_fit::{pair_guesses, real_pole_guesses};
use crate::core::identification::words::root_words;

/// A zero farther than this from the origin shapes nothing: the factor (z − z₀)/(1 − z₀) it adds
/// stays within 2/|z₀| of 1 around the unit circle: under 2 % (0.2 dB) of gain and 0.6° of phase at
/// every frequency, so it only rescales the gain the static map absorbs.
const FAR_ZERO: f64 = 100.0;

/// "the linear block needs a zero at 0.412", or, for a zero beyond [`FAR_ZERO`], that it only
/// rescales the gain (the fit ran the zero away, so the structure does not need one).
fn zero_words(z: f64) -> String {
    if z.abs() > FAR_ZERO {
        format!(
            "a zero does not help: the fit puts it at {}, so far out that it changes the frequency response by \
             under 2 %",
            crate::core::numerics::stats::significant(z, 3)
        )
    } else {
        format!("the linear block needs a zero at {z:.3}")
    }
}

/// Real zeros a new zero is started from: a lead (0.9, 0.6), none (0), a lag (−0.5) — the span of
/// what one zero beside the poles can do to a step response.
const ZERO_GUESSES: [f64; 5] = [0.9, 0.6, 0.3, 0.0, -0.5];

/// A refinement of the model's structure.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum StructuralChange {
    RealPole,
    PolePair,
    Zero,
    MapOrder,
    ScheduledTimeConstant,
}

impl StructuralChange {
    /// Every refinement, in the order they are tried.
    pub const ALL: [Self; 5] =
        [Self::RealPole, Self::PolePair, Self::Zero, Self::MapOrder, Self::ScheduledTimeConstant];

    /// The id the diagnosis lists it under.
    pub fn id(self) -> &'static str {
        match self {
            Self::RealPole => "extra_real_pole",
            Self::PolePair => "extra_pole_pair",
            Self::Zero => "extra_zero",
            Self::MapOrder => "higher_map_order",
            Self::ScheduledTimeConstant => EffectId::ScheduledTimeConstant.name(),
        }
    }

    /// What the refinement changes, in one sentence.
    pub fn meaning(self) -> &'static str {
        match self {
            Self::RealPole => {
                "model structure: the linear block gets one more real pole (a lag the clusters did not give)"
            }
            Self::PolePair => {
                "model structure: the linear block gets one more pole pair (an oscillatory mode the clusters did not give)"
            }
            Self::Zero => {
                "model structure: the linear block gets one more zero (a lead or lag the clusters did not give)"
            }
            Self::MapOrder => "model structure: the static map gets one more polynomial order",
            Self::ScheduledTimeConstant => {
                "model structure: the spool time constant follows the operating point (a turbojet's spool \
                 is slower at low speed)"
            }
        }
    }
}

impl std::fmt::Display for StructuralChange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.id())
    }
}

/// "the spool time constant follows the operating point (its power balance, compressor power
/// growing as N^3.1): 2.40 times as long at the low end of the identified range as at the high end".
fn schedule_words(model: &ExtendedModel, s: &super::ScheduledTimeConstant) -> String {
    let form = match s.is_power_balance() {
        true => format!(" (its power balance, compressor power growing as N^{:.1})", s.load_exponent),
        false => String::new(),
    };
    let ratio = match model.identified_inputs() {
        Some((lo, hi)) => model.steady_spool_factor(lo) / model.steady_spool_factor(hi),
        None => (s.log_ratio + s.state_log_ratio).exp(),
    };
    format!(
        "the spool time constant follows the operating point{form}: {ratio:.2} times as long at the low \
         end of the identified range as at the high end"
    )
}

/// The model with one structural refinement, refitted on the identification data, and a sentence
/// naming what was added ("the linear block needs a pole pair near 2.31 rad/s (ζ 0.60)").
pub fn refine_structure(
    model: &ExtendedModel,
    change: StructuralChange,
    data: &FitData,
) -> Result<(ExtendedModel, String), EffectError> {
    if change == StructuralChange::ScheduledTimeConstant {
        let fitted = apply_effect(model, EffectId::ScheduledTimeConstant, data)?;
        let words = fitted.effect(EffectId::ScheduledTimeConstant).map_or_else(String::new, |b| match b {
            EffectBlock::ScheduledTimeConstant(s) => schedule_words(&fitted, s),
            _ => String::new(),
        });
        return Ok((fitted, words));
    }
    let base = Structure::of(model)?;
    let failed =
        |reason: &str| EffectError::FitFailed { run: data.run.name.clone(), reason: reason.to_owned() };
    let starts: Vec<Structure> = match change {
        StructuralChange::RealPole => real_pole_guesses(data.dt_secs, data.longest_segment_secs)
            .into_iter()
            .map(|z| with_poles(&base, &[z]))
            .collect(),
        StructuralChange::PolePair => pair_guesses(data.dt_secs, data.longest_segment_secs)
            .into_iter()
            .map(|z| with_poles(&base, &[z, z.conj()]))
            .collect(),
        StructuralChange::Zero => {
            if base.zeros.len() >= base.poles.len() {
                return Err(EffectError::NotApplicable {
                    effect: change.id().to_owned(),
                    reason: "the linear block has as many zeros as poles".to_owned(),
                });
            }
            ZERO_GUESSES
                .iter()
                .map(|&x| {
                    let mut s = base.clone();
                    s.zeros.push(Complex64::new(x, 0.0));
                    s
                })
                .collect()
        }
        StructuralChange::MapOrder => {
            if base.map_order > data.max_static_order.max(1)
                || base.map_order >= data.steady_windows.len().saturating_sub(2)
            {
                return Err(EffectError::NotApplicable {
                    effect: change.id().to_owned(),
                    reason: format!(
                        "the static map already has order {} for {} steady points",
                        base.map_order,
                        data.steady_windows.len()
                    ),
                });
            }
            vec![Structure { map_order: base.map_order + 1, ..base.clone() }]
        }
        StructuralChange::ScheduledTimeConstant => Vec::new(),
    };
    let mut screened: Vec<(f64, Structure)> =
        starts.into_iter().filter_map(|s| assemble(&s, data).map(|a| (a.cost, s))).collect();
    screened.sort_by(|a, b| a.0.total_cmp(&b.0));
    let best: Option<Assembled> = screened
        .into_iter()
        .take(REFINED_STARTS)
        .filter_map(|(_, s)| refine(&s, data).or_else(|| assemble(&s, data)))
        .min_by(|a, b| a.cost.total_cmp(&b.cost));
    let best = best.ok_or_else(|| failed("no admissible starting point"))?;
    let words = describe(change, &best.structure, data.dt_secs);
    Ok((best.model, words))
}

/// The structure with extra poles appended (the added group stays last through the refit).
fn with_poles(base: &Structure, extra: &[Complex64]) -> Structure {
    let mut s = base.clone();
    s.poles.extend_from_slice(extra);
    s
}

/// "the linear block needs a pole pair near 2.31 rad/s (ζ 0.60)", from the refitted structure, whose
/// last pole group (or zero) is the one added.
fn describe(change: StructuralChange, s: &Structure, dt_secs: f64) -> String {
    let words = |z: Complex64, pair: bool| {
        let (omega, zeta) = natural_freq_and_damping(z, dt_secs);
        root_words(z, pair, omega, zeta)
    };
    match change {
        StructuralChange::RealPole => s
            .poles
            .last()
            .map_or_else(String::new, |z| format!("the linear block needs a {}", words(*z, false))),
        StructuralChange::PolePair => {
            let upper = s.poles.iter().rev().take(2).find(|z| z.im >= 0.0).copied();
            upper.map_or_else(String::new, |z| format!("the linear block needs a pole {}", words(z, true)))
        }
        StructuralChange::Zero => s.zeros.last().map_or_else(String::new, |z| zero_words(z.re)),
        StructuralChange::MapOrder => format!("the static map needs order {}", s.map_order),
        StructuralChange::ScheduledTimeConstant => String::new(),
    }
}
