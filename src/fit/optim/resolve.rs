//! A line search's stop where the data stop telling: once the bracket around the best point is
//! narrower than a fraction of the parameter's own standard error, a narrower one moves the
//! answer by less than the data can tell.
//!
//! The objective is a root mean square of `n` residuals, `f(p) = √(Σ rᵢ(p)² / n)`. Near its
//! minimum the sum of squares is a parabola, `Σ r² ≈ S₀ + JᵀJ (p − p̂)²` (Gauss–Newton), and the
//! parameter's linearised standard error is `√(s² c / JᵀJ)` with `s² = S₀ / (n − 1)` and `c`
//! the variance inflation of the residual's serial correlation — the noise model of the
//! reported standard errors (`s²(JᵀJ)⁺`, AR(1)-inflated:
//! [`crate::fit::stats::uncertainty_from_jacobian`], [`crate::fit::stats::ar1_variance_inflation`]).
//! The line search knows `JᵀJ` without a Jacobian: it is `n` times the second divided difference
//! of `f²` through three evaluated points. So, from the best point `(x, f(x))` and the two
//! others Brent's method keeps, `SE = f(x) √(c / ((n − 1) q))` with `q` that divided difference.
//!
//! It is used only where the curvature means something: the best point strictly lower than the
//! other two and strictly between them (so the parabola is convex and its vertex between them).
//! On a plateau (a tie), a flat profile, a monotone or concave one there is no standard error,
//! and the search goes on to its tolerance. Of the standard errors the usable parabolas give
//! the largest is kept ([`Resolution::stop`]: closer than a replayed RMSE's ripple, three
//! points measure the ripple). The stop adds no evaluation: the residual whose noise it needs
//! is the best point's, replayed already.

/// The noise behind a root-mean-square objective at a point: how many residuals it averages
/// and their variance inflation for serial correlation (≥ 1; 1 for independent ones).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Noise {
    /// Residuals the objective is the root mean square of [count].
    pub n: usize,
    /// Variance inflation of their serial correlation [ratio, ≥ 1].
    pub inflation: f64,
}

/// When a line search may stop before its tolerance: once the minimum is located within
/// `fraction` standard errors of its best point, the standard error from the profile's
/// curvature ([`profile_stderr`]) and the objective's noise at the best point (`noise`: `None`
/// when unknown — no stop there).
pub struct Resolution<'r> {
    /// How finely the parameter is resolved relative to its uncertainty [standard errors].
    pub fraction: f64,
    /// The objective's noise at a point of the searched variable (evaluated already).
    pub noise: &'r (dyn Fn(f64) -> Option<Noise> + Sync),
}

/// What a line search's refinement has learnt of the standard error so far: the largest one a
/// usable parabola gave (the widest-scale measure: see [`Resolution::stop`]) and the last point
/// whose noise was asked, with its answer (a best point that did not move is not asked again).
#[derive(Debug, Default)]
pub(super) struct Resolved {
    se: Option<f64>,
    memo: Option<(f64, Option<Noise>)>,
}

impl Resolution<'_> {
    /// Whether the bracket `[a, b]` around the best point `best` locates the minimum within
    /// `fraction` standard errors, `others` being the line search's two next-best points.
    /// Each usable parabola through the three ([`profile_stderr`]) gives a standard error; the
    /// largest so far is the one kept: a replayed RMSE is piecewise smooth in a non-smooth
    /// effect's parameter (a play's contacts start a sample earlier or later), and once the
    /// three points are closer than its ripple their parabola measures the ripple's curvature,
    /// not the data's information — a smaller standard error that would never let the search
    /// stop. No stop while the best point is not strictly lower than the other two (a tie: a
    /// plateau says nothing of where the minimum is) or before a usable parabola was seen.
    pub(super) fn stop(
        &self,
        (a, b): (f64, f64),
        best: (f64, f64),
        others: [(f64, f64); 2],
        state: &mut Resolved,
    ) -> bool {
        if !(self.fraction > 0.0) {
            return false;
        }
        if curvature(best, others).is_some() {
            let noise = match state.memo {
                Some((x, n)) if x == best.0 => n,
                _ => {
                    let n = (self.noise)(best.0);
                    state.memo = Some((best.0, n));
                    n
                }
            };
            if let Some(se) = noise.and_then(|n| profile_stderr(best, others, n)) {
                state.se = Some(state.se.map_or(se, |s| s.max(se)));
            }
        }
        let half = (best.0 - a).max(b - best.0);
        let lowest = others.iter().all(|o| best.1 < o.1);
        lowest && half.is_finite() && state.se.is_some_and(|se| half <= self.fraction * se)
    }
}

