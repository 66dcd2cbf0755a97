//! Bounded, derivative-free / least-squares optimisers for fitting physical
//! model parameters to recordings.
//!
//! Conventions shared by every method:
//! * Objectives are expensive and may be non-smooth. A NaN (or −∞) value is
//!   treated as `+∞`, i.e. a failed evaluation that is avoided, never
//!   propagated.
//! * Parameters are optimised in a normalised `[0,1]` space derived from
//!   [`Bounds`]; the objective is only ever called with points inside
//!   `[lo, hi]`. Parameters with `lo == hi` are held fixed.
//! * Everything is deterministic (the tool's splitmix64 RNG, `util::Rng`). Parallel evaluation
//!   (rayon) always gathers results in a fixed order, so results do not
//!   depend on the thread count.
//! * Invalid input (empty `x0`, length mismatch with bounds, non-finite
//!   bounds, `hi < lo`) never panics: the result has `converged == false`.

//!
//! This module owns the shared types ([`Bounds`], [`OptResult`]), the RNG and the normalised
//! search space; each method has its own file: [`nelder_mead()`], [`cmaes()`], [`line_search`]
//! (in `golden`, refined by [`brent_refine`] in `brent`, which stops early at a [`Resolution`]
//! of the parameter's standard error: `resolve`) and [`levenberg_marquardt`] (in `lm`).

mod brent;
mod cmaes;
mod golden;
mod lm;
mod lm_held;
mod lm_resolution;
mod nelder_mead;
mod resolve;

use serde::Serialize;

pub(crate) use crate::util::Rng;

pub use brent::brent_refine;
pub use cmaes::{CmaesOpts, cmaes};
pub use golden::{GRID_POINTS, golden_refine, line_search, line_search_resolved};
pub use lm::{
    LmOpts, LmResult, ROLLOUT_REL_STEP, ROLLOUT_SHORT_STEP, ROLLOUT_STAT_TOL, WIDEST_REL_STEP,
    levenberg_marquardt, levenberg_marquardt_from,
};
pub use lm_held::HeldJacobian;
pub use nelder_mead::{NelderMeadOpts, nelder_mead};
pub use resolve::{Noise, Resolution, profile_stderr};

/// Box bounds, one entry per parameter. `lo[i] <= hi[i]`, both finite.
#[derive(Debug, Clone, Serialize)]
pub struct Bounds {
    pub lo: Vec<f64>,
    pub hi: Vec<f64>,
}

/// Result of a scalar-objective minimisation.
#[derive(Debug, Clone, Serialize)]
pub struct OptResult {
    /// Best point found (always inside the bounds when input is valid).
    pub x: Vec<f64>,
    /// Objective at `x` (`+∞` if no finite value was ever seen).
    pub f: f64,
    /// Number of objective evaluations performed.
    pub evals: usize,
    /// Whether a tolerance criterion (rather than the budget) ended the search.
    pub converged: bool,
}

// ---------------------------------------------------------------------------
// Shared helpers
// ---------------------------------------------------------------------------

/// The optimisers' generator: the tool's splitmix64 ([`crate::util::Rng`]) seeded with
/// `seed ^ 0x5DEE_CE66_D1CE_4E5B`.
pub(crate) fn seeded_rng(seed: u64) -> Rng {
    Rng::from_state(seed ^ 0x5DEE_CE66_D1CE_4E5B)
}

/// Failed evaluations (NaN, −∞) become +∞.
#[inline]
fn sanitize(v: f64) -> f64 {
    if v.is_nan() || v == f64::NEG_INFINITY { f64::INFINITY } else { v }
}

/// Mapping between the user's parameter space and the normalised unit cube of
/// the free (non-fixed) parameters.
#[derive(Debug, Clone)]
struct Space {
    lo: Vec<f64>,
    span: Vec<f64>,
    free: Vec<usize>,
}

impl Space {
    fn new(b: &Bounds, n: usize) -> Option<Space> {
        if n == 0 || b.lo.len() != n || b.hi.len() != n {
            return None;
        }
        let mut span = Vec::with_capacity(n);
        let mut free = Vec::new();
        for i in 0..n {
            let (lo, hi) = (b.lo[i], b.hi[i]);
            let s = hi - lo;
            if !lo.is_finite() || !hi.is_finite() || !s.is_finite() || s < 0.0 {
                return None;
            }
            if s > 0.0 {
                free.push(i);
            }
            span.push(s);
        }
        Some(Space { lo: b.lo.clone(), span, free })
    }
    fn dim(&self) -> usize {
        self.free.len()
    }
    fn to_unit(&self, x: &[f64]) -> Vec<f64> {
        self.free
            .iter()
            .map(|&i| {
                let u = (x[i] - self.lo[i]) / self.span[i];
                if u.is_nan() { 0.5 } else { u.clamp(0.0, 1.0) }
            })
            .collect()
    }
    fn params_of(&self, u: &[f64]) -> Vec<f64> {
        let mut x = self.lo.clone();
        for (k, &i) in self.free.iter().enumerate() {
            let uk = if u[k].is_nan() { 0.5 } else { u[k].clamp(0.0, 1.0) };
            x[i] = (self.lo[i] + uk * self.span[i]).min(self.lo[i] + self.span[i]);
        }
        x
    }
    /// `x0` clamped into the bounds (used for results of trivial problems).
    fn clamp_x(&self, x0: &[f64]) -> Vec<f64> {
        let u = self.to_unit(x0);
        self.params_of(&u)
    }
}

