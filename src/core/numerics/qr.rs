//! Householder QR of a tall matrix given by its columns, applied to a right-hand side as it goes:
//! for the least-squares steps of [`super::lm::StepSolver::QrOnce`] (the Jacobian is reduced to its
//! p × p triangular factor once per iteration, and each damped step is a small 2p × p problem) and
//! for [`super::lstsq::solve_lstsq`] (the SVD then only of the p × p factor). No normal equations
//! are formed.

/// Householder QR of the columns `cols` (each of length m ≥ p), applied to `rhs` as well.
/// Returns the p × p upper factor (by columns) and the first p entries of `Qᵀ rhs`.
pub fn qr_reduce(mut cols: Vec<Vec<f64>>, mut rhs: Vec<f64>) -> (Vec<Vec<f64>>, Vec<f64>) {
    let p = cols.len();
    for k in 0..p {
        let Some(col) = cols.get(k) else { break };
        let m = col.len();
        if k >= m {
            break;
        }
        let norm = col[k..].iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm <= f64::MIN_POSITIVE {
            continue;
        }
        let alpha = if col[k] > 0.0 { -norm } else { norm };
        let mut v: Vec<f64> = col[k..].to_vec();
        v[0] -= alpha;
        let vnorm2: f64 = v.iter().map(|x| x * x).sum();
        if vnorm2 <= f64::MIN_POSITIVE {
            continue;
        }
        let mut tails: Vec<&mut [f64]> = cols.iter_mut().skip(k).filter_map(|col| col.get_mut(k..)).collect();
        tails.extend(rhs.get_mut(k..));
        reflect_each(&v, vnorm2, &mut tails);
    }
    let r = cols.iter().map(|c| c.iter().take(p).copied().collect()).collect();
    (r, rhs.into_iter().take(p).collect())
}

/// Reflect each of `tails` in the hyperplane normal to `v` (`y ← y − 2 (v·y / v·v) v`, `vnorm2` = v·v).
fn reflect_each(v: &[f64], vnorm2: f64, tails: &mut [&mut [f64]]) {
    let dots = dot_each(v, tails);
    for (y, dot) in tails.iter_mut().zip(&dots) {
        let f = 2.0 * dot / vnorm2;
        for (yi, vi) in y.iter_mut().zip(v) {
            *yi -= f * vi;
        }
    }
}

/// `v · y` for each of `ys`, four at a time in one pass where they have the same length. Each dot
/// product is a chain of dependent additions whose latency sets its pace; four independent chains
/// overlap theirs. Each is the sum `Iterator::sum` gives, bit for bit: the same products added in
/// the same order from the same start (−0, where `Sum for f64` starts).
fn dot_each(v: &[f64], ys: &[&mut [f64]]) -> Vec<f64> {
    let dot = |y: &[f64]| -> f64 { v.iter().zip(y).map(|(a, b)| a * b).sum() };
    let mut dots = Vec::with_capacity(ys.len());
    let mut fours = ys.chunks_exact(4);
    for four in &mut fours {
        match four {
            [a, b, c, d] if a.len() == b.len() && a.len() == c.len() && a.len() == d.len() => {
                let mut sums = [-0.0_f64; 4];
                for ((((vi, ai), bi), ci), di) in
                    v.iter().zip(a.iter()).zip(b.iter()).zip(c.iter()).zip(d.iter())
                {
                    sums[0] += vi * ai;
                    sums[1] += vi * bi;
                    sums[2] += vi * ci;
                    sums[3] += vi * di;
                }
                dots.extend(sums);
            }
            _ => dots.extend(four.iter().map(|y| dot(y))),
        }
    }
    dots.extend(fours.remainder().iter().map(|y| dot(y)));
    dots
}

/// Solve the upper-triangular `R x = c`; components whose pivot is negligible are set to zero.
pub fn back_substitute(r: &[Vec<f64>], c: &[f64]) -> Vec<f64> {
    let p = r.len();
    let at = |i: usize, j: usize| r.get(j).and_then(|col| col.get(i)).copied().unwrap_or(0.0);
    let big = (0..p).map(|i| at(i, i).abs()).fold(0.0, f64::max);
    let tol = f64::EPSILON * p.max(1) as f64 * 100.0 * big;
    let mut x = vec![0.0; p];
    for i in (0..p).rev() {
        let pivot = at(i, i);
        if pivot.abs() <= tol {
            continue;
        }
        let s: f64 = (i + 1..p).map(|j| at(i, j) * x[j]).sum();
        x[i] = (c.get(i).copied().unwrap_or(0.0) - s) / pivot;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Four columns at a time, with a remainder and a column of another length: each dot product
    /// is the one `Iterator::sum` gives, bit for bit.
    #[test]
    fn dots_summed_together_are_each_dot_alone() {
        let v: Vec<f64> = (0..997).map(|k| (0.37 * k as f64).sin() * 1e3).collect();
        let mut cols: Vec<Vec<f64>> = (0..6)
            .map(|j| (0..997).map(|k| ((j + 1) as f64 * 0.11 * k as f64).cos() / 7.0).collect())
            .collect();
        cols[5].truncate(500);
        let tails: Vec<&mut [f64]> = cols.iter_mut().map(Vec::as_mut_slice).collect();
        let dots = dot_each(&v, &tails);
        for (y, dot) in tails.iter().zip(&dots) {
            let alone: f64 = v.iter().zip(y.iter()).map(|(a, b)| a * b).sum();
            assert_eq!(alone.to_bits(), dot.to_bits());
        }
        assert_eq!(dots.len(), 6);
    }

    #[test]
    fn solves_least_squares() {
        // Overdetermined linear system: the residual of the solution is orthogonal to the columns.
        let cols = vec![vec![1.0, 1.0, 1.0, 1.0], vec![0.0, 1.0, 2.0, 3.0]];
        let b = vec![1.0, 2.9, 5.1, 7.0];
        let (r, c) = qr_reduce(cols.clone(), b.clone());
        let x = back_substitute(&r, &c);
        let res: Vec<f64> = (0..4).map(|i| b[i] - x[0] * cols[0][i] - x[1] * cols[1][i]).collect();
        for col in &cols {
            assert!(col.iter().zip(&res).map(|(a, b)| a * b).sum::<f64>().abs() < 1e-12);
        }
    }
}
