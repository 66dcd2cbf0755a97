//! Bounded Levenberg–Marquardt least squares with a finite-difference Jacobian.

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use serde::Serialize;

use super::lm_held::HeldJacobian;
use super::lm_resolution::model_optimum;
use super::{Bounds, Space, clamp01};

/// Forward-difference step (fraction of the parameter box) for objectives that are MuJoCo
/// rollouts: 1 % of the box steps over the small-scale ripple that friction stick/slip and the
/// solver's tolerance put on a rollout error (measured on the Asimov knee: ~1 % cost ripple at
/// 0.04 % of the damping box, which stopped a 1e-3 difference at 2.48 for a true 3.0).
pub const ROLLOUT_REL_STEP: f64 = 1e-2;

/// The widest forward difference (fraction of the parameter box) a Levenberg–Marquardt fit
/// widens to when no step along its narrower one descends (a rollout's jagged error).
pub const WIDEST_REL_STEP: f64 = 0.05;

/// [`LmOpts::stat_tol`] for rollout fits: stop once a step moves every parameter by less than a
/// tenth of its standard error.
pub const ROLLOUT_STAT_TOL: f64 = 0.1;

/// [`LmOpts::short_step`] for rollout fits: a trial step under 1 % of the difference step.
pub const ROLLOUT_SHORT_STEP: f64 = 1e-2;

/// Options for [`levenberg_marquardt`].
#[derive(Debug, Clone, Serialize)]
pub struct LmOpts {
    /// Maximum number of Jacobian evaluations (outer iterations).
    pub max_iters: usize,
    /// Forward finite-difference step in normalised units.
    pub rel_step: f64,
    /// Convergence tolerance: relative cost decrease, normalised step size
    /// and projected-gradient size (relative to the cost).
    pub tol: f64,
    /// Whether to return the Jacobian at the solution (for an uncertainty): one more
    /// evaluation per free parameter when the last step was accepted.
    pub final_jacobian: bool,
    /// Statistical stop (0 disables): an accepted step shorter than `stat_tol` standard errors
    /// on every free parameter ends the fit (standard errors from the Gauss–Newton covariance
    /// `s² (JᵀJ)⁻¹` of the iteration, `s² = Σr² / (m − n)`). Further steps move the estimate by
    /// less than the data can tell apart: on a rollout objective each costs a simulation.
    pub stat_tol: f64,
    /// For objectives where every evaluation is expensive (a rollout), 0 disables: a rejected
    /// trial step shorter than `short_step` times the difference step ends the damping ladder
    /// (the Jacobian does not resolve it), and the first rejection at a small damping goes
    /// straight to half the Gauss–Newton step (below 1 the damping barely shortens it).
    pub short_step: f64,
    /// The resolution stop (0 disables) [standard errors]: a rejected trial step (replayed and
    /// worse, or, at the start, under `short_step` and not replayed) that, with the
    /// Gauss–Newton model's own optimum, lies within `resolution` standard errors of the point
    /// on every free parameter ends the fit there, converged — no shorter step is replayed and
    /// the difference is not widened. The standard errors are the model's at its
    /// optimum: `s² (JᵀJ)⁻¹` with `s²` the noise of the residual it predicts there (`r + J s_GN`),
    /// inflated for that residual's serial correlation as AR(1) (`lm_resolution`). The search
    /// passes its `line_resolution`: a least-squares fit locates its minimum as finely as a
    /// line search does.
    pub resolution: f64,
}

impl Default for LmOpts {
    fn default() -> Self {
        LmOpts {
            max_iters: 100,
            rel_step: 1e-3,
            tol: 1e-8,
            final_jacobian: true,
            stat_tol: 0.0,
            short_step: 0.0,
            resolution: 0.0,
        }
    }
}