fn invalid_result(x0: &[f64]) -> OptResult {
    OptResult { x: x0.to_vec(), f: f64::INFINITY, evals: 0, converged: false }
}

/// Reflect a coordinate into [0, 1] (period-2 mirror).
#[inline]
fn reflect01(u: f64) -> f64 {
    if !u.is_finite() {
        return 0.5;
    }
    if (0.0..=1.0).contains(&u) {
        return u;
    }
    let r = u.rem_euclid(2.0);
    if r > 1.0 { 2.0 - r } else { r }
}

#[inline]
fn clamp01(u: f64) -> f64 {
    if u.is_nan() { 0.5 } else { u.clamp(0.0, 1.0) }
}

/// Counts the evaluations of `f` made by `search`, and returns its answer with the count (the
/// line searches' tests, brent.rs and resolve.rs).
#[cfg(test)]
fn counted(
    f: &(dyn Fn(f64) -> f64 + Sync),
    search: impl Fn(&(dyn Fn(f64) -> f64 + Sync)) -> (f64, f64),
) -> ((f64, f64), usize) {
    use std::sync::atomic::{AtomicUsize, Ordering};
    let n = AtomicUsize::new(0);
    let g = |x: f64| {
        n.fetch_add(1, Ordering::Relaxed);
        f(x)
    };
    let r = search(&g);
    (r, n.load(Ordering::Relaxed))
}

