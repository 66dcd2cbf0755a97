//! 1-D refinement of a bracketed minimum by Brent's method: a parabola through the three best
//! points evaluated so far where it is trustworthy, a golden-section step where it is not.
//!
//! Brent, R. P. (1973), *Algorithms for Minimization without Derivatives*, ch. 5 (the
//! procedure `localmin`). On a profile that is smooth near its minimum each parabolic step
//! gains about 1.3 digits (superlinear convergence) where a golden-section step gains 0.21;
//! where the parabola is rejected (its vertex outside the bracket, nearer the current best
//! point than the tolerance, or not less than half the step before last, which forbids slow
//! cycling on a kink or a ripple) the step is golden section's. So the bracket still shrinks at
//! worst geometrically, and the answer meets the same guarantee as golden section's: the best
//! point evaluated, with the minimum of a unimodal profile within `tol` of it.
//!
//! Two rules make it hold on a replayed RMSE. A point as low as the best one becomes the best
//! (Brent's `fu <= fx`): on a plateau — an effect inert over part of its range, such as a
//! torque limit above the largest torque the recording asks for, where every point replays the
//! same motion and the RMSE is equal to the last bit — a tie says nothing about where a lower
//! point lies, and keeping the old best would cut away the side the new point was taken on,
//! the side away from the plateau. And a parabolic step is taken only through three points
//! whose parabola is convex (a positive second divided difference): the vertex of a concave
//! one is its maximum.
//!
//! Where the data stop telling, it stops before its tolerance when given a [`Resolution`]: once
//! the bracket locates the minimum within a fraction of the parameter's own standard error,
//! that error from the curvature of the parabola through the three points (`resolve`).

use super::resolve::{Resolution, Resolved};
use super::sanitize;

/// Brent refinement of the bracket `[a, b]` around `best` (a point inside it, evaluated
/// already: the grid's best point), whose ends were evaluated too when `ends` gives their
/// values (the grid's neighbours of `best`: the first step is then the parabola through the
/// three, no golden step needed to start one). Stops when the minimum of a unimodal profile is
/// within `tol` of the best point (the bracket around it no wider than `tol` on either side)
/// or after `max_evals` evaluations; returns the best point evaluated (of equal ones, the last:
/// see the module's note on plateaus), or `best` when none is as low. Fewer than two
/// evaluations, a non-finite `best` or one outside the bracket return `best` unevaluated.
/// With a `resolution` it also stops once the bracket locates the minimum within its fraction
/// of the parameter's standard error ([`Resolution::stop`]: from the parabolas through the
/// best point and the two others kept, where convex with the best strictly lowest between).
pub fn brent_refine(
    f: &(dyn Fn(f64) -> f64 + Sync),
    (a, b): (f64, f64),
    tol: f64,
    max_evals: usize,
    best: (f64, f64),
    ends: Option<(f64, f64)>,
    resolution: Option<&Resolution<'_>>,
) -> (f64, f64) {
    let (mut a, mut b) = if a <= b { (a, b) } else { (b, a) };
    let (mut x, mut fx) = best;
    if max_evals < 2 || !fx.is_finite() || !(a..=b).contains(&x) || !(b > a) {
        return best;
    }
    // The golden section's fraction of the longer side, (3 − √5) / 2.
    let cgold = 0.5 * (3.0 - 5f64.sqrt());
    // The step never shorter than `tol1`: the minimum lies within 2 tol1 = `tol` of x at the
    // stop (the same guarantee as golden section's final bracket of width `tol`).
    let tol1 = 0.5 * if tol.is_finite() && tol > 0.0 { tol } else { (b - a) * 1e-9 };
    // w: the second best point, v: the previous w. Known ends stand in for them.
    let ((mut w, mut fw), (mut v, mut fv)) = match ends {
        Some((fa, fb)) => {
            let (fa, fb) = (sanitize(fa), sanitize(fb));
            if fa <= fb { ((a, fa), (b, fb)) } else { ((b, fb), (a, fa)) }
        }
        None => ((x, fx), (x, fx)),
    };
    // d: the last step; e: the step before it (the bracket's width at the start, so that a
    // first parabolic step through known ends is taken when it is shorter than half of it).
    let mut d: f64 = 0.0;
    let mut e: f64 = if ends.is_some() { b - a } else { 0.0 };
    let mut n = 0;
    // What the resolution learnt of the parameter's standard error so far.
    let mut resolved = Resolved::default();
    while n < max_evals {
        let m = 0.5 * (a + b);
        if (x - m).abs() <= 2.0 * tol1 - 0.5 * (b - a) {
            break;
        }
        if resolution.is_some_and(|r| r.stop((a, b), (x, fx), [(w, fw), (v, fv)], &mut resolved)) {
            break;
        }
        let mut parabolic = false;
        // A convex parabola through the three points: a positive second divided difference.
        let convex = v != w && w != x && v != x && {
            let (s_xw, s_wv) = ((fx - fw) / (x - w), (fw - fv) / (w - v));
            (s_xw - s_wv) / (x - v) > 0.0
        };
        if e.abs() > tol1 && convex {
            // The vertex of the parabola through (v, fv), (w, fw), (x, fx): x + p / q.
            let r = (x - w) * (fx - fv);
            let mut q = (x - v) * (fx - fw);
            let mut p = (x - v) * q - (x - w) * r;
            q = 2.0 * (q - r);
            if q > 0.0 {
                p = -p;
            } else {
                q = -q;
            }
            let e_prev = e;
            // (A finite vertex inside the bracket, less than half the step before last.)
            if p.is_finite()
                && q.is_finite()
                && p.abs() < (0.5 * q * e_prev).abs()
                && p > q * (a - x)
                && p < q * (b - x)
            {
                e = d;
                d = p / q;
                let u = x + d;
                // Not within tol1 of the bracket's ends: a point there brackets nothing new.
                if u - a < 2.0 * tol1 || b - u < 2.0 * tol1 {
                    d = if x < m { tol1 } else { -tol1 };
                }
                parabolic = true;
            }
        }
        if !parabolic {
            // A golden-section step into the longer side.
            e = if x < m { b - x } else { a - x };
            d = cgold * e;
        }
        let u = if d.abs() >= tol1 { x + d } else { x + tol1.copysign(d) };
        let fu = sanitize(f(u));
        n += 1;
        // Brent's rule: a tie moves the best point (a plateau's tie cuts nothing away).
        if fu <= fx {
            if u < x {
                b = x;
            } else {
                a = x;
            }
            (v, fv) = (w, fw);
            (w, fw) = (x, fx);
            (x, fx) = (u, fu);
        } else {
            if u < x {
                a = u;
            } else {
                b = u;
            }
            if fu <= fw || w == x {
                (v, fv) = (w, fw);
                (w, fw) = (u, fu);
            } else if fu <= fv || v == x || v == w {
                (v, fv) = (u, fu);
            }
        }
    }
    (x, fx)
}