/// Result of [`levenberg_marquardt`].
#[derive(Debug, Clone, Serialize)]
pub struct LmResult {
    pub x: Vec<f64>,
    /// `0.5 * Σ r²` at `x` (`+∞` if the residuals could never be evaluated).
    pub cost: f64,
    /// Finite-difference Jacobian at `x`, `n_resid x n_param`, in the user's
    /// parameter units (columns of fixed parameters are zero); empty unless
    /// [`LmOpts::final_jacobian`].
    pub jacobian: Vec<Vec<f64>>,
    /// Number of residuals (0 when they could never be evaluated).
    pub n_resid: usize,
    pub iters: usize,
    pub converged: bool,
}

/// Bounded Levenberg–Marquardt least squares (`min 0.5 Σ r(x)²`).
///
/// Works in the normalised box; steps are projected onto it. Damping is
/// Marquardt's diagonal scaling. The Jacobian is computed by forward
/// differences (stepping inward at an upper bound), its columns evaluated in
/// parallel. Residual vectors containing non-finite values, or whose length
/// differs from the one at `x0`, count as failures: such trial steps are
/// rejected (damping increased), such Jacobian columns fall back to the
/// opposite-side difference or zero.
pub fn levenberg_marquardt(
    r: &(dyn Fn(&[f64]) -> Vec<f64> + Sync),
    x0: &[f64],
    b: &Bounds,
    o: &LmOpts,
) -> LmResult {
    levenberg_marquardt_from(r, x0, b, o, None)
}

