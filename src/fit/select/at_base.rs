//! Points of a candidate whose replay is the base replay, known without a rollout.
//!
//! A fit replays its candidate at each point its optimiser asks for. Some points provably
//! replay exactly (to the last bit) as the base model without the candidate does: the
//! candidate's start where it changes nothing ([`Effect::neutral_at`]), and a move of one
//! parameter from its start that [`Effect::unmoved`] judges to change nothing given what the
//! base replay of the same data reached on the joint ([`Seen`]: a torque limit above every
//! force the joint's actuators applied at a physics step, with its torque–speed line clear, is
//! a clamp that never acts). At such a point the candidate's set *is* the base set: the search
//! holds its replay (the fit's base was replayed to score the candidate against it), so the
//! point costs no simulation and scores what the replay would have, bit for bit. Every
//! optimiser's path, and so every fit, is unchanged; only the replays are saved. On the
//! armature leg (KR8) the torque limit's grid on ln(effort) puts its upper points above the
//! servo's peak force on the probes' data: those points were replays of the base.
//!
//! The base replay's peaks are read only for an effect whose judgement needs them
//! ([`Effect::unmoved_reads_peaks`]), and only from a base replay the search already counted
//! (never a replay made for this); without them nothing is judged and every point is replayed.
//!
//! [`Effect::neutral_at`]: crate::fit::effects::Effect::neutral_at
//! [`Effect::unmoved`]: crate::fit::effects::Effect::unmoved
//! [`Effect::unmoved_reads_peaks`]: crate::fit::effects::Effect::unmoved_reads_peaks

use mujoco_rs::prelude::MjModel;

use crate::fit::effects::{Applied, Effect, Entry, JointTarget, Seen};
use crate::sim2real::recording::Recording;

use super::Errors;
use super::engine::{Engine, neutral_params, with_candidate};

/// What the base replay `err` reached on `joint` ([`Seen`]): the servo's peak only when no
/// actuator hook of `base` acts on the joint (a hook's own servo torque is not bounded by
/// MuJoCo's actuator force).
pub(super) fn seen(err: &Errors, base: &[Applied], joint: &str) -> Seen {
    let hooked = base.iter().any(|a| {
        matches!(a.effect.entry(), Entry::Command | Entry::Torque)
            && a.joints.iter().any(|j| j == joint)
    });
    let at = |ep: &crate::sim2real::replay::Episode| ep.joints.iter().position(|j| j == joint);
    let peaks = err.eps.iter().map(|ep| (&ep.peaks, at(ep).unwrap_or(usize::MAX)));
    Seen::of(peaks, hooked)
}

/// A candidate (effect on a joint group) on a base model and data set: which of its points
/// replay as the base does.
pub(super) struct AtBase {
    effect: &'static dyn Effect,
    /// The parameters at which the candidate changes nothing on any replay
    /// ([`neutral_params`]).
    neutral: Option<Vec<f64>>,
    /// The base's compiled model, each joint's target, its start and what the base replay of
    /// the data reached there; empty when nothing can be judged.
    m0: Option<MjModel>,
    joints: Vec<(JointTarget, Vec<f64>, Seen)>,
}

impl AtBase {
    /// The candidate `effect` on `group` over `base` (compiled: `m0`), fitted on `data`.
    pub(super) fn new(
        engine: &Engine,
        data: &[Recording],
        base: &[Applied],
        (effect, group): (&'static dyn Effect, &[String]),
        m0: &MjModel,
    ) -> AtBase {
        let neutral = neutral_params(engine.robot, m0, (effect, group));
        let mut at = AtBase { effect, neutral, m0: None, joints: vec![] };
        // (Under the start estimate a sticking effect changes which joints it corrects: not
        // judged.)
        if effect.holds_start() || effect.entry() == Entry::Measurement {
            return at;
        }
        let unmeasured = Seen { servo: None, speed: f64::INFINITY };
        let err =
            if effect.unmoved_reads_peaks() { engine.errors_counted(data, base) } else { None };
        let joints: Option<Vec<(JointTarget, Vec<f64>, Seen)>> = group
            .iter()
            .map(|j| {
                let t = JointTarget::of(engine.robot, j)?;
                let start = effect.initial(m0, &t);
                let seen = err.as_ref().map_or(unmeasured, |e| seen(e, base, j));
                Some((t, start, seen))
            })
            .collect();
        if let Some(joints) = joints.filter(|j| !j.is_empty()) {
            at.joints = joints;
            at.m0 = Some(m0.clone());
        }
        at
    }

    /// Whether the candidate at `p` replays exactly as the base: `p` is its neutral point, or
    /// on every joint of the group `p` differs from the joint's start in at most one
    /// parameter and [`Effect::unmoved`] judges that parameter's value to change nothing (the
    /// first parameter's value when `p` is the start itself).
    pub(super) fn replays_base(&self, p: &[f64]) -> bool {
        if self.neutral.as_deref() == Some(p) {
            return true;
        }
        let Some(m0) = &self.m0 else { return false };
        self.joints.iter().all(|(t, start, seen)| {
            if p.len() != start.len() || p.is_empty() {
                return false;
            }
            let mut moved = (0..p.len()).filter(|&i| p[i].to_bits() != start[i].to_bits());
            let j = match (moved.next(), moved.next()) {
                (None, _) => 0,
                (Some(j), None) => j,
                _ => return false,
            };
            self.effect.unmoved(m0, t, start, (j, p[j]), *seen).is_some()
        })
    }

    /// `base` with the candidate at `p` — or `base` itself when the candidate there replays as
    /// the base ([`AtBase::replays_base`]): the same replay, which the search holds already.
    pub(super) fn set(&self, base: &[Applied], group: &[String], p: Vec<f64>) -> Vec<Applied> {
        if self.replays_base(&p) {
            return base.to_vec();
        }
        with_candidate(base, (self.effect, group), p, None)
    }
}

#[cfg(test)]
#[path = "at_base_tests.rs"]
mod tests;
