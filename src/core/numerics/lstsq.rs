//! Linear least squares by SVD, with the numerical rank and condition number returned beside the
//! answer. Rank deficiency gives the minimum-norm solution and is reported, never a crash.
use faer::Mat;

use super::qr::qr_reduce;

/// A least-squares answer `x` minimising `‖A x − b‖₂`, with what the caller needs to trust it.
#[derive(Clone, Debug, PartialEq)]
pub struct LstsqSolution {
    pub x: Vec<f64>,
    /// Numerical rank of the column-scaled regressor matrix.
    pub rank: usize,
    /// Condition number (largest / smallest retained singular value) of the column-scaled matrix.
    pub cond: f64,
    /// Root mean square of the residual `b − A x`.
    pub residual_rms: f64,
}

impl LstsqSolution {
    pub fn is_full_rank(&self) -> bool {
        self.rank == self.x.len()
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LstsqError {
    #[error("least squares needs at least one row and one column (got {rows}×{cols})")]
    Empty { rows: usize, cols: usize },
    #[error("right-hand side has {rhs} rows but the regressor matrix has {rows}")]
    ShapeMismatch { rows: usize, rhs: usize },
    #[error("{rows} equations cannot determine {cols} unknowns")]
    Underdetermined { rows: usize, cols: usize },
    #[error("non-finite value in the regressors at row {row}, column {col}")]
    NonFiniteRegressor { row: usize, col: usize },
    #[error("non-finite value in the right-hand side at row {row}")]
    NonFiniteRhs { row: usize },
    #[error("all regressors are zero")]
    ZeroMatrix,
    #[error("singular value decomposition did not converge")]
    SvdFailed,
}

/// Solve `min ‖A x − b‖` for a dense `A` (rows × cols, rows ≥ cols).
///
/// Columns are scaled to unit norm first (so the rank test is not fooled by units), then a thin SVD
/// is truncated at `σ > ε · max(rows, cols) · σ_max`.
pub fn solve_lstsq(a: &Mat<f64>, b: &[f64]) -> Result<LstsqSolution, LstsqError> {
    let (rows, cols) = (a.nrows(), a.ncols());
    if rows == 0 || cols == 0 {
        return Err(LstsqError::Empty { rows, cols });
    }
    if b.len() != rows {
        return Err(LstsqError::ShapeMismatch { rows, rhs: b.len() });
    }
    if rows < cols {
        return Err(LstsqError::Underdetermined { rows, cols });
    }
    for col in 0..cols {
        for row in 0..rows {
            if !a[(row, col)].is_finite() {
                return Err(LstsqError::NonFiniteRegressor { row, col });
            }
        }
    }
    if let Some(row) = b.iter().position(|v| !v.is_finite()) {
        return Err(LstsqError::NonFiniteRhs { row });
    }
    let scales: Vec<f64> = (0..cols)
        .map(|col| {
            let norm = (0..rows).map(|row| a[(row, col)].powi(2)).sum::<f64>().sqrt();
            if norm > 0.0 { norm } else { 1.0 }
        })
        .collect();
    // The scaled matrix is Q·R with R square (Householder, applied to b on the way): it has R's
    // singular values, and its SVD is Q·U_R Σ Vᵀ. So only the cols × cols factor is decomposed, and
    // Uᵀb is U_Rᵀ(Qᵀb): a tall regressor (thousands of samples, a handful of columns) costs one
    // pass of reflections instead of a blocked SVD that forms its rows × cols U.
    let scaled: Vec<Vec<f64>> =
        (0..cols).map(|col| (0..rows).map(|row| a[(row, col)] / scales[col]).collect()).collect();
    let (r, qtb) = qr_reduce(scaled, b.to_vec());
    let r = Mat::from_fn(cols, cols, |row, col| match row <= col {
        true => r.get(col).and_then(|c| c.get(row)).copied().unwrap_or(0.0),
        false => 0.0,
    });
    let svd = r.thin_svd().map_err(|_| LstsqError::SvdFailed)?;
    let (u, s, v) = (svd.U(), svd.S().column_vector(), svd.V());
    let sigma_max = s[0];
    if sigma_max <= 0.0 {
        return Err(LstsqError::ZeroMatrix);
    }
    let tol = f64::EPSILON * rows.max(cols) as f64 * sigma_max;
    let rank = (0..cols).filter(|&i| s[i] > tol).count();
    let mut x_scaled = vec![0.0; cols];
    for i in 0..rank {
        let ub: f64 = (0..cols).map(|row| u[(row, i)] * qtb[row]).sum();
        let coeff = ub / s[i];
        for (j, xj) in x_scaled.iter_mut().enumerate() {
            *xj += v[(j, i)] * coeff;
        }
    }
    let x: Vec<f64> = x_scaled.iter().zip(&scales).map(|(xs, sc)| xs / sc).collect();
    let residual_rms = (b
        .iter()
        .enumerate()
        .map(|(row, bi)| {
            let fit: f64 = (0..cols).map(|col| a[(row, col)] * x[col]).sum();
            (bi - fit).powi(2)
        })
        .sum::<f64>()
        / rows as f64)
        .sqrt();
    let cond = sigma_max / s[rank.saturating_sub(1)];
    Ok(LstsqSolution { x, rank, cond, residual_rms })
}

/// Build a dense matrix from rows (all rows must have `cols` entries; missing entries read as 0).
pub fn mat_from_rows(rows: &[Vec<f64>], cols: usize) -> Mat<f64> {
    Mat::from_fn(rows.len(), cols, |i, j| rows.get(i).and_then(|r| r.get(j)).copied().unwrap_or(0.0))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn exact_system_is_solved() {
        let a = mat_from_rows(&[vec![1.0, 0.0], vec![0.0, 2.0], vec![1.0, 1.0]], 2);
        let x_true = [3.0, -1.0];
        let b: Vec<f64> = (0..3).map(|i| a[(i, 0)] * x_true[0] + a[(i, 1)] * x_true[1]).collect();
        let sol = solve_lstsq(&a, &b).unwrap();
        assert!((sol.x[0] - 3.0).abs() < 1e-12 && (sol.x[1] + 1.0).abs() < 1e-12);
        assert_eq!(sol.rank, 2);
        assert!(sol.residual_rms < 1e-12);
    }

    #[test]
    fn rank_deficiency_is_reported_not_crashed() {
        let a = mat_from_rows(&[vec![1.0, 2.0], vec![2.0, 4.0], vec![3.0, 6.0]], 2);
        let sol = solve_lstsq(&a, &[1.0, 2.0, 3.0]).unwrap();
        assert_eq!(sol.rank, 1);
        assert!(!sol.is_full_rank());
        assert!(sol.residual_rms < 1e-12);
    }

    #[test]
    fn bad_shapes_and_values_are_errors() {
        let a = mat_from_rows(&[vec![1.0, 2.0]], 2);
        assert_eq!(solve_lstsq(&a, &[1.0]), Err(LstsqError::Underdetermined { rows: 1, cols: 2 }));
        let a = mat_from_rows(&[vec![1.0], vec![f64::NAN]], 1);
        assert_eq!(solve_lstsq(&a, &[1.0, 2.0]), Err(LstsqError::NonFiniteRegressor { row: 1, col: 0 }));
        let a = mat_from_rows(&[vec![1.0], vec![1.0]], 1);
        assert_eq!(solve_lstsq(&a, &[1.0]), Err(LstsqError::ShapeMismatch { rows: 2, rhs: 1 }));
        let a = mat_from_rows(&[vec![0.0], vec![0.0]], 1);
        assert_eq!(solve_lstsq(&a, &[1.0, 1.0]), Err(LstsqError::ZeroMatrix));
    }

    proptest! {
        /// The residual of a full-rank least-squares fit is orthogonal to every regressor column.
        #[test]
        fn residual_is_orthogonal_to_regressors(
            entries in proptest::collection::vec(-10.0f64..10.0, 24),
            b in proptest::collection::vec(-10.0f64..10.0, 8),
        ) {
            let a = Mat::from_fn(8, 3, |i, j| entries[i * 3 + j]);
            let sol = solve_lstsq(&a, &b).unwrap();
            prop_assume!(sol.is_full_rank() && sol.cond < 1e6);
            for col in 0..3 {
                let dot: f64 = (0..8)
                    .map(|row| {
                        let fit: f64 = (0..3).map(|c| a[(row, c)] * sol.x[c]).sum();
                        a[(row, col)] * (b[row] - fit)
                    })
                    .sum();
                let scale: f64 = (0..8).map(|row| a[(row, col)].abs()).sum::<f64>()
                    * b.iter().map(|v| v.abs()).sum::<f64>();
                prop_assert!(dot.abs() <= 1e-9 * scale.max(1.0));
            }
        }
    }
}
