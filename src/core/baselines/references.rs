//! The simple references every comparison shows beside the gray-box model, fitted on the same
//! identification range, so that a user sees whether the gray-box beats the simple thing:
//!
//! - the linear ARX(2,2) `y(k) = −a₁y(k−1) − a₂y(k−2) + b₁u(k−1) + b₂u(k−2) + c`;
//! - the Hammerstein ARX: the same with `[u, u², u³]` at both input lags;
//! - the static cubic map `y = p(u)`, no dynamics at all.
//!
//! Each is fitted by one linear least-squares problem (one-step-ahead equation error for the ARX
//! models) and judged, like every other model, by its free-run simulation from the input alone.
//! The input enters as `ũ = (u − centre)/half-range` over the identification range, so that the
//! powers of a pump voltage or a fuel flow are of order one and the regressors well conditioned.
use faer::Mat;
use serde::{Deserialize, Serialize};

use super::{BaselineError, Scaling, check_signals};
use crate::core::numerics::lstsq::solve_lstsq;

/// Output lags and input lags of the ARX references (the na = nb = 2).
const ORDER: usize = 2;

/// An ARX model whose input enters through a polynomial of degree `degree` (1: linear).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PolyArx {
    pub degree: usize,
    input_scaling: Scaling,
    /// `a₁, a₂`.
    pub a: [f64; ORDER],
    /// Per input lag (1, 2), the coefficients of `ũ, ũ², …`.
    pub b: Vec<Vec<f64>>,
    /// The constant term.
    pub c: f64,
}

/// The static map `y = Σ cₚ ũᵖ` (p = 0…3).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StaticCubic {
    input_scaling: Scaling,
    pub coefficients: [f64; 4],
}

fn powers(x: f64, degree: usize) -> impl Iterator<Item = f64> {
    (1..=degree).scan(1.0, move |p, _| {
        *p *= x;
        Some(*p)
    })
}

fn input_scaling(u: &[f64]) -> Result<Scaling, BaselineError> {
    Scaling::unit_range(u).ok_or(BaselineError::ConstantSignal { what: "input" })
}

impl PolyArx {
    /// Fit by least squares on the one-step equation error of `u`, `y` (one record).
    pub fn fit(u: &[f64], y: &[f64], degree: usize) -> Result<Self, BaselineError> {
        let n_params = ORDER + ORDER * degree + 1;
        check_signals(u, y, ORDER + 2 * n_params)?;
        let input_scaling = input_scaling(u)?;
        let u_n = input_scaling.normalise_all(u);
        let rows = u.len() - ORDER;
        let mut a = Mat::<f64>::zeros(rows, n_params);
        let mut rhs = Vec::with_capacity(rows);
        for (r, k) in (ORDER..u.len()).enumerate() {
            for (j, col) in (1..=ORDER).zip(0..) {
                a[(r, col)] = -y[k - j];
            }
            for j in 1..=ORDER {
                for (p, value) in powers(u_n[k - j], degree).enumerate() {
                    a[(r, ORDER + (j - 1) * degree + p)] = value;
                }
            }
            a[(r, n_params - 1)] = 1.0;
            rhs.push(y[k]);
        }
        let theta = solve_lstsq(&a, &rhs)?.x;
        let at = |i: usize| theta.get(i).copied().unwrap_or(0.0);
        Ok(Self {
            degree,
            input_scaling,
            a: [at(0), at(1)],
            b: (0..ORDER).map(|j| (0..degree).map(|p| at(ORDER + j * degree + p)).collect()).collect(),
            c: at(n_params - 1),
        })
    }

    /// The input term `Σⱼ Σₚ b_{j,p} ũ(k−j)ᵖ + c` for the inputs at lags 1 and 2.
    fn forced(&self, lagged: [f64; ORDER]) -> f64 {
        let mut sum = self.c;
        for (b, u) in self.b.iter().zip(lagged) {
            sum += b
                .iter()
                .zip(powers(self.input_scaling.normalised_from_physical(u), self.degree))
                .map(|(b, x)| b * x)
                .sum::<f64>();
        }
        sum
    }

    /// The output the model settles at for a constant input `u0` (`None` when `1 + a₁ + a₂` is zero:
    /// an integrator has no steady state).
    pub fn steady_state(&self, u0: f64) -> Option<f64> {
        let den = 1.0 + self.a[0] + self.a[1];
        (den.abs() > 1e-12).then(|| self.forced([u0, u0]) / den)
    }

    /// Free-run simulation of `u` from `past`, the outputs before the first sample (most recent first).
    fn simulate_from(&self, u: &[f64], past: [f64; ORDER]) -> Vec<f64> {
        let u0 = u.first().copied().unwrap_or(0.0);
        let mut out = Vec::with_capacity(u.len());
        let (mut y1, mut y2) = (past[0], past[1]);
        for k in 0..u.len() {
            let lag = |j: usize| if k >= j { u[k - j] } else { u0 };
            let y = -self.a[0] * y1 - self.a[1] * y2 + self.forced([lag(1), lag(2)]);
            out.push(y);
            (y2, y1) = (y1, y);
        }
        out
    }

    /// Free-run simulation of `u` from the steady state of `u[0]`.
    pub fn simulate(&self, u: &[f64]) -> Vec<f64> {
        let u0 = u.first().copied().unwrap_or(0.0);
        let y0 = self.steady_state(u0).unwrap_or(0.0);
        self.simulate_from(u, [y0, y0])
    }