/// [`levenberg_marquardt`] whose first iteration takes the Jacobian `held` the caller already
/// has of the same residual (the same data and model: the caller's to tell) where it applies
/// ([`HeldJacobian::unit_columns`]: the same box and difference step, differenced within one
/// step of `x0`), instead of differencing at `x0`; every later iteration differences as before.
pub fn levenberg_marquardt_from(
    r: &(dyn Fn(&[f64]) -> Vec<f64> + Sync),
    x0: &[f64],
    b: &Bounds,
    o: &LmOpts,
    held: Option<&HeldJacobian>,
) -> LmResult {
    let mut held = held;
    let fail = |x: Vec<f64>| LmResult {
        x,
        cost: f64::INFINITY,
        jacobian: vec![],
        n_resid: 0,
        iters: 0,
        converged: false,
    };
    let Some(sp) = Space::new(b, x0.len()) else {
        return fail(x0.to_vec());
    };
    let np = x0.len();
    let n = sp.dim();
    let mut u = sp.to_unit(x0);
    let Some(mut res) =
        Some(r(&sp.params_of(&u))).filter(|v| !v.is_empty() && v.iter().all(|x| x.is_finite()))
    else {
        return fail(sp.params_of(&u));
    };
    let m = res.len();
    let eval = |u: &[f64]| -> Option<Vec<f64>> {
        let v = r(&sp.params_of(u));
        if v.len() == m && v.iter().all(|x| x.is_finite()) { Some(v) } else { None }
    };
    let cost_of = |v: &[f64]| 0.5 * v.iter().map(|x| x * x).sum::<f64>();
    let h0 = if o.rel_step.is_finite() && o.rel_step > 0.0 { o.rel_step.min(0.25) } else { 1e-3 };
    // A rollout objective is jagged below some scale (friction stick/slip, contacts, the
    // solver's tolerance): a forward difference that small can point uphill. When no step
    // along it descends, the difference is widened (×10, up to `H_MAX` of the box) before
    // the point is called a minimum.
    const H_MAX: f64 = WIDEST_REL_STEP;
    let mut h = h0;
    let tol = if o.tol.is_finite() && o.tol >= 0.0 { o.tol } else { 1e-8 };

    // Jacobian in unit space, m x n, columns in parallel (fixed order).
    let jac_unit = |u: &[f64], res: &[f64], h: f64| -> DMatrix<f64> {
        let cols: Vec<Vec<f64>> = (0..n)
            .into_par_iter()
            .map(|j| {
                let try_step = |s: f64| -> Option<Vec<f64>> {
                    let mut up = u.to_vec();
                    up[j] = clamp01(u[j] + s);
                    let ds = up[j] - u[j];
                    if ds == 0.0 {
                        return None;
                    }
                    eval(&up).map(|rp| rp.iter().zip(res).map(|(a, b)| (a - b) / ds).collect())
                };
                let first = if u[j] + h <= 1.0 { h } else { -h };
                try_step(first).or_else(|| try_step(-first)).unwrap_or_else(|| vec![0.0; m])
            })
            .collect();
        DMatrix::from_fn(m, n, |i, j| cols[j][i])
    };

    let mut cost = cost_of(&res);
    let mut lambda = 1e-3;
    let mut iters = 0usize;
    let mut converged = false;
    let mut jac: Option<DMatrix<f64>> = None;
    // Whether a step was accepted: a fit that never left its start is widened before it stops
    // on a bound there.
    let mut moved = false;

    if n == 0 || cost == 0.0 {
        converged = true;
    }
    // Whether the Jacobian of the current iteration is the held one (not reported as the fit's).
    let mut from_held = false;
    'outer: while !converged && iters < o.max_iters {
        let given = held.take().and_then(|hj| hj.unit_columns(b, &u, h, m));
        from_held = given.is_some();
        let j = match given {
            Some(cols) => DMatrix::from_fn(m, n, |i, k| cols[k][i]),
            None => jac_unit(&u, &res, h),
        };
        iters += 1;
        let jt = j.transpose();
        let a = &jt * &j;
        let g = &jt * DVector::from_column_slice(&res);
        jac = Some(j);

        // Projected gradient: components pushing out of the box don't count.
        let active: Vec<bool> =
            (0..n).map(|k| (u[k] <= 0.0 && g[k] > 0.0) || (u[k] >= 1.0 && g[k] < 0.0)).collect();
        let pg = (0..n).map(|k| if active[k] { 0.0 } else { g[k].abs() }).fold(0.0, f64::max);
        if pg <= tol * 1e-4 * cost.max(f64::MIN_POSITIVE) {
            // Still at the start, held there by a bound its slope pushes against (an added mass
            // of 0 kg, a damping of 0): on a jagged rollout objective that slope may be the
            // ripple's, as for a free minimum below — the difference is widened before the
            // bound is called the minimum. (Unitree H1 with 1 kg in its hand, told link_mass on
            // the elbow: at 1 % of the box the mass's column pointed out of it and the fit stayed
            // at 0 kg; at 5 % it pointed in and the fit went to 0.86 kg.)
            if !moved && h < H_MAX && active.iter().any(|&a| a) {
                h = (h * 10.0).min(H_MAX);
                lambda = 1e-3;
                jac = None;
                continue 'outer;
            }
            converged = true;
            break;
        }
        // Standard errors (unit space) for the statistical stop.
        let se: Option<Vec<f64>> =
            (o.stat_tol > 0.0 && m > n).then(|| a.clone().cholesky()).flatten().map(|ch| {
                let inv = ch.inverse();
                let s2 = 2.0 * cost / (m - n) as f64;
                (0..n).map(|k| (s2 * inv[(k, k)]).max(0.0).sqrt()).collect()
            });
        // The model's optimum and its standard errors, for the resolution stop.
        let optimum = (o.resolution > 0.0)
            .then(|| jac.as_ref().and_then(|j| model_optimum(j, &res, &active)))
            .flatten();
        let maxdiag = (0..n).map(|k| a[(k, k)]).fold(0.0, f64::max);
        let dfloor = (maxdiag * 1e-9).max(1e-300);
        loop {
            // Active-set reduction: variables held at a bound they are pushed
            // against are frozen (identity row/column, zero right-hand side).
            let mut damped = a.clone();
            let mut rhs = -&g;
            for k in 0..n {
                if active[k] {
                    damped.row_mut(k).fill(0.0);
                    damped.column_mut(k).fill(0.0);
                    damped[(k, k)] = 1.0;
                    rhs[k] = 0.0;
                } else {
                    damped[(k, k)] += lambda * a[(k, k)].max(dfloor);
                }
            }
            let step = damped.cholesky().map(|ch| ch.solve(&rhs));
            let Some(step) = step.filter(|s| s.iter().all(|v| v.is_finite())) else {
                lambda *= 10.0;
                if lambda > 1e16 {
                    break 'outer;
                }
                continue;
            };
            let un: Vec<f64> = (0..n).map(|k| clamp01(u[k] + step[k])).collect();
            let du = (0..n).map(|k| (un[k] - u[k]).abs()).fold(0.0, f64::max);
            if du == 0.0 {
                // Projected step vanished: stationary w.r.t. the active bounds (or, with every
                // variable free, a step below rounding: widen the difference first).
                if h < H_MAX && !active.iter().any(|&a| a) {
                    h = (h * 10.0).min(H_MAX);
                    lambda = 1e-3;
                    jac = None;
                    continue 'outer;
                }
                converged = true;
                break 'outer;
            }
            // Still at the start (a re-fit from an answer on other data: the winner's on the
            // whole training set, dry friction on short windows), a trial step shorter than
            // `short_step` times the difference step is below what the Jacobian resolves, as a
            // rejected one is below: it is not replayed (its replay would measure the ripple),
            // the difference is widened, and at its widest the start is the minimum at that
            // resolution. (KR3's Coulomb friction, 0.0316 N·m in a 5 N·m box: each re-fit from
            // it proposed steps of 0.7 and 2 standard errors, 0.5 % and 6 % of the difference,
            // and replayed both to find them worse.)
            if o.short_step > 0.0 && !moved && du < o.short_step * h {
                // (Below the resolution too, with the model's optimum: the start is the answer
                // at the data's resolution, and no wider difference is taken: `resolution`.)
                let d: Vec<f64> = (0..n).map(|k| un[k] - u[k]).collect();
                if optimum.as_ref().is_some_and(|mo| mo.within(&d, o.resolution)) {
                    converged = true;
                    break 'outer;
                }
                if h < H_MAX {
                    h = (h * 10.0).min(H_MAX);
                    lambda = 1e-3;
                    jac = None;
                    continue 'outer;
                }
                converged = true;
                break 'outer;
            }
            let trial = eval(&un);
            let cn = trial.as_deref().map(cost_of).unwrap_or(f64::INFINITY);
            if cn < cost {
                let rel_drop = (cost - cn) / cost;
                let tiny = se
                    .as_ref()
                    .is_some_and(|se| (0..n).all(|k| (un[k] - u[k]).abs() <= o.stat_tol * se[k]));
                u = un;
                moved = true;
                res = trial.unwrap();
                cost = cn;
                jac = None;
                lambda = (lambda / 3.0).max(1e-12);
                if cost == 0.0 || rel_drop <= tol || du <= tol || tiny {
                    converged = true;
                }
                break;
            }
            // The rejected step and the model's optimum both within `resolution` standard errors
            // of the point: the minimum is located at the data's resolution, and more damping
            // (or a wider difference) would hunt for it below that (`lm_resolution`).
            let d: Vec<f64> = (0..n).map(|k| un[k] - u[k]).collect();
            if cn.is_finite() && optimum.as_ref().is_some_and(|mo| mo.within(&d, o.resolution)) {
                converged = true;
                break 'outer;
            }
            lambda = if o.short_step > 0.0 && lambda < 0.1 { 1.0 } else { lambda * 10.0 };
            if lambda > 1e16 || du < o.short_step * h {
                // No descent even for tiny steps: widen the difference, or it is a local
                // minimum up to FD accuracy. A step much shorter than the difference the
                // Jacobian was taken over (`short_step`) is below what that Jacobian resolves:
                // shrinking it further only replays the ripple (each trial is a simulation).
                if h < H_MAX {
                    h = (h * 10.0).min(H_MAX);
                    lambda = 1e-3;
                    jac = None;
                    continue 'outer;
                }
                converged = du <= (tol * 1e3).max(1e-6).max(o.short_step * h);
                break 'outer;
            }
        }
    }

    if !o.final_jacobian {
        return LmResult {
            x: sp.params_of(&u),
            cost,
            jacobian: vec![],
            n_resid: m,
            iters,
            converged,
        };
    }
    // The reported Jacobian (for the uncertainty) uses the requested difference step.
    let j = match jac {
        Some(j) if h == h0 && !from_held => j,
        _ => jac_unit(&u, &res, h0),
    };
    let mut jacobian = vec![vec![0.0; np]; m];
    for (k, &i) in sp.free.iter().enumerate() {
        for row in 0..m {
            jacobian[row][i] = j[(row, k)] / sp.span[i];
        }
    }
    LmResult { x: sp.params_of(&u), cost, jacobian, n_resid: m, iters, converged }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
