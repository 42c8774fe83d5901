//! Linear least squares under homogeneous linear inequalities: `min ‖A x − b‖₂` subject to
//! `dᵢ · x ≥ 0` for every row `dᵢ` of `D`. Used to keep a fitted static map monotone.
//!
//! The unconstrained answer ([`solve_lstsq`]) is returned unchanged when it already satisfies every
//! inequality, so a constraint that does not bind costs nothing and changes nothing. Otherwise a
//! primal active-set method (Nocedal & Wright, *Numerical Optimization*, Algorithm 16.3) starts from
//! `x = 0`, which satisfies homogeneous inequalities, and moves towards the optimum, stopping at
//! each inequality it meets. The problems here are small (a handful of unknowns, a few dozen
//! inequalities), so each step is solved densely.
use faer::Mat;
use nalgebra::{DMatrix, DVector};

use super::lstsq::{LstsqError, solve_lstsq};

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConstrainedError {
    #[error(transparent)]
    Lstsq(#[from] LstsqError),
    #[error("a constraint row has {got} entries, the regressors have {want} columns")]
    RowLength { got: usize, want: usize },
    #[error("constraint row {row} holds a non-finite value")]
    NonFiniteRow { row: usize },
    #[error("the constrained least-squares problem is singular (regressors of rank below {cols})")]
    Singular { cols: usize },
    #[error("the active-set iteration did not settle in {iterations} steps")]
    NotConverged { iterations: usize },
}

/// A constrained answer and the inequalities that hold with equality at it.
#[derive(Clone, Debug, PartialEq)]
pub struct ConstrainedSolution {
    pub x: Vec<f64>,
    /// Indices of the rows of `D` that bind (empty when the unconstrained answer was feasible).
    pub active: Vec<usize>,
}

/// `min ‖A x − b‖₂` subject to `D x ≥ 0` (each entry of `constraints` is one row of `D`).
pub fn solve_lstsq_nonneg(
    a: &Mat<f64>,
    b: &[f64],
    constraints: &[Vec<f64>],
) -> Result<ConstrainedSolution, ConstrainedError> {
    let cols = a.ncols();
    if let Some(row) = constraints.iter().find(|row| row.len() != cols) {
        return Err(ConstrainedError::RowLength { got: row.len(), want: cols });
    }
    if let Some(row) = constraints.iter().position(|row| row.iter().any(|v| !v.is_finite())) {
        return Err(ConstrainedError::NonFiniteRow { row });
    }
    let free = solve_lstsq(a, b)?;
    if constraints.iter().all(|d| dot(d, &free.x) >= 0.0) {
        return Ok(ConstrainedSolution { x: free.x, active: Vec::new() });
    }
    active_set(a, b, constraints)
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Nocedal & Wright's Algorithm 16.3 on `½ xᵀHx − gᵀx` with `H = AᵀA`, `g = Aᵀb`. Each step is
/// taken in the null space of the working set's rows (the null-space method), so a row that
/// depends on the others (two slope rows fix a parabola's slope everywhere) never makes a system
/// singular, and the step is exactly zero once the working set leaves no freedom.
fn active_set(
    a: &Mat<f64>,
    b: &[f64],
    constraints: &[Vec<f64>],
) -> Result<ConstrainedSolution, ConstrainedError> {
    let (rows, cols) = (a.nrows(), a.ncols());
    let h = DMatrix::from_fn(cols, cols, |i, j| (0..rows).map(|r| a[(r, i)] * a[(r, j)]).sum());
    let g = DVector::from_fn(cols, |i, _| (0..rows).map(|r| a[(r, i)] * b[r]).sum());
    // A step shorter than this, relative to the answer, is no step; a multiplier above minus this,
    // relative to the gradient, is not negative. Both sit a few digits above rounding of H and g.
    let step_tol = 1e-12;
    let multiplier_tol = 1e-10 * (1.0 + g.amax());
    let mut x = DVector::zeros(cols);
    let mut working: Vec<usize> = Vec::new();
    // Each pass adds or drops one inequality; with no cycling that ends within a few sweeps.
    let iterations = 10 * (constraints.len() + cols);
    for _ in 0..iterations {
        let q = &h * &x - &g;
        let p = null_space_step(&h, &q, constraints, &working)?;
        if p.amax() <= step_tol * (1.0 + x.amax()) {
            let lambda = multipliers(&(&h * &p + &q), constraints, &working)?;
            match lambda.iter().copied().enumerate().min_by(|(_, l), (_, m)| l.total_cmp(m)) {
                Some((worst, value)) if value < -multiplier_tol => {
                    working.remove(worst);
                    continue;
                }
                _ => return Ok(ConstrainedSolution { x: x.as_slice().to_vec(), active: working }),
            }
        }
        // The nearest inequality the step crosses; a row the step runs along (to rounding) is not
        // crossed.
        let p_norm = p.norm();
        let mut alpha = 1.0;
        let mut blocking = None;
        for (i, d) in constraints.iter().enumerate().filter(|(i, _)| !working.contains(i)) {
            let d_norm = d.iter().map(|v| v * v).sum::<f64>().sqrt();
            let dp = dot(d, p.as_slice());
            if dp >= -step_tol * d_norm * p_norm {
                continue;
            }
            let t = (-dot(d, x.as_slice()) / dp).max(0.0);
            if t < alpha {
                alpha = t;
                blocking = Some(i);
            }
        }
        x += alpha * p;
        working.extend(blocking);
    }
    Err(ConstrainedError::NotConverged { iterations })
}

/// Orthonormal vectors spanning the null space of the working set's rows: Gram–Schmidt over the
/// rows (a row within 1e-9 of the span of those before it adds nothing), then over the unit
/// vectors, which completes the basis.
fn null_space(constraints: &[Vec<f64>], working: &[usize], n: usize) -> Vec<DVector<f64>> {
    let mut basis: Vec<DVector<f64>> = Vec::with_capacity(n);
    let add = |v: DVector<f64>, basis: &mut Vec<DVector<f64>>| -> bool {
        let scale = v.norm();
        let mut r = v;
        // Twice, as classical Gram–Schmidt loses orthogonality once.
        for _ in 0..2 {
            for q in basis.iter() {
                let along = r.dot(q);
                r -= along * q;
            }
        }
        let norm = r.norm();
        let independent = norm > 1e-9 * scale;
        if independent {
            basis.push(r / norm);
        }
        independent
    };
    for &i in working {
        add(DVector::from_column_slice(&constraints[i]), &mut basis);
    }
    let row_rank = basis.len();
    for k in 0..n {
        if basis.len() == n {
            break;
        }
        add(DVector::from_fn(n, |i, _| if i == k { 1.0 } else { 0.0 }), &mut basis);
    }
    basis.split_off(row_rank)
}

/// The step `p` minimising the quadratic from `x` (gradient `q`) with the working set held at
/// equality: `p = −Z (ZᵀHZ)⁻¹ Zᵀq` over a basis `Z` of the working set's null space.
fn null_space_step(
    h: &DMatrix<f64>,
    q: &DVector<f64>,
    constraints: &[Vec<f64>],
    working: &[usize],
) -> Result<DVector<f64>, ConstrainedError> {
    let n = h.nrows();
    let z = null_space(constraints, working, n);
    if z.is_empty() {
        return Ok(DVector::zeros(n));
    }
    let z = DMatrix::from_columns(&z);
    let reduced = z.transpose() * h * &z;
    let w = reduced.lu().solve(&(-(z.transpose() * q))).ok_or(ConstrainedError::Singular { cols: n })?;
    let p = z * w;
    if p.iter().any(|v| !v.is_finite()) {
        return Err(ConstrainedError::Singular { cols: n });
    }
    Ok(p)
}

/// The working set's multipliers `λ` at a stationary point: `Dᵀ λ = H p + q`, by least squares
/// (minimum norm where rows of the working set depend on each other).
fn multipliers(
    gradient: &DVector<f64>,
    constraints: &[Vec<f64>],
    working: &[usize],
) -> Result<Vec<f64>, ConstrainedError> {
    if working.is_empty() {
        return Ok(Vec::new());
    }
    let n = gradient.len();
    let dt = DMatrix::from_fn(n, working.len(), |r, c| constraints[working[c]][r]);
    let lambda =
        dt.svd(true, true).solve(gradient, 1e-12).map_err(|_| ConstrainedError::Singular { cols: n })?;
    Ok(lambda.iter().copied().collect())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn design(x: &[f64], cols: usize) -> Mat<f64> {
        Mat::from_fn(x.len(), cols, |r, c| x[r].powi(c as i32))
    }

    #[test]
    fn a_feasible_answer_is_the_plain_least_squares_one() {
        let x: Vec<f64> = (0..9).map(|i| -1.0 + 0.25 * i as f64).collect();
        let y: Vec<f64> = x.iter().map(|v| 1.0 + 2.0 * v + 0.3 * v * v).collect();
        let slope_rows: Vec<Vec<f64>> = x.iter().map(|v| vec![0.0, 1.0, 2.0 * v]).collect();
        let got = solve_lstsq_nonneg(&design(&x, 3), &y, &slope_rows).unwrap();
        assert!(got.active.is_empty());
        assert!((got.x[2] - 0.3).abs() < 1e-12, "{:?}", got.x);
    }

    #[test]
    fn a_bending_parabola_becomes_the_best_monotone_one() {
        // y = x − x² on [−1, 1] turns over at x = 0.5. Among parabolas whose slope is non-negative
        // on the grid, the optimum must have zero slope at the right end (a binding constraint).
        let x: Vec<f64> = (0..21).map(|i| -1.0 + 0.1 * i as f64).collect();
        let y: Vec<f64> = x.iter().map(|v| v - v * v).collect();
        let slope_rows: Vec<Vec<f64>> = x.iter().map(|v| vec![0.0, 1.0, 2.0 * v]).collect();
        let got = solve_lstsq_nonneg(&design(&x, 3), &y, &slope_rows).unwrap();
        for d in &slope_rows {
            assert!(dot(d, &got.x) >= -1e-12, "{:?}", got.x);
        }
        assert_eq!(got.active, vec![20], "{:?}", got.x);
        // Against a brute-force search over slopes that keep c1 + 2 c2 ≥ 0 and c1 − 2 c2 ≥ 0.
        let a = design(&x, 3);
        let sse = |c: &[f64]| -> f64 {
            (0..x.len()).map(|r| ((0..3).map(|k| a[(r, k)] * c[k]).sum::<f64>() - y[r]).powi(2)).sum()
        };
        let best = sse(&got.x);
        for i in 0..=200 {
            let c2 = -0.5 + 0.005 * i as f64;
            for j in 0..=200 {
                let c1 = 0.005 * j as f64;
                if c1 + 2.0 * c2 < 0.0 || c1 - 2.0 * c2 < 0.0 {
                    continue;
                }
                // For fixed c1, c2 the best c0 is the mean residual.
                let c0 =
                    (0..x.len()).map(|r| y[r] - c1 * x[r] - c2 * x[r] * x[r]).sum::<f64>() / x.len() as f64;
                assert!(sse(&[c0, c1, c2]) >= best - 1e-9, "({c0}, {c1}, {c2}) beats {:?}", got.x);
            }
        }
    }

    #[test]
    fn a_row_of_the_wrong_length_or_not_finite_is_refused() {
        let x = [0.0, 1.0, 2.0];
        let got = solve_lstsq_nonneg(&design(&x, 2), &[0.0, 1.0, 2.0], &[vec![1.0]]);
        assert_eq!(got, Err(ConstrainedError::RowLength { got: 1, want: 2 }));
        let got =
            solve_lstsq_nonneg(&design(&x, 2), &[0.0, 1.0, 2.0], &[vec![0.0, 1.0], vec![f64::NAN, 1.0]]);
        assert_eq!(got, Err(ConstrainedError::NonFiniteRow { row: 1 }));
    }

    #[test]
    fn scattered_points_that_pull_a_cubic_both_ways_settle_at_a_feasible_optimum() {
        // Steady points of a real log read with no windows (an idle, a start and a shutdown among
        // the holds): the free cubic falls at both ends, and three slope rows fix its slope
        // everywhere, so a naive working set grows dependent rows and cycles.
        let x = [
            -0.9402208194049119,
            -0.7797413476735219,
            -0.707074753956541,
            0.29924662098786114,
            -0.2976009143051581,
            -0.5583750231708204,
            -0.02849770865140295,
            -0.4724924155675033,
            1.0,
            -1.0,
            -0.9404904444995422,
            -0.7860029916126067,
            -0.7138953397242835,
            0.2665966582991982,
            -0.30039943236502786,
            -0.5627477579408012,
            0.262315028597296,
            -0.9999999999984174,
        ];
        let y = [
            3508.59649122807,
            23934.56140350877,
            33476.14035087719,
            99894.0350877193,
            75004.38596491228,
            49984.912280701756,
            89994.0350877193,
            60025.61403508772,
            51225.78947368421,
            2990.0,
            3568.7719298245615,
            24087.36842105263,
            33171.754385964916,
            99951.9298245614,
            74994.0350877193,
            50004.56140350877,
            74582.45614035087,
            0.0,
        ];
        let a = design(&x, 4);
        let rows: Vec<Vec<f64>> = (0..65)
            .map(|j| -1.0 + 2.0 * j as f64 / 64.0)
            .map(|v| vec![0.0, 1.0, 2.0 * v, 3.0 * v * v])
            .collect();
        let got = solve_lstsq_nonneg(&a, &y, &rows).unwrap();
        let scale = got.x.iter().fold(0.0_f64, |m, c| m.max(c.abs()));
        assert!(rows.iter().all(|d| dot(d, &got.x) >= -1e-9 * scale), "{:?}", got.x);
        let sse = |c: &[f64]| -> f64 {
            (0..x.len()).map(|r| ((0..4).map(|k| a[(r, k)] * c[k]).sum::<f64>() - y[r]).powi(2)).sum()
        };
        // No feasible point nearby does better: steps along every pair of coordinate directions.
        let best = sse(&got.x);
        for i in 0..4 {
            for j in 0..4 {
                for (si, sj) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
                    let mut c = got.x.clone();
                    c[i] += si * 1e-3 * scale;
                    c[j] += sj * 1e-3 * scale;
                    if rows.iter().all(|d| dot(d, &c) >= 0.0) {
                        assert!(sse(&c) >= best * (1.0 - 1e-12), "{c:?} beats {:?}", got.x);
                    }
                }
            }
        }
    }
}
