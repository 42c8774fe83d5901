//! Operating points: where a model holds still, how much the output moves per unit of input there,
//! and the local linear model a controller is designed on.
//!
//! At a steady input u* the linear block settles at `v* = G(1)·u* + offset` and the output at
//! `y* = F(v*)`, F the static map with its kink. For small deviations the model is the linear
//! block scaled by the map's slope: `K·G(z)/G(1)` with the local gain `K = F′(v*)·G(1)`. The effects
//! are linearised where they act:
//! - `transport_delay`: the interpolated delay `(1 − f)·z^(−n) + f·z^(−n−1)` (exactly linear);
//! - `scheduled_time_constant`: the spool root at the time constant of u* (state and target both at
//!   u*), `p → p^(1/factor)`;
//! - `asymmetric_dynamics`: the rising time constant (a small step up; the falling one is the
//!   block's `decel_factor` times longer);
//! - `thermal_soak`: its branch `(1 − g) + g·(1 − a)/(1 − a·z⁻¹)` (unit steady gain);
//! - `sensor_dynamics`: lag and resonance as the simulation discretises them;
//! - `ambient_correction`: taken at ISA sea-level conditions (θ = δ = 1), where corrected and
//!   physical quantities coincide;
//! - `calibration_drift`: a per-run input offset, no part of the dynamics (u* is the logged input);
//! - `read_off_speed`: the polynomial's slope at the steady speed, `P′(F(v*))`, multiplies K.
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::d2c::{ContinuousTf, d2c_zoh};
use crate::core::effects::{AsymmetricDynamics, EffectBlock, ExtendedModel};
use crate::core::numerics::cutoff::{LowFrequencyLevel, cutoff_rad_s};
use crate::core::numerics::poly::{self, convolve};
use crate::core::numerics::tf::{DiscreteTf, alternates_sign, log_space};

/// Where an operating point comes from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind", content = "run")]
pub enum PointSource {
    /// Evenly spaced across the identified input range.
    Grid,
    /// The plateau of a steady run (its name).
    SteadyRun(String),
}

/// One root of a local model, in z and as its zero-order-hold continuous equivalent.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LocalPole {
    /// The discrete root.
    pub z: Complex64,
    /// `ln(z)/T`, rad/s; `None` on the negative real axis (no continuous equivalent).
    pub s: Option<Complex64>,
    /// Time constant −1/Re(s) of a real root, s.
    pub tau_s: Option<f64>,
    /// Natural frequency |s|, rad/s.
    pub wn_rad_s: Option<f64>,
    /// Damping ratio −Re(s)/|s|.
    pub zeta: Option<f64>,
    /// 95 % intervals of the three from the model's parameter covariance (see
    /// `core::control::bands`); `None` until they are computed or where they do not apply.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tau_s_ci95: Option<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wn_rad_s_ci95: Option<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub zeta_ci95: Option<[f64; 2]>,
}

impl LocalPole {
    /// "τ 1.820 s" for a real pole, "ωn 2.928, ζ 0.515" for a pair, the z-plane root otherwise;
    /// `digits` after the point.
    pub fn describe(&self, digits: usize) -> String {
        match (self.tau_s, self.wn_rad_s, self.zeta) {
            (Some(tau), _, _) => format!("τ {tau:.digits$} s"),
            (None, Some(wn), Some(zeta)) => format!("ωn {wn:.digits$}, ζ {zeta:.digits$}"),
            _ => format!("z {:.4}{:+.4}i", self.z.re, self.z.im),
        }
    }
}

/// Share of the identification input left out at each end of the identified range: a dropout or a
/// spike (a few samples of a run of thousands) must not stretch the range a gain schedule covers.
const RANGE_TAIL: f64 = 0.01;

/// The identified input range of an identification input: its 1st to 99th percentile.
pub fn identified_range(u: &[f64]) -> (f64, f64) {
    use crate::core::numerics::stats::quantile;
    (quantile(u, RANGE_TAIL), quantile(u, 1.0 - RANGE_TAIL))
}

