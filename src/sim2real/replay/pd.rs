//! Torque-driven joints replayed as the policy's PD controller (the legged_gym / Isaac Lab
//! setup: the model's actuators are `<motor>`s, the PD runs in the policy's code).
//!
//! A recorded joint whose every actuator is a torque actuator on the joint itself
//! ([`ActuatorKind::Motor`]: a `<motor>`, or a `<general>` with fixed gain and no bias) is
//! driven at **every physics step** with `torque = kp·(q_cmd − q) − kd·q̇` from the step's own
//! state, `q_cmd` the command in force (held over the control tick) and `kp`/`kd` the recording's
//! columns (held at the control ticks like a position servo's) or, without them, the gains of the
//! joint's motor family in the spec. That is how legged_gym (its `decimation` loop recomputes
//! the torque at each simulation step) and Isaac Lab's explicit PD actuators run the controller.
//! The torque is split evenly over the joint's motors and written as their `ctrl`
//! (`torque / (gain · gear)`), so MuJoCo clamps it to each actuator's `ctrlrange` and
//! `forcerange` as it would clamp the policy's own torque.

use std::collections::BTreeMap;

use mujoco_rs::prelude::*;

use crate::model::{ActuatorKind, Robot, Transmission};
use crate::spec::Spec;

/// The torque actuators of a joint the replay runs as a PD: (actuator id, its force per unit
/// ctrl on the joint, `gainprm[0] · gear`).
#[derive(Debug, Clone)]
pub(super) struct PdJoint {
    pub acts: Vec<(usize, f64)>,
    /// Gains when the recording has no `kp`/`kd` column (from the spec), N·m/rad, N·m·s/rad.
    pub kp: f64,
    pub kd: f64,
}

impl PdJoint {
    /// The ctrl of each motor for a joint torque `tau` [N·m or N].
    pub fn ctrl(&self, tau: f64) -> impl Iterator<Item = (usize, f64)> + '_ {
        let n = self.acts.len() as f64;
        self.acts.iter().map(move |&(a, f)| (a, if f != 0.0 { tau / (n * f) } else { 0.0 }))
    }

    /// The joint-torque range MuJoCo lets the motors apply: each motor's `forcerange` × gear when
    /// force-limited, else its `ctrlrange` × gain × gear when ctrl-limited; `None` when any of
    /// them is unlimited.
    pub fn torque_range(&self, m: &MjModel) -> Option<(f64, f64)> {
        let (fl, fr, cl, cr, gear) = (
            m.actuator_forcelimited(),
            m.actuator_forcerange(),
            m.actuator_ctrllimited(),
            m.actuator_ctrlrange(),
            m.actuator_gear(),
        );
        let (mut lo, mut hi) = (0.0, 0.0);
        for &(a, f) in &self.acts {
            let g = gear[a][0];
            let (x, y) = if fl[a] {
                (g * fr[a][0], g * fr[a][1])
            } else if cl[a] {
                (f * cr[a][0], f * cr[a][1])
            } else {
                return None;
            };
            lo += x.min(y);
            hi += x.max(y);
        }
        Some((lo, hi))
    }
}

/// The torque actuators of joint `j` when every actuator reaching it is one acting on the joint
/// itself (`None` otherwise: a servo, a tendon, or no actuator).
pub(super) fn torque_actuators(robot: &Robot, j: usize) -> Option<Vec<usize>> {
    let acts = robot.actuators_on_joint(j);
    let ok = !acts.is_empty()
        && acts.iter().all(|a| {
            a.kind == ActuatorKind::Motor
                && matches!(a.trn, Transmission::Joint | Transmission::JointInParent)
        });
    ok.then(|| acts.iter().map(|a| a.id).collect())
}

/// The PD gains the spec gives joints driven by torque: `[motors.F] kp, kd` of the family
/// `[joints."glob"] motor = "F"` names, for every joint with both (joint name → (kp, kd)).
pub fn spec_pd_gains(spec: Option<&Spec>, robot: &Robot) -> BTreeMap<String, (f64, f64)> {
    let Some(spec) = spec else { return BTreeMap::new() };
    robot
        .joints
        .iter()
        .filter(|j| torque_actuators(robot, j.id).is_some())
        .filter_map(|j| {
            let m = spec.motor(spec.joint(&j.name)?.motor.as_deref()?)?;
            Some((j.name.clone(), (crate::spec::v(&m.kp)?, crate::spec::v(&m.kd)?)))
        })
        .collect()
}

/// Why joint `joint` (driven by torque actuators `names`) cannot be replayed: its PD gains are
/// missing (`kp`, `kd`: whether each is) — and how to give them.
pub(super) fn missing_gains(joint: &str, names: &str, kp: bool, kd: bool) -> String {
    let what = match (kp, kd) {
        (false, false) => "kp and kd",
        (false, true) => "kp",
        _ => "kd",
    };
    format!(
        "joint '{joint}' is driven by torque ({names}: a <motor> or a <general> without bias) and \
         the recording has no {what} for it: the replay runs the policy's PD, torque = kp·(q_cmd − q) \
         − kd·q̇ at every physics step, clamped by the actuator's ctrlrange/forcerange. Give the \
         gains as CSV columns `{joint}.kp` [N·m/rad] and `{joint}.kd` [N·m·s/rad] (constant \
         columns do), or, for any log format, in the spec (--spec): \
         [motors.FAMILY] kp = …, kd = … with [joints.\"{joint}\"] motor = \"FAMILY\""
    )
}

/// What actuator kind `kind` is, for the error on a joint the replay cannot drive.
pub(super) fn unsupported(kind: ActuatorKind, beside_servo: bool) -> &'static str {
    match kind {
        ActuatorKind::DcMotor { .. } => "a <dcmotor> (its ctrl is a voltage)",
        ActuatorKind::Motor if beside_servo => "a torque actuator beside a servo on the same joint",
        ActuatorKind::Motor => "a torque actuator acting through a tendon",
        _ => {
            "an actuator whose gain/bias law is neither a servo's nor a motor's (e.g. <intvelocity>, \
             <muscle>, <cylinder>, a <general> with another bias)"
        }
    }
}

/// The actuators a replay can drive, for the same error.
pub(super) const SUPPORTED: &str = "the replay drives a recorded joint through position servos \
     (<position>, or a <general> with bias −kp·q − kv·q̇), velocity servos (<velocity>), or torque \
     actuators on the joint (<motor>, or a <general> without bias) run as the policy's PD from \
     the recording's kp/kd";
