//! The standard errors of a fit, from a finite-difference Jacobian of its residuals at the
//! answer; the Jacobian is kept ([`Jacobian`]) for Gauss–Newton steps from that answer on other
//! settings of the same data (the timestep check's finer step:
//! [`crate::fit::select::chord`]).

use nalgebra::{DMatrix, DVector};

use crate::fit::effects::{Applied, JointTarget, model_with};
use crate::fit::stats::{
    NULL_SV_REL, ar1_variance_inflation, cluster_robust_stderr, uncertainty_from_jacobian,
};
use crate::sim2real::recording::Recording;

use super::Engine;

/// Finite-difference step of the standard errors' Jacobian [fraction of the parameter's range].
pub(super) const FD_STEP: f64 = 1e-3;
/// Most residual rows a Jacobian holds (the residual is subsampled evenly beyond them).
const MAX_ROWS: usize = 20_000;

/// One column: (effect index in the set, parameter index, lower bound, upper bound).
type Slot = (usize, usize, f64, f64);

/// Standard errors and identifiability of each effect's fitted parameters.
pub type StdErrs = Vec<(Vec<f64>, Vec<bool>)>;

/// The residual (real − sim, on the effects' joints) of a set of applied effects at its values
/// and its finite-difference columns, one per free fitted parameter of the effects `which`.
#[derive(Clone, Debug)]
pub struct Jacobian {
    /// The set it was measured at.
    pub applied: Vec<Applied>,
    which: Vec<usize>,
    joints: Vec<String>,
    /// Every fitted parameter of `which`, held ones (bounds of zero width) included.
    slots_all: Vec<Slot>,
    /// The free ones: the columns, in order.
    slots: Vec<Slot>,
    /// n × k, a row per residual.
    rows: Vec<Vec<f64>>,
    r0: Vec<f64>,
    /// The training recording of each residual (the clusters of [`cluster_robust_stderr`]).
    episode: Vec<usize>,
}

impl Engine<'_> {
    /// Linearised standard errors of the fitted parameters of `applied.last()`, the others held
    /// at their values (used while the search runs; [`Engine::uncertainty_all`] gives the final
    /// ones).
    pub(in crate::fit::select) fn uncertainty(
        &self,
        train: &[Recording],
        applied: &[Applied],
    ) -> (Vec<f64>, Vec<bool>) {
        let last = applied.len() - 1;
        let j = self.jacobian(train, applied, &[last]);
        j.map_or_else(|| failed(applied, &[last]), |j| j.stderr(&j.r0)).pop().expect("one effect")
    }

    /// Linearised standard errors of every applied effect's fitted parameters, from one joint
    /// Jacobian: a parameter correlated with another effect's (an armature and a gain error on
    /// one joint) gets the wider marginal error, not the one conditional on the other held fixed.
    /// The Jacobian comes with them (`None` when a replay failed).
    pub(in crate::fit::select) fn uncertainty_all(
        &self,
        train: &[Recording],
        applied: &[Applied],
    ) -> (StdErrs, Option<Jacobian>) {
        let all: Vec<usize> = (0..applied.len()).collect();
        match self.jacobian(train, applied, &all) {
            Some(j) => (j.stderr(&j.r0), Some(j)),
            None => (failed(applied, &all), None),
        }
    }

    /// The residual of `applied` on `train` on the joints of `j`'s effects, row for row like
    /// `j`'s (the same recordings on this engine's model: another timestep).
    pub(in crate::fit::select) fn residuals_like(
        &self,
        train: &[Recording],
        applied: &[Applied],
        j: &Jacobian,
    ) -> Option<Vec<f64>> {
        self.residuals(train, applied, &j.joints, MAX_ROWS).filter(|r| r.len() == j.r0.len())
    }

    /// The [`Jacobian`] of the fitted parameters of the effects `which` of `applied` on `train`:
    /// one replay for the residual and one per free parameter (step [`FD_STEP`] of its range,
    /// inward at the upper bound). `None` when a replay fails.
    pub(in crate::fit::select) fn jacobian(
        &self,
        train: &[Recording],
        applied: &[Applied],
        which: &[usize],
    ) -> Option<Jacobian> {
        let mut slots_all: Vec<Slot> = Vec::new();
        let mut joints: Vec<String> = Vec::new();
        for &ai in which {
            let a = &applied[ai];
            let t = JointTarget::of(self.robot, &a.joints[0])?;
            let m0 = model_with(self.robot, &applied[..ai]);
            let (lo, hi) = a.effect.bounds(&m0, &t);
            for i in 0..a.effect.fitted().min(a.params.len()) {
                slots_all.push((ai, i, lo[i], hi[i]));
            }
            for j in &a.joints {
                if !joints.contains(j) {
                    joints.push(j.clone());
                }
            }
        }
        let (r0, episode) = self.residuals_by_episode(train, applied, &joints, MAX_ROWS)?;
        // A parameter held by bounds of zero width (a body's place along a direction no
        // rotation moves it) is no estimate: no column, reported as held (0, identified).
        let slots: Vec<Slot> = slots_all.iter().copied().filter(|s| s.3 > s.2).collect();
        let mut cols = Vec::with_capacity(slots.len());
        for &(ai, i, lo, hi) in &slots {
            let mut h = FD_STEP * (hi - lo).max(1e-9);
            if applied[ai].params[i] + h > hi {
                h = -h;
            }
            let mut a = applied.to_vec();
            a[ai].params[i] += h;
            // Residuals are real − sim, so ∂r/∂p = −∂sim/∂p; the sign does not matter for J^T J.
            let r1 =
                self.residuals(train, &a, &joints, MAX_ROWS).filter(|r| r.len() == r0.len())?;
            cols.push(r1.iter().zip(&r0).map(|(a, b)| (a - b) / h).collect::<Vec<f64>>());
        }
        let rows: Vec<Vec<f64>> =
            (0..r0.len()).map(|row| cols.iter().map(|c| c[row]).collect()).collect();
        let which = which.to_vec();
        Some(Jacobian {
            applied: applied.to_vec(),
            which,
            joints,
            slots_all,
            slots,
            rows,
            r0,
            episode,
        })
    }
}