pub(super) mod tests {
    use super::super::tests::{exp_data, exp_model};
    use super::super::{NelderMeadOpts, nelder_mead, seeded_rng};
    use super::*;

    /// The resolution the search passes a rollout fit (`SearchPolicy::line_resolution`).
    pub(in crate::fit::optim) const ROLLOUT_RESOLUTION: f64 = 0.1;

    /// The options the search gives a rollout fit (`select::solve`: no final Jacobian), at most
    /// 12 iterations, its resolution stop at `resolution` standard errors (0: off).
    pub(in crate::fit::optim) fn rollout_opts(resolution: f64) -> LmOpts {
        LmOpts {
            max_iters: 12,
            rel_step: ROLLOUT_REL_STEP,
            tol: 1e-5,
            final_jacobian: false,
            stat_tol: ROLLOUT_STAT_TOL,
            short_step: ROLLOUT_SHORT_STEP,
            resolution,
        }
    }

    #[test]
    fn the_rollout_resolution_is_the_searchs_line_resolution() {
        let line = crate::fit::select::SearchPolicy::default().line_resolution;
        assert_eq!(ROLLOUT_RESOLUTION, line);
    }

    #[test]
    fn lm_exp_fit_and_uncertainty_calibration() {
        use crate::fit::stats::uncertainty_from_jacobian;
        let truth = [2.0, 1.3, 0.5];
        let sigma = 0.05;
        let b = Bounds { lo: vec![0.0, 0.01, -2.0], hi: vec![5.0, 5.0, 2.0] };
        let ranges: Vec<f64> = b.lo.iter().zip(&b.hi).map(|(l, h)| h - l).collect();
        let o = LmOpts::default();
        let n_seeds = 50;
        let mut est: Vec<Vec<f64>> = vec![];
        let mut pred: Vec<Vec<f64>> = vec![];
        let mut within2 = 0;
        for seed in 0..n_seeds {
            let (t, y) = exp_data(seed, &truth, sigma);
            let r = |p: &[f64]| {
                t.iter().zip(&y).map(|(&ti, &yi)| exp_model(p, ti) - yi).collect::<Vec<f64>>()
            };
            let fit = levenberg_marquardt(&r, &[1.0, 0.5, 0.0], &b, &o);
            assert!(fit.converged, "seed {seed}: {fit:?}");
            let resid = r(&fit.x);
            assert!((fit.cost - 0.5 * resid.iter().map(|v| v * v).sum::<f64>()).abs() < 1e-15);
            assert_eq!(fit.jacobian.len(), 60);
            // Jacobian (user units) vs analytic at the solution.
            let (a_, b_) = (fit.x[0], fit.x[1]);
            for (i, &ti) in t.iter().enumerate() {
                let e = (-b_ * ti).exp();
                let an = [e, -a_ * ti * e, 1.0];
                for k in 0..3 {
                    assert!((fit.jacobian[i][k] - an[k]).abs() < 0.02, "J[{i}][{k}]");
                }
            }
            let u = uncertainty_from_jacobian(&fit.jacobian, &resid, 3, &ranges);
            assert!(u.identifiable.iter().all(|&v| v));
            if (0..3).all(|k| (fit.x[k] - truth[k]).abs() < 2.0 * u.stderr[k]) {
                within2 += 1;
            }
            if seed == 0 {
                for k in 0..3 {
                    assert!(
                        (fit.x[k] - truth[k]).abs() < 2.0 * u.stderr[k],
                        "param {k}: {:?} {:?}",
                        fit.x,
                        u.stderr
                    );
                }
            }
            est.push(fit.x.clone());
            pred.push(u.stderr.clone());
        }
        // Nominal joint coverage of three ±2σ intervals is ≳ 0.86.
        assert!(within2 >= 40, "only {within2}/50 within 2 stderr");
        for k in 0..3 {
            let mean = est.iter().map(|e| e[k]).sum::<f64>() / n_seeds as f64;
            let emp = (est.iter().map(|e| (e[k] - mean).powi(2)).sum::<f64>()
                / (n_seeds - 1) as f64)
                .sqrt();
            let p = pred.iter().map(|s| s[k]).sum::<f64>() / n_seeds as f64;
            let ratio = p / emp;
            assert!((1.0 / 1.5..=1.5).contains(&ratio), "param {k}: predicted {p} empirical {emp}");
            // Estimator is unbiased to well within its spread.
            assert!(
                (mean - truth[k]).abs() < 3.0 * emp / (n_seeds as f64).sqrt() + 1e-3,
                "param {k} mean {mean}"
            );
        }
    }

