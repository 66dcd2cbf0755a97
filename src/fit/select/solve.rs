//! The search's one optimiser entry point: every fit of the selection (a candidate, a pair, a
//! polish of the kept set) states its problem and [`Method`] and calls [`solve`].
//!
//! Which method a fit uses follows from the effect, not from the phase of the search: smooth
//! effects ([`crate::fit::effects::Effect::smooth`]) are least-squares problems on the rollout
//! residuals (Levenberg–Marquardt, k + 1 rollouts of the training set per iteration); one
//! non-smooth parameter is a line search (a grid, then Brent's parabolic steps with
//! golden-section fallback, on ln p for a scale spanning decades); two or three a simplex
//! (Nelder–Mead); more an evolution strategy (CMA-ES).

use crate::fit::optim::{
    Bounds, CmaesOpts, GRID_POINTS, HeldJacobian, LmOpts, NelderMeadOpts, Noise, ROLLOUT_REL_STEP,
    ROLLOUT_SHORT_STEP, ROLLOUT_STAT_TOL, Resolution, brent_refine, cmaes,
    levenberg_marquardt_from, line_search_resolved, nelder_mead,
};
use crate::fit::stats::ar1_variance_inflation;

/// Relative tolerance of a line search [fraction of the bracket].
const LINE_TOL: f64 = 2e-4;
/// Relative tolerance of Levenberg–Marquardt's step [fraction of the parameter].
const LM_TOL: f64 = 1e-5;
/// Objective tolerance of the simplex [RMSE units, absolute].
const SIMPLEX_FTOL: f64 = 1e-12;

/// How to search a problem's parameters.
#[derive(Debug, Clone, Copy)]
pub(super) enum Method {
    /// Levenberg–Marquardt on the residual vector, at most `max_iters` iterations; a rejected
    /// step that, with the Gauss–Newton model's optimum, lies within `resolve` standard errors
    /// of the point ends it there (`LmOpts::resolution`; 0: never).
    LeastSquares { max_iters: usize, resolve: f64 },
    /// A line search on one parameter (on ln p when `log` and the bracket is positive): a
    /// 9-point grid, then Brent's refinement around its best point, at most `max_evals`
    /// evaluations; the refinement stops early once the minimum is located within `resolve`
    /// standard errors of the parameter (from the profile's curvature and the noise of the
    /// problem's residual: [`Resolution`]; 0: never).
    Line { log: bool, max_evals: usize, resolve: f64 },
    /// [`Method::Line`] from a start (a coarse fit's point): only the line search's grid
    /// points around it are replayed, and refined as the whole search refines its grid's best
    /// point when they hold a minimum of the grid; else the whole line search.
    LineFrom { log: bool, max_evals: usize, resolve: f64 },
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
    /// A Jacobian of the residuals the caller already has (the same data and model), for
    /// least squares' first iteration where it applies ([`HeldJacobian`]).
    pub(super) held: Option<&'p HeldJacobian>,
}

/// The optimiser's answer: the parameters, their objective (training RMSE) and whether a
/// tolerance (not the budget) ended the search.
#[derive(Debug)]
pub(super) struct Solution {
    pub(super) x: Vec<f64>,
    pub(super) f: f64,
    pub(super) converged: bool,
}

