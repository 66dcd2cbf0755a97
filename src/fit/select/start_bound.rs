//! After round 0, before a smooth candidate of several fitted parameters is coarse-fitted: the
//! held-out bound of its full fit ([`super::before_full`], `heldout_bound`) made at the
//! effect's start instead of at its coarse fit ([`short_at_start`]).
//!
//! After round 0 such a candidate reaches a full fit only through the held-out bound: the
//! Gauss–Newton model of the whole held-out set at its point — one forward difference per free
//! parameter ([`ROLLOUT_REL_STEP`] of its range, one held-out replay each) and the secant from
//! the round's base — and its least-squares optimum, the most any value of its parameters
//! lowers the held-out error to first order, unbounded by the box, whatever the training fit
//! finds; that optimum's predicted episodes are put to the round's gate at the trust's edge
//! ([`at_trust_edge`]: z, decisive improvement and `min_rel_improvement` × `linear_trust`).
//! The same model can be made before the coarse fit, at the point where the screen made the
//! candidate's linear model: the effect's start. There the secant vanishes (a start that
//! changes nothing, [`Effect::neutral_start`], replays the round's base, which the round holds)
//! or is one held-out replay more. The model at the start is a first-order model of the whole
//! box as the one at the coarse fit is: its optimum is not bounded by the box nor by the
//! training fit's direction, so it holds every point a coarse fit and a full fit from it could
//! reach to the same order. When even that optimum cannot pass the gate at the trust's edge,
//! no coarse fit of the candidate can be fitted in full (the held-out bound at the coarse fit
//! would stop it, or the screen's bar), and none is made: logged `heldout_bound`, without
//! parameters, its `heldout_improvement` the optimum's relative improvement; as a candidate
//! [`super::trust::heldout_out`] leaves out, it is coarse-fitted still when the round keeps
//! nothing and it could start a joint pair (the bound says nothing of a pair whose members
//! mimic each other). Its replays are booked to the round's `heldout_linear`, the held-out
//! set's linear models. No constant of its own.
//!
//! [`Effect::neutral_start`]: crate::fit::effects::Effect::neutral_start
//! [`ROLLOUT_REL_STEP`]: crate::fit::optim::ROLLOUT_REL_STEP

use crate::fit::effects::{Applied, Effect, JointTarget, model_with};
use crate::sim2real::recording::Recording;

use super::Errors;
use super::before_full::heldout_optimum;
use super::engine::{Engine, neutral_params};
use super::trust::at_trust_edge;
use super::verdict::{Gate, verdict};

/// Whether a candidate `e` on `g` is judged here: after round 0, a smooth effect of two or
/// more fitted parameters (the candidates the held-out bound at the coarse fit judges; a smooth
/// one-parameter candidate is a one-line descent, judged at its coarse fit's replay).
pub(super) fn judged(e: &dyn Effect, round: usize) -> bool {
    round > 0 && e.smooth() && e.fitted() >= 2
}

