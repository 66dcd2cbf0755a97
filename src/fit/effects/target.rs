//! [`JointTarget`]: the model-side indices and nominal properties of one joint an effect is
//! applied to, and the parameter bounds sized by its drive.

use super::ground_contact::{GroundGeom, ground_geoms};
use super::{Effect, inertial};
use crate::model::{ActuatorKind, Robot};

/// The model-side indices of one joint an effect is applied to.
#[derive(Debug, Clone)]
pub struct JointTarget {
    /// MuJoCo joint id.
    pub jnt: usize,
    pub dof: usize,
    pub qposadr: usize,
    /// Actuators reaching the joint.
    pub acts: Vec<usize>,
    /// Those of them that are position servos ([`ActuatorKind::Position`], as the replay
    /// reads them).
    pub servos: Vec<usize>,
    /// Joint position at the keyframe (or qpos0).
    pub key_q: f64,
    /// Stiffness of the joint's position servos on the joint, Σ kp·gear² [N·m/rad] (0 without
    /// one).
    pub servo_kp: f64,
    /// The largest torque the joint's actuators are declared to reach [N·m]: Σ of each
    /// force-limited actuator's `forcerange` and each motor's `ctrlrange` × gain, times gear
    /// (0 when none is declared).
    pub max_torque: f64,
    /// The joint's child body as given (body effects; `None` on the world body).
    pub body: Option<inertial::BodyAxes>,
    /// The child body's geoms that touch the ground, with the contact as given
    /// ([`super::ground_contact`]; empty for a body off the ground).
    pub ground: Vec<GroundGeom>,
}

/// Drive strength that the absolute parameter bounds (damping, friction, stiffness, torque) are
/// sized for: a 100 N·m/rad servo or a 100 N·m actuator (the arms, small legs and servos the
/// fixed bounds were set on). A stronger drive widens them in proportion ([`JointTarget::strength`]).
const REFERENCE_DRIVE: f64 = 100.0;

impl JointTarget {
    /// Whether an actuator of the model reaches the joint (directly or through a tendon): the
    /// actuator's effects (a delay, a torque limit) exist only there.
    pub fn driven(&self) -> bool {
        !self.acts.is_empty()
    }

    /// Whether a position servo of the model reaches the joint: the servo's effects (its gains,
    /// its motor law, its play) exist only there.
    pub fn servoed(&self) -> bool {
        !self.servos.is_empty()
    }

    pub fn of(robot: &Robot, name: &str) -> Option<JointTarget> {
        let j = robot.joint(name)?;
        let acts = robot.actuators_on_joint(j.id);
        let (mut servo_kp, mut max_torque) = (0.0, 0.0);
        for a in &acts {
            let g = if a.gear != 0.0 { a.gear.abs() } else { 1.0 };
            let span = |r: [f64; 2]| r[0].abs().max(r[1].abs());
            if let ActuatorKind::Position { kp, .. } = a.kind {
                servo_kp += kp.abs() * g * g;
            }
            if a.forcelimited {
                max_torque += span(a.forcerange) * g;
            } else if matches!(a.kind, ActuatorKind::Motor) && a.ctrllimited {
                max_torque += a.gainprm[0].abs() * span(a.ctrlrange) * g;
            }
        }
        let finite = |v: f64| if v.is_finite() { v } else { 0.0 };
        Some(JointTarget {
            jnt: j.id,
            dof: j.dofadr,
            qposadr: j.qposadr,
            acts: acts.iter().map(|a| a.id).collect(),
            servos: acts
                .iter()
                .filter(|a| matches!(a.kind, ActuatorKind::Position { .. }))
                .map(|a| a.id)
                .collect(),
            key_q: robot.key.qpos.get(j.qposadr).copied().unwrap_or(0.0),
            servo_kp: finite(servo_kp),
            max_torque: finite(max_torque),
            body: inertial::BodyAxes::of(&robot.mj, j.id),
            ground: usize::try_from(robot.mj.jnt_bodyid().get(j.id).copied().unwrap_or(0))
                .map_or(vec![], |b| ground_geoms(robot, b)),
        })
    }

    /// How many times stronger the joint's drive is than the one the fixed bounds of damping,
    /// friction and stiffness were sized for (at least 1): max(1, kp / 100 N·m/rad, torque /
    /// 100 N·m). A humanoid knee (kp 200–300, 150–300 N·m) can carry damping and friction
    /// beyond the 5 N·m(·s/rad) that suit a hobby servo or a small arm.
    pub fn strength(&self) -> f64 {
        (self.servo_kp / REFERENCE_DRIVE).max(self.max_torque / REFERENCE_DRIVE).max(1.0)
    }
}

/// An effect's [`ParamDef`] bounds with the upper bounds of the parameters `scaled` (torques,
/// damping) widened by the joint's drive strength ([`JointTarget::strength`]).
pub fn bounds_for_drive(e: &dyn Effect, t: &JointTarget, scaled: &[usize]) -> (Vec<f64>, Vec<f64>) {
    let k = t.strength();
    let ps = e.params();
    let hi = ps.iter().enumerate().map(|(i, p)| if scaled.contains(&i) { p.hi * k } else { p.hi });
    (ps.iter().map(|p| p.lo).collect(), hi.collect())
}
