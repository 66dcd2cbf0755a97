//! Before a candidate's full fit: whether what the round already holds at its coarse fit shows
//! that the full fit cannot be kept.
//!
//! A full fit goes on from the coarse fit on the same training data (Levenberg–Marquardt on the
//! screen's data), and is kept only when it passes the round's held-out gate and, for a smooth
//! effect, the same gate at a finer timestep ([`super::discretisation`]). Where the coarse fit
//! already shows that neither can be passed, the full fit (several replays of the screen's data
//! per parameter and iteration) is not made:
//! - the held-out screen ([`heldout_short`]): the coarse fit does not lower the held-out error,
//!   or (a one-line descent) does not pass the gate at the trust's edge;
//! - after round 0, a one-line descent ([`one_line_descent`]) whose coarse fit, replayed at the
//!   finer timestep, does not pass the gate there at the trust's edge
//!   ([`coarse_within_discretisation`]; `tried` phase `discretisation_screen`): the gain it made
//!   at the model's step was the integration step's (KR8's action delay after the armature);
//! - after round 0, a smooth candidate of several parameters whose held-out optimum by the
//!   Gauss–Newton model at its coarse fit ([`HeldoutModel::optimum`]; phase `heldout_bound`)
//!   does not lower the held-out RMSE by `linear_trust` × `min_rel_improvement` (the gate's
//!   relative improvement at the trust's edge): to first order no value of its parameters
//!   lowers it enough, whatever the training fit finds. Only the RMSE is judged there, as at
//!   the candidate's start ([`super::start_bound`]): the least-squares optimum is the largest
//!   fall of the RMSE, not the most significant one — the paired per-window tests can pass at
//!   a point of smaller gain spread over more windows, and the full fit lands at the training
//!   optimum, not the held-out one (BAM kp-400's round-2 motor constants);
//! - past that bound, the full fit's own first iteration, made first
//!   ([`short_after_first_step`]; phase `heldout_bound`): where it confirms its Gauss–Newton
//!   model up to the model's optimum, the held-out replay of its step must pass the gate at the
//!   trust's edge for the fit to go on.

use rayon::prelude::*;

use crate::fit::effects::{Applied, JointTarget, model_with};
use crate::fit::optim::ROLLOUT_REL_STEP;
use crate::sim2real::metrics::gap_mask;
use crate::sim2real::recording::Recording;

use super::discretisation::{Judged, coarse_within_discretisation};
use super::engine::Engine;
use super::first_step::short_after_first_step;
use super::policy::Phase;
use super::screen::combine;
use super::trust::{heldout_short, one_line_descent};
use super::verdict::Gate;
use super::{Errors, FitOutcome, Floor, Search};

/// Why the full fit of the candidate at its coarse fit (the last entry of `at_coarse`, the
/// round's base `applied` with it) cannot be kept (see the module docs): the phase to log and
/// the relative held-out improvement that decided it (NaN for the held-out screen); `None` when
/// it is fitted in full. `ho` holds the round's held-out errors and the coarse fit's (`None`:
/// its replay failed); `gains` the predicted and achieved relative gains on the screen's data,
/// `gate` the round's, `floors` the round's floors, `data` what its full fit would run on.
pub(super) fn short_of_keep(
    s: &Search,
    (applied, at_coarse): (&[Applied], &[Applied]),
    (ho_err, ho_c): (&Errors, Option<&Errors>),
    (gains, gate, round): ((Option<f64>, f64), Gate, usize),
    (floors, data): (&[Floor], &[Recording]),
    out: &mut FitOutcome,
) -> Option<(Phase, f64)> {
    let engine = s.engine;
    let pol = &engine.opts.policy;
    let a = at_coarse.last()?;
    let (e, group) = (a.effect, &a.joints);
    let descent = one_line_descent(e, round);
    if heldout_short((ho_err, ho_c), group, gains, (gate, descent), pol) {
        return Some((Phase::HeldoutScreen, f64::NAN));
    }
    if descent {
        let j = Judged { base: applied, trial: at_coarse, gate, floors, round };
        let rel = coarse_within_discretisation(engine, s.heldout, &j, out);
        return rel.map(|r| (Phase::DiscretisationScreen, r));
    }
    if round == 0 || !e.smooth() || e.fitted() < 2 {
        return None;
    }
    let ho_c = ho_c?;
    let ho = HeldoutModel::at(engine, s.heldout, (applied, at_coarse), (ho_err, ho_c))?;
    let best = ho.errors_at(engine, s.heldout, &ho.optimum())?;
    let rel = 1.0 - best.rmse() / ho_err.rmse();
    if !(rel >= pol.linear_trust * pol.min_rel_improvement) {
        return Some((Phase::HeldoutBound, rel));
    }
    let sets = (applied, at_coarse);
    short_after_first_step(engine, (s.heldout, data), sets, ho_err, gate)
        .map(|r| (Phase::HeldoutBound, r))
}

