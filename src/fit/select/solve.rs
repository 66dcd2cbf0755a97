//! The search's one optimiser entry point: every fit of the selection (a candidate, a pair, a
//! polish of the kept set) states its problem and [`Method`] and calls [`solve`].
//!
//! Which method a fit uses follows from the effect, not from the phase of the search: smooth
//! effects ([`crate::fit::effects::Effect::smooth`]) are least-squares problems on the rollout
//! residuals (Levenberg–Marquardt, k + 1 rollouts of the training set per iteration); one
//! non-smooth parameter is a line search (golden section, on ln p for a scale spanning
//! decades); two or three a simplex (Nelder–Mead); more an evolution strategy (CMA-ES).

use crate::fit::optim::{
    Bounds, CmaesOpts, LmOpts, NelderMeadOpts, ROLLOUT_REL_STEP, ROLLOUT_SHORT_STEP,
    ROLLOUT_STAT_TOL, cmaes, golden_section, levenberg_marquardt, nelder_mead,
};

/// Relative tolerance of a line search [fraction of the bracket].
const LINE_TOL: f64 = 2e-4;
/// Relative tolerance of Levenberg–Marquardt's step [fraction of the parameter].
const LM_TOL: f64 = 1e-5;
/// Objective tolerance of the simplex [RMSE units, absolute].
const SIMPLEX_FTOL: f64 = 1e-12;

/// How to search a problem's parameters.
#[derive(Debug, Clone, Copy)]
pub(super) enum Method {
    /// Levenberg–Marquardt on the residual vector, at most `max_iters` iterations.
    LeastSquares { max_iters: usize },
    /// Golden section on one parameter (on ln p when `log` and the bracket is positive), at
    /// most `max_evals` evaluations.
    Line { log: bool, max_evals: usize },
    /// Nelder–Mead from an initial simplex of `step` × each parameter's range, stopping at
    /// `xtol` (normalised) or after `max_evals` evaluations.
    Simplex { max_evals: usize, xtol: f64, step: f64 },
    /// CMA-ES with `max_evals` evaluations.
    Evolution { max_evals: usize },
}

/// The residual vector (real − sim over the scored samples) of a parameter vector.
pub(super) type Residuals<'p> = &'p (dyn Fn(&[f64]) -> Vec<f64> + Sync);

/// A fit: the scalar objective (training RMSE of the parameters, +∞ when a rollout fails), the
/// residual vector for least squares (real − sim over the scored samples), and box bounds.
pub(super) struct Problem<'p> {
    pub(super) objective: &'p (dyn Fn(&[f64]) -> f64 + Sync),
    pub(super) residuals: Option<Residuals<'p>>,
    pub(super) bounds: Bounds,
}

/// The optimiser's answer: the parameters, their objective (training RMSE) and whether a
/// tolerance (not the budget) ended the search.
pub(super) struct Solution {
    pub(super) x: Vec<f64>,
    pub(super) f: f64,
    pub(super) converged: bool,
}

/// Minimises `p` from `x0` with `method`.
pub(super) fn solve(p: &Problem<'_>, x0: &[f64], method: Method) -> Solution {
    let b = &p.bounds;
    match method {
        Method::LeastSquares { max_iters } => {
            let Some(res) = p.residuals else {
                // No residual vector: the simplex on the objective instead.
                let m = Method::Simplex { max_evals: 20 * max_iters, xtol: 1e-4, step: 0.1 };
                return solve(p, x0, m);
            };
            let o = LmOpts {
                max_iters,
                rel_step: ROLLOUT_REL_STEP,
                tol: LM_TOL,
                final_jacobian: false,
                stat_tol: ROLLOUT_STAT_TOL,
                short_step: ROLLOUT_SHORT_STEP,
            };
            let r = levenberg_marquardt(res, x0, b, &o);
            let n = r.n_resid;
            let f = if n > 0 { (2.0 * r.cost / n as f64).sqrt() } else { f64::INFINITY };
            Solution { x: r.x, f, converged: r.converged }
        }
        Method::Line { log, max_evals } => {
            let (lo, hi) = (b.lo[0], b.hi[0]);
            let obj = p.objective;
            if log && lo > 0.0 && hi > lo {
                // On ln v: a narrow optimum a decade below the top of the range falls between
                // two points of a uniform grid.
                let (a, c) = (lo.ln(), hi.ln());
                let (u, f) =
                    golden_section(&|u| obj(&[u.exp()]), a, c, LINE_TOL * (c - a), max_evals);
                Solution { x: vec![u.exp().clamp(lo, hi)], f, converged: true }
            } else {
                let (x, f) =
                    golden_section(&|v| obj(&[v]), lo, hi, LINE_TOL * (hi - lo), max_evals);
                Solution { x: vec![x], f, converged: true }
            }
        }
        Method::Simplex { max_evals, xtol, step } => {
            let o = NelderMeadOpts { max_evals, xtol, ftol: SIMPLEX_FTOL, initial_step: step };
            let r = nelder_mead(p.objective, x0, b, &o);
            Solution { x: r.x, f: r.f, converged: r.converged }
        }
        Method::Evolution { max_evals } => {
            let o = CmaesOpts { max_evals, ..Default::default() };
            let r = cmaes(p.objective, x0, b, &o);
            Solution { x: r.x, f: r.f, converged: r.converged }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every method finds the minimum of a smooth bowl inside its bounds.
    #[test]
    fn every_method_finds_a_bowls_minimum() {
        let truth = [0.3, 2.0];
        let res = |x: &[f64]| vec![x[0] - truth[0], (x[1] - truth[1]) * 0.5];
        let obj = |x: &[f64]| {
            let r = res(x);
            (r.iter().map(|v| v * v).sum::<f64>() / r.len() as f64).sqrt()
        };
        let p = Problem {
            objective: &obj,
            residuals: Some(&res),
            bounds: Bounds { lo: vec![0.0, 0.5], hi: vec![1.0, 5.0] },
        };
        for m in [
            Method::LeastSquares { max_iters: 20 },
            Method::Simplex { max_evals: 400, xtol: 1e-6, step: 0.1 },
            Method::Evolution { max_evals: 2000 },
        ] {
            let s = solve(&p, &[0.9, 1.0], m);
            assert!((s.x[0] - 0.3).abs() < 1e-3 && (s.x[1] - 2.0).abs() < 1e-3, "{m:?}: {:?}", s.x);
        }
        // One parameter: a line search, linear and on ln p.
        let one = |x: &[f64]| (x[0].ln() - 0.04f64.ln()).abs();
        let p1 = Problem {
            objective: &one,
            residuals: None,
            bounds: Bounds { lo: vec![1e-3], hi: vec![10.0] },
        };
        for log in [false, true] {
            let s = solve(&p1, &[1.0], Method::Line { log, max_evals: 60 });
            assert!((s.x[0] / 0.04 - 1.0).abs() < 0.1, "log {log}: {:?}", s.x);
        }
    }
}