    #[test]
    fn lm_bound_active_and_exact() {
        // Noise-free: exact recovery.
        let truth = [2.0, 1.3, 0.5];
        let (t, y) = exp_data(1, &truth, 0.0);
        let b = Bounds { lo: vec![0.0, 0.01, -2.0], hi: vec![5.0, 5.0, 2.0] };
        let r = |p: &[f64]| {
            t.iter().zip(&y).map(|(&ti, &yi)| exp_model(p, ti) - yi).collect::<Vec<f64>>()
        };
        let fit = levenberg_marquardt(&r, &[1.0, 0.5, 0.0], &b, &LmOpts::default());
        for k in 0..3 {
            assert!((fit.x[k] - truth[k]).abs() < 1e-6, "{fit:?}");
        }
        assert!(fit.cost < 1e-12);
        // Offset c forced to be >= 0.8 while data has c = 0.5: c ends at the bound.
        let b2 = Bounds { lo: vec![0.0, 0.01, 0.8], hi: vec![5.0, 5.0, 2.0] };
        let fit2 = levenberg_marquardt(&r, &[1.0, 0.5, 1.5], &b2, &LmOpts::default());
        assert_eq!(fit2.x[2], 0.8, "{fit2:?}");
        assert!(fit2.converged);
        // Reference: Nelder–Mead on the same problem with c fixed at the bound.
        let b3 = Bounds { lo: vec![0.0, 0.01, 0.8], hi: vec![5.0, 5.0, 0.8] };
        let sse = |p: &[f64]| 0.5 * r(p).iter().map(|v| v * v).sum::<f64>();
        let nm = nelder_mead(
            &sse,
            &[1.0, 0.5, 0.8],
            &b3,
            &NelderMeadOpts { xtol: 1e-10, ftol: 1e-15, ..Default::default() },
        );
        assert!((fit2.cost - nm.f).abs() < 1e-9 * (1.0 + nm.f), "{fit2:?} {nm:?}");
        assert!(
            (fit2.x[0] - nm.x[0]).abs() < 1e-4 && (fit2.x[1] - nm.x[1]).abs() < 1e-4,
            "{fit2:?} {nm:?}"
        );
        // Linear case y = 3 + 2 t: stderr equals the OLS closed form.
        let ts: Vec<f64> = (0..20).map(|i| i as f64).collect();
        let mut rng = seeded_rng(11);
        let ys: Vec<f64> =
            ts.iter().map(|&x| 3.0 + 2.0 * x + 0.3 * rng.normal_complement()).collect();
        let rl = |p: &[f64]| {
            ts.iter().zip(&ys).map(|(&x, &y)| p[0] + p[1] * x - y).collect::<Vec<f64>>()
        };
        let bl = Bounds { lo: vec![-10.0, -10.0], hi: vec![10.0, 10.0] };
        let fl = levenberg_marquardt(&rl, &[0.0, 0.0], &bl, &LmOpts::default());
        let n = 20.0;
        let (sx, sy): (f64, f64) = (ts.iter().sum(), ys.iter().sum());
        let sxx: f64 = ts.iter().map(|x| x * x).sum();
        let sxy: f64 = ts.iter().zip(&ys).map(|(x, y)| x * y).sum();
        let slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
        let icpt = (sy - slope * sx) / n;
        assert!(
            (fl.x[1] - slope).abs() < 1e-7 && (fl.x[0] - icpt).abs() < 1e-6,
            "{fl:?} {icpt} {slope}"
        );
        let u = crate::fit::stats::uncertainty_from_jacobian(
            &fl.jacobian,
            &rl(&fl.x),
            2,
            &[20.0, 20.0],
        );
        let s2 = 2.0 * fl.cost / (n - 2.0);
        let se_slope = (s2 * n / (n * sxx - sx * sx)).sqrt();
        assert!((u.stderr[1] / se_slope - 1.0).abs() < 1e-6);
    }

