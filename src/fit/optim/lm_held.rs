//! A Jacobian a caller already holds, handed to Levenberg–Marquardt for its first iteration
//! ([`super::levenberg_marquardt_from`]) instead of differencing the residual again.
//!
//! A rollout fit's first iteration differences the residual at its start (one replay per free
//! parameter, a step of `rel_step` of each parameter's range). Where the caller differenced the
//! same residual — the same data and base model, which only the caller can tell — at the same
//! step of the same box, at a point within one difference step of the start on every free
//! parameter, those columns are that iteration's Jacobian: two forward differences of a step
//! `h` taken less than `h` apart measure the same secant slope to within the difference's own
//! resolution (what a difference of step `h` resolves is the residual's change over `h`). The
//! columns are used for the first iteration only; every later one (and a widened difference)
//! is differenced at its own point. Anything else (another box, another step, a point further
//! away, a column missing or of another length) and the fit differences as before.

use super::Bounds;

/// Forward-difference columns of a residual vector, differenced at `at` with a step of
/// `rel_step` of each parameter's range in `bounds`.
#[derive(Debug, Clone)]
pub struct HeldJacobian {
    /// The point (the fit's parameters, their units) the columns were differenced at.
    pub at: Vec<f64>,
    /// The difference step [fraction of each parameter's range].
    pub rel_step: f64,
    /// The box whose ranges the step is a fraction of.
    pub bounds: Bounds,
    /// One column per parameter (`None` for one held fixed): the change of each residual per
    /// unit of the parameter [residual units / parameter units].
    pub columns: Vec<Option<Vec<f64>>>,
}

