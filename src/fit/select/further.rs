//! What a further coarse fit of a smooth candidate could add at a point already replayed on
//! the screen's data: the largest gain the candidate's own least-squares model predicts there.
//!
//! A smooth candidate's coarse fit on the screen's data is Levenberg–Marquardt: each iteration
//! differentiates the rollout residual at its point (one replay per free parameter) and steps
//! to the minimum of the Gauss–Newton model it makes of the residual there. Where the
//! candidate's coarse fit on the probes' data was replayed once on the screen's data, at
//! `p`, that replay's gain is what the candidate gains there at that point (a lower bound on
//! its coarse fit's); the Gauss–Newton model at `p` — the columns of a forward difference at
//! `p` (the step of the least-squares fit's own Jacobian, [`ROLLOUT_REL_STEP`] of each
//! parameter's range) and the secant through the round's base model, whose replay the screen
//! holds — predicts the most any step from `p` can add, unbounded by the parameters' box and
//! by a trust region (both would only shorten the step). When even that prediction cannot
//! reach the round's bar for a full fit, no coarse fit on the screen's data is made
//! ([`super::coarse`]): it would end below the bar, as the point itself does. The prediction
//! costs one replay per free parameter of the screen's data; the coarse fit it replaces, two
//! iterations of k + 1 replays or more. When it can reach the bar, the same differences give the
//! step the fit's first iteration at `p` would take (Gauss–Newton, undamped, held inside the
//! box; [`Model::step`]): one more replay tells whether it gains what the model predicts, and
//! where it does (or reaches the bar) it is the coarse fit, for k + 1 replays instead of the
//! fit's.

use rayon::prelude::*;

use crate::fit::effects::{Applied, Effect, JointTarget, model_with};
use crate::fit::optim::{Bounds, HeldJacobian, ROLLOUT_REL_STEP};
use crate::sim2real::recording::Recording;

use super::at_base::AtBase;
use super::engine::Engine;
use super::screen::combine;

/// The Gauss–Newton model of a smooth candidate at a point replayed on the screen's data
/// ([`model_at`]): what it predicts any step can reach, and the step it takes.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Model {
    /// The lowest RMSE the model predicts (its columns: the forward differences and the secant
    /// from the base), unbounded by the box.
    pub(super) least: f64,
    /// The Gauss–Newton step of the forward differences alone — the step Levenberg–Marquardt's
    /// first iteration at the point takes, undamped — held inside the box: its parameters and
    /// the RMSE that model predicts there. `None` when it moves nothing.
    pub(super) step: Option<(Vec<f64>, f64)>,
}