    #[test]
    fn lm_crosses_a_jagged_objective() {
        // A rollout objective is smooth at large scales and jagged at small ones (friction
        // stick/slip, solver tolerance): here a slope towards x = 3 plus a ripple whose own
        // slope (0.01 · 500 = 5) beats the trend's, so a forward difference of 1e-3 of the box
        // (0.005) can point either way; the rollout step (1 % of the box, 0.05) cannot be fooled
        // by it. The fit must get near 3 from 0.
        let ts: Vec<f64> = (1..=20).map(|i| i as f64 / 20.0).collect();
        let r = |p: &[f64]| {
            ts.iter()
                .enumerate()
                .map(|(i, &t)| (p[0] - 3.0) * t + 0.01 * (500.0 * p[0] + i as f64).sin())
                .collect::<Vec<f64>>()
        };
        let b = Bounds { lo: vec![0.0], hi: vec![5.0] };
        // (The options the fit uses on rollouts.)
        let o = LmOpts { final_jacobian: true, ..rollout_opts(ROLLOUT_RESOLUTION) };
        let fit = levenberg_marquardt(&r, &[0.0], &b, &o);
        assert!(
            (fit.x[0] - 3.0).abs() < 0.05,
            "{:?} iters {} conv {} cost {}",
            fit.x,
            fit.iters,
            fit.converged,
            fit.cost
        );
        // On a smooth objective the widening never kicks in before convergence: exact.
        let smooth = |p: &[f64]| ts.iter().map(|&t| (p[0] - 3.0) * t).collect::<Vec<f64>>();
        let fit = levenberg_marquardt(&smooth, &[0.0], &b, &o);
        assert!((fit.x[0] - 3.0).abs() < 1e-6, "{:?}", fit.x);
    }