/// Infinite standard errors, nothing identified, for the effects `which` of `applied`.
fn failed(applied: &[Applied], which: &[usize]) -> StdErrs {
    which
        .iter()
        .map(|&ai| {
            let a = &applied[ai];
            let k = a.effect.fitted().min(a.params.len());
            (vec![f64::INFINITY; k], vec![false; k])
        })
        .collect()
}

impl Jacobian {
    /// The residual at the set it was measured at.
    pub fn residual(&self) -> &[f64] {
        &self.r0
    }

    /// Standard errors (and identifiability) of the fitted parameters of its effects, jointly,
    /// with the residual `r` (row for row like the Jacobian's; its own for the fit it was
    /// measured at): the larger of `s²(JᵀJ)⁺` with s² inflated for serial correlation (AR(1))
    /// and the cluster-robust estimate with one cluster per training episode
    /// ([`cluster_robust_stderr`]).
    pub fn stderr(&self, r: &[f64]) -> StdErrs {
        let k = self.slots.len();
        if k == 0 {
            let n = |ai: usize| self.slots_all.iter().filter(|s| s.0 == ai).count();
            return self.which.iter().map(|&ai| (vec![0.0; n(ai)], vec![true; n(ai)])).collect();
        }
        let ranges: Vec<f64> = self.slots.iter().map(|s| s.3 - s.2).collect();
        // Serially correlated residuals: scaling them by √inflation scales s² (and so the
        // covariance s²(JᵀJ)⁺ and the identifiability check) by the AR(1) inflation.
        let c = ar1_variance_inflation(r).sqrt();
        let scaled: Vec<f64> = r.iter().map(|x| x * c).collect();
        let mut u = uncertainty_from_jacobian(&self.rows, &scaled, k, &ranges);
        // Episodes that disagree about a parameter (or an error that lasts a whole episode)
        // widen it beyond what the pooled residuals show: the larger of the two is reported,
        // and a parameter whose error then exceeds half its range is not identifiable.
        if let Some(robust) = cluster_robust_stderr(&self.rows, r, &self.episode, k) {
            u.widen(&robust, &ranges);
        }
        self.which
            .iter()
            .map(|&ai| {
                let pos = |s: &Slot| self.slots.iter().position(|x| x == s);
                let of: Vec<Option<usize>> =
                    self.slots_all.iter().filter(|s| s.0 == ai).map(pos).collect();
                (
                    of.iter().map(|p| p.map_or(0.0, |s| u.stderr[s])).collect(),
                    of.iter().map(|p| p.is_none_or(|s| u.identifiable[s])).collect(),
                )
            })
            .collect()
    }