/// Step-response figures of a local model (from rest, normalised by its final value).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StepFigures {
    /// 10–90 % rise time, s.
    pub rise_s: Option<f64>,
    /// Time after which the response stays within 2 % of its final value, s.
    pub settling_s: Option<f64>,
    /// Peak above the final value, % of the final value.
    pub overshoot_pct: f64,
    /// 95 % intervals of the rise and settling times (see `core::control::bands`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rise_s_ci95: Option<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub settling_s_ci95: Option<[f64; 2]>,
}

/// A model's steady state at one input and its local linear model there.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OperatingPoint {
    /// Where the point comes from.
    pub source: PointSource,
    /// Steady input u*.
    pub u: f64,
    /// The linear block's steady output v*.
    pub v: f64,
    /// Steady output y*.
    pub y: f64,
    /// Local gain dy/du at u*.
    pub gain: f64,
    /// 95 % intervals of the local gain and the bandwidth from the model's parameter covariance
    /// (see `core::control::bands`); `None` until they are computed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gain_ci95: Option<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bandwidth_rad_s_ci95: Option<[f64; 2]>,
    /// Local linear model K·G(z)/G(1), the effects linearised (see the module documentation).
    pub local: DiscreteTf,
    /// Its poles (one per conjugate pair, upper half-plane), slowest first.
    pub poles: Vec<LocalPole>,
    /// −3 dB bandwidth of the local model, rad/s (`None` when it does not fall 3 dB below
    /// Nyquist).
    pub bandwidth_rad_s: Option<f64>,
    /// Step-response figures.
    pub step: StepFigures,
    /// Zero-order-hold continuous equivalent of the local model.
    pub continuous: Option<ContinuousTf>,
    /// Why there is no continuous equivalent, when there is none.
    pub continuous_note: Option<String>,
}

/// Why operating points cannot be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OperatingPointError {
    #[error("the linear block of '{output}' has no steady state: {reason}")]
    NoSteadyState { output: String, reason: String },
    #[error("the input range {lo}..{hi} of '{output}' is empty or not finite")]
    BadRange { output: String, lo: f64, hi: f64 },
    #[error("the local model of '{output}' at u = {u}: {reason}")]
    LocalModel { output: String, u: f64, reason: String },
}

/// Grid points across the identified input range: the range split into eight equal steps, its ends
/// included, so a gain schedule has a point every 12.5 % of the range.
pub const GRID_POINTS: usize = 9;

/// Operating points of `model`: [`GRID_POINTS`] across `input_range` (the identified range), then
/// one per steady plateau `(run name, steady input)`.
pub fn operating_points(
    model: &ExtendedModel,
    input_range: (f64, f64),
    plateaus: &[(String, f64)],
) -> Result<Vec<OperatingPoint>, OperatingPointError> {
    points_at(model, input_range, plateaus, Detail::Full)
}

/// [`operating_points`] for the models drawn from a covariance: without the continuous-time
/// equivalents (`continuous` is `None`) and with the bandwidth searched on [`DRAW_POINTS_PER_DECADE`],
/// what the intervals need at a fraction of the cost.
pub(crate) fn operating_points_without_continuous(
    model: &ExtendedModel,
    input_range: (f64, f64),
    plateaus: &[(String, f64)],
) -> Result<Vec<OperatingPoint>, OperatingPointError> {
    points_at(model, input_range, plateaus, Detail::Draw)
}

/// The grid's points and the plateaus' in `detail`; a range that is empty or not finite refused.
fn points_at(
    model: &ExtendedModel,
    input_range: (f64, f64),
    plateaus: &[(String, f64)],
    detail: Detail,
) -> Result<Vec<OperatingPoint>, OperatingPointError> {
    let (lo, hi) = input_range;
    if !(lo.is_finite() && hi.is_finite() && hi > lo) {
        return Err(OperatingPointError::BadRange { output: model.output.clone(), lo, hi });
    }
    let grid =
        (0..GRID_POINTS).map(|i| (PointSource::Grid, lo + (hi - lo) * i as f64 / (GRID_POINTS - 1) as f64));
    let steady = plateaus.iter().map(|(run, u)| (PointSource::SteadyRun(run.clone()), *u));
    grid.chain(steady).map(|(source, u)| operating_point(model, source, u, detail)).collect()
}

