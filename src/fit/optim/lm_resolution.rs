//! Levenberg–Marquardt's resolution stop ([`super::LmOpts::resolution`]): a rejected trial step
//! ends the fit at its point when it and the Gauss–Newton model's own optimum both lie within
//! `resolution` standard errors of the point on every free parameter.
//!
//! The standard errors are those of the model's optimum, not of the current point: the
//! covariance `s² (JᵀJ)⁻¹` of the iteration's Jacobian with the noise `s²` of the residual the
//! model predicts at its optimum, `r + J s_GN` (its sum of squares over `m − n` degrees of
//! freedom), inflated for that residual's serial correlation as AR(1)
//! ([`ar1_variance_inflation`]: the noise model of the standard errors a fit reports). At a point
//! far from the minimum the residual there still holds the misfit its parameters explain (a large
//! `s²`, a lag-1 correlation at its cap): standard errors measured on it are long, and a tenth of
//! one can be a descent's step. The predicted residual leaves out what the model explains; what
//! it cannot explain (physics it does not have) stays in it, so the standard error is never
//! below the noise's. A parameter held at a bound it is pushed against counts as located.

use nalgebra::{DMatrix, DVector};

use crate::fit::stats::ar1_variance_inflation;

/// The Gauss–Newton model of one Levenberg–Marquardt iteration: its optimum and standard errors
/// (unit space of the fit).
#[derive(Debug, Clone)]
pub(super) struct ModelOptimum {
    /// The undamped Gauss–Newton step `s_GN` (zero on the held parameters), unbounded by the box.
    pub(super) step: Vec<f64>,
    /// The standard error of each parameter at the optimum (zero on the held ones).
    pub(super) se: Vec<f64>,
}

/// The model of the Jacobian `j` (m × n) at a point whose residual is `res`, with the
/// parameters `held` frozen (an active bound: identity row and column); `None` when no
/// parameter is free, the residuals do not outnumber the free ones, the normal matrix is not
/// positive definite or a value is not finite.
pub(super) fn model_optimum(j: &DMatrix<f64>, res: &[f64], held: &[bool]) -> Option<ModelOptimum> {
    let (m, n) = j.shape();
    let free = held.iter().filter(|h| !**h).count();
    if free == 0 || m <= free || res.len() != m || held.len() != n {
        return None;
    }
    let r = DVector::from_column_slice(res);
    let mut a = j.transpose() * j;
    let mut rhs = -(j.transpose() * &r);
    for k in (0..n).filter(|&k| held[k]) {
        a.row_mut(k).fill(0.0);
        a.column_mut(k).fill(0.0);
        a[(k, k)] = 1.0;
        rhs[k] = 0.0;
    }
    let ch = a.cholesky()?;
    let step = ch.solve(&rhs);
    let inv = ch.inverse();
    let predicted: Vec<f64> = (r + j * &step).iter().copied().collect();
    let ss: f64 = predicted.iter().map(|v| v * v).sum();
    let s2 = ss / (m - free) as f64 * ar1_variance_inflation(&predicted);
    let se: Vec<f64> =
        (0..n).map(|k| if held[k] { 0.0 } else { (s2 * inv[(k, k)]).max(0.0).sqrt() }).collect();
    let step: Vec<f64> = step.iter().copied().collect();
    (se.iter().chain(&step).all(|v| v.is_finite())).then_some(ModelOptimum { step, se })
}

impl ModelOptimum {
    /// Whether the model's optimum and the step `d` both move every parameter by at most `tol`
    /// of its standard error.
    pub(super) fn within(&self, d: &[f64], tol: f64) -> bool {
        d.len() == self.se.len()
            && (0..d.len()).all(|k| {
                let w = tol * self.se[k];
                self.step[k].abs() <= w && d[k].abs() <= w
            })
    }
}

#[cfg(test)]
#[path = "lm_resolution_tests.rs"]
mod tests;
