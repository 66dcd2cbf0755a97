//! What the keyframe rules (`keyframe-motor-ctrl`, `keyframe-servo-ctrl`) read: the actuators
//! of one kind on scalar joints, and each keyframe's positions and controls.

use crate::model::mj;
use crate::model::{Actuator, Robot, Transmission};

/// An actuator on a hinge or slide joint through a joint transmission.
#[derive(Clone, Copy)]
pub struct KeyActuator {
    /// Actuator id.
    pub actuator: usize,
    /// Joint id.
    pub joint: usize,
    /// Index of its (first) control in `ctrl`.
    pub ctrl: usize,
}

/// One keyframe's compiled positions and controls.
pub struct Keyframe<'a> {
    /// Keyframe index.
    pub index: usize,
    /// Its name (empty when unnamed).
    pub name: String,
    /// `key_qpos` of this keyframe (nq values).
    pub qpos: &'a [f64],
    /// `key_ctrl` of this keyframe (nu values).
    pub ctrl: &'a [f64],
}

impl Keyframe<'_> {
    /// How a message names the keyframe: `` `home` ``, or `#k` when unnamed.
    pub fn label(&self) -> String {
        if self.name.is_empty() { format!("#{}", self.index) } else { format!("`{}`", self.name) }
    }

    /// The keyframe's position of `joint` (a scalar joint).
    pub fn joint_pos(&self, robot: &Robot, joint: usize) -> f64 {
        self.qpos[robot.joints[joint].qposadr]
    }
}

/// The actuators of a kind `keep` accepts that drive a scalar joint directly, with a control.
pub fn key_actuators(robot: &Robot, keep: impl Fn(&Actuator) -> bool) -> Vec<KeyActuator> {
    let m = &robot.mj;
    let nu = mj::raw(m).nu.max(0) as usize;
    let (cadr, cnum) = (m.actuator_ctrladr(), m.actuator_ctrlnum());
    robot
        .actuators
        .iter()
        .filter(|a| keep(a) && matches!(a.trn, Transmission::Joint | Transmission::JointInParent))
        .filter_map(|a| {
            let j = robot.joints.get(usize::try_from(a.target).ok()?)?;
            let c = usize::try_from(*cadr.get(a.id)?).ok()?;
            (j.is_scalar() && *cnum.get(a.id)? >= 1 && c < nu).then_some(KeyActuator {
                actuator: a.id,
                joint: j.id,
                ctrl: c,
            })
        })
        .collect()
}

/// Every keyframe of the compiled model whose position and control arrays are whole.
pub fn keyframes(robot: &Robot) -> Vec<Keyframe<'_>> {
    let m = &robot.mj;
    let r = mj::raw(m);
    let (nq, nu, nkey) = (r.nq.max(0) as usize, r.nu.max(0) as usize, r.nkey.max(0) as usize);
    let (kq, kc) = (m.key_qpos(), m.key_ctrl());
    (0..nkey)
        .filter_map(|k| {
            Some(Keyframe {
                index: k,
                name: robot.keys.get(k).cloned().unwrap_or_default(),
                qpos: kq.get(k * nq..(k + 1) * nq)?,
                ctrl: kc.get(k * nu..(k + 1) * nu)?,
            })
        })
        .collect()
}
