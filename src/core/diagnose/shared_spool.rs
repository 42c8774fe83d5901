//! The spool's own dynamics, measured where the spool is measured and shared with every output that
//! follows it.
//!
//! Shaft speed and thrust follow one spool. How its time constant follows the operating point, how
//! much slower it decelerates than it accelerates and how much of a power change soaks into the
//! metal are properties of the spool, the same numbers whichever output is read. The shaft speed
//! measures the spool directly, with a noise of a few tenths of a percent; thrust sees it through a
//! strongly curved map and a load cell whose noise at idle is a good part of the value. Fitted on
//! thrust's own data, those blocks follow the load cell's noise and the map's curvature. On 20
//! effect-free engines of the family, thrust's held-out error after the loop has a median of
//! 1.76 %; with the speed's time-constant schedule carried over unchanged where thrust's validation
//! runs do not lean against it, 1.08 % (lower on the 15 engines where it was kept, the same on the
//! other 5); refitted on thrust from there, about 1.5 %. So the speed model's spool blocks are given
//! to the other outputs' models as they are ([`share_spool_dynamics`]), and each output's own
//! validation runs can only speak against them.
//!
//! Some of the spool's blocks cannot be carried over alone: a rate limit on the spool's
//! acceleration is stated in rpm/s through the speed's own map, which another output's model does not
//! hold. So last the output is also offered read off the speed's whole model (one spool, a static
//! map per output: [`ReadOffSpeed`]), on the same terms. On the same 20 engines it is kept on 15,
//! and thrust's median held-out error falls from 1.08 % to 0.81 %; on the family's rate-limit
//! engines 7 and 11 thrust goes from 2.96 and 3.62 % to 0.45 and 0.58 %.
use super::witness::{Comparison, Scores, ValidationResponses, p_text};
use super::{DiagnoseError, RIVAL_LEVEL, measured};
use crate::core::effects::thermal_soak::{exponent_affine_in_power, power_exponent_without_speed};
use crate::core::effects::{
    AmbientCorrection, EffectBlock, EffectId, ExtendedModel, ReadOffSpeed, ThermalSoak,
};
use crate::core::identification::initial_state::InitialState;
use crate::core::run::{Quantity, Run};

/// The blocks whose parameters are the spool's own, the same on every output: the scheduled time
/// constant (its schedule is written in units of the input, which the unit-gain spool state of
/// every output's linear block shares), asymmetric dynamics (a ratio of time constants) and the
/// thermal soak (a share of every power change and a time constant, applied to the unit-gain
/// response; each output soaks its own power, see `with_block`). Not shared, although they act before the spool too: the rate limit (a speed model
/// states it in rpm/s through its own map, another output in units of its own `v`), the dead time
/// (each output's linear block carries its own; adding the speed's would count it twice) and the
/// calibration drift (each output calibrates a run on its own holds).
pub const SHARED_SPOOL_BLOCKS: [EffectId; 3] =
    [EffectId::ScheduledTimeConstant, EffectId::AsymmetricDynamics, EffectId::ThermalSoak];

/// One spool block offered to another output's model, and what that output's validation runs said
/// (report.json `outputs.<o>.shared_spool`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SharedBlock {
    pub id: EffectId,
    /// The output the block was fitted on (the shaft speed).
    pub from: String,
    /// Whether the output already had a block of this kind, fitted on its own data (replaced).
    pub replaces_own: bool,
    /// The output's validation error beyond the noise without and with the block (see `loss`).
    pub beyond_noise_before: f64,
    pub beyond_noise_after: f64,
    /// The output's validation RMSPE without and with the block, %.
    pub rmspe_before_pct: f64,
    pub rmspe_after_pct: f64,
    /// One-sided p-value of "the output's model is no worse with it" on the output's validation
    /// runs (the diagnosis's comparison, samples and responses, read the other way round).
    pub p_worse: f64,
    /// Whether the model keeps it: the validation runs do not lean against it (`p_worse` ≥
    /// [`RIVAL_LEVEL`]).
    pub taken: bool,
    /// The other blocks offered with it, as one set (the speed's blocks were fitted together).
    pub with: Vec<EffectId>,
}

impl SharedBlock {
    /// The blocks of `set` from the output `from`, offered together, judged once on the output's
    /// validation scores `before` and `after` them: kept unless the runs lean against them, the
    /// diagnosis's comparison read the other way round giving "no worse" a p-value below
    /// [`RIVAL_LEVEL`]. `replaces_own` says of each block whether the output had its own of the kind.
    fn judged(
        set: &[EffectId],
        from: &str,
        replaces_own: impl Fn(EffectId) -> bool,
        before: &Scores,
        after: &Scores,
    ) -> Vec<Self> {
        let worse = Comparison::of(after, before, after);
        let taken = after.beyond_noise().is_finite() && worse.p_value >= RIVAL_LEVEL;
        let block = |id: EffectId| Self {
            id,
            from: from.to_owned(),
            replaces_own: replaces_own(id),
            beyond_noise_before: before.beyond_noise(),
            beyond_noise_after: after.beyond_noise(),
            rmspe_before_pct: before.rmspe(),
            rmspe_after_pct: after.rmspe(),
            taken,
            p_worse: worse.p_value,
            with: set.iter().copied().filter(|other| *other != id).collect(),
        };
        set.iter().map(|id| block(*id)).collect()
    }