/// How much of an operating point to compute.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Detail {
    /// Everything, the bandwidth on [`BODE_POINTS_PER_DECADE`].
    Full,
    /// No continuous-time equivalent, the bandwidth on [`DRAW_POINTS_PER_DECADE`].
    Draw,
}

fn operating_point(
    model: &ExtendedModel,
    source: PointSource,
    u: f64,
    detail: Detail,
) -> Result<OperatingPoint, OperatingPointError> {
    let output = model.output.clone();
    let linear = &model.wiener.linear;
    let g1 = linear
        .tf
        .dc_gain()
        .map_err(|e| OperatingPointError::NoSteadyState { output: output.clone(), reason: e.to_string() })?;
    let v = g1 * u + linear.offset;
    let y = model.static_output(v);
    let gain = model.static_slope(v) * g1;
    let unit = local_dynamics(model, u).map_err(|reason| OperatingPointError::LocalModel {
        output: output.clone(),
        u,
        reason,
    })?;
    let local = DiscreteTf::new(
        unit.num_zinv.iter().map(|b| b * gain).collect(),
        unit.den_zinv.clone(),
        unit.dt_secs,
    )
    .map_err(|e| OperatingPointError::LocalModel { output: output.clone(), u, reason: e.to_string() })?;
    let poles = local_poles(&unit).map_err(|e| OperatingPointError::LocalModel {
        output: output.clone(),
        u,
        reason: e.to_string(),
    })?;
    let (continuous, continuous_note) = match (detail == Detail::Full).then(|| d2c_zoh(&local)) {
        Some(Ok(c)) => (Some(c), None),
        Some(Err(e)) => (None, Some(e.to_string())),
        None => (None, None),
    };
    Ok(OperatingPoint {
        source,
        u,
        v,
        y,
        gain,
        gain_ci95: None,
        bandwidth_rad_s_ci95: None,
        bandwidth_rad_s: bandwidth(
            &unit,
            if detail == Detail::Full { BODE_POINTS_PER_DECADE } else { DRAW_POINTS_PER_DECADE },
        ),
        step: step_figures(&unit, &poles),
        local,
        poles,
        continuous,
        continuous_note,
    })
}

/// The unit-steady-gain local dynamics of `model` at steady input `u` (see the module
/// documentation for how each effect enters).
pub fn local_dynamics(model: &ExtendedModel, u: f64) -> Result<DiscreteTf, String> {
    let tf = &model.wiener.linear.tf;
    let dt = tf.dt_secs;
    let g1 = tf.dc_gain().map_err(|e| e.to_string())?;
    let split_needed = model
        .effects
        .iter()
        .any(|e| matches!(e, EffectBlock::ScheduledTimeConstant(_) | EffectBlock::AsymmetricDynamics(_)));
    let (num, den) = if split_needed {
        let (poles, zeros) = model.roots().map_err(|e| e.to_string())?;
        let split = AsymmetricDynamics::split(&poles, &zeros, dt).map_err(|e| e.to_string())?;
        let factor = model.steady_spool_factor(u).max(f64::MIN_POSITIVE);
        let ln_root = Complex64::new(split.spool.norm().max(f64::MIN_POSITIVE).ln(), split.spool.arg());
        let root = (ln_root / factor).exp();
        let (spool_num, spool_den) = if split.is_pair() {
            let (a1, a2) = (2.0 * root.re, root.norm_sqr());
            (vec![0.0, 0.0, 1.0 - a1 + a2], vec![1.0, -a1, a2])
        } else {
            (vec![0.0, 1.0 - root.re], vec![1.0, -root.re])
        };
        let mut num: Vec<f64> = vec![0.0; tf.input_delay()];
        num.push(1.0);
        let (mut num, mut den) = (convolve(&num, &spool_num), spool_den);
        if let Some(rest) = &split.rest {
            num = convolve(&num, &rest.num_zinv);
            den = convolve(&den, &rest.den_zinv);
        }
        (num, den)
    } else {
        (tf.num_zinv.iter().map(|b| b / g1).collect(), tf.den_zinv.clone())
    };
    let (fixed_num, fixed_den) = effect_dynamics(model);
    let (num, den) = (convolve(&num, &fixed_num), convolve(&den, &fixed_den));
    let local = DiscreteTf::new(num, den, dt).map_err(|e| e.to_string())?;
    // Unit steady gain by construction; dividing by the computed gain removes rounding.
    let gain = local.dc_gain().map_err(|e| e.to_string())?;
    DiscreteTf::new(local.num_zinv.iter().map(|b| b / gain).collect(), local.den_zinv.clone(), dt)
        .map_err(|e| e.to_string())
}

