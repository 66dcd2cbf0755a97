//! Joint fits of several kept effects at once: the polish of every kept parameter, and the
//! joint fit of the effects added last (a pair).

use crate::fit::effects::{Applied, JointTarget, model_with};
use crate::fit::optim::Bounds;
use crate::sim2real::recording::Recording;

use super::engine::Engine;
use super::solve::{Method, Problem, Solution, solve};
use super::{FitOutcome, Search, sync_selected};

/// Joint re-fit of every kept effect's fitted parameters from the greedy values
/// ([`polish_from`]: least squares when all are smooth, else Nelder–Mead); kept only when
/// both the training and the held-out RMSE do not get worse.
pub(super) fn polish(s: &Search, out: &mut FitOutcome) {
    let applied = std::mem::take(&mut out.applied);
    out.applied =
        polish_set(s.engine, s.train, s.heldout, applied, s.engine.opts.policy.polish_step);
    sync_selected(out);
}

pub(super) fn polish_set(
    engine: &Engine,
    train: &[Recording],
    heldout: &[Recording],
    applied: Vec<Applied>,
    step: f64,
) -> Vec<Applied> {
    polish_budget(engine, train, heldout, applied, step, engine.opts.policy.max_evals * 2)
}

/// [`polish_set`] with a budget of `max_evals` objective evaluations.
pub(super) fn polish_budget(
    engine: &Engine,
    train: &[Recording],
    heldout: &[Recording],
    applied: Vec<Applied>,
    step: f64,
    max_evals: usize,
) -> Vec<Applied> {
    polish_from(engine, (train, heldout), applied, 0, (step, max_evals))
}

/// [`polish_budget`] of the parameters of `applied[first..]` only (the effects before stay as
/// they are), with a budget of `max_evals` evaluations of `train`: Levenberg–Marquardt on the
/// rollout residuals when every polished effect is smooth ([`Effect::smooth`]: k + 1 replays
/// an iteration, at most `max_evals / (k + 2)` iterations, stopping at the first step shorter
/// than the parameters' standard errors resolve — from values already fitted together that is
/// one Jacobian and one step), else Nelder–Mead with initial step `step` (fraction of each
/// range); kept only when neither the training nor the held-out RMSE gets worse.
///
/// [`Effect::smooth`]: crate::fit::effects::Effect::smooth
pub(super) fn polish_from(
    engine: &Engine,
    (train, heldout): (&[Recording], &[Recording]),
    applied: Vec<Applied>,
    first: usize,
    (step, max_evals): (f64, usize),
) -> Vec<Applied> {
    let Some(slots) = param_slots(engine, &applied, first, |ai| ai) else { return applied };
    let make = |x: &[f64]| with_params(&applied, &slots, x);
    let x0: Vec<f64> = slots.iter().map(|&(ai, k, ..)| applied[ai].params[k]).collect();
    let b =
        Bounds { lo: slots.iter().map(|s| s.2).collect(), hi: slots.iter().map(|s| s.3).collect() };
    let obj = |x: &[f64]| engine.errors(train, &make(x)).map_or(f64::INFINITY, |e| e.rmse());
    let f0 = obj(&x0);
    let res = |x: &[f64]| {
        engine.residuals(train, &make(x), &engine.joints, usize::MAX).unwrap_or_default()
    };
    let smooth = !slots.is_empty() && applied[first..].iter().all(|a| a.effect.smooth());
    let method = if smooth {
        Method::LeastSquares {
            max_iters: (max_evals / (slots.len() + 2)).clamp(2, 12),
            resolve: engine.opts.policy.line_resolution,
        }
    } else {
        Method::Simplex { max_evals, xtol: 1e-4, step }
    };
    let problem =
        Problem { objective: &obj, residuals: smooth.then_some(&res), bounds: b, held: None };
    let r = solve(&problem, &x0, method);
    if r.f.is_nan() || r.f >= f0 {
        return applied;
    }
    let new = make(&r.x);
    let (Some(h0), Some(h1)) = (engine.errors(heldout, &applied), engine.errors(heldout, &new))
    else {
        return applied;
    };
    if h1.rmse() > h0.rmse() {
        return applied;
    }
    new
}