    /// "the spool's scheduled_time_constant from shaft_speed_rpm (in place of its own, fitted on this
    /// output): validation from 4.779 % to 4.731 %, from 0.24 σ to 0.17 σ beyond the noise (worse
    /// beyond noise: p = 0.9420); shared".
    pub fn words(&self) -> String {
        let what = if self.id == EffectId::ReadOffSpeed {
            format!(
                "read off {}'s model (its linear block, effects and map, then a quartic in the speed fitted on \
                 the identification run) in place of its own",
                self.from
            )
        } else {
            format!(
                "the spool's {} from {}{}",
                self.id,
                self.from,
                if self.replaces_own { " (in place of its own, fitted on this output)" } else { "" }
            )
        };
        let with = match self.with.as_slice() {
            [] => String::new(),
            others => format!(
                ", offered together with {}",
                others.iter().map(|id| id.name()).collect::<Vec<_>>().join(" and ")
            ),
        };
        format!(
            "{what}{with}: validation from {:.3} % to {:.3} %, from {:.2} σ to {:.2} σ beyond the noise (worse \
             beyond noise: p = {}); {}",
            self.rmspe_before_pct,
            self.rmspe_after_pct,
            self.beyond_noise_before,
            self.beyond_noise_after,
            p_text(self.p_worse),
            match (self.taken, self.id == EffectId::ReadOffSpeed) {
                (true, true) => "taken",
                (true, false) => "shared",
                (false, _) => "not taken: this output's validation runs lean against it",
            }
        )
    }
}

/// `model` (of an output other than the shaft speed) with the spool blocks of `spool` (the shaft
/// speed's model) in [`SHARED_SPOOL_BLOCKS`], with the speed's parameters: all of them together
/// first (the speed's blocks were fitted together), then each not yet taken alone, in the catalog's
/// order. A set is kept unless the output's validation runs lean against it: the diagnosis's own
/// comparison, read the other way round, gives "no worse" a p-value below [`RIVAL_LEVEL`] (worse is
/// more likely than not). The speed has shown the blocks where the spool is measured, and this
/// output's data, too noisy to show them (that is why they are shared), need only not speak against
/// them: on the family's engines a set that thrust's validation runs leaned against but did not
/// refute at p < 0.01 still raised thrust's held-out error (asymmetric dynamics on engine 11, 2.49 %
/// to 3.56 %). A kept set replaces the output's own blocks of the kind.
///
/// Last, the output read off the speed's whole model is offered ([`read_off_the_speed`]), on the
/// same terms against the model the blocks left.
pub fn share_spool_dynamics(
    model: &ExtendedModel,
    spool: &ExtendedModel,
    ident: &Run,
    validation: &[&Run],
    initial: InitialState,
) -> Result<(ExtendedModel, Vec<SharedBlock>), DiagnoseError> {
    let is_speed = |output: &str| Quantity::of(output) == Some(Quantity::ShaftSpeed);
    if is_speed(&model.output) || !is_speed(&spool.output) || validation.is_empty() {
        return Ok((model.clone(), Vec::new()));
    }
    for run in validation {
        measured(run, &model.output)?;
    }
    let responses = ValidationResponses::of(validation);
    let blocks: Vec<&EffectBlock> = spool.effects.iter().filter(|b| carried_alone(b)).collect();
    let mut current = model.clone();
    let mut scores = Scores::of(&current, validation, initial, &responses)?;
    let mut offered = Vec::new();
    // The speed's blocks were fitted together: offered together first, then each alone.
    let together = (blocks.len() > 1).then(|| blocks.clone());
    for set in together.into_iter().chain(blocks.iter().map(|b| vec![*b])) {
        if set.iter().all(|b| offered.iter().any(|o: &SharedBlock| o.taken && o.id == b.id())) {
            continue;
        }
        let candidate = set.iter().fold(current.clone(), |m, b| with_block(&m, b, spool));
        // Blocks the output's model cannot run (no spool root to schedule) are not offered.
        let Ok(after) = Scores::of(&candidate, validation, initial, &responses) else { continue };
        let ids: Vec<EffectId> = set.iter().map(|b| b.id()).collect();
        let judged =
            SharedBlock::judged(&ids, &spool.output, |id| current.effect(id).is_some(), &scores, &after);
        let taken = judged.first().is_some_and(|b| b.taken);
        offered.extend(judged);
        if taken {
            (current, scores) = (candidate, after);
        }
    }
    if let Some(candidate) = read_off_the_speed(&current, spool, ident)
        && let Ok(after) = Scores::of(&candidate, validation, initial, &responses)
    {
        let read_off =
            SharedBlock::judged(&[EffectId::ReadOffSpeed], &spool.output, |_| true, &scores, &after);
        if read_off.first().is_some_and(|b| b.taken) {
            current = candidate;
        }
        offered.extend(read_off);
    }
    Ok((current, offered))
}