    #[test]
    fn lm_does_not_replay_a_first_step_below_the_jacobians_resolution() {
        // A re-fit from an answer: the start is the trend's minimum, and a ripple far below
        // the rollout difference's scale makes the Gauss–Newton step from it a hair (~1e-6 of
        // the box, under `short_step` × the difference at 1 % and at 5 %). Only the start's
        // residual and the two Jacobians (1 %, then widened to 5 %) are evaluated — no trial
        // step — and the start is the answer, converged.
        use std::sync::atomic::{AtomicUsize, Ordering};
        let evals = AtomicUsize::new(0);
        let r = |p: &[f64]| {
            evals.fetch_add(1, Ordering::Relaxed);
            (1..=20)
                .map(|i| (p[0] - 0.3) * i as f64 / 20.0 + 1e-6 * (1000.0 * p[0] + i as f64).sin())
                .collect::<Vec<f64>>()
        };
        let b = Bounds { lo: vec![0.0], hi: vec![1.0] };
        let o = rollout_opts(ROLLOUT_RESOLUTION);
        let fit = levenberg_marquardt(&r, &[0.3], &b, &o);
        assert!(fit.converged && fit.x == vec![0.3], "{fit:?}");
        assert_eq!(evals.load(Ordering::Relaxed), 3);
        // A step the Jacobian resolves is still taken: from 0.25 the fit reaches the minimum.
        let fit = levenberg_marquardt(&r, &[0.25], &b, &o);
        assert!((fit.x[0] - 0.3).abs() < 1e-4, "{fit:?}");
    }