/// The second divided difference of `f²` through `best` and `others` when `best` is strictly
/// lower than both and strictly between them (a convex parabola, its vertex between them);
/// else `None`.
fn curvature((x, fx): (f64, f64), [(w, fw), (v, fv)]: [(f64, f64); 2]) -> Option<f64> {
    let finite = [x, fx, w, fw, v, fv].iter().all(|t| t.is_finite());
    let between = (w < x && x < v) || (v < x && x < w);
    let lowest = 0.0 <= fx && fx < fw && fx < fv;
    if !finite || !between || !lowest {
        return None;
    }
    let (gx, gw, gv) = (fx * fx, fw * fw, fv * fv);
    let q = ((gw - gx) / (w - x) - (gv - gx) / (v - x)) / (w - v);
    (q.is_finite() && q > 0.0).then_some(q)
}

/// The standard error of the minimiser of a root-mean-square profile from the parabola of its
/// square through the best point and two others (see the module's note), with the noise of the
/// best point's residual; `None` when the curvature is not usable (a plateau's tie, a flat,
/// monotone or concave profile), for fewer than two residuals or a non-finite answer.
pub fn profile_stderr(best: (f64, f64), others: [(f64, f64); 2], noise: Noise) -> Option<f64> {
    let q = curvature(best, others)?;
    let c = noise.inflation.max(1.0);
    if noise.n < 2 || !c.is_finite() {
        return None;
    }
    let se = best.1 * (c / ((noise.n - 1) as f64 * q)).sqrt();
    se.is_finite().then_some(se)
}

#[cfg(test)]
mod tests {
    use super::super::{counted, plateau_dip};
    use super::super::{line_search, line_search_resolved, seeded_rng};
    use super::{Noise, Resolution, profile_stderr};

    /// A least-squares problem whose answer and standard error are known in closed form: n
    /// residuals `rᵢ(p) = σ zᵢ − gᵢ (p − p*)` (white noise of size σ, a sensitivity gᵢ), so the
    /// root-mean-square profile is the root of a parabola plus noise; its minimiser is
    /// `p̂ = p* + Σ gᵢσzᵢ / Σ gᵢ²` and the standard error `σ / √Σ gᵢ²`.
    struct Bowl {
        z: Vec<f64>,
        g: Vec<f64>,
        sigma: f64,
        truth: f64,
    }

    impl Bowl {
        fn new(seed: u64, n: usize, sigma: f64, truth: f64) -> Bowl {
            let mut rng = seeded_rng(seed);
            let z = (0..n).map(|_| rng.normal()).collect();
            let g = (0..n).map(|i| 1.5 + (0.37 * i as f64).cos()).collect();
            Bowl { z, g, sigma, truth }
        }
        fn rms(&self, p: f64) -> f64 {
            let ss: f64 = self
                .z
                .iter()
                .zip(&self.g)
                .map(|(z, g)| (self.sigma * z - g * (p - self.truth)).powi(2))
                .sum();
            (ss / self.z.len() as f64).sqrt()
        }
        fn answer(&self) -> (f64, f64) {
            let gg: f64 = self.g.iter().map(|g| g * g).sum();
            let gz: f64 = self.g.iter().zip(&self.z).map(|(g, z)| g * self.sigma * z).sum();
            (self.truth + gz / gg, self.sigma / gg.sqrt())
        }
    }

    /// On the exact parabola the three-point curvature is exact: the standard error from any
    /// three points around the minimum is the closed form's, up to the estimate of σ² from the
    /// residual (n = 4000: a few per cent); an inflation c widens it by √c.
    #[test]
    fn the_profiles_standard_error_is_the_closed_forms() {
        for (seed, sigma) in [(1, 0.01), (2, 0.3), (3, 2.0)] {
            let bowl = Bowl::new(seed, 4000, sigma, 0.4);
            let (p, se) = bowl.answer();
            for h in [0.1 * se, se, 30.0 * se] {
                let pt = |x: f64| (x, bowl.rms(x));
                let three = (pt(p), [pt(p - h), pt(p + 0.7 * h)]);
                let white = Noise { n: 4000, inflation: 1.0 };
                let got = profile_stderr(three.0, three.1, white).expect("a usable parabola");
                assert!((got / se - 1.0).abs() < 0.05, "σ {sigma}, h {h}: {got} for {se}");
                let wide = profile_stderr(three.0, three.1, Noise { n: 4000, inflation: 9.0 });
                assert!((wide.expect("usable") / got - 3.0).abs() < 1e-9);
            }
        }
        // Not usable: a tie (a plateau), the best point not between the others (a monotone
        // profile), not the lowest (a concave or monotone one), fewer than two residuals.
        let white = Noise { n: 100, inflation: 1.0 };
        for (best, others) in [
            ((0.5, 1.0), [(0.4, 1.0), (0.6, 1.2)]),
            ((0.5, 1.0), [(0.6, 1.1), (0.7, 1.2)]),
            ((0.5, 2.0), [(0.4, 1.0), (0.6, 3.0)]),
            ((0.5, 2.0), [(0.4, 1.0), (0.6, 1.0)]),
        ] {
            assert_eq!(profile_stderr(best, others, white), None, "{best:?} {others:?}");
        }
        let one = Noise { n: 1, inflation: 1.0 };
        assert_eq!(profile_stderr((0.5, 1.0), [(0.4, 1.1), (0.6, 1.1)], one), None);
    }