/// Whether the speed model's block can be carried over to another output's model as it is: one of
/// [`SHARED_SPOOL_BLOCKS`], but not a schedule that runs the spool's power balance, which reads the
/// speed through the speed's own map (another output's map would read it wrongly, as the rate
/// limit's rpm/s would be): the read-off of the speed carries it.
fn carried_alone(block: &EffectBlock) -> bool {
    match block {
        EffectBlock::ScheduledTimeConstant(s) => !s.is_power_balance(),
        b => SHARED_SPOOL_BLOCKS.contains(&b.id()),
    }
}

/// The output of `model` read off the speed's model `spool`: the speed's linear block, effects and
/// map, then a [`ReadOffSpeed`] polynomial fitted on `ident`'s measured speed and output. Where
/// the speed's model is corrected for the inlet conditions, the polynomial relates the corrected
/// speed and the output corrected by its own law (`F/δ` for thrust). `None` when the run lacks
/// either output or the conditions, or the polynomial cannot be fitted.
fn read_off_the_speed(model: &ExtendedModel, spool: &ExtendedModel, ident: &Run) -> Option<ExtendedModel> {
    let mut speed = ident.output(&spool.output)?.values.clone();
    let mut output = ident.output(&model.output)?.values.clone();
    let correction = match spool.effect(EffectId::AmbientCorrection) {
        Some(EffectBlock::AmbientCorrection(speed_correction)) => {
            let conditions = AmbientCorrection::conditions(ident).ok()?;
            let own = AmbientCorrection::for_output(&model.output).ok()?;
            let divide = |y: &mut [f64], by: Vec<f64>| y.iter_mut().zip(by).for_each(|(y, f)| *y /= f);
            divide(&mut speed, speed_correction.output_factor(&conditions));
            divide(&mut output, own.output_factor(&conditions));
            Some(own)
        }
        _ => None,
    };
    let block = ReadOffSpeed::fit(&speed, &output, correction.as_ref()).ok()?;
    let mut read = spool.clone();
    read.output = model.output.clone();
    read.with_effect(EffectBlock::ReadOffSpeed(block)).ok()
}

/// `model` with `block` in place of its own of the kind (or added), the blocks in catalog order. A
/// soak keeps the share and time constant of the speed's model `spool`, and acts on this output's
/// own power ([`own_power_exponent`]).
fn with_block(model: &ExtendedModel, block: &EffectBlock, spool: &ExtendedModel) -> ExtendedModel {
    let mut m = model.clone();
    let block = match block {
        EffectBlock::ThermalSoak(soak) => EffectBlock::ThermalSoak(ThermalSoak {
            power_exponent: own_power_exponent(model, spool),
            ..soak.clone()
        }),
        _ => block.clone(),
    };
    m.effects.retain(|e| e.id() != block.id());
    m.effects.push(block);
    m.effects.sort_by_key(EffectBlock::rank);
    m
}

/// The power of `model`'s output a soak acts on: its own soak's exponent (fitted where the run
/// measured the speed beside it), or else the power of its output most nearly affine in N³ over
/// the two models' steady states across the range its map was identified on
/// ([`exponent_affine_in_power`]), or where that cannot be read the exponent for a run without
/// the speed.
fn own_power_exponent(model: &ExtendedModel, spool: &ExtendedModel) -> f64 {
    if let Some(EffectBlock::ThermalSoak(own)) = model.effect(EffectId::ThermalSoak) {
        return own.power_exponent;
    }
    let steady = model.identified_inputs().map(|(lo, hi)| {
        (0..=STEADY_POINTS)
            .map(|i| lo + (hi - lo) * i as f64 / STEADY_POINTS as f64)
            .filter_map(|u| Some((spool.steady_output(u)?, model.steady_output(u)?)))
            .unzip::<_, _, Vec<f64>, Vec<f64>>()
    });
    steady
        .and_then(|(n, y)| exponent_affine_in_power(&n, &y))
        .unwrap_or_else(|| power_exponent_without_speed(&model.output))
}

/// Steady states sampled across the identified range: a smooth map's power law needs no more.
const STEADY_POINTS: usize = 50;