/// One fitted parameter of a set of applied effects: (effect index, parameter index, lo, hi).
type Slot = (usize, usize, f64, f64);

/// The fitted parameters of `set[first..]` with their bounds; effect `ai`'s bounds come from the
/// model with `set[..base(ai)]` applied. `None` when an effect's joint is not in the model.
pub(super) fn param_slots(
    engine: &Engine,
    set: &[Applied],
    first: usize,
    base: impl Fn(usize) -> usize,
) -> Option<Vec<Slot>> {
    let mut slots = Vec::new();
    for (ai, a) in set.iter().enumerate().skip(first) {
        let t = JointTarget::of(engine.robot, &a.joints[0])?;
        let m0 = model_with(engine.robot, &set[..base(ai)]);
        let (lo, hi) = a.effect.bounds(&m0, &t);
        for k in 0..a.effect.fitted().min(a.params.len()) {
            slots.push((ai, k, lo[k], hi[k]));
        }
    }
    Some(slots)
}

/// `set` with the parameters of `slots` set to `x`.
pub(super) fn with_params(set: &[Applied], slots: &[Slot], x: &[f64]) -> Vec<Applied> {
    let mut a = set.to_vec();
    for (&(ai, k, ..), v) in slots.iter().zip(x) {
        a[ai].params[k] = *v;
    }
    a
}

/// Fits the effects `set[first..]` jointly on `train` (the ones before stay fixed), starting from
/// their current parameters: Levenberg–Marquardt when all are smooth, else Nelder–Mead. Returns
/// the set unchanged when the joint fit does not lower the training error.
pub(super) fn fit_jointly(
    engine: &Engine,
    train: &[Recording],
    set: Vec<Applied>,
    first: usize,
) -> Vec<Applied> {
    fit_jointly_iters(engine, train, set, first, 12)
}

/// [`fit_jointly`] with at most `lm_iters` Levenberg–Marquardt iterations (k + 1 replays of
/// `train` each; it stops earlier when its step or its improvement is below the recordings'
/// resolution). The simplex for non-smooth effects keeps its budget.
pub(super) fn fit_jointly_iters(
    engine: &Engine,
    train: &[Recording],
    set: Vec<Applied>,
    first: usize,
    lm_iters: usize,
) -> Vec<Applied> {
    let Some(slots) = param_slots(engine, &set, first, |_| first) else { return set };
    let make = |x: &[f64]| with_params(&set, &slots, x);
    let x0: Vec<f64> =
        slots.iter().map(|&(ai, k, lo, hi)| set[ai].params[k].clamp(lo, hi)).collect();
    let b =
        Bounds { lo: slots.iter().map(|s| s.2).collect(), hi: slots.iter().map(|s| s.3).collect() };
    let obj = |x: &[f64]| engine.errors(train, &make(x)).map_or(f64::INFINITY, |e| e.rmse());
    let f0 = obj(&x0);
    let res = |x: &[f64]| {
        engine.residuals(train, &make(x), &engine.joints, usize::MAX).unwrap_or_default()
    };
    let problem = Problem { objective: &obj, residuals: Some(&res), bounds: b, held: None };
    let method = if set[first..].iter().all(|a| a.effect.smooth()) {
        Method::LeastSquares { max_iters: lm_iters, resolve: engine.opts.policy.line_resolution }
    } else {
        Method::Simplex { max_evals: engine.opts.policy.max_evals * 3, xtol: 1e-4, step: 0.1 }
    };
    let Solution { x, f, .. } = solve(&problem, &x0, method);
    if !(f < f0) {
        return set;
    }
    make(&x)
}
