//! After round 0, the first iteration of a smooth several-parameter candidate's full fit, made
//! before the rest of it: where that iteration shows the fit ends about where it stepped and
//! the held-out replay there does not pass the round's gate at the trust's edge, the fit is not
//! continued ([`short_after_first_step`]).
//!
//! A full fit of a smooth effect is Levenberg–Marquardt on the training data (the screen's; the
//! whole training set for the round's lead) from the candidate's coarse fit. Its first
//! iteration — the forward-difference Jacobian there (one replay per free parameter) and the
//! damped Gauss–Newton steps until one lowers the training error — is made here exactly as the
//! full fit makes it (the same problem, start and differences: when the fit goes on, it replays
//! none of it again). The Gauss–Newton model of that Jacobian is believed as far as the step
//! it checked, and only there:
//! - the training gain the step achieved is between `linear_trust` and its inverse times the
//!   one the model predicted for it — the trust's ratio ([`believed`]), not the screen's test
//!   that also takes two gains under `min_rel_improvement` as agreeing: a step from a coarse
//!   fit gains little by construction — and
//! - the step reached the model's own optimum: the gain the model predicts at the step is at
//!   least `linear_trust` times the one it predicts at its least-squares optimum (unbounded by
//!   the box).
//!
//! Then the model's optimum is where the fit goes, checked by a replay, and the fit's later
//! iterations move its measures at most 1 / `linear_trust` times further, as a confirmed coarse
//! fit's are taken to move ([`super::trust::heldout_needed`]): the step's held-out replay (one
//! held-out replay) must pass the round's gate at the trust's edge ([`at_trust_edge`]) for the
//! fit to go on. A first iteration that ends the fit (its statistical stop), does not move, or
//! whose model the step does not confirm says nothing here: the fit goes on as before. No
//! constant of its own.

use crate::fit::effects::{Applied, JointTarget, model_with};
use crate::fit::optim::{Bounds, ROLLOUT_REL_STEP, WIDEST_REL_STEP};
use crate::sim2real::recording::Recording;

use super::Errors;
use super::at_base::AtBase;
use super::engine::Engine;
use super::policy::SearchPolicy;
use super::solve::{Method, Problem, solve};
use super::trust::at_trust_edge;
use super::verdict::{Gate, verdict};

/// The relative held-out improvement (over the candidate's joints) at the point the first
/// iteration of the full fit of the candidate (the last entry of `sets.1`, on the base
/// `sets.0`, from its coarse fit's parameters) on `data` steps to, when that iteration confirms
/// its Gauss–Newton model up to the model's optimum and the held-out replay there does not
/// pass `gate` at the trust's edge against the round's held-out errors `ho_err` (see the module
/// docs); `None` (the fit goes on) otherwise, or when a replay fails.
pub(super) fn short_after_first_step(
    engine: &Engine,
    (heldout, data): (&[Recording], &[Recording]),
    (applied, at_coarse): (&[Applied], &[Applied]),
    ho_err: &Errors,
    gate: Gate,
) -> Option<f64> {
    let a = at_coarse.last()?;
    let (e, g) = (a.effect, &a.joints);
    let t = JointTarget::of(engine.robot, g.first()?)?;
    let m0 = model_with(engine.robot, applied);
    let full0 = e.initial(&m0, &t);
    let (lo, hi) = e.bounds(&m0, &t);
    let k = e.fitted().min(full0.len());
    if k == 0 || a.params.len() < k || lo.len() < k || hi.len() < k {
        return None;
    }
    // The full fit's problem (`Engine::fit_from` from the coarse fit's point).
    let at = AtBase::new(engine, data, applied, (e, g), &m0);
    let make = |x: &[f64]| {
        let mut p = full0.clone();
        p[..k].copy_from_slice(&x[..k]);
        at.set(applied, g, p)
    };
    let obj = |x: &[f64]| engine.score(data, &make(x));
    let res = |x: &[f64]| engine.residuals(data, &make(x), &engine.joints, usize::MAX);
    let res_or_empty = |x: &[f64]| res(x).unwrap_or_default();
    let b = Bounds { lo: lo[..k].to_vec(), hi: hi[..k].to_vec() };
    let x0: Vec<f64> = (0..k).map(|i| a.params[i].clamp(lo[i], hi[i])).collect();
    let held = engine.held_jacobian((data, applied), (e, g));
    let problem = Problem {
        objective: &obj,
        residuals: Some(&res_or_empty),
        bounds: b.clone(),
        held: held.as_ref(),
    };
    let unit = Unit::new(&b);
    let u0 = unit.to_unit(&x0);
    // The iterations up to the first that moves: a fit that has not moved yet widens its
    // difference once, to the widest, when its step is below what the difference resolves.
    let mut moved = None;
    for (iters, h) in [(1, ROLLOUT_REL_STEP), (2, WIDEST_REL_STEP)] {
        let resolve = engine.opts.policy.line_resolution;
        let s = solve(&problem, &x0, Method::LeastSquares { max_iters: iters, resolve });
        if s.converged || !s.f.is_finite() {
            return None;
        }
        if unit.to_unit(&s.x) != u0 {
            moved = Some((s, h));
            break;
        }
    }
    let (first, h) = moved?;
    let u1 = unit.to_unit(&first.x);
    // The Gauss–Newton model of the iteration's Jacobian (its replays, made already).
    let r0 = res(&unit.params_of(&u0)).filter(|r| !r.is_empty())?;
    let r1 = res(&first.x).filter(|r| r.len() == r0.len())?;
    // (The held Jacobian where the fit's first iteration took it: `HeldJacobian`.)
    let given = held.as_ref().and_then(|hj| hj.unit_columns(&b, &u0, h, r0.len()));
    let cols: Vec<Vec<f64>> = match given {
        Some(cols) => cols,
        None => (0..u0.len())
            .map(|j| unit.column((&u0, j, h), |x| res(x).filter(|r| r.len() == r0.len()), &r0))
            .collect::<Option<_>>()?,
    };
    let gram: Vec<Vec<f64>> =
        cols.iter().map(|c| cols.iter().map(|d| dot(c, d)).collect()).collect();
    let minus_b: Vec<f64> = cols.iter().map(|c| -dot(c, &r0)).collect();
    let ss0 = dot(&r0, &r0);
    let du: Vec<f64> = u1.iter().zip(&u0).map(|(a, b)| a - b).collect();
    let at_step: Vec<f64> = (0..r0.len())
        .map(|i| r0[i] + cols.iter().zip(&du).map(|(c, d)| c[i] * d).sum::<f64>())
        .collect();
    let gain = |ss: f64| 1.0 - (ss.max(0.0) / ss0).sqrt();
    let (want, got) = (gain(dot(&at_step, &at_step)), gain(dot(&r1, &r1)));
    let optimum = gain(ss0 - super::screen::combine(&minus_b, &gram).0);
    let pol = &engine.opts.policy;
    if !(ss0 > 0.0 && believed((got, want, optimum), pol)) {
        return None;
    }
    let ho1 = engine.errors(heldout, &make(&first.x))?;
    let v = verdict(ho_err, &ho1, g, gate);
    (!at_trust_edge((ho_err, &ho1), g, gate, pol)).then_some(v.rel)
}

