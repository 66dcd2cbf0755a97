//! The held-out gate at a finer timestep: an effect that only makes up for the model's own time
//! discretisation is reported as a note, not as missing physics.
//!
//! A real robot moves in continuous time; MuJoCo steps its model at `dt` (semi-implicit Euler
//! or another fixed-step method), which on a lightly damped servo looks like a sub-millisecond
//! action delay or a little armature. When the recordings move in finer time than the model
//! (the discretisation floor, [`Engine::discretisation_floor`], has a part on some joint), a
//! candidate that passed the held-out gate at `dt` is judged again with both sides replayed at
//! `dt / r²` ([`SearchPolicy::discretisation_refine`]), where the integration error is a
//! fraction of what it is at `dt`: an effect that is physics still improves the held-out
//! recordings beyond noise there; one that absorbed the integration error does not (an
//! action delay shorter than the integrator's equivalent phase lag makes the finer replay
//! worse).
//!
//! [`Engine::discretisation_floor`]: super::engine::Engine::discretisation_floor
//! [`SearchPolicy::discretisation_refine`]: super::policy::SearchPolicy::discretisation_refine

use crate::fit::effects::{Applied, num};
use crate::sim2real::recording::Recording;

use super::engine::Engine;
use super::policy::Phase;
use super::verdict::{Gate, verdict};
use super::{FitOutcome, Floor, Tried};

/// What [`beyond_discretisation`] judges: the round's base set, the base with the candidate
/// (its last entry), the gate the candidate passed and the round's floors.
pub(super) struct Judged<'a> {
    pub(super) base: &'a [Applied],
    pub(super) trial: &'a [Applied],
    pub(super) gate: Gate,
    pub(super) floors: &'a [Floor],
    pub(super) round: usize,
}

/// `true` when the candidate (the last effect of `j.trial`), which passed the held-out gate at
/// the model's timestep, is physics beyond the model's time discretisation: the recordings do
/// not move in finer time than the model (no discretisation part in `j.floors`: nothing is
/// simulated), or the candidate also passes `j.gate` (and `min_rel_improvement`) with both
/// sides replayed on `heldout` at `dt / r²`. Otherwise the attempt is logged (phase
/// `discretisation`) and a note says so.
pub(super) fn beyond_discretisation(
    engine: &Engine,
    heldout: &[Recording],
    j: &Judged,
    out: &mut FitOutcome,
) -> bool {
    let Some(cand) = j.trial.last() else { return true };
    if !j.floors.iter().any(|f| f.discretisation > 0.0) {
        return true;
    }
    let r = engine.opts.policy.discretisation_refine.max(2);
    let k = (r * r) as u32;
    let (Some(before), Some(after)) =
        (engine.errors_at(heldout, j.base, k), engine.errors_at(heldout, j.trial, k))
    else {
        // Not measurable at the finer step: the gate at `dt` stands.
        return true;
    };
    let v = verdict(&before, &after, &cand.joints, j.gate);
    if v.significant && v.rel >= engine.opts.policy.min_rel_improvement {
        return true;
    }
    out.log(Tried {
        round: j.round,
        phase: Phase::Discretisation,
        effect: cand.effect.id().into(),
        joints: cand.joints.clone(),
        params: cand.params.clone(),
        train_rmse: f64::NAN,
        heldout_improvement: v.rel,
        significant: v.significant,
        bic_decreased: false,
        kept: false,
        predicted: None,
    });
    let dt = engine.robot.mj.opt().timestep;
    let params: Vec<String> = cand
        .effect
        .params()
        .iter()
        .zip(&cand.params)
        .map(|(d, v)| format!("{} {}", d.name, num(*v)))
        .collect();
    let note = format!(
        "{} on {} ({}) is within the model's time discretisation at dt = {} s, not reported as \
         missing physics: replayed at dt / {k} it does not improve the held-out recordings \
         beyond noise ({:+.1} %); a finer timestep would resolve it",
        cand.effect.id(),
        cand.joints.join(","),
        params.join(", "),
        num(dt),
        100.0 * v.rel,
    );
    // One note per effect and joint group (a later round may fit it again).
    let head = format!("{} on {} (", cand.effect.id(), cand.joints.join(","));
    if !out.notes.iter().any(|n| n.starts_with(&head) && n.contains("time discretisation")) {
        out.notes.push(note);
    }
    false
}