/// The lowest RMSE on `short` that the Gauss–Newton model of `e` on `g` at `p` (RMSE `fp`
/// there, replayed) predicts ([`Model::least`]). `None` when a replay fails, the candidate has
/// no free parameter or its residuals do not line up.
#[cfg(test)]
pub(super) fn least_rmse(
    engine: &Engine,
    data: (&[Recording], &[Applied]),
    cand: (&'static dyn Effect, &[String]),
    at: (&[f64], f64),
) -> Option<f64> {
    model_at(engine, data, cand, at).map(|m| m.least)
}

/// The Gauss–Newton model of `e` on `g` at `p` (RMSE `fp` on `short` there, replayed): its
/// least RMSE, `fp` scaled by the root of the share of the residual's sum of squares that its
/// columns — one forward difference per free fitted parameter and the secant from the base
/// `applied` — leave unexplained; and the step of the differences alone ([`Model::step`]).
/// `None` when a replay fails, the candidate has no free parameter or its residuals do not
/// line up.
pub(super) fn model_at(
    engine: &Engine,
    (short, applied): (&[Recording], &[Applied]),
    (e, g): (&'static dyn Effect, &[String]),
    (p, fp): (&[f64], f64),
) -> Option<Model> {
    let t = JointTarget::of(engine.robot, g.first()?)?;
    let m0 = model_with(engine.robot, applied);
    let (lo, hi) = e.bounds(&m0, &t);
    let at = AtBase::new(engine, short, applied, (e, g), &m0);
    let k = e.fitted().min(p.len()).min(lo.len()).min(hi.len());
    let set = |x: Vec<f64>| at.set(applied, g, x);
    let resid = |a: &[Applied]| engine.residuals(short, a, &engine.joints, usize::MAX);
    let r = resid(&set(p.to_vec()))?;
    let free: Vec<usize> = (0..k).filter(|&i| hi[i] > lo[i]).collect();
    if free.is_empty() || r.is_empty() {
        return None;
    }
    let cols: Vec<Option<Vec<f64>>> = free
        .par_iter()
        .map(|&i| {
            let mut h = ROLLOUT_REL_STEP * (hi[i] - lo[i]);
            if p[i] + h > hi[i] {
                h = -h;
            }
            let mut x = p.to_vec();
            x[i] += h;
            let ri = resid(&set(x)).filter(|v| v.len() == r.len())?;
            Some(ri.iter().zip(&r).map(|(a, b)| (a - b) / h).collect())
        })
        .collect();
    let mut cols: Vec<Vec<f64>> = cols.into_iter().collect::<Option<_>>()?;
    // The differences are a least-squares fit's first Jacobian at `p` (the same residual, step
    // and box): held for the candidate's fit on `short` (`HeldJacobian`), which starts at `p` or
    // within a step of it (the model's step below, replayed) — when `p` beyond its fitted
    // parameters is the effect's start, as a fit's point is.
    let start = e.initial(&m0, &t);
    if p.len() == start.len() && p[k..] == start[k..] {
        let mut columns = vec![None; k];
        for (&i, c) in free.iter().zip(&cols) {
            columns[i] = Some(c.clone());
        }
        let bounds = Bounds { lo: lo[..k].to_vec(), hi: hi[..k].to_vec() };
        let j = HeldJacobian { at: p[..k].to_vec(), rel_step: ROLLOUT_REL_STEP, bounds, columns };
        engine.hold_jacobian((short, applied), (e, g), j);
    }
    let ss = dot(&r, &r);
    if !(ss > 0.0) || !fp.is_finite() {
        return None;
    }
    let left = |explained: f64| fp * ((ss - explained).max(0.0) / ss).sqrt();
    // The step: the differences' least-squares coefficients, negated (r + Σ aᵢ cᵢ least).
    let (explained, x) = explain(&cols, &r);
    let mut q = p.to_vec();
    for (&i, a) in free.iter().zip(&x) {
        q[i] = (p[i] - a).clamp(lo[i], hi[i]);
    }
    let step = (q.as_slice() != p && q.iter().all(|v| v.is_finite())).then(|| (q, left(explained)));
    if let Some(rb) = resid(applied).filter(|v| v.len() == r.len()) {
        cols.push(r.iter().zip(&rb).map(|(a, b)| a - b).collect());
    }
    let (explained, _) = explain(&cols, &r);
    Some(Model { least: left(explained), step })
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>()
}

/// The residual `r`'s sum of squares that the columns `cols` explain in least squares, and
/// their coefficients ([`combine`]).
fn explain(cols: &[Vec<f64>], r: &[f64]) -> (f64, Vec<f64>) {
    let b: Vec<f64> = cols.iter().map(|c| dot(c, r)).collect();
    let gram: Vec<Vec<f64>> =
        cols.iter().map(|a| cols.iter().map(|c| dot(a, c)).collect()).collect();
    combine(&b, &gram)
}

#[cfg(test)]
mod tests {
    use super::{least_rmse, model_at};
    use crate::fit::effects::{Applied, Effect, GainError};
    use crate::fit::select::{Engine, FitOptions};
    use crate::sim2real::recording::Recording;

    /// On a servo whose gains are off (kp × 0.9, kd × 1.4), recorded by the synth: from a point
    /// off the truth, the Gauss–Newton model predicts about what the full least-squares fit
    /// from there reaches, for one replay per parameter; at that fit's answer it predicts
    /// nothing more.
    #[test]
    fn the_model_at_a_point_predicts_what_a_fit_from_it_reaches() {
        let (robot, recs) =
            crate::synth::recorded::pendulum(Some((GainError.id(), vec![0.9, 1.4])), 3, 7);
        let opts = FitOptions::default();
        let engine = Engine::new(&robot, &recs, &opts);
        let g = vec!["servo".to_string()];
        let e: &'static dyn Effect = &GainError;
        let secs: f64 = recs.iter().map(|r| r.t.last().unwrap() - r.t[0]).sum();
        let at = |p: &[f64]| {
            let a = Applied { effect: e, joints: g.clone(), params: p.to_vec() };
            engine.score(&recs, &[a])
        };
        let _ = engine.score(&recs, &[]);
        let p = [1.0, 1.1];
        let fp = at(&p);
        let before = engine.rollout_stats().simulated_s;
        let most = least_rmse(&engine, (&recs, &[]), (e, &g), (&p, fp)).expect("modelled");
        let cost = engine.rollout_stats().simulated_s - before;
        assert!(cost <= 2.0 * secs + 1e-9, "{cost} s replayed for two parameters");
        let (q, fq) = engine.fit_from(&recs, &[], (e, &g), Some(&p));
        assert!(fq < 0.5 * fp, "the fit closes most of it: {fq} from {fp}");
        assert!(most < fp && (most - fq).abs() <= 0.25 * (fp - fq), "{most}: fit {fq}, {fp}");
        // Its step (the differences' alone), replayed, gains on the point about what it predicts.
        let m = model_at(&engine, (&recs, &[]), (e, &g), (&p, fp)).expect("modelled");
        let (x, want) = m.step.expect("a step");
        let fx = at(&x);
        assert!(fx < fp && (fx - want).abs() <= 0.25 * (fp - want), "{fx}: {want} from {fp}");
        let at_q = least_rmse(&engine, (&recs, &[]), (e, &g), (&q, fq)).expect("modelled");
        assert!(at_q >= 0.9 * fq && at_q <= fq, "{at_q} at the fit's {fq}");
        // Nothing to step: no prediction.
        let none: &[Recording] = &[];
        assert!(least_rmse(&engine, (none, &[]), (e, &g), (&p, fp)).is_none());
    }

    /// The model's differences are held as the first Jacobian of a least-squares fit of the
    /// candidate on the same data and base from its point: the point's replay, the model and a
    /// coarse fit from the point replay at most two sets more (the point and the base) than the
    /// same coarse fit on an engine that holds nothing, where the model's two columns, replayed
    /// again by the fit, would make it four — and they are held for that data and base alone.
    #[test]
    fn the_models_differences_start_a_fit_from_its_point() {
        let (robot, recs) =
            crate::synth::recorded::pendulum(Some((GainError.id(), vec![0.9, 1.4])), 3, 7);
        let opts = FitOptions::default();
        let g = vec!["servo".to_string()];
        let e: &'static dyn Effect = &GainError;
        let secs: f64 = recs.iter().map(|r| r.t.last().unwrap() - r.t[0]).sum();
        let p = [1.0, 1.1];
        let evals = opts.policy.screen_evals;
        let fit = |engine: &Engine| engine.fit_budget_from(&recs, &[], (e, &g), evals, &p);
        let plain = Engine::new(&robot, &recs, &opts);
        let alone = fit(&plain);
        let cost_alone = plain.rollout_stats().simulated_s;
        let engine = Engine::new(&robot, &recs, &opts);
        let a = Applied { effect: e, joints: g.clone(), params: p.to_vec() };
        let fp = engine.score(&recs, &[a]);
        model_at(&engine, (&recs, &[]), (e, &g), (&p, fp)).expect("modelled");
        assert!(engine.held_jacobian((&recs, &[]), (e, &g)).is_some());
        let other = recs[..1].to_vec();
        assert!(engine.held_jacobian((&other, &[]), (e, &g)).is_none());
        let held = fit(&engine);
        let cost = engine.rollout_stats().simulated_s;
        assert!(cost <= cost_alone + 2.0 * secs + 1e-9, "{cost} s, {cost_alone} s alone");
        let (ga, gh) = (1.0 - alone.1 / fp, 1.0 - held.1 / fp);
        assert!((gh - ga).abs() <= 0.1 * ga.abs(), "{held:?} {alone:?} from {fp}");
    }
}
