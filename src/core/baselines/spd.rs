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
                let sum = a[i * p + j] - dot(&l[i * p..i * p + j], &l[j * p..j * p + j]);
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
            let row = &self.l[i * p..i * p + i];
            z[i] = (z[i] - dot(row, &z[..i])) / self.l[i * p + i];
        }
        z
    }

    /// `A⁻¹ b`.
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let p = self.p;
        let mut x = self.forward(b);
        for i in (0..p).rev() {
            let below: f64 = x.iter().enumerate().skip(i + 1).map(|(k, xk)| self.l[k * p + i] * xk).sum();
            x[i] = (x[i] - below) / self.l[i * p + i];
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
                column[i] = -dot(&self.l[i * p + c..i * p + i], &column[c..i]) / self.l[i * p + i];
                total += column[i] * column[i];
            }
        }
        total
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
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