/// The Gauss–Newton model of a candidate's replay on a dataset at its point (the last entry of
/// a set `trial`): the columns along which the simulated positions move — one forward
/// difference per free fitted parameter (the step of its fit's own Jacobian,
/// [`ROLLOUT_REL_STEP`] of each range) and, when given, the secant from the base (the replay
/// without it) — on the samples [`Engine::errors_of`] scores, and the residual real − sim there. A
/// combination `x` of the columns is a move of the parameters to first order (its parameters
/// unbounded by their box).
struct PointModel {
    cols: Vec<Vec<f64>>,
    resid: Vec<f64>,
}

impl PointModel {
    /// The model of `trial`'s last entry on `recs`, whose replays with `trial` and with
    /// `base_set` (its base) are `at` and `base` (`None`: no secant column); one replay of
    /// `recs` per free parameter.
    /// Also the replays moved along each column, for [`HeldoutModel::errors_at`]. `None` when a
    /// replay fails or nothing is free.
    fn at(
        engine: &Engine,
        recs: &[Recording],
        (base_set, trial): (&[Applied], &[Applied]),
        (base, at): (Option<&Errors>, &Errors),
    ) -> Option<(PointModel, Vec<Errors>)> {
        let a = trial.last()?;
        let (e, g, p) = (a.effect, &a.joints, &a.params);
        let t = JointTarget::of(engine.robot, g.first()?)?;
        let (lo, hi) = e.bounds(&model_with(engine.robot, base_set), &t);
        let k = e.fitted().min(p.len()).min(lo.len()).min(hi.len());
        let free: Vec<usize> = (0..k).filter(|&i| hi[i] > lo[i]).collect();
        if free.is_empty() || at.eps.len() != recs.len() {
            return None;
        }
        let replays: Vec<Option<Errors>> = free
            .par_iter()
            .map(|&i| {
                let mut h = ROLLOUT_REL_STEP * (hi[i] - lo[i]);
                if p[i] + h > hi[i] {
                    h = -h;
                }
                let mut set = trial.to_vec();
                set.last_mut()?.params[i] += h;
                engine.errors(recs, &set)
            })
            .collect();
        let mut moved: Vec<Errors> = replays.into_iter().collect::<Option<_>>()?;
        if let Some(b) = base {
            moved.push(b.clone());
        }
        let sim0 = scored(engine, recs, at, |_, sim| sim)?;
        let cols: Vec<Vec<f64>> = moved
            .iter()
            .map(|m| {
                let c = scored(engine, recs, m, |_, sim| sim).filter(|c| c.len() == sim0.len())?;
                Some(c.iter().zip(&sim0).map(|(x, y)| x - y).collect())
            })
            .collect::<Option<_>>()?;
        let resid = scored(engine, recs, at, |real, sim| real - sim)?;
        Some((PointModel { cols, resid }, moved))
    }