/// [`Method::LineFrom`]: the two points of [`Method::Line`]'s grid that enclose `x0` (on ln p
/// when `log` and the bounds are positive), then the grid neighbour beyond the lower of them —
/// three points, one replayed already when `x0` is a point of the grid (a coarse fit's on the
/// probes' data). When the best of them has both its grid neighbours among them (or is an end
/// of the range), the grid has a minimum there, and Brent's method refines the bracket of
/// its neighbours exactly as the whole search does from that grid point: the same answer for
/// three evaluations of the grid's nine, whenever the grid's best point is among them. Else
/// (the lowest at their edge) the whole search of [`Method::Line`], whose grid then holds
/// those three points.
fn line_from(p: &Problem<'_>, x0: &[f64], log: bool, max_evals: usize, resolve: f64) -> Solution {
    use rayon::prelude::*;
    let (lo, hi) = (p.bounds.lo[0], p.bounds.hi[0]);
    let whole = || solve(p, x0, Method::Line { log, max_evals, resolve });
    let n = max_evals.min(GRID_POINTS);
    let Some(&start) = x0.first().filter(|x| x.is_finite() && lo < hi && n >= 3) else {
        return whole();
    };
    let logs = log && lo > 0.0;
    let (a, c) = if logs { (lo.ln(), hi.ln()) } else { (lo, hi) };
    let obj = |u: f64| {
        let v = if logs { (p.objective)(&[u.exp()]) } else { (p.objective)(&[u]) };
        if v.is_nan() { f64::INFINITY } else { v }
    };
    // The grid of `line_search` on [a, c], point for point.
    let grid = |i: usize| a + (c - a) * i as f64 / (n - 1) as f64;
    let u0 = if logs { start.clamp(lo, hi).ln() } else { start.clamp(lo, hi) };
    let i0 = (((u0 - a) / (c - a) * (n - 1) as f64).floor().max(0.0) as usize).min(n - 2);
    // The two grid points enclosing the start, then the neighbour beyond the lower one (the
    // grid's rule on ties: the first index of the minimum), which a minimum there needs.
    let first_min = |f: &[f64]| (0..f.len()).fold(0, |b, i| if f[i] < f[b] { i } else { b });
    let mut window: Vec<usize> = vec![i0, i0 + 1];
    let mut f: Vec<f64> = window.par_iter().map(|&i| obj(grid(i))).collect();
    let beyond = if first_min(&f) == 0 { i0.checked_sub(1) } else { Some(i0 + 2) };
    if let Some(j) = beyond.filter(|&j| j < n) {
        let at = usize::from(j > i0) * 2;
        window.insert(at, j);
        f.insert(at, obj(grid(j)));
    }
    let k = first_min(&f);
    let ib = window[k];
    let inside = (k > 0 || ib == 0) && (k + 1 < window.len() || ib == n - 1);
    if !inside || !f[k].is_finite() {
        return whole();
    }
    let x_of = |u: f64| if logs { u.exp().clamp(lo, hi) } else { u };
    if n + 2 > max_evals {
        return Solution { x: vec![x_of(grid(ib))], f: f[k], converged: true };
    }
    let bracket = (grid(ib.saturating_sub(1)), grid((ib + 1).min(n - 1)));
    let tol = LINE_TOL * (c - a);
    let ends = (k > 0 && k + 1 < window.len()).then(|| (f[k - 1], f[k + 1]));
    let noise = |u: f64| noise_at(p, if logs { u.exp() } else { u });
    let r = Resolution { fraction: resolve, noise: &noise };
    let best = (grid(ib), f[k]);
    let (u, fu) = brent_refine(&obj, bracket, tol, max_evals - n, best, ends, Some(&r));
    Solution { x: vec![x_of(u)], f: fu, converged: true }
}

/// The noise of `p`'s objective at the parameter `x` (evaluated already: its replay is
/// remembered) for a line search's [`Resolution`]: the count of its residuals and their AR(1)
/// variance inflation, the noise model of the reported standard errors
/// (`engine::uncertainty`). `None` without a residual vector.
fn noise_at(p: &Problem<'_>, x: f64) -> Option<Noise> {
    let r = (p.residuals?)(&[x]);
    (r.len() >= 2).then(|| Noise { n: r.len(), inflation: ar1_variance_inflation(&r) })
}