/// Whether a step's achieved relative training gain `got` confirms its Gauss–Newton model:
/// between `linear_trust` and its inverse times the gain `want` the model predicts for it, and
/// `want` at least `linear_trust` times the gain at the model's own optimum `optimum` (the step
/// reached it, to the trust). The trust's ratio only, however small the gains: a step from a
/// coarse fit gains little by construction, and two gains under `min_rel_improvement` that
/// differ five-fold confirm nothing (BAM kp-400's round-2 motor constants: 0.19 % achieved for
/// 0.95 % predicted; their full fit went on to the gate, 8.9 % lower on held-out).
fn believed((got, want, optimum): (f64, f64, f64), pol: &SearchPolicy) -> bool {
    let lt = pol.linear_trust;
    want > 0.0 && got >= lt * want && got * lt <= want && want >= lt * optimum
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The Levenberg–Marquardt fit's unit box of the free parameters of `Bounds` (those of
/// positive width), with its arithmetic, so that the points it differences at are the fit's
/// own to the bit.
struct Unit {
    lo: Vec<f64>,
    span: Vec<f64>,
    free: Vec<usize>,
}

impl Unit {
    fn new(b: &Bounds) -> Unit {
        let span: Vec<f64> = b.lo.iter().zip(&b.hi).map(|(l, h)| h - l).collect();
        let free = (0..span.len()).filter(|&i| span[i] > 0.0).collect();
        Unit { lo: b.lo.clone(), span, free }
    }

    fn to_unit(&self, x: &[f64]) -> Vec<f64> {
        let u = |i: usize| (x[i] - self.lo[i]) / self.span[i];
        self.free.iter().map(|&i| clamp01(u(i))).collect()
    }

    fn params_of(&self, u: &[f64]) -> Vec<f64> {
        let mut x = self.lo.clone();
        for (k, &i) in self.free.iter().enumerate() {
            x[i] = (self.lo[i] + clamp01(u[k]) * self.span[i]).min(self.lo[i] + self.span[i]);
        }
        x
    }

    /// The fit's forward-difference column `j` at `u` (residuals `r0` there): a step of `h` of
    /// the box inward, the other way when that replay fails.
    fn column(
        &self,
        (u, j, h): (&[f64], usize, f64),
        res: impl Fn(&[f64]) -> Option<Vec<f64>>,
        r0: &[f64],
    ) -> Option<Vec<f64>> {
        let try_step = |s: f64| {
            let mut up = u.to_vec();
            up[j] = clamp01(u[j] + s);
            let ds = up[j] - u[j];
            if ds == 0.0 {
                return None;
            }
            let rp = res(&self.params_of(&up))?;
            Some(rp.iter().zip(r0).map(|(a, b)| (a - b) / ds).collect())
        };
        let first = if u[j] + h <= 1.0 { h } else { -h };
        try_step(first).or_else(|| try_step(-first))
    }
}

fn clamp01(u: f64) -> f64 {
    if u.is_nan() { 0.5 } else { u.clamp(0.0, 1.0) }
}

#[cfg(test)]
#[path = "first_step_tests.rs"]
mod tests;