    /// Gram matrix `CᵀC` and `Cᵀr` of the columns.
    fn normal(&self) -> (Vec<Vec<f64>>, Vec<f64>) {
        let c = &self.cols;
        let gram = c.iter().map(|a| c.iter().map(|b| dot(a, b)).collect()).collect();
        (gram, c.iter().map(|a| dot(a, &self.resid)).collect())
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The held-out set's Gauss–Newton model of a candidate at its coarse fit ([`PointModel`]),
/// with the replays it was made from, to put the episodes a combination predicts together.
struct HeldoutModel {
    model: PointModel,
    at: Errors,
    moved: Vec<Errors>,
}

impl HeldoutModel {
    /// The model of `trial`'s last entry on `heldout` (replays `base` without it, `at` with it):
    /// one held-out replay per free parameter.
    fn at(
        engine: &Engine,
        heldout: &[Recording],
        sets: (&[Applied], &[Applied]),
        (base, at): (&Errors, &Errors),
    ) -> Option<HeldoutModel> {
        let (model, moved) = PointModel::at(engine, heldout, sets, (Some(base), at))?;
        Some(HeldoutModel { model, at: at.clone(), moved })
    }

    /// The least-squares combination on the held-out set: the most any value of the
    /// parameters lowers the held-out error to first order, whatever the training fit finds.
    fn optimum(&self) -> Vec<f64> {
        let (gram, b) = self.model.normal();
        combine(&b, &gram).1
    }

    /// The held-out errors the model predicts at combination `x`: the coarse fit's replay moved
    /// along the columns, scored by the same windows as a replay.
    fn errors_at(&self, engine: &Engine, heldout: &[Recording], x: &[f64]) -> Option<Errors> {
        let mut eps = self.at.eps.clone();
        for (m, xc) in self.moved.iter().zip(x).filter(|(_, xc)| **xc != 0.0) {
            for ((ep, em), e0) in eps.iter_mut().zip(&m.eps).zip(&self.at.eps) {
                for ((q, qm), q0) in ep.q_sim.iter_mut().zip(&em.q_sim).zip(&e0.q_sim) {
                    for ((v, vm), v0) in q.iter_mut().zip(qm).zip(q0) {
                        *v += xc * (vm - v0);
                    }
                }
            }
        }
        engine.errors_of(heldout, eps)
    }
}

/// The held-out errors at the held-out optimum of the Gauss–Newton model of the candidate (the
/// last entry of `trial`) at its point ([`HeldoutModel::optimum`]). One held-out replay per
/// free parameter. `None` when a replay fails or nothing is free.
pub(super) fn heldout_optimum(
    engine: &Engine,
    heldout: &[Recording],
    sets: (&[Applied], &[Applied]),
    errs: (&Errors, &Errors),
) -> Option<Errors> {
    let m = HeldoutModel::at(engine, heldout, sets, errs)?;
    m.errors_at(engine, heldout, &m.optimum())
}

/// `f(real, simulated)` of every sample [`Engine::errors_of`] scores for `errs` (the fitted
/// joints' samples outside the gap mask whose recorded value is finite), in its order; `None`
/// when `errs` does not hold an episode of every recording.
fn scored(
    engine: &Engine,
    recs: &[Recording],
    errs: &Errors,
    f: impl Fn(f64, f64) -> f64,
) -> Option<Vec<f64>> {
    if errs.eps.len() != recs.len() {
        return None;
    }
    let mut out = Vec::new();
    for (rec, ep) in recs.iter().zip(&errs.eps) {
        let mask = gap_mask(&rec.t, engine.opts.gap_mask_s);
        for (k, jt) in rec.joints.iter().enumerate() {
            if !engine.joints.contains(&jt.name) {
                continue;
            }
            let sim = ep.q_sim.get(k)?;
            for ((real, s), m) in jt.q.iter().zip(sim).zip(&mask) {
                if *m && real.is_finite() {
                    out.push(f(*real, *s));
                }
            }
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::heldout_optimum;
    use crate::fit::effects::{Applied, Effect, GainError};
    use crate::fit::select::{Engine, FitOptions};

    /// On a servo whose gains are off (kp × 0.9, kd × 1.4), recorded by the synth: from a point
    /// off the truth, the held-out optimum the Gauss–Newton model predicts there is about what a
    /// least-squares fit on those recordings from that point reaches — its predicted errors, put
    /// together by the same windows as a replay's, near the fit's replayed ones — for one replay
    /// per parameter; at that fit's answer it predicts nothing more.
    #[test]
    fn the_heldout_optimum_at_a_point_is_what_a_fit_there_reaches() {
        let (robot, recs) =
            crate::synth::recorded::pendulum(Some((GainError.id(), vec![0.9, 1.4])), 3, 11);
        let opts = FitOptions::default();
        let engine = Engine::new(&robot, &recs, &opts);
        let g = vec!["servo".to_string()];
        let e: &'static dyn Effect = &GainError;
        let set = |p: &[f64]| vec![Applied { effect: e, joints: g.clone(), params: p.to_vec() }];
        let base = engine.errors(&recs, &[]).expect("replay");
        let p = [1.0, 1.1];
        let at = engine.errors(&recs, &set(&p)).expect("replay");
        let secs: f64 = recs.iter().map(|r| r.t.last().unwrap() - r.t[0]).sum();
        let before = engine.rollout_stats().simulated_s;
        let best = heldout_optimum(&engine, &recs, (&[], &set(&p)), (&base, &at)).expect("model");
        let cost = engine.rollout_stats().simulated_s - before;
        assert!(cost <= 2.0 * secs + 1e-9, "{cost} s replayed for two parameters");
        let (q, _) = engine.fit_from(&recs, &[], (e, &g), Some(&p));
        let fit = engine.errors(&recs, &set(&q)).expect("replay");
        let (fp, fq, most) = (at.rmse(), fit.rmse(), best.rmse());
        assert!(fq < 0.5 * fp, "the fit closes most of it: {fq} from {fp}");
        assert!(most < fp && (most - fq).abs() <= 0.25 * (fp - fq), "{most}: fit {fq}, {fp}");
        // Window by window, as the gate reads them.
        assert_eq!(best.windows.len(), fit.windows.len());
        let off: f64 = best.windows.iter().zip(&fit.windows).map(|(a, b)| (a.1 - b.1).abs()).sum();
        let moved: f64 = at.windows.iter().zip(&fit.windows).map(|(a, b)| (a.1 - b.1).abs()).sum();
        assert!(off <= 0.25 * moved, "windows off by {off} of {moved}");
        let at_q = heldout_optimum(&engine, &recs, (&[], &set(&q)), (&base, &fit)).expect("model");
        assert!(
            at_q.rmse() >= 0.9 * fq && at_q.rmse() <= fq * (1.0 + 1e-9),
            "{} {fq}",
            at_q.rmse()
        );
    }
}