    /// The Gauss–Newton step of the free parameters for the residual `r` (row for row like the
    /// Jacobian's): `−J⁺ r`, the pseudo-inverse through the SVD without the singular values
    /// below [`NULL_SV_REL`] of the largest. `None` when `r` does not match or the Jacobian is
    /// degenerate.
    pub fn step(&self, r: &[f64]) -> Option<Vec<f64>> {
        let (m, k) = (self.rows.len(), self.slots.len());
        if k == 0 || r.len() != m || m <= k || r.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let j = DMatrix::from_fn(m, k, |a, b| self.rows[a][b]);
        let svd = j.svd(true, true);
        let smax = svd.singular_values.iter().copied().fold(0.0_f64, f64::max);
        if !(smax > 0.0) {
            return None;
        }
        let rhs = DVector::from_iterator(m, r.iter().map(|v| -v));
        let x = svd.solve(&rhs, NULL_SV_REL * smax).ok()?;
        x.iter().all(|v| v.is_finite()).then(|| x.iter().copied().collect())
    }

    /// Broyden's update: the columns corrected by the rank-one change that makes them map the
    /// step `dx` (free parameters, as [`Jacobian::step`]) to the change of residual `dr` it
    /// was replayed to make (`J += (dr − J dx) dxᵀ / dxᵀdx`), the secant through the two points.
    /// On one parameter the column becomes the secant itself. Nothing for a zero step or a
    /// residual that does not match.
    pub fn secant(&mut self, dx: &[f64], dr: &[f64]) {
        let dd: f64 = dx.iter().map(|d| d * d).sum();
        if !(dd > 0.0) || dx.len() != self.slots.len() || dr.len() != self.rows.len() {
            return;
        }
        for (row, d) in self.rows.iter_mut().zip(dr) {
            let jd: f64 = row.iter().zip(dx).map(|(a, b)| a * b).sum();
            let c = (d - jd) / dd;
            for (a, b) in row.iter_mut().zip(dx) {
                *a += c * b;
            }
        }
    }

    /// `set` (the Jacobian's set at other values) moved by `dx` (one entry per free parameter,
    /// as [`Jacobian::step`]), each parameter held inside its bounds.
    pub fn moved(&self, set: &[Applied], dx: &[f64]) -> Vec<Applied> {
        let mut out = set.to_vec();
        for (&(ai, i, lo, hi), d) in self.slots.iter().zip(dx) {
            out[ai].params[i] = (out[ai].params[i] + d).clamp(lo, hi);
        }
        out
    }

    /// The step from `a` to `b` (two values of the Jacobian's set) in its free parameters.
    pub fn taken(&self, a: &[Applied], b: &[Applied]) -> Vec<f64> {
        self.slots.iter().map(|&(ai, i, ..)| b[ai].params[i] - a[ai].params[i]).collect()
    }

