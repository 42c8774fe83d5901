//! The static map's estimating equations: least squares on the steady windows' means, and the
//! variance those means carry.
use std::ops::Range;

use nalgebra::DMatrix;

use super::{Layout, slot_len};

/// Which parameters are the map's, and each kept sample's weight in the map's least squares
/// (`1/len` inside a steady window of `len` samples, 0 elsewhere); no weights without windows.
pub(super) struct MapRows {
    pub(super) range: Range<usize>,
    pub(super) weights: Option<Vec<f64>>,
}

pub(super) fn map_rows(layout: &Layout, steady_windows: &[Range<usize>], kept: &[usize]) -> MapRows {
    let start = slot_len(&layout.poles) + slot_len(&layout.zeros);
    let range = start..start + layout.map;
    if steady_windows.is_empty() {
        return MapRows { range, weights: None };
    }
    let weight =
        |k: usize| steady_windows.iter().find(|w| w.contains(&k)).map_or(0.0, |w| 1.0 / w.len() as f64);
    MapRows { range, weights: Some(kept.iter().map(|&k| weight(k)).collect()) }
}

/// Each steady window as the positions in `kept` (the run's samples the covariance uses) it covers.
pub(super) fn window_positions(steady_windows: &[Range<usize>], kept: &[usize]) -> Vec<Vec<usize>> {
    steady_windows
        .iter()
        .map(|w| (0..kept.len()).filter(|&p| w.contains(&kept[p])).collect::<Vec<usize>>())
        .filter(|positions| !positions.is_empty())
        .collect()
}

/// Widen the map equations' block of the scores' variance `scores` to at least what a stationary
/// residual gives them: `Σ_w Σ_{k,l∈w} cₖ cₗᵀ γ_{|k−l|}` over the steady windows `windows`, with
/// `γ` the residual `e`'s autocovariance over the whole run.
///
/// Why: a map coefficient's equation is a weighted mean of the residual over each steady window,
/// so its variance is that of the windows' mean errors. The Newey–West sum over the window's own
/// residuals cannot give it: with a bandwidth as long as the window it collapses to the squared
/// window mean, which the map's fit itself has pulled towards zero (a handful of windows for three
/// or four coefficients); with the residual's short bandwidth it misses the part that is
/// correlated over the spool's settling time, the measured input's noise filtered by the model,
/// which is a small share of the residual's variance but not of a window mean's. On the paper's own
/// shaft-speed model with a tenth of its sensor noise, the steady gains' 95 % intervals covered the
/// truth 78 % of the time before this (87 % with the fuel noise left out). The residual's
/// autocovariance over the whole run sees that correlation wherever it is; the whole run also
/// carries the transients' model error, so the bound is on the side of wider intervals. Only the
/// part of the bound above the sandwich's own block is added (its positive part), so the result
/// stays a covariance and no interval narrows.
pub(super) fn at_least_stationary(
    scores: &mut DMatrix<f64>,
    map_equations: &[usize],
    equations: &[Vec<f64>],
    e: &[f64],
    windows: &[Vec<usize>],
) {
    let q = map_equations.len();
    let longest = windows.iter().map(Vec::len).max().unwrap_or(0);
    if q == 0 || longest == 0 || e.is_empty() {
        return;
    }
    let n = e.len();
    let mean = e.iter().sum::<f64>() / n as f64;
    let gamma: Vec<f64> = (0..longest.min(n))
        .map(|lag| e[lag..].iter().zip(e).map(|(a, b)| (a - mean) * (b - mean)).sum::<f64>() / n as f64)
        .collect();
    let mut bound = DMatrix::<f64>::zeros(q, q);
    for positions in windows {
        for (i, &a) in map_equations.iter().enumerate() {
            for (j, &b) in map_equations.iter().enumerate().take(i + 1) {
                let mut sum = 0.0;
                for &k in positions {
                    for &l in positions {
                        sum += equations[a][k] * equations[b][l] * gamma[k.abs_diff(l).min(gamma.len() - 1)];
                    }
                }
                bound[(i, j)] += sum;
                if i != j {
                    bound[(j, i)] += sum;
                }
            }
        }
    }
    let own = DMatrix::from_fn(q, q, |i, j| scores[(map_equations[i], map_equations[j])]);
    let eigen = (bound - own).symmetric_eigen();
    let clipped = eigen.eigenvalues.map(|v| v.max(0.0));
    let extra = &eigen.eigenvectors * DMatrix::from_diagonal(&clipped) * eigen.eigenvectors.transpose();
    for (i, &a) in map_equations.iter().enumerate() {
        for (j, &b) in map_equations.iter().enumerate() {
            scores[(a, b)] += extra[(i, j)];
        }
    }
}