    #[test]
    fn lm_leaves_a_bound_start_whose_slope_is_the_ripples() {
        // A trend towards x = 0.6 from a start on the lower bound, and a ripple (period 0.04 of
        // the box) whose residual is not zero at the start: over the rollout difference (1 % of
        // the box, a quarter period) the ripple's slope points out of the box and outweighs the
        // trend's, over 5 % (a period and a quarter) it does not. The fit must leave the bound.
        let r = |p: &[f64]| {
            vec![p[0] - 0.6, 0.1 + 0.1 * (2.0 * std::f64::consts::PI * p[0] / 0.04).sin()]
        };
        let b = Bounds { lo: vec![0.0], hi: vec![1.0] };
        let o = rollout_opts(ROLLOUT_RESOLUTION);
        // The precondition: at the rollout difference the slope J^T r points out of the box.
        let (r0, r1) = (r(&[0.0]), r(&[ROLLOUT_REL_STEP]));
        let g: f64 = r0.iter().zip(&r1).map(|(a, b)| a * (b - a) / ROLLOUT_REL_STEP).sum();
        assert!(g > 0.0, "the ripple's slope must point out of the box at the start: {g}");
        let fit = levenberg_marquardt(&r, &[0.0], &b, &o);
        assert!(fit.x[0] > 0.3, "stayed near the bound: {:?} iters {}", fit.x, fit.iters);
    }

    #[test]
    fn lm_rollout_options_save_evaluations_not_accuracy() {
        // The rollout options (statistical stop, short damping ladder, no final Jacobian) on a
        // noisy exponential fit: fewer residual evaluations, an estimate within a tenth of
        // its standard error of the full fit's, and the residual count still reported.
        use crate::fit::stats::uncertainty_from_jacobian;
        use std::sync::atomic::{AtomicUsize, Ordering};
        let truth = [2.0, 1.3, 0.5];
        let (t, y) = exp_data(3, &truth, 0.05);
        let b = Bounds { lo: vec![0.0, 0.01, -2.0], hi: vec![5.0, 5.0, 2.0] };
        let evals = AtomicUsize::new(0);
        let r = |p: &[f64]| {
            evals.fetch_add(1, Ordering::Relaxed);
            t.iter().zip(&y).map(|(&ti, &yi)| exp_model(p, ti) - yi).collect::<Vec<f64>>()
        };
        let full = levenberg_marquardt(&r, &[1.0, 0.5, 0.0], &b, &LmOpts::default());
        let n_full = evals.swap(0, Ordering::Relaxed);
        let o = LmOpts {
            max_iters: 100,
            rel_step: 1e-3,
            tol: 1e-8,
            ..rollout_opts(ROLLOUT_RESOLUTION)
        };
        let quick = levenberg_marquardt(&r, &[1.0, 0.5, 0.0], &b, &o);
        let n_quick = evals.load(Ordering::Relaxed);
        assert!(quick.jacobian.is_empty() && quick.n_resid == t.len());
        // (At least the final Jacobian's three columns are saved; 17 vs 24 when written.)
        assert!(n_quick + 3 <= n_full, "{n_quick} evaluations vs {n_full}");
        let ranges: Vec<f64> = b.lo.iter().zip(&b.hi).map(|(l, h)| h - l).collect();
        let u = uncertainty_from_jacobian(&full.jacobian, &r(&full.x), 3, &ranges);
        for k in 0..3 {
            assert!(
                (quick.x[k] - full.x[k]).abs() <= 0.1 * u.stderr[k],
                "param {k}: {} vs {} (stderr {})",
                quick.x[k],
                full.x[k],
                u.stderr[k]
            );
        }
        // At a minimum already, the short ladder ends after a few trials (each a simulation on
        // a rollout) where the plain one climbs to λ = 1e16.
        evals.store(0, Ordering::Relaxed);
        let again = levenberg_marquardt(&r, &full.x, &b, &o);
        let n_again = evals.load(Ordering::Relaxed);
        assert!(again.converged && n_again <= 12, "{n_again} evaluations from the minimum");
        for k in 0..3 {
            assert!((again.x[k] - full.x[k]).abs() <= 0.1 * u.stderr[k]);
        }
    }
}