/// Minimises `p` from `x0` with `method`.
pub(super) fn solve(p: &Problem<'_>, x0: &[f64], method: Method) -> Solution {
    let b = &p.bounds;
    match method {
        Method::LeastSquares { max_iters, resolve } => {
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
                resolution: resolve,
            };
            let r = levenberg_marquardt_from(res, x0, b, &o, p.held);
            let n = r.n_resid;
            let f = if n > 0 { (2.0 * r.cost / n as f64).sqrt() } else { f64::INFINITY };
            Solution { x: r.x, f, converged: r.converged }
        }
        Method::Line { log, max_evals, resolve } => {
            let (lo, hi) = (b.lo[0], b.hi[0]);
            let obj = p.objective;
            if log && lo > 0.0 && hi > lo {
                // On ln v: a narrow optimum a decade below the top of the range falls between
                // two points of a uniform grid.
                let (a, c) = (lo.ln(), hi.ln());
                let noise = |u: f64| noise_at(p, u.exp());
                let r = Resolution { fraction: resolve, noise: &noise };
                let f = |u: f64| obj(&[u.exp()]);
                let (u, f) =
                    line_search_resolved(&f, (a, c), LINE_TOL * (c - a), max_evals, Some(&r));
                Solution { x: vec![u.exp().clamp(lo, hi)], f, converged: true }
            } else {
                let noise = |v: f64| noise_at(p, v);
                let r = Resolution { fraction: resolve, noise: &noise };
                let f = |v: f64| obj(&[v]);
                let (x, f) =
                    line_search_resolved(&f, (lo, hi), LINE_TOL * (hi - lo), max_evals, Some(&r));
                Solution { x: vec![x], f, converged: true }
            }
        }
        Method::LineFrom { log, max_evals, resolve } => line_from(p, x0, log, max_evals, resolve),
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
            held: None,
        };
        for m in [
            Method::LeastSquares { max_iters: 20, resolve: 0.1 },
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
            held: None,
        };
        for log in [false, true] {
            let s = solve(&p1, &[1.0], Method::Line { log, max_evals: 60, resolve: 0.0 });
            assert!((s.x[0] / 0.04 - 1.0).abs() < 0.1, "log {log}: {:?}", s.x);
        }
    }

    /// From a start near the minimum (a coarse fit's point), the line search replays only the
    /// two grid points enclosing it and the neighbour beyond the lower one, and refines as the
    /// whole search does: the same answer, bit for bit, for six evaluations fewer — whichever
    /// of the two enclosing points is the lower. From a start whose grid points hold no minimum
    /// of the grid (the lowest at their edge), the whole search, after those three.
    #[test]
    fn a_line_search_from_a_start_refines_the_bracket_around_it() {
        use std::sync::atomic::{AtomicUsize, Ordering};
        // A kink at the minimum, as a gear play's RMSE has.
        let truth = 0.0413;
        let n = AtomicUsize::new(0);
        let obj = |x: &[f64]| {
            n.fetch_add(1, Ordering::Relaxed);
            (x[0] - truth).abs().sqrt() + 0.01
        };
        let p = Problem {
            objective: &obj,
            residuals: None,
            bounds: Bounds { lo: vec![0.0], hi: vec![0.2] },
            held: None,
        };
        let tol = LINE_TOL * 0.2;
        let count = |m: Method, x0: f64| {
            n.store(0, Ordering::Relaxed);
            let s = solve(&p, &[x0], m);
            (s, n.load(Ordering::Relaxed))
        };
        let (whole, nw) = count(Method::Line { log: false, max_evals: 40, resolve: 0.0 }, 0.0);
        let (near, nn) = count(Method::LineFrom { log: false, max_evals: 40, resolve: 0.0 }, 0.04);
        assert!((whole.x[0] - truth).abs() < tol, "{whole:?}");
        assert_eq!((near.x[0], near.f), (whole.x[0], whole.f));
        assert_eq!(nn + 6, nw, "{nn} evaluations from the start, {nw} for the whole range");
        // From either side of the grid point 0.05 (enclosed by 0.025 and 0.05, or by 0.05 and
        // 0.075: the upper or the lower one is the lower), and from 0.05 itself: the far side of
        // the lower enclosing point is replayed, three evaluations each time.
        for x0 in [0.03, 0.045, 0.05, 0.06] {
            let (s, k) = count(Method::LineFrom { log: false, max_evals: 40, resolve: 0.0 }, x0);
            assert_eq!((s.x[0], s.f), (whole.x[0], whole.f), "from {x0}");
            assert_eq!(k + 6, nw, "from {x0}: {k} evaluations");
        }
        // Far from it: the lowest of its grid points is the one nearest the minimum, at their
        // edge.
        let (far, nf) = count(Method::LineFrom { log: false, max_evals: 40, resolve: 0.0 }, 0.16);
        assert_eq!((far.x[0], far.f), (whole.x[0], whole.f));
        assert_eq!(nf, nw + 3);
        // On ln p, and from a start on the range's end.
        for (log, x0) in [(true, 0.04), (false, 0.0), (false, 0.2)] {
            let (w, _) = count(Method::Line { log, max_evals: 40, resolve: 0.0 }, x0);
            let (s, _) = count(Method::LineFrom { log, max_evals: 40, resolve: 0.0 }, x0);
            assert_eq!((s.x[0], s.f), (w.x[0], w.f), "log {log} from {x0}");
        }
    }

    /// A line search takes the noise of its stop from the problem's residual vector: on n
    /// residuals `σ zᵢ − gᵢ (p − p*)` (white noise of known size, a fixed sensitivity; on ln p
    /// too) the stop at a tenth of a standard error ends within 0.11 closed-form standard errors
    /// (`σ / √Σ gᵢ²`; the residual's AR(1) factor is near 1) of the least-squares answer; at ten
    /// standard errors the grid's own parabola stops it — no Brent step after the grid's nine
    /// points, nor after a start's three; without a residual vector there is no stop.
    #[test]
    fn a_line_search_stops_at_its_resolution_of_the_residuals_standard_error() {
        use std::sync::atomic::{AtomicUsize, Ordering};
        let n = 2000;
        let mut rng = crate::util::Rng::from_state(11);
        let z: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
        let g: Vec<f64> = (0..n).map(|i| 1.0 + 0.5 * (0.21 * i as f64).sin()).collect();
        let (sigma, truth) = (1.0, 0.137);
        let res = |x: &[f64]| -> Vec<f64> {
            z.iter().zip(&g).map(|(z, g)| sigma * z - g * (x[0] - truth)).collect()
        };
        let evals = AtomicUsize::new(0);
        let obj = |x: &[f64]| {
            evals.fetch_add(1, Ordering::Relaxed);
            let r = res(x);
            (r.iter().map(|v| v * v).sum::<f64>() / r.len() as f64).sqrt()
        };
        let gg: f64 = g.iter().map(|g| g * g).sum();
        let gz: f64 = g.iter().zip(&z).map(|(g, z)| g * sigma * z).sum();
        let (answer, se) = (truth + gz / gg, sigma / gg.sqrt());
        let bounds = Bounds { lo: vec![0.01], hi: vec![1.0] };
        let with =
            Problem { objective: &obj, residuals: Some(&res), bounds: bounds.clone(), held: None };
        let without = Problem { objective: &obj, residuals: None, bounds, held: None };
        let run = |p: &Problem<'_>, m: Method| {
            evals.store(0, Ordering::Relaxed);
            let start = if matches!(m, Method::LineFrom { .. }) { 0.14 } else { 0.5 };
            let s = solve(p, &[start], m);
            (s.x[0], evals.load(Ordering::Relaxed))
        };
        for log in [false, true] {
            let (x0, n0) = run(&with, Method::Line { log, max_evals: 40, resolve: 0.0 });
            assert!(n0 > GRID_POINTS + 2, "log {log}: {n0} evaluations");
            let (x, _) = run(&with, Method::Line { log, max_evals: 40, resolve: 0.1 });
            assert!((x - answer).abs() <= 0.11 * se, "log {log}: {x} for {answer} ± {se}");
            let (_, k) = run(&with, Method::Line { log, max_evals: 40, resolve: 10.0 });
            assert_eq!(k, GRID_POINTS, "log {log}: stopped by the grid's parabola");
            let (_, ks) = run(&with, Method::LineFrom { log, max_evals: 40, resolve: 10.0 });
            assert_eq!(ks, 3, "log {log}: stopped by the start's three grid points");
            let (x1, k1) = run(&without, Method::Line { log, max_evals: 40, resolve: 10.0 });
            assert_eq!((x1, k1), (x0, n0), "log {log}: no residuals, no stop");
        }
    }
}