#[cfg(test)]
mod tests {
    use super::super::golden_refine;
    use super::super::{counted, plateau_dip};
    use super::brent_refine;

    /// A named profile: the function, its minimiser, and whether it is smooth there.
    type Profile = (&'static str, Box<dyn Fn(f64) -> f64 + Sync>, f64, bool);

    /// Profiles of the shapes a one-parameter fit meets, each with its minimiser: a smooth bowl
    /// (off-centre and skewed), a kink (|x − m|, a play's RMSE near its width), a square-root
    /// cusp, and a bowl with a ripple of 1 % of its depth (a rollout's jagged error). From a
    /// grid point and its two neighbours, Brent's method ends within `tol` of the minimiser
    /// (the ripple's global one within the ripple's period) and never uses more evaluations
    /// than golden section from the same bracket — fewer on every smooth profile.
    #[test]
    fn brent_meets_golden_sections_tolerance_in_fewer_evaluations() {
        let (lo, hi) = (0.0, 0.2);
        let h = (hi - lo) / 8.0;
        let tol = 2e-4 * (hi - lo);
        let profiles: Vec<Profile> = vec![
            ("bowl", Box::new(|x: f64| (x - 0.0413).powi(2) + 1e-3), 0.0413, true),
            (
                "skewed bowl",
                Box::new(|x: f64| (x - 0.0731).powi(2) * (1.0 + 20.0 * x) + 0.02),
                0.0731,
                true,
            ),
            ("kink", Box::new(|x: f64| (x - 0.1237).abs() + 0.01), 0.1237, false),
            ("cusp", Box::new(|x: f64| (x - 0.0413).abs().sqrt() + 0.01), 0.0413, false),
            (
                "ripple",
                Box::new(|x: f64| (x - 0.0613).powi(2) + 1e-7 * (x / 3e-4).sin()),
                0.0613,
                false,
            ),
        ];
        for (name, f, truth, smooth) in &profiles {
            // The 9-point grid's best point and its neighbours.
            let grid: Vec<f64> = (0..9).map(|i| lo + h * i as f64).collect();
            let ib = (0..9).fold(0, |b, i| if f(grid[i]) < f(grid[b]) { i } else { b });
            let (a, b) = (grid[ib - 1], grid[ib + 1]);
            let best = (grid[ib], f(grid[ib]));
            let ends = Some((f(a), f(b)));
            let (rb, nb) =
                counted(f.as_ref(), |g| brent_refine(g, (a, b), tol, 31, best, ends, None));
            let (rg, ng) = counted(f.as_ref(), |g| golden_refine(g, (a, b), tol, 31, best));
            let off = if *name == "ripple" { 3e-4 * std::f64::consts::TAU } else { tol };
            assert!((rb.0 - truth).abs() <= off, "{name}: {rb:?} for {truth}");
            assert!((rg.0 - truth).abs() <= off, "{name}: golden {rg:?} for {truth}");
            assert!(rb.1 <= f(rb.0) && rb.1 == f(rb.0), "{name}: the value is the point's");
            assert!(nb <= ng, "{name}: Brent {nb} evaluations, golden section {ng}");
            if *smooth {
                assert!(2 * nb <= ng, "{name}: Brent {nb} evaluations, golden section {ng}");
            }
        }
    }

    /// A torque limit's profile: a dip (the limit) narrower than the grid's spacing, steep
    /// below it (the limit clips), and a plateau above it where the limit never binds — every
    /// point there replays the same motion, the same RMSE to the last bit. The grid's best point
    /// is the plateau's end of the range, and the first step inside its bracket lands on the
    /// plateau: a tie, which must not cut away the dip's side. On the range's either end (the
    /// profile mirrored: a play below which nothing moves), from the grid on [−1, 1].
    #[test]
    fn a_tie_on_a_plateau_keeps_the_dip_beside_it() {
        for side in [1.0, -1.0] {
            let dip = plateau_dip(side);
            let tol = 2e-4 * 2.0;
            let ((x, fx), n) = counted(&dip, |g| super::super::line_search(g, -1.0, 1.0, tol, 40));
            assert!((x - side * 0.85).abs() <= tol, "side {side}: {x} ({fx}) after {n}");
            assert!(fx < 0.71 && n <= 40, "side {side}: {x} ({fx}) after {n}");
            // From the grid's bracket around its best point, the range's end (ends unknown).
            let (a, b) = if side > 0.0 { (0.75, 1.0) } else { (-1.0, -0.75) };
            let ((xb, _), nb) =
                counted(&dip, |g| brent_refine(g, (a, b), tol, 31, (side, 1.0), None, None));
            let ((xg, _), ng) = counted(&dip, |g| golden_refine(g, (a, b), tol, 31, (side, 1.0)));
            assert!((xb - side * 0.85).abs() <= tol, "side {side}: Brent {xb} after {nb}");
            assert!((xg - side * 0.85).abs() <= tol, "side {side}: golden {xg} after {ng}");
        }
    }

    /// Without known ends the first step is golden section's; the budget is kept; a best point
    /// on the bracket's end (a minimum on the range's bound: no play) is refined towards it and
    /// stays there; a degenerate call returns `best` unevaluated.
    #[test]
    fn brent_keeps_its_budget_and_its_bounds() {
        let f = |x: f64| (x - 0.3).powi(2);
        let ((x, _), n) =
            counted(&f, |g| brent_refine(g, (0.0, 1.0), 1e-6, 50, (0.5, 0.04), None, None));
        assert!((x - 0.3).abs() < 1e-6 && n <= 50, "{x} after {n}");
        let (_, n) =
            counted(&f, |g| brent_refine(g, (0.0, 1.0), 1e-12, 5, (0.5, 0.04), None, None));
        assert_eq!(n, 5);
        // The minimum on the bound: every step lands inside and is worse.
        let up = |x: f64| x + 1.0;
        let ((x, fx), n) = counted(&up, |g| {
            brent_refine(g, (0.0, 0.25), 5e-5, 40, (0.0, 1.0), Some((1.0, 1.25)), None)
        });
        assert_eq!((x, fx), (0.0, 1.0));
        assert!(n < 20, "{n} evaluations to close on the bound");
        for (best, m) in [((0.5, 0.04), 1), ((2.0, 1.0), 10), ((0.5, f64::INFINITY), 10)] {
            let (r, n) = counted(&f, |g| brent_refine(g, (0.0, 1.0), 1e-6, m, best, None, None));
            assert_eq!((r, n), (best, 0));
        }
    }
}