    /// A parabola plus noise of known size, searched from the line search's grid on a range
    /// hundreds of standard errors wide: with a resolution the search stops with the
    /// closed-form minimum within `fraction` standard errors of its answer, in fewer
    /// evaluations than its tolerance needs. With a ripple on the RMSE (a replay's jagged
    /// error: half the rise one standard error makes, of a period of 0.44 of one) it still
    /// stops early, within half a standard error of where the plain search ends. With a
    /// fraction of 0 it is the plain line search, evaluation for evaluation.
    #[test]
    fn a_noisy_parabola_stops_within_the_fraction() {
        for (seed, sigma, truth) in [(7, 0.05, 0.31), (8, 0.2, 0.77), (9, 0.02, 0.052)] {
            let bowl = Bowl::new(seed, 3000, sigma, truth);
            let (p, se) = bowl.answer();
            assert!(se < 5e-3 && se > 1e-5, "a range of hundreds of standard errors: {se}");
            let tol = 1e-9;
            let white = |_: f64| Some(Noise { n: 3000, inflation: 1.0 });
            for ripple in [0.0, 0.5 / (2.0 * 3000.0)] {
                let f = |x: f64| bowl.rms(x) * (1.0 + ripple * (x / (0.07 * se)).sin());
                let ((x0, _), n0) = counted(&f, |g| line_search(g, 0.0, 1.0, tol, 40));
                for fraction in [0.1, 0.25, 0.5] {
                    let r = Resolution { fraction, noise: &white };
                    let search = |g: &(dyn Fn(f64) -> f64 + Sync)| {
                        line_search_resolved(g, (0.0, 1.0), tol, 40, Some(&r))
                    };
                    let ((x, fx), n) = counted(&f, search);
                    if ripple > 0.0 {
                        assert!((x - x0).abs() <= 0.5 * se, "{fraction}: {x} for {x0} ± {se}");
                    } else {
                        let bound = 1.05 * fraction * se;
                        assert!((x - p).abs() <= bound, "{fraction}: {x} for {p} ± {se}");
                    }
                    assert!(n < n0, "{fraction}, ripple {ripple}: {n} evaluations, {n0} without");
                    assert_eq!(fx, f(x));
                }
                let off = |_: f64| -> Option<Noise> { panic!("asked the noise at fraction 0") };
                let r = Resolution { fraction: 0.0, noise: &off };
                let search = |g: &(dyn Fn(f64) -> f64 + Sync)| {
                    line_search_resolved(g, (0.0, 1.0), tol, 40, Some(&r))
                };
                let ((x, _), n) = counted(&f, search);
                assert_eq!((x, n), (x0, n0));
            }
        }
    }

    /// A torque limit's profile (the dip of `brent`'s plateau test: steep below the limit,
    /// a plateau above it where every point replays alike) as the RMSE of 1000 residuals:
    /// searched from the grid's best point on the plateau's end of the range, with a resolution
    /// so coarse that any usable parabola stops the search at once, the search still leaves
    /// the plateau for the dip — a tie stops nothing — and ends in it. A flat or a monotone
    /// profile never stops early: the same evaluations as without a resolution.
    #[test]
    fn a_plateau_beside_a_dip_does_not_stop() {
        let white = |_: f64| Some(Noise { n: 1000, inflation: 1.0 });
        let coarse = Resolution { fraction: 1e6, noise: &white };
        for side in [1.0, -1.0] {
            let dip = plateau_dip(side);
            let (a, b) = if side > 0.0 { (0.75, 1.0) } else { (-1.0, -0.75) };
            let refine = |g: &(dyn Fn(f64) -> f64 + Sync)| {
                super::super::brent_refine(g, (a, b), 4e-4, 31, (side, 1.0), None, Some(&coarse))
            };
            let ((x, fx), _) = counted(&dip, refine);
            assert!(fx < 0.75 && (x - side * 0.85).abs() < 0.03, "side {side}: {x} ({fx})");
            // With a resolution of a quarter of a standard error: the dip's minimum.
            let fine = Resolution { fraction: 0.25, noise: &white };
            let ((x, fx), _) =
                counted(&dip, |g| line_search_resolved(g, (-1.0, 1.0), 4e-4, 40, Some(&fine)));
            assert!((x - side * 0.85).abs() <= 4e-3 && fx < 0.71, "side {side}: {x} ({fx})");
        }
        let flat = |_: f64| 1.0;
        let up = |x: f64| 2.0 + x;
        for f in [&flat as &(dyn Fn(f64) -> f64 + Sync), &up] {
            let (r0, n0) = counted(f, |g| line_search(g, 0.0, 1.0, 1e-6, 40));
            let plain = |g: &(dyn Fn(f64) -> f64 + Sync)| {
                line_search_resolved(g, (0.0, 1.0), 1e-6, 40, Some(&coarse))
            };
            assert_eq!(counted(f, plain), (r0, n0));
        }
    }
}
