//! Cholesky factorisation `A = L·Lᵀ` of a small dense symmetric positive-definite matrix, with the
//! solve, `ln det A` and `tr(A⁻¹)` that the evidence framework needs. Row-major storage; only the
//! lower triangle of `A` is read. Plain loops: the matrices are ~60×60 and this runs every
//! training iteration.

pub(super) struct Cholesky {
    /// Row-major lower factor; the strict upper triangle is zero.
    l: Vec<f64>,
    p: usize,
}

impl Cholesky {
    /// `None` when `a` is not `p × p` or not numerically positive definite.
    pub fn new(a: &[f64], p: usize) -> Option<Self> {
        if a.len() != p * p {
            return None;
        }
        let mut l = vec![0.0; p * p];
        for i in 0..p {
            for j in 0..=i {
                let mut sum = a[i * p + j];
                for k in 0..j {
                    sum -= l[i * p + k] * l[j * p + k];
                }
                if i == j {
                    if !(sum > 0.0 && sum.is_finite()) {
                        return None;
                    }
                    l[i * p + i] = sum.sqrt();
                } else {
                    l[i * p + j] = sum / l[j * p + j];
                }
            }
        }
        Some(Self { l, p })
    }

    /// `L⁻¹ b` by forward substitution (`b` of length `p`).
    fn forward(&self, b: &[f64]) -> Vec<f64> {
        let p = self.p;
        let mut z = b.to_vec();
        z.resize(p, 0.0);
        for i in 0..p {
            let mut sum = z[i];
            for k in 0..i {
                sum -= self.l[i * p + k] * z[k];
            }
            z[i] = sum / self.l[i * p + i];
        }
        z
    }

    /// `A⁻¹ b`.
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let p = self.p;
        let mut x = self.forward(b);
        for i in (0..p).rev() {
            let mut sum = x[i];
            for k in i + 1..p {
                sum -= self.l[k * p + i] * x[k];
            }
            x[i] = sum / self.l[i * p + i];
        }
        x
    }

    pub fn log_det(&self) -> f64 {
        (0..self.p).map(|i| 2.0 * self.l[i * self.p + i].ln()).sum()
    }

    /// `tr(A⁻¹) = ‖L⁻¹‖²_F`, column by column of `L⁻¹`.
    pub fn trace_inverse(&self) -> f64 {
        let p = self.p;
        let mut total = 0.0;
        let mut column = vec![0.0; p];
        for c in 0..p {
            column.iter_mut().for_each(|v| *v = 0.0);
            column[c] = 1.0 / self.l[c * p + c];
            total += column[c] * column[c];
            for i in c + 1..p {
                let mut sum = 0.0;
                for k in c..i {
                    sum -= self.l[i * p + k] * column[k];
                }
                column[i] = sum / self.l[i * p + i];
                total += column[i] * column[i];
            }
        }
        total
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn solve_determinant_and_trace_of_a_known_matrix() {
        // A = [[4, 2, 0], [2, 5, 1], [0, 1, 3]]: det = 4·14 − 2·6 = 44.
        let a = [4.0, 2.0, 0.0, 2.0, 5.0, 1.0, 0.0, 1.0, 3.0];
        let c = Cholesky::new(&a, 3).unwrap();
        let x = c.solve(&[1.0, 2.0, 3.0]);
        for i in 0..3 {
            let ax: f64 = (0..3).map(|j| a[i * 3 + j] * x[j]).sum();
            assert!((ax - [1.0, 2.0, 3.0][i]).abs() < 1e-12);
        }
        assert!((c.log_det() - 44.0f64.ln()).abs() < 1e-12);
        // tr(A⁻¹) = (cofactors 14 + 12 + 16) / 44.
        assert!((c.trace_inverse() - 42.0 / 44.0).abs() < 1e-12);
        assert!(Cholesky::new(&[1.0, 2.0, 2.0, 1.0], 2).is_none());
    }
}