/// A torque limit's RMSE profile on [−1, 1] (the line searches' tests): a plateau from 0.9 on
/// (above every torque the recording asks for, every point replays alike), a kink down to a
/// dip at 0.85 beside it; `side` −1 mirrors it (a play below which nothing moves).
#[cfg(test)]
fn plateau_dip(side: f64) -> impl Fn(f64) -> f64 + Sync {
    move |x: f64| {
        let x = side * x;
        if x >= 0.9 {
            1.0
        } else if x >= 0.85 {
            0.7 + 6.0 * (x - 0.85)
        } else {
            0.7 + 100.0 * (x - 0.85).powi(2)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// y = a exp(-b t) + c
    pub(super) fn exp_model(p: &[f64], t: f64) -> f64 {
        p[0] * (-p[1] * t).exp() + p[2]
    }

    pub(super) fn exp_data(seed: u64, truth: &[f64], sigma: f64) -> (Vec<f64>, Vec<f64>) {
        let mut rng = seeded_rng(seed);
        let t: Vec<f64> = (0..60).map(|i| i as f64 * 0.1).collect();
        let y =
            t.iter().map(|&ti| exp_model(truth, ti) + sigma * rng.normal_complement()).collect();
        (t, y)
    }

    #[test]
    fn nan_regions_avoided() {
        // Unconstrained optimum (1,1) sits in a region where the "simulation" fails.
        let f = |x: &[f64]| {
            if x[0] + x[1] > 1.5 { f64::NAN } else { (x[0] - 1.0).powi(2) + (x[1] - 1.0).powi(2) }
        };
        let b = Bounds { lo: vec![-2.0, -2.0], hi: vec![2.0, 2.0] };
        let nm = nelder_mead(&f, &[-1.0, 0.0], &b, &NelderMeadOpts::default());
        assert!(nm.f.is_finite() && nm.x[0] + nm.x[1] <= 1.5, "{nm:?}");
        // Constrained optimum on the failure boundary: (0.75, 0.75), f = 0.125.
        assert!(nm.f < 0.125 + 1e-6 && (nm.x[0] - 0.75).abs() < 1e-4, "{nm:?}");
        let cm = cmaes(&f, &[-1.0, 0.0], &b, &CmaesOpts { max_evals: 3000, ..Default::default() });
        assert!(cm.f.is_finite() && cm.x[0] + cm.x[1] <= 1.5, "{cm:?}");
        assert!(cm.f < 0.125 + 1e-3, "{cm:?}");
        let (gx, gf) = line_search(&|x: f64| f(&[x, x]), -2.0, 2.0, 1e-9, 60);
        assert!(gf.is_finite() && (gx - 0.75).abs() < 1e-6, "{gx} {gf}");
        // Objective that is NaN everywhere: no panic, infinite f, not converged.
        let all_nan = |_: &[f64]| f64::NAN;
        let r = nelder_mead(
            &all_nan,
            &[0.0, 0.0],
            &b,
            &NelderMeadOpts { max_evals: 100, ..Default::default() },
        );
        assert!(r.f.is_infinite() && !r.converged && r.evals <= 100);
        let r =
            cmaes(&all_nan, &[0.0, 0.0], &b, &CmaesOpts { max_evals: 200, ..Default::default() });
        assert!(r.f.is_infinite() && !r.converged && r.evals <= 200);
        // LM: residuals NaN for b > 1.6; start at b = 1.5 so naive steps overshoot into it.
        let truth = [2.0, 1.3, 0.5];
        let (t, y) = exp_data(5, &truth, 0.02);
        let rr = |p: &[f64]| {
            if p[1] > 1.6 {
                return vec![f64::NAN; t.len()];
            }
            t.iter().zip(&y).map(|(&ti, &yi)| exp_model(p, ti) - yi).collect::<Vec<f64>>()
        };
        let bb = Bounds { lo: vec![0.0, 0.01, -2.0], hi: vec![5.0, 5.0, 2.0] };
        let fit = levenberg_marquardt(&rr, &[4.0, 1.55, -1.0], &bb, &LmOpts::default());
        assert!(fit.cost.is_finite() && fit.converged, "{fit:?}");
        assert!((fit.x[1] - 1.3).abs() < 0.1 && (fit.x[0] - 2.0).abs() < 0.1, "{fit:?}");
        assert!(fit.jacobian.iter().flatten().all(|v| v.is_finite()));
    }

    #[test]
    fn degenerate_inputs() {
        let f = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>();
        let rf = |x: &[f64]| x.to_vec();
        let empty = Bounds { lo: vec![], hi: vec![] };
        let b2 = Bounds { lo: vec![0.0, 0.0], hi: vec![1.0, 1.0] };
        let bad = Bounds { lo: vec![1.0, 0.0], hi: vec![0.0, f64::NAN] };
        for (x0, b) in [(&[][..], &empty), (&[0.5][..], &b2), (&[0.5, 0.5][..], &bad)] {
            let r = nelder_mead(&f, x0, b, &NelderMeadOpts::default());
            assert!(!r.converged && r.evals == 0);
            let r = cmaes(&f, x0, b, &CmaesOpts::default());
            assert!(!r.converged && r.evals == 0);
            let r = levenberg_marquardt(&rf, x0, b, &LmOpts::default());
            assert!(!r.converged && r.iters == 0);
        }
        // Zero budgets.
        assert!(
            !nelder_mead(
                &f,
                &[0.5, 0.5],
                &b2,
                &NelderMeadOpts { max_evals: 0, ..Default::default() }
            )
            .converged
        );
        assert!(
            !cmaes(&f, &[0.5, 0.5], &b2, &CmaesOpts { max_evals: 0, ..Default::default() })
                .converged
        );
        let r = cmaes(
            &f,
            &[0.5, 0.5],
            &b2,
            &CmaesOpts { max_evals: 3, popsize: Some(1), ..Default::default() },
        );
        assert!(r.evals <= 3 && r.f.is_finite());
        // Empty residual vector.
        let r = levenberg_marquardt(
            &|_: &[f64]| vec![],
            &[0.5],
            &Bounds { lo: vec![0.0], hi: vec![1.0] },
            &LmOpts::default(),
        );
        assert!(!r.converged);
        // x0 outside the box and all-fixed parameters.
        let fixed = Bounds { lo: vec![0.3, 0.4], hi: vec![0.3, 0.4] };
        let r = nelder_mead(&f, &[9.0, -9.0], &fixed, &NelderMeadOpts::default());
        assert_eq!(r.x, vec![0.3, 0.4]);
        assert_eq!(r.evals, 1);
        let r = cmaes(&f, &[9.0, 9.0], &b2, &CmaesOpts { max_evals: 500, ..Default::default() });
        assert!(r.x.iter().all(|v| (0.0..=1.0).contains(v)) && r.f < 1e-8, "{r:?}");
        let lr = levenberg_marquardt(&rf, &[9.0, 9.0], &fixed, &LmOpts::default());
        assert_eq!(lr.x, vec![0.3, 0.4]);
        assert!(lr.converged);
        // line_search degenerate bounds.
        assert_eq!(line_search(&|x| x * x, 2.0, 2.0, 1e-6, 10), (2.0, 4.0));
        assert!(line_search(&|x| x, f64::NAN, 1.0, 1e-6, 10).1.is_infinite());
        assert!(line_search(&|x| x, 0.0, 1.0, 1e-6, 0).1.is_infinite());
        let (x1, _) = line_search(&|x: f64| (x - 0.3).abs(), 0.0, 1.0, 0.0, 1);
        assert_eq!(x1, 0.5);
    }
}