    /// Free-run simulation of `u` started at the measured output: the model's past outputs are the
    /// first measured sample (the run starts at rest where it was measured), as the other models'
    /// estimated start begins from the measured state.
    pub fn simulate_from_measured(&self, u: &[f64], y: &[f64]) -> Vec<f64> {
        match y.first() {
            Some(&y0) if y0.is_finite() => self.simulate_from(u, [y0, y0]),
            _ => self.simulate(u),
        }
    }
}

impl StaticCubic {
    /// Fit `y = p(u)` by least squares on every sample of `u`, `y`.
    pub fn fit(u: &[f64], y: &[f64]) -> Result<Self, BaselineError> {
        check_signals(u, y, 8)?;
        let input_scaling = input_scaling(u)?;
        let mut a = Mat::<f64>::zeros(u.len(), 4);
        for (k, &uk) in u.iter().enumerate() {
            a[(k, 0)] = 1.0;
            for (p, value) in powers(input_scaling.normalised_from_physical(uk), 3).enumerate() {
                a[(k, p + 1)] = value;
            }
        }
        let x = solve_lstsq(&a, y)?.x;
        let at = |i: usize| x.get(i).copied().unwrap_or(0.0);
        Ok(Self { input_scaling, coefficients: [at(0), at(1), at(2), at(3)] })
    }

    pub fn eval(&self, u: f64) -> f64 {
        let x = self.input_scaling.normalised_from_physical(u);
        self.coefficients.iter().rev().fold(0.0, |acc, c| acc * x + c)
    }

    /// The map applied to every sample: a static model has no state to start.
    pub fn simulate(&self, u: &[f64]) -> Vec<f64> {
        u.iter().map(|u| self.eval(*u)).collect()
    }
}

/// The three references of one output, each `None` when it could not be fitted (with the reason in
/// the caller's notes).
#[derive(Clone, Debug, Default)]
pub struct References {
    pub arx: Option<PolyArx>,
    pub hammerstein_arx: Option<PolyArx>,
    pub static_cubic: Option<StaticCubic>,
}

impl References {
    /// Fit all three on `u`, `y`; a reference that fails is a note.
    pub fn fit(u: &[f64], y: &[f64], output: &str, notes: &mut Vec<String>) -> Self {
        let mut keep = |what: &str, fitted| match fitted {
            Ok(model) => Some(model),
            Err(e) => {
                notes.push(format!("{what} reference for '{output}': {e}"));
                None
            }
        };
        let arx = keep("ARX(2,2)", PolyArx::fit(u, y, 1));
        let hammerstein_arx = keep("Hammerstein ARX", PolyArx::fit(u, y, 3));
        let static_cubic = match StaticCubic::fit(u, y) {
            Ok(m) => Some(m),
            Err(e) => {
                notes.push(format!("static cubic reference for '{output}': {e}"));
                None
            }
        };
        Self { arx, hammerstein_arx, static_cubic }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// A second-order system through a cubic input nonlinearity, excited by steps.
    fn hammerstein_data() -> (Vec<f64>, Vec<f64>) {
        let u: Vec<f64> = (0..600).map(|k| 2.0 + ((k / 60) % 5) as f64).collect();
        let f = |u: f64| 10.0 + 3.0 * u + 0.4 * u * u * u;
        let (a1, a2, b1, b2) = (-1.5, 0.6, 0.06, 0.04);
        let mut y = vec![0.0; u.len()];
        let ss = (b1 + b2) * f(u[0]) / (1.0 + a1 + a2);
        let (mut y1, mut y2) = (ss, ss);
        for k in 0..u.len() {
            let lag = |j: usize| if k >= j { u[k - j] } else { u[0] };
            let yk = -a1 * y1 - a2 * y2 + b1 * f(lag(1)) + b2 * f(lag(2));
            y[k] = yk;
            (y2, y1) = (y1, yk);
        }
        (u, y)
    }

    #[test]
    fn the_hammerstein_arx_recovers_a_hammerstein_system_and_the_linear_one_cannot() {
        let (u, y) = hammerstein_data();
        let rms = |yh: &[f64]| {
            (yh.iter().zip(&y).map(|(a, b)| (a - b).powi(2)).sum::<f64>() / y.len() as f64).sqrt()
        };
        let ham = PolyArx::fit(&u, &y, 3).unwrap();
        let lin = PolyArx::fit(&u, &y, 1).unwrap();
        let cubic = StaticCubic::fit(&u, &y).unwrap();
        let (e_ham, e_lin, e_cubic) =
            (rms(&ham.simulate(&u)), rms(&lin.simulate(&u)), rms(&cubic.simulate(&u)));
        assert!(e_ham < 1e-6, "exact structure: {e_ham}");
        assert!(e_lin > 100.0 * e_ham.max(1e-9), "a linear model misses the curvature: {e_lin}");
        assert!(e_cubic > e_ham, "no dynamics: {e_cubic}");
        // Started from the measured output, the simulation begins where the run does.
        assert!((ham.simulate_from_measured(&u, &y)[0] - y[0]).abs() < 1e-6);
    }

    #[test]
    fn bad_records_are_typed_errors() {
        assert!(matches!(PolyArx::fit(&[1.0; 50], &[2.0; 50], 1), Err(BaselineError::ConstantSignal { .. })));
        assert!(matches!(
            StaticCubic::fit(&[1.0, 2.0], &[1.0, 2.0]),
            Err(BaselineError::TooFewSamples { .. })
        ));
        let mut y: Vec<f64> = (0..50).map(f64::from).collect();
        y[7] = f64::NAN;
        let u: Vec<f64> = (0..50).map(f64::from).collect();
        assert!(matches!(PolyArx::fit(&u, &y, 3), Err(BaselineError::NonFinite { index: 7, .. })));
    }
}
