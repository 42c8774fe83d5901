//! `thermal_soak`: casing and rotor absorb heat after a power change.
use super::Evidence;
use super::ParamSpec;
use super::stats::{ResidualTrace, correlation, low_pass};

/// Casing and rotor soak: after a power change the metal absorbs a share `gain` of it and gives it
/// back with the slow time constant `tau_s` (tens of seconds). In the model a parallel slow
/// first-order branch is added to the linear block's output,
/// `v ← (1 − g)·v + g·S_τ(z)·v` with `S_τ` a unit-gain first-order lag, so steady states are
/// unchanged and every step ends in a creeping tail.
#[derive(Clone, Debug, PartialEq)]
pub struct ThermalSoak {
    /// Share g of a power change that arrives slowly.
    pub gain: f64,
    /// Soak time constant τ, s.
    pub tau_s: f64,
}

/// Time constants tried as starting points, s.
const TAU_GRID_S: [f64; 6] = [5.0, 10.0, 20.0, 40.0, 80.0, 160.0];

impl ThermalSoak {
    /// The linear block's output with the soak branch added.
    pub fn apply(&self, v: &[f64], dt_secs: f64) -> Vec<f64> {
        let slow = low_pass(v, dt_secs, self.tau_s);
        v.iter().zip(&slow).map(|(vk, sk)| vk + self.gain * (sk - vk)).collect()
    }

    pub(super) fn free_params(&self) -> Vec<f64> {
        vec![self.gain, self.tau_s.ln()]
    }

    pub(super) fn with_free_params(&self, theta: &[f64]) -> Option<Self> {
        let (&gain, &ln_tau) = (theta.first()?, theta.get(1)?);
        let tau_s = ln_tau.exp();
        let admissible = gain.abs() < 0.9 && (0.5..=5000.0).contains(&tau_s);
        admissible.then_some(Self { gain, tau_s })
    }

    pub(super) fn guesses() -> Vec<Self> {
        TAU_GRID_S.iter().flat_map(|&tau_s| [-0.1, 0.05, 0.1, 0.2].map(|gain| Self { gain, tau_s })).collect()
    }
}

/// How well the residual follows the slow-filtered history of the model's own response (what a
/// missing soak leaves behind), at the best time constant of the grid.
pub(super) fn evidence(traces: &[ResidualTrace]) -> Evidence {
    let best = TAU_GRID_S
        .iter()
        .map(|&tau_s| {
            let (mut r_sum, mut n) = (0.0, 0usize);
            for t in traces {
                let slow = low_pass(&t.y_hat, t.dt_secs, tau_s);
                let creep: Vec<f64> = slow.iter().zip(&t.y_hat).map(|(s, y)| s - y).collect();
                r_sum += correlation(&t.residual(), &creep) * t.y.len() as f64;
                n += t.y.len();
            }
            (tau_s, r_sum / n.max(1) as f64)
        })
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()));
    let Some((tau_s, r)) = best else { return Evidence::none("no response to look at") };
    let meaning = if r.abs() > 0.5 {
        "the response keeps creeping long after each power change"
    } else if r.abs() > 0.2 {
        "some slow creep after power changes"
    } else {
        "little slow creep after power changes"
    };
    Evidence {
        sentence: format!(
            "residual follows the {tau_s:.0} s-filtered history of the response, r = {r:.2}: {meaning}"
        ),
        supports: r.abs() > 0.2,
    }
}

block_impl!(
    ThermalSoak { gain, tau_s },
    params: &[ParamSpec::real("gain", -0.9, 0.9), ParamSpec::real("tau_s", 0.1, 5000.0)],
    physics: "casing and rotor absorb heat after a power change: a share g of every change arrives \
         with a slow time constant τ",
    evidence: evidence
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn soak_keeps_steady_states_and_creeps() {
        let soak = ThermalSoak { gain: 0.2, tau_s: 10.0 };
        let mut v = vec![1.0; 10];
        v.extend(vec![2.0; 2000]);
        let out = soak.apply(&v, 0.1);
        assert!((out[5] - 1.0).abs() < 1e-12);
        assert!((out[10] - 1.8).abs() < 0.01, "{}", out[10]);
        assert!((out[2009] - 2.0).abs() < 1e-6);
        let back =
            soak.with_free_params(&soak.free_params()).unwrap_or(ThermalSoak { gain: 0.0, tau_s: 1.0 });
        assert!((back.tau_s - 10.0).abs() < 1e-9);
        assert!(soak.with_free_params(&[0.95, 1.0]).is_none());
    }
}