impl HeldJacobian {
    /// The columns in the unit box of the free parameters of `b` (those of positive width, in
    /// order), for a fit from `u0` (their unit coordinates) differencing at `h` with `m`
    /// residuals; `None` when they do not apply (see the module docs).
    pub(crate) fn unit_columns(
        &self,
        b: &Bounds,
        u0: &[f64],
        h: f64,
        m: usize,
    ) -> Option<Vec<Vec<f64>>> {
        let np = b.lo.len();
        let same_box = self.bounds.lo.len() == np
            && self.bounds.hi.len() == np
            && (0..np).all(|i| {
                self.bounds.lo[i].to_bits() == b.lo[i].to_bits()
                    && self.bounds.hi[i].to_bits() == b.hi[i].to_bits()
            });
        if !same_box || self.rel_step != h || self.at.len() != np || self.columns.len() != np {
            return None;
        }
        let free: Vec<usize> = (0..np).filter(|&i| b.hi[i] > b.lo[i]).collect();
        if free.len() != u0.len() {
            return None;
        }
        free.iter()
            .zip(u0)
            .map(|(&i, &u)| {
                let span = b.hi[i] - b.lo[i];
                let near = ((self.at[i] - b.lo[i]) / span - u).abs() <= h;
                let col = self.columns[i].as_ref().filter(|c| c.len() == m)?;
                (near && col.iter().all(|v| v.is_finite()))
                    .then(|| col.iter().map(|v| v * span).collect())
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicUsize, Ordering};

    use super::super::lm::tests::{ROLLOUT_RESOLUTION, rollout_opts};
    use super::super::tests::{exp_data, exp_model};
    use super::super::{LmOpts, ROLLOUT_REL_STEP, levenberg_marquardt, levenberg_marquardt_from};
    use super::*;

    /// Forward differences of `r` at `x` of `rel` of each range of `b`, made here apart from the
    /// optimiser (in the parameters' own units, as the search's screen makes them).
    fn differenced(
        r: &dyn Fn(&[f64]) -> Vec<f64>,
        x: &[f64],
        b: &Bounds,
        rel: f64,
    ) -> HeldJacobian {
        let r0 = r(x);
        let columns = (0..x.len())
            .map(|i| {
                let d = rel * (b.hi[i] - b.lo[i]);
                let mut xp = x.to_vec();
                xp[i] += d;
                Some(r(&xp).iter().zip(&r0).map(|(a, c)| (a - c) / d).collect())
            })
            .collect();
        HeldJacobian { at: x.to_vec(), rel_step: rel, bounds: b.clone(), columns }
    }

    /// A noisy exponential fitted with the rollout options: given forward differences of the
    /// same residual made at the start — or half a step from it — the fit's first iteration
    /// replays none of its own (one evaluation per parameter fewer), and it ends where the fit
    /// without them ends, within a fifth of a standard error (its statistical stop's tenth, twice); given
    /// differences two steps away, or of another step, it differences as before.
    #[test]
    fn a_held_jacobian_replaces_the_first_differences_only_where_it_applies() {
        let (t, y) = exp_data(3, &[2.0, 1.3, 0.5], 0.05);
        let b = Bounds { lo: vec![0.0, 0.01, -2.0], hi: vec![5.0, 5.0, 2.0] };
        let evals = AtomicUsize::new(0);
        let r = |p: &[f64]| {
            evals.fetch_add(1, Ordering::Relaxed);
            t.iter().zip(&y).map(|(&ti, &yi)| exp_model(p, ti) - yi).collect::<Vec<f64>>()
        };
        let plain = |p: &[f64]| {
            t.iter().zip(&y).map(|(&ti, &yi)| exp_model(p, ti) - yi).collect::<Vec<f64>>()
        };
        let x0 = [1.0, 0.5, 0.0];
        let o = rollout_opts(ROLLOUT_RESOLUTION);
        let run = |held: Option<&HeldJacobian>, iters: usize| {
            evals.store(0, Ordering::Relaxed);
            let fit = levenberg_marquardt_from(
                &r,
                &x0,
                &b,
                &LmOpts { max_iters: iters, ..o.clone() },
                held,
            );
            (fit, evals.load(Ordering::Relaxed))
        };
        let (one, n_one) = run(None, 1);
        let here = differenced(&plain, &x0, &b, ROLLOUT_REL_STEP);
        let (one_held, n_held) = run(Some(&here), 1);
        assert_eq!(n_held + 3, n_one, "{one:?} {one_held:?}");
        let half = [1.0 + 0.005 * 5.0, 0.5, 0.0];
        let near = differenced(&plain, &half, &b, ROLLOUT_REL_STEP);
        assert_eq!(run(Some(&near), 1).1 + 3, n_one);
        let far = differenced(&plain, &[1.0 + 0.02 * 5.0, 0.5, 0.0], &b, ROLLOUT_REL_STEP);
        let wide = differenced(&plain, &x0, &b, 0.05);
        for other in [&far, &wide] {
            let (fit, n) = run(Some(other), 1);
            assert!(n == n_one && fit.x == one.x, "{fit:?} {one:?}");
        }
        // The whole fit: the same minimum.
        let (whole, _) = run(None, 12);
        let (whole_held, _) = run(Some(&near), 12);
        let full = levenberg_marquardt(&plain, &x0, &b, &LmOpts::default());
        let u = crate::fit::stats::uncertainty_from_jacobian(
            &full.jacobian,
            &plain(&full.x),
            3,
            &[5.0, 4.99, 4.0],
        );
        for (k, se) in u.stderr.iter().enumerate() {
            let off = (whole_held.x[k] - whole.x[k]).abs();
            assert!(off <= 0.2 * se, "param {k}: {whole_held:?} {whole:?}");
        }
    }

    fn held() -> HeldJacobian {
        HeldJacobian {
            at: vec![1.0, 0.5],
            rel_step: 0.01,
            bounds: Bounds { lo: vec![0.0, 0.5], hi: vec![2.0, 0.5] },
            columns: vec![Some(vec![1.0, -2.0, 0.5]), None],
        }
    }

    /// The held columns, scaled to the unit box, apply within one difference step of the start
    /// on the same box and step; nowhere else.
    #[test]
    fn held_columns_apply_only_on_the_same_box_and_step_near_their_point() {
        let h = held();
        let b = h.bounds.clone();
        assert_eq!(h.unit_columns(&b, &[0.5], 0.01, 3), Some(vec![vec![2.0, -4.0, 1.0]]));
        assert!(h.unit_columns(&b, &[0.509], 0.01, 3).is_some());
        assert!(h.unit_columns(&b, &[0.52], 0.01, 3).is_none(), "two steps away");
        assert!(h.unit_columns(&b, &[0.5], 0.05, 3).is_none(), "another step");
        assert!(h.unit_columns(&b, &[0.5], 0.01, 4).is_none(), "another residual");
        let wider = Bounds { lo: vec![0.0, 0.5], hi: vec![2.5, 0.5] };
        assert!(h.unit_columns(&wider, &[0.4], 0.01, 3).is_none(), "another box");
        let both = Bounds { lo: vec![0.0, 0.0], hi: vec![2.0, 1.0] };
        let h2 = HeldJacobian { bounds: both.clone(), ..held() };
        assert!(h2.unit_columns(&both, &[0.5, 0.5], 0.01, 3).is_none(), "a column missing");
    }
}