    /// Whether every free parameter of `dx` is shorter than `tol` × its standard error in `se`
    /// (as [`Jacobian::stderr`] gives them).
    pub fn within(&self, dx: &[f64], se: &StdErrs, tol: f64) -> bool {
        self.slots.iter().zip(dx).all(|(&(ai, i, ..), d)| {
            let w = self.which.iter().position(|&x| x == ai);
            let s = w.and_then(|w| se[w].0.get(i).copied()).unwrap_or(f64::INFINITY);
            s.is_finite() && d.abs() <= tol * s
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A straight line `a + b t` through points off it: the residual's Jacobian is `[−1, −t]`
    /// whatever the parameters, so one Gauss–Newton step from anywhere is the least-squares
    /// line, here computed from the normal equations in closed form.
    fn line(a0: f64, b0: f64) -> (Jacobian, Vec<f64>, (f64, f64)) {
        let effect = crate::fit::effects::all()
            .into_iter()
            .find(|e| e.fitted() >= 2)
            .expect("an effect of two parameters");
        let t: Vec<f64> = (0..50).map(|i| i as f64 * 0.1).collect();
        let y: Vec<f64> = t.iter().map(|t| 1.5 + 0.7 * t + 0.05 * (7.3 * t).sin()).collect();
        let n = t.len() as f64;
        let (st, sy, stt, sty) = t
            .iter()
            .zip(&y)
            .fold((0.0, 0.0, 0.0, 0.0), |s, (t, y)| (s.0 + t, s.1 + y, s.2 + t * t, s.3 + t * y));
        let b = (n * sty - st * sy) / (n * stt - st * st);
        let a = (sy - b * st) / n;
        let r: Vec<f64> = t.iter().zip(&y).map(|(t, y)| y - (a0 + b0 * t)).collect();
        let mut params = vec![0.0; effect.params().len()];
        (params[0], params[1]) = (a0, b0);
        let slots = vec![(0, 0, -10.0, 10.0), (0, 1, -10.0, 10.0)];
        let j = Jacobian {
            applied: vec![Applied { effect, joints: vec!["j".into()], params }],
            which: vec![0],
            joints: vec!["j".into()],
            slots_all: slots.clone(),
            slots,
            rows: t.iter().map(|t| vec![-1.0, -t]).collect(),
            r0: r.clone(),
            episode: (0..t.len()).map(|i| i % 3).collect(),
        };
        (j, r, (a, b))
    }

    #[test]
    fn a_gauss_newton_step_on_a_linear_residual_lands_on_the_least_squares_answer() {
        let (j, r, (a, b)) = line(0.2, -0.4);
        let dx = j.step(&r).expect("a step");
        let moved = j.moved(&j.applied, &dx);
        let p = &moved[0].params;
        assert!((p[0] - a).abs() < 1e-9 && (p[1] - b).abs() < 1e-9, "{p:?} for ({a}, {b})");
        // The next step from there is nothing (the residual left is orthogonal to J's columns).
        let r1: Vec<f64> = r
            .iter()
            .zip(&j.rows)
            .map(|(r, row)| r + row[0] * (p[0] - 0.2) + row[1] * (p[1] + 0.4))
            .collect();
        let se = j.stderr(&r1);
        assert!(se[0].0.iter().all(|s| s.is_finite() && *s > 0.0), "{se:?}");
        assert!(j.within(&j.step(&r1).expect("a step"), &se, 1e-6));
        assert!(!j.within(&dx, &se, 0.1), "the first step {dx:?} is not short: {se:?}");
    }

    /// On a residual that is not linear in the parameters (`y − b² t`, J measured at another
    /// point), the secant columns after a step map it exactly to the change it made, and the
    /// next step lands where the secant through the two points crosses zero.
    #[test]
    fn broydens_update_makes_the_columns_the_secant_of_the_step() {
        let (mut j, _, _) = line(0.0, 0.0);
        let t: Vec<f64> = (0..50).map(|i| i as f64 * 0.1).collect();
        let r = |a: f64, b: f64| -> Vec<f64> {
            t.iter().map(|t| 2.0 + 1.0 * t - a - b * b * t).collect()
        };
        let (r0, r1) = (r(0.0, 0.5), r(0.5, 0.8));
        let dx = [0.5, 0.3];
        let dr: Vec<f64> = r1.iter().zip(&r0).map(|(a, b)| a - b).collect();
        j.secant(&dx, &dr);
        for (row, d) in j.rows.iter().zip(&dr) {
            assert!((row[0] * dx[0] + row[1] * dx[1] - d).abs() < 1e-12);
        }
        // A zero step changes nothing.
        let before = j.rows.clone();
        j.secant(&[0.0, 0.0], &dr);
        assert_eq!(j.rows, before);
    }

    #[test]
    fn a_step_is_held_inside_the_bounds_and_a_residual_of_another_length_has_none() {
        let (j, r, _) = line(9.9, 0.0);
        let moved = j.moved(&j.applied, &[-20.0, 30.0]);
        assert_eq!((moved[0].params[0], moved[0].params[1]), (-10.0, 10.0));
        assert!(j.step(&r[1..]).is_none());
        assert!(j.step(&[f64::NAN; 50]).is_none());
    }
}
