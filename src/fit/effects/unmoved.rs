//! Facts that make a probe's sensitivity column exactly zero before it is replayed
//! ([`Effect::unmoved`]): a move of an effect's parameter that provably leaves the replay as it
//! was, to the last bit. The search's screen makes no probe of such a move and says why (JSON
//! `search.unprobed`); the column it would have measured is the zero column a replay gives.
//!
//! [`Effect::unmoved`]: super::Effect::unmoved

use mujoco_rs::prelude::*;
use serde::Serialize;

use super::JointTarget;
use crate::sim2real::replay::StepPeaks;

/// Why a probe was not made: its move changes no replay.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Unmoved {
    /// The joint's body has neither mass nor inertia (and its tree has mass): where its centre
    /// of mass sits and how its mass spreads weigh nothing in the dynamics, every inertial term
    /// of a body being scaled by its mass or its inertia.
    MasslessBody,
    /// A torque limit at or above every force the joint's actuators applied at a physics step of
    /// the base replay, with a torque–speed line the joint's peak speed does not reach, clamps
    /// nothing.
    LimitAboveServoForce,
}

/// What the base replay's physics steps reached on one joint, over its episodes
/// ([`StepPeaks`]). `servo` is `None` when not measured (RK4, a joint not recorded) or when an
/// actuator hook of the base model acts on the joint: a hook's own servo torque, clamped to the
/// same range, is not bounded by MuJoCo's actuator force.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seen {
    /// Peak |actuator force| in joint units [N·m or N].
    pub servo: Option<f64>,
    /// Peak |q̇| at a step's start [rad/s or m/s] (∞ when not measured).
    pub speed: f64,
}

impl Seen {
    /// The peaks of recorded joint `k` over `peaks` (one per episode); `hooked`: an actuator
    /// hook of the base model acts on it.
    pub fn of<'a>(peaks: impl IntoIterator<Item = (&'a StepPeaks, usize)>, hooked: bool) -> Seen {
        let (mut servo, mut speed) = (Some(0.0f64), 0.0f64);
        for (p, k) in peaks {
            servo = servo.zip(p.servo.get(k)).map(|(a, b)| a.max(*b));
            speed = speed.max(p.speed.get(k).copied().unwrap_or(f64::INFINITY));
        }
        Seen { servo: servo.filter(|s| !hooked && s.is_finite()), speed }
    }
}

/// Whether `t`'s body has neither mass nor inertia in `m` while its tree (the body's root
/// ancestor's subtree) has mass: the tree's centre of mass, the point MuJoCo's dynamics are
/// expressed about, then does not move with the body's own centre of mass.
pub fn massless(m: &MjModel, t: &JointTarget) -> bool {
    let Some(b) = t.body.as_ref().map(|b| b.body) else { return false };
    let root = m.body_rootid().get(b).map_or(b, |&r| r.max(0) as usize);
    m.body_mass().get(b) == Some(&0.0)
        && m.body_inertia().get(b).is_some_and(|i| i.iter().all(|&x| x == 0.0))
        && m.body_subtreemass().get(root).is_some_and(|&s| s > 1e-10)
}