/// The relative held-out improvement of the held-out Gauss–Newton optimum of `e` on `g` at its
/// start (the round's base `applied`, held-out errors `ho_err`) when that optimum does not pass
/// `gate` at the trust's edge; `None` when it does, the candidate is not [`judged`] here, or a
/// replay fails. One held-out replay per free parameter, one more when the start changes the
/// motion.
pub(super) fn short_at_start(
    engine: &Engine,
    (heldout, applied, ho_err): (&[Recording], &[Applied], &Errors),
    (e, g): (&'static dyn Effect, &[String]),
    (gate, round): (Gate, usize),
) -> Option<f64> {
    if !judged(e, round) {
        return None;
    }
    let m0 = model_with(engine.robot, applied);
    let t = JointTarget::of(engine.robot, g.first()?)?;
    let p0 = e.initial(&m0, &t);
    let neutral = neutral_params(engine.robot, &m0, (e, g));
    let mut trial = applied.to_vec();
    trial.push(Applied { effect: e, joints: g.to_vec(), params: p0.clone() });
    // (At a start that changes nothing the replay is the base's, held.)
    let at = if neutral.as_deref() == Some(p0.as_slice()) {
        ho_err.clone()
    } else {
        engine.errors(heldout, &trial)?
    };
    let best = heldout_optimum(engine, heldout, (applied, &trial), (ho_err, &at))?;
    let pol = &engine.opts.policy;
    (!at_trust_edge((ho_err, &best), g, gate, pol)).then(|| verdict(ho_err, &best, g, gate).rel)
}

#[cfg(test)]
mod tests {
    use super::{short_at_start, verdict};
    use crate::fit::effects::{Applied, Effect, GainError};
    use crate::fit::select::{Engine, FitOptions};
    use crate::model::Robot;
    use crate::sim2real::recording::Recording;
    use crate::synth::recorded::pendulum;

    /// The pendulum servo recorded by the synth with `hidden`, 4 × 3 s: three episodes to
    /// train on, the last held out.
    fn split(hidden: Option<Vec<f64>>, seed: u64) -> (Robot, Vec<Recording>, Vec<Recording>) {
        let (robot, mut recs) = pendulum(hidden.map(|p| (GainError.id(), p)), 4, seed);
        let held = recs.split_off(3);
        (robot, recs, held)
    }

    const E: &dyn Effect = &GainError;

    /// Where the servo's gains are off (kp × 0.9 and kd × 1.4; kp × 1.12 and kd × 0.75), the
    /// held-out optimum at the gain error's start passes the gate at the trust's edge: not
    /// left out, in round 1 as in round 0 (where it is not judged at all).
    #[test]
    fn a_gain_error_that_is_there_is_not_left_out_at_its_start() {
        for (p, seed) in [(vec![0.9, 1.4], 11), (vec![1.12, 0.75], 5)] {
            let (robot, train, held) = split(Some(p.clone()), seed);
            let opts = FitOptions::default();
            let engine = Engine::new(&robot, &train, &opts);
            let ho = engine.errors(&held, &[]).expect("replay");
            let (g, gate) = (vec!["servo".to_string()], opts.policy.gate());
            for round in [0, 1] {
                let got = short_at_start(&engine, (&held, &[], &ho), (E, &g), (gate, round));
                assert_eq!(got, None, "{p:?}, round {round}");
            }
        }
    }

    /// Where the gains are right (nothing missing; three synth seeds), the held-out optimum at
    /// the start cannot pass the gate at the trust's edge: left out, its relative improvement
    /// short of `min_rel_improvement`, for one held-out replay per parameter (the start, a gain
    /// of one, replays the base); and the full fit from that start on the training episodes,
    /// put to the gate on the held-out one, is not kept either.
    #[test]
    fn a_gain_error_that_is_not_there_is_left_out_at_its_start_as_its_full_fit_would_be() {
        for seed in [3, 7, 21] {
            let (robot, train, held) = split(None, seed);
            let opts = FitOptions::default();
            let pol = &opts.policy;
            let engine = Engine::new(&robot, &train, &opts);
            let ho = engine.errors(&held, &[]).expect("replay");
            let (g, gate) = (vec!["servo".to_string()], pol.gate());
            let secs: f64 = held.iter().map(|r| r.t.last().unwrap() - r.t[0]).sum();
            let before = engine.rollout_stats().simulated_s;
            let got = short_at_start(&engine, (&held, &[], &ho), (E, &g), (gate, 1));
            let cost = engine.rollout_stats().simulated_s - before;
            let rel = got.unwrap_or_else(|| panic!("seed {seed}: not left out"));
            assert!(rel < pol.min_rel_improvement, "seed {seed}: {rel}");
            assert!(cost > 0.0 && cost <= 2.0 * secs + 1e-9, "seed {seed}: {cost} s");
            let (q, _) = engine.fit_from(&train, &[], (E, &g), None);
            let set = vec![Applied { effect: E, joints: g.clone(), params: q.clone() }];
            let after = engine.errors(&held, &set).expect("replay");
            let v = verdict(&ho, &after, &g, gate);
            let kept = v.significant && v.rel >= pol.min_rel_improvement;
            assert!(!kept, "seed {seed}: the full fit {q:?} passes ({} held-out)", v.rel);
        }
    }
}