/// The part of every local model that does not depend on the operating point, in z⁻¹ (numerator,
/// denominator; unit steady gain): the effects' linear dynamics — a dead time's interpolating FIR,
/// the soak branch, the sensor's lag and resonance — in series.
pub fn effect_dynamics(model: &ExtendedModel) -> (Vec<f64>, Vec<f64>) {
    let dt = model.wiener.linear.tf.dt_secs;
    let (mut num, mut den) = (vec![1.0], vec![1.0]);
    for effect in &model.effects {
        let (n, d) = match effect {
            EffectBlock::TransportDelay(delay) => {
                let whole = delay.delay_samples.floor();
                let frac = delay.delay_samples - whole;
                let mut n = vec![0.0; whole as usize];
                n.extend([1.0 - frac, frac]);
                (n, vec![1.0])
            }
            EffectBlock::ThermalSoak(soak) => {
                let a = (-dt / soak.tau_s.max(f64::MIN_POSITIVE)).exp();
                (vec![1.0 - soak.gain * a, -(1.0 - soak.gain) * a], vec![1.0, -a])
            }
            EffectBlock::SensorDynamics(sensor) => sensor.discrete_tf(dt),
            _ => continue,
        };
        num = convolve(&num, &n);
        den = convolve(&den, &d);
    }
    (num, den)
}

fn local_poles(tf: &DiscreteTf) -> Result<Vec<LocalPole>, poly::PolyError> {
    let dt = tf.dt_secs;
    let mut roots: Vec<Complex64> =
        tf.poles()?.into_iter().filter(|p| p.im >= -1e-12 && p.norm() > 1e-12).collect();
    roots.sort_by(|a, b| b.norm().total_cmp(&a.norm()));
    Ok(roots
        .into_iter()
        .map(|z| {
            let s = (!alternates_sign(z)).then(|| Complex64::new(z.norm().ln(), z.arg()) / dt);
            let wn = s.map(|s| s.norm());
            LocalPole {
                z,
                s,
                tau_s: s.filter(|s| s.im.abs() <= 1e-12 && s.re < 0.0).map(|s| -1.0 / s.re),
                wn_rad_s: wn,
                zeta: s.filter(|s| s.norm() > 0.0).map(|s| -s.re / s.norm()),
                tau_s_ci95: None,
                wn_rad_s_ci95: None,
                zeta_ci95: None,
            }
        })
        .collect())
}

/// Frequencies of the bandwidth search per decade: a 0.5 % step in ω, far finer than a cut-off is
/// read to.
const BODE_POINTS_PER_DECADE: usize = 400;
/// Frequencies per decade of the bandwidth search on models drawn from a covariance: a 4.7 % step,
/// with the crossing interpolated between grid points. A local model's magnitude is smooth on that
/// scale (its poles lie at least a few percent of their frequency from the unit circle), so the
/// interpolation errs by a small fraction of a percent, far below the ~1.6 % that the percentiles
/// of 200 draws carry themselves; the search costs an eighth of the full one.
const DRAW_POINTS_PER_DECADE: usize = 50;

/// −3 dB bandwidth of a unit-gain model: the first fall 3 dB below its steady gain, searched from
/// four decades below its slowest pole (where the magnitude is flat) up to Nyquist.
fn bandwidth(unit: &DiscreteTf, points_per_decade: usize) -> Option<f64> {
    let nyquist = std::f64::consts::PI / unit.dt_secs;
    let slowest = local_poles(unit).ok()?.iter().filter_map(|p| p.wn_rad_s).fold(f64::INFINITY, f64::min);
    let lo = (slowest.min(nyquist) * 1e-4).max(nyquist * 1e-9);
    let decades = (nyquist / lo).log10();
    let omegas = log_space(lo, nyquist * 0.999, (decades * points_per_decade as f64).ceil() as usize + 2);
    let mag_db: Vec<f64> = omegas.iter().map(|w| 20.0 * unit.freq_response(*w).norm().log10()).collect();
    cutoff_rad_s(&omegas, &mag_db, LowFrequencyLevel::Db(0.0)).ok().flatten()
}

