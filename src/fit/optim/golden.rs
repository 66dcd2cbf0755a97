//! 1-D bounded minimisation: a coarse grid, then Brent's refinement of the bracket around its
//! best point ([`super::brent_refine`]: parabolic steps, golden-section steps where those are
//! not trusted). Golden-section refinement alone ([`golden_refine`]) is kept as the reference
//! the tests compare it with.

use rayon::prelude::*;

use super::brent::brent_refine;
use super::resolve::Resolution;
use super::sanitize;

/// Points of [`line_search`]'s first grid, ends included [count].
pub const GRID_POINTS: usize = 9;

/// 1-D bounded minimisation on `[lo, hi]` returning `(x, f(x))`.
///
/// A 9-point uniform grid (endpoints included) is scanned first so a
/// multimodal objective is refined around the globally best grid point; the
/// bracket between its neighbours is then refined by Brent's method (the first
/// step the parabola through the grid's three points) until the minimum is
/// within `tol` of the best point or `max_evals` evaluations have been spent.
/// The best point ever evaluated is returned. `lo > hi` is swapped;
/// non-finite bounds or `max_evals == 0` return `f = +∞` without evaluating.
pub fn line_search(
    f: &(dyn Fn(f64) -> f64 + Sync),
    lo: f64,
    hi: f64,
    tol: f64,
    max_evals: usize,
) -> (f64, f64) {
    line_search_resolved(f, (lo, hi), tol, max_evals, None)
}

/// [`line_search`] whose refinement also stops once the minimum is located within the
/// `resolution`'s fraction of the parameter's standard error ([`Resolution`]).
pub fn line_search_resolved(
    f: &(dyn Fn(f64) -> f64 + Sync),
    (lo, hi): (f64, f64),
    tol: f64,
    max_evals: usize,
    resolution: Option<&Resolution<'_>>,
) -> (f64, f64) {
    if !lo.is_finite() || !hi.is_finite() || max_evals == 0 {
        let x = if lo.is_finite() {
            lo
        } else if hi.is_finite() {
            hi
        } else {
            0.0
        };
        return (x, f64::INFINITY);
    }
    let (lo, hi) = if lo <= hi { (lo, hi) } else { (hi, lo) };
    let mut evals = 0usize;
    let mut best = (lo, f64::INFINITY);
    let ev_known = |x: f64, v: f64, evals: &mut usize, best: &mut (f64, f64)| -> f64 {
        *evals += 1;
        let v = sanitize(v);
        if v < best.1 || best.1 == f64::INFINITY && *evals == 1 {
            *best = (x, v);
        }
        v
    };
    let ev = |x: f64, evals: &mut usize, best: &mut (f64, f64)| -> f64 {
        ev_known(x, f(x), evals, best)
    };
    if hi == lo {
        let v = ev(lo, &mut evals, &mut best);
        return (lo, v);
    }
    let tol = if tol.is_finite() && tol > 0.0 { tol } else { (hi - lo) * 1e-9 };
    let n_grid = max_evals.min(GRID_POINTS);
    if n_grid == 1 {
        let x = 0.5 * (lo + hi);
        let v = ev(x, &mut evals, &mut best);
        return (x, v);
    }
    let grid: Vec<f64> =
        (0..n_grid).map(|i| lo + (hi - lo) * i as f64 / (n_grid - 1) as f64).collect();
    // The grid's points are independent: evaluated as one parallel batch, then taken in order
    // (the same best, ties included, as one after another).
    let raw: Vec<f64> = grid.par_iter().map(|&x| f(x)).collect();
    let gf: Vec<f64> =
        grid.iter().zip(raw).map(|(&x, v)| ev_known(x, v, &mut evals, &mut best)).collect();
    // First index of the minimum (deterministic on ties).
    let ib = (0..n_grid).fold(0, |b, i| if gf[i] < gf[b] { i } else { b });
    let a = grid[ib.saturating_sub(1)];
    let bb = grid[(ib + 1).min(n_grid - 1)];

    if evals + 2 > max_evals {
        return best;
    }
    let ends = (ib > 0 && ib + 1 < n_grid).then(|| (gf[ib - 1], gf[ib + 1]));
    brent_refine(f, (a, bb), tol, max_evals - evals, (grid[ib], gf[ib]), ends, resolution)
}

/// Golden-section refinement of the bracket `[a, b]` (which holds a minimum: no point inside is
/// known lower than its best end) until it is narrower than `tol` or `max_evals` evaluations
/// have been spent; returns the best point evaluated, or `best` (a point known already, e.g.
/// the grid's) when none is lower. Fewer than two evaluations return `best` unevaluated.
pub fn golden_refine(
    f: &(dyn Fn(f64) -> f64 + Sync),
    (mut a, mut bb): (f64, f64),
    tol: f64,
    max_evals: usize,
    mut best: (f64, f64),
) -> (f64, f64) {
    if max_evals < 2 {
        return best;
    }
    let ev = |x: f64, best: &mut (f64, f64)| -> f64 {
        let v = sanitize(f(x));
        if v < best.1 {
            *best = (x, v);
        }
        v
    };
    let invphi = (5f64.sqrt() - 1.0) / 2.0; // 0.618...
    let mut x1 = bb - invphi * (bb - a);
    let mut x2 = a + invphi * (bb - a);
    let mut f1 = ev(x1, &mut best);
    let mut f2 = ev(x2, &mut best);
    let mut n = 2;
    while (bb - a) > tol && n < max_evals {
        n += 1;
        if f1 <= f2 {
            bb = x2;
            x2 = x1;
            f2 = f1;
            x1 = bb - invphi * (bb - a);
            f1 = ev(x1, &mut best);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + invphi * (bb - a);
            f2 = ev(x2, &mut best);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    #[test]
    fn golden_multimodal_picks_global() {
        // Broad local minimum at -1 (depth 1), narrow global at 2.1 (depth 2).
        let f =
            |x: f64| -2.0 * (-((x - 2.1) / 0.3).powi(2)).exp() - (-((x + 1.0) / 1.0).powi(2)).exp();
        let count = AtomicUsize::new(0);
        let fc = |x: f64| {
            count.fetch_add(1, Ordering::Relaxed);
            assert!((-4.0..=4.0).contains(&x));
            f(x)
        };
        let (x, fx) = line_search(&fc, -4.0, 4.0, 1e-7, 100);
        assert!((x - 2.1).abs() < 1e-5, "x = {x}");
        assert!((fx - f(x)).abs() == 0.0 && fx < -1.99);
        assert!(count.load(Ordering::Relaxed) <= 100);
        // Budget respected when tiny.
        count.store(0, Ordering::Relaxed);
        let (x5, _) = line_search(&fc, -4.0, 4.0, 1e-7, 5);
        assert!(count.load(Ordering::Relaxed) <= 5);
        assert_eq!(x5, 2.0);
        // Reversed bounds and a bound-active minimum.
        let (xb, fb) = line_search(&|x: f64| x, 3.0, 1.0, 1e-9, 50);
        assert_eq!((xb, fb), (1.0, 1.0));
    }
}
