//! Bounded Nelder–Mead simplex minimisation, with restarts when the simplex collapses.

use rayon::prelude::*;
use serde::Serialize;

use super::{Bounds, OptResult, Space, clamp01, invalid_result, sanitize};

/// Options for [`nelder_mead`].
#[derive(Debug, Clone, Serialize)]
pub struct NelderMeadOpts {
    /// Evaluation budget.
    pub max_evals: usize,
    /// Simplex size tolerance in normalised units (max ∞-distance of any
    /// vertex from the best one).
    pub xtol: f64,
    /// Absolute tolerance on the spread of objective values in the simplex.
    pub ftol: f64,
    /// Initial simplex edge, normalised (fraction of each bounds range).
    pub initial_step: f64,
}

impl Default for NelderMeadOpts {
    fn default() -> Self {
        NelderMeadOpts { max_evals: 1000, xtol: 1e-6, ftol: 1e-10, initial_step: 0.15 }
    }
}

/// Bounded Nelder–Mead simplex minimisation.
///
/// Works in the normalised box; trial points are clamped onto the box (so
/// bound-active optima are reached exactly). Uses the dimension-adaptive
/// coefficients of Gao & Han for `n > 2`. When the simplex collapses the
/// search is restarted around the best point (a collapsed simplex on a bound
/// face can otherwise stall); it is declared converged when a restart no
/// longer improves the best value by more than `ftol`.
pub fn nelder_mead(
    f: &(dyn Fn(&[f64]) -> f64 + Sync),
    x0: &[f64],
    b: &Bounds,
    o: &NelderMeadOpts,
) -> OptResult {
    let Some(sp) = Space::new(b, x0.len()) else {
        return invalid_result(x0);
    };
    let n = sp.dim();
    let mut evals = 0usize;
    let feval = |u: &[f64], evals: &mut usize| -> f64 {
        *evals += 1;
        sanitize(f(&sp.params_of(u)))
    };
    if o.max_evals == 0 {
        return OptResult { x: sp.clamp_x(x0), f: f64::INFINITY, evals: 0, converged: false };
    }
    let u0 = sp.to_unit(x0);
    if n == 0 {
        let fx = feval(&u0, &mut evals);
        return OptResult { x: sp.params_of(&u0), f: fx, evals, converged: true };
    }
    let nf = n as f64;
    let (alpha, gamma, rho, delta) = if n > 2 {
        (1.0, 1.0 + 2.0 / nf, 0.75 - 1.0 / (2.0 * nf), 1.0 - 1.0 / nf)
    } else {
        (1.0, 2.0, 0.5, 0.5)
    };
    let step0 = if o.initial_step.is_finite() && o.initial_step > 0.0 {
        o.initial_step.min(0.5)
    } else {
        0.15
    };
    let xtol = if o.xtol.is_finite() { o.xtol.max(0.0) } else { 1e-6 };
    let ftol = if o.ftol.is_finite() { o.ftol.max(0.0) } else { 1e-10 };

    let mut best_u = u0.clone();
    let mut best_f = feval(&u0, &mut evals);
    let mut converged = false;
    let mut prev_restart_best: Option<f64> = None;
    const MAX_RESTARTS: usize = 6;

    'restarts: for restart in 0..=MAX_RESTARTS {
        // Build simplex around the best point, stepping inward at the bounds.
        let step = if restart == 0 {
            step0
        } else {
            (step0 * 0.5f64.powi(restart as i32)).max(10.0 * xtol).min(step0)
        };
        let mut pts: Vec<Vec<f64>> = vec![best_u.clone()];
        let mut fs: Vec<f64> = vec![best_f];
        // The n new vertices are independent: one parallel batch, within the budget (as many
        // as one after another would have evaluated before running out).
        let count = n.min(o.max_evals.saturating_sub(evals));
        let verts: Vec<Vec<f64>> = (0..count)
            .map(|i| {
                let mut p = best_u.clone();
                p[i] = if p[i] + step <= 1.0 { p[i] + step } else { p[i] - step };
                p[i] = clamp01(p[i]);
                p
            })
            .collect();
        let vf: Vec<f64> = verts.par_iter().map(|p| sanitize(f(&sp.params_of(p)))).collect();
        evals += count;
        pts.extend(verts);
        fs.extend(vf);
        if count < n {
            break 'restarts;
        }

        loop {
            // Order vertices (stable on ties so the run is deterministic).
            let mut idx: Vec<usize> = (0..=n).collect();
            idx.sort_by(|&a, &b| fs[a].total_cmp(&fs[b]));
            pts = idx.iter().map(|&i| pts[i].clone()).collect();
            fs = idx.iter().map(|&i| fs[i]).collect();
            if fs[0] < best_f || (fs[0] == best_f && best_u != pts[0]) {
                best_f = fs[0];
                best_u = pts[0].clone();
            }

            let size = pts[1..]
                .iter()
                .map(|p| p.iter().zip(&pts[0]).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max))
                .fold(0.0, f64::max);
            let spread = fs[n] - fs[0];
            if size <= xtol && spread <= ftol {
                break; // this run converged
            }
            if size <= xtol * 1e-3 {
                break; // collapsed (e.g. all-infinite simplex); restart
            }
            if evals >= o.max_evals {
                break 'restarts;
            }

            // Centroid of all but the worst.
            let mut c = vec![0.0; n];
            for p in &pts[..n] {
                for (ci, pi) in c.iter_mut().zip(p) {
                    *ci += pi / nf;
                }
            }
            let worst = pts[n].clone();
            let along = |t: f64| -> Vec<f64> {
                c.iter().zip(&worst).map(|(ci, wi)| clamp01(ci + t * (ci - wi))).collect()
            };

            let xr = along(alpha);
            let fr = feval(&xr, &mut evals);
            if fr < fs[0] {
                if evals >= o.max_evals {
                    pts[n] = xr;
                    fs[n] = fr;
                    continue;
                }
                let xe = along(gamma);
                let fe = feval(&xe, &mut evals);
                if fe < fr {
                    pts[n] = xe;
                    fs[n] = fe;
                } else {
                    pts[n] = xr;
                    fs[n] = fr;
                }
                continue;
            }
            if fr < fs[n - 1] {
                pts[n] = xr;
                fs[n] = fr;
                continue;
            }
            if evals >= o.max_evals {
                continue; // loop head records best and exits on budget
            }
            // Contraction (outside if the reflection improved on the worst).
            let (xc, fc_ref) = if fr < fs[n] { (along(rho), fr) } else { (along(-rho), fs[n]) };
            let fc = feval(&xc, &mut evals);
            if fc <= fc_ref && fc.is_finite() || fc < fc_ref {
                pts[n] = xc;
                fs[n] = fc;
                continue;
            }
            // Shrink towards the best vertex.
            for i in 1..=n {
                if evals >= o.max_evals {
                    break;
                }
                let p: Vec<f64> = pts[i]
                    .iter()
                    .zip(&pts[0])
                    .map(|(pi, bi)| clamp01(bi + delta * (pi - bi)))
                    .collect();
                fs[i] = feval(&p, &mut evals);
                pts[i] = p;
            }
        }

        if let Some(prev) = prev_restart_best
            && prev - best_f <= ftol
        {
            converged = best_f.is_finite();
            break;
        }
        prev_restart_best = Some(best_f);
        if restart == MAX_RESTARTS {
            converged = best_f.is_finite();
        }
    }

    OptResult { x: sp.params_of(&best_u), f: best_f, evals, converged }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    fn rosenbrock(x: &[f64]) -> f64 {
        (1.0 - x[0]).powi(2) + 100.0 * (x[1] - x[0] * x[0]).powi(2)
    }

    #[test]
    fn nm_rosenbrock_2d() {
        let b = Bounds { lo: vec![-2.0, -2.0], hi: vec![2.0, 2.0] };
        let o = NelderMeadOpts { max_evals: 2000, xtol: 1e-9, ftol: 1e-14, ..Default::default() };
        let count = AtomicUsize::new(0);
        let f = |x: &[f64]| {
            count.fetch_add(1, Ordering::Relaxed);
            assert!(x.iter().all(|v| (-2.0..=2.0).contains(v)));
            rosenbrock(x)
        };
        let r = nelder_mead(&f, &[-1.2, 1.0], &b, &o);
        assert!((r.x[0] - 1.0).abs() < 1e-4 && (r.x[1] - 1.0).abs() < 1e-4, "{r:?}");
        assert!(r.f < 1e-8);
        assert!(r.evals <= 2000);
        assert_eq!(r.evals, count.load(Ordering::Relaxed));
        assert!(r.converged);
        assert_eq!(r.f, rosenbrock(&r.x));
    }

    #[test]
    fn nm_bound_active() {
        // Unconstrained minimum (3, -0.5) lies outside x <= 2.
        let b = Bounds { lo: vec![-1.0, -1.0], hi: vec![2.0, 1.0] };
        let f = |x: &[f64]| (x[0] - 3.0).powi(2) + (x[1] + 0.5).powi(2);
        let r = nelder_mead(&f, &[0.0, 0.5], &b, &NelderMeadOpts::default());
        assert_eq!(r.x[0], 2.0, "{r:?}");
        assert!((r.x[1] + 0.5).abs() < 1e-5, "{r:?}");
        assert!((r.f - 1.0).abs() < 1e-9);
        assert!(r.converged);
        // Corner optimum, 3-D, with a fixed parameter (lo == hi) that must stay put.
        let b = Bounds { lo: vec![0.0, 0.0, 0.7, 0.0], hi: vec![1.0, 1.0, 0.7, 1.0] };
        let f =
            |x: &[f64]| (x[0] - 3.0).powi(2) + (x[1] + 2.0).powi(2) + (x[3] - 0.25).powi(2) + x[2];
        let r = nelder_mead(&f, &[0.5, 0.5, 123.0, 0.5], &b, &NelderMeadOpts::default());
        assert_eq!(r.x[0], 1.0);
        assert_eq!(r.x[1], 0.0);
        assert_eq!(r.x[2], 0.7);
        assert!((r.x[3] - 0.25).abs() < 1e-5, "{r:?}");
    }
}