/// Step response horizon: ten time constants of the slowest pole (e⁻¹⁰ of its transient is left,
/// far inside the 2 % band), at most this many samples.
const MAX_STEP_SAMPLES: usize = 200_000;

fn step_figures(unit: &DiscreteTf, poles: &[LocalPole]) -> StepFigures {
    let dt = unit.dt_secs;
    let slowest = poles.iter().map(|p| p.z.norm()).fold(0.0, f64::max);
    let tau_samples = if slowest > 0.0 && slowest < 1.0 { -1.0 / slowest.ln() } else { 1.0 };
    let delay = unit.num_zinv.len() as f64;
    let n = ((10.0 * tau_samples + delay + 10.0).ceil() as usize).clamp(20, MAX_STEP_SAMPLES);
    let y = unit.simulate_with_history(&vec![1.0; n], 0.0, 0.0);
    let crossing = |level: f64| {
        y.iter().position(|v| *v >= level).map(|k| {
            let prev = if k > 0 { y[k - 1] } else { 0.0 };
            let frac = if y[k] > prev { (level - prev) / (y[k] - prev) } else { 1.0 };
            (k as f64 - 1.0 + frac) * dt
        })
    };
    let rise_s = match (crossing(0.1), crossing(0.9)) {
        (Some(a), Some(b)) => Some(b - a),
        _ => None,
    };
    let settling_s = y.iter().rposition(|v| (v - 1.0).abs() > 0.02).map(|k| (k + 1) as f64 * dt);
    let peak = y.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    StepFigures {
        rise_s,
        settling_s,
        overshoot_pct: (100.0 * (peak - 1.0)).max(0.0),
        ..StepFigures::default()
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn a_first_order_lag_has_its_textbook_figures() {
        // τ = 1 s sampled at 10 ms: rise 2.197 τ, settling 3.912 τ, no overshoot, bandwidth 1/τ.
        let dt = 0.01;
        let a = (-dt / 1.0f64).exp();
        let unit = DiscreteTf::new(vec![0.0, 1.0 - a], vec![1.0, -a], dt).unwrap();
        let poles = local_poles(&unit).unwrap();
        assert!((poles[0].tau_s.unwrap() - 1.0).abs() < 1e-9);
        let step = step_figures(&unit, &poles);
        assert!((step.rise_s.unwrap() - 9f64.ln()).abs() < 0.011, "{step:?}");
        assert!((step.settling_s.unwrap() - 50f64.ln()).abs() < 0.011, "{step:?}");
        assert!(step.overshoot_pct.abs() < 1e-9);
        let bw = bandwidth(&unit, BODE_POINTS_PER_DECADE).unwrap();
        assert!((bw - 1.0).abs() < 0.01, "{bw}");
    }

    #[test]
    fn a_light_pair_overshoots_as_its_damping_says() {
        // ζ = 0.3: overshoot exp(−πζ/√(1 − ζ²)) = 37.2 %.
        let (dt, wn, zeta) = (0.001, 5.0, 0.3);
        let s = Complex64::new(-zeta * wn, wn * (1.0 - zeta * zeta).sqrt());
        let p = (s * dt).exp();
        let unit = crate::core::identification::wiener::unit_gain_tf(&[p, p.conj()], &[], dt).unwrap();
        let poles = local_poles(&unit).unwrap();
        assert_eq!(poles.len(), 1);
        assert!(
            (poles[0].wn_rad_s.unwrap() - wn).abs() < 1e-9 && (poles[0].zeta.unwrap() - zeta).abs() < 1e-9
        );
        let step = step_figures(&unit, &poles);
        let expected = 100.0 * (-std::f64::consts::PI * zeta / (1.0 - zeta * zeta).sqrt()).exp();
        assert!((step.overshoot_pct - expected).abs() < 0.3, "{} vs {expected}", step.overshoot_pct);
    }
}
