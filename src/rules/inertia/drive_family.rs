//! Which joints a motor drives, and which of them share one motor: the families that
//! `armature-mismatch` compares reflected inertia within and `drive-friction-mismatch` compares
//! joint friction and damping within.

use std::collections::BTreeMap;

use crate::model::mjcf::ElemKind;
use crate::model::{Format, Joint, JointType};
use crate::rules::Context;
use crate::rules::limits::effort_limit_mismatch::joint_torque_limit;
use crate::util::fmt_num;

/// Fewest joints one value must be shared by (or one family must hold) to be judged as a
/// group: a limb's worth (a shoulder, an elbow and a wrist), not a pair that happens to match
/// (a mirror pair is `mirror-asymmetry`'s).
pub const GROUP_MIN: usize = 3;

/// Whether joint `j` is coupled to another by a joint equality: it drives (or follows) a
/// linkage — a gripper's linked fingers —, so its drive's numbers are the linkage's.
pub fn coupled(cx: &Context, j: usize) -> bool {
    const JOINT_EQUALITY: i32 = 2;
    cx.robot
        .equalities
        .iter()
        .any(|e| e.etype == JOINT_EQUALITY && (e.obj1 == j as i32 || e.obj2 == j as i32))
}

/// A hinge or slide a motor drives at the joint: an actuator acts on it (MJCF) or, in a URDF
/// (which has no actuators), it states a positive `effort` (MuJoCo's importer makes it the
/// joint's `actuatorfrcrange`); not passive in the spec and not coupled by a joint equality.
pub fn motor_driven(cx: &Context, j: &Joint) -> bool {
    let robot = cx.robot;
    let driven = !robot.actuators_on_joint(j.id).is_empty()
        || (robot.format == Format::Urdf
            && joint_torque_limit(robot, j.id).is_some_and(|(l, _)| l > 0.0));
    j.is_scalar() && driven && !cx.facts(&j.name).is_some_and(|f| f.passive) && !coupled(cx, j.id)
}

/// Joints of one motor family.
pub struct Family {
    /// How the family was formed: "the spec's motor `X`" or "equal force limits of 1000 N·m".
    pub label: String,
    pub joints: Vec<usize>,
}

/// The motor families among the motor-driven joints ([`motor_driven`]), wheels left out: with
/// a spec, the joints its `motor` names; without one, the joints of one type whose torque
/// limits ([`joint_torque_limit`]) are equal (to 6 significant digits: one motor written once
/// and copied). In an MJCF file the joint's and its actuator's `<default class>` split a family
/// further: a joint given its own class (a deliberately damped one) is its own design. Joints
/// with no motor known and no torque limit belong to no family.
pub fn motor_families(cx: &Context) -> Vec<Family> {
    let robot = cx.robot;
    let class = |kind: ElemKind, id: usize, name: &str| {
        robot.elem(kind, id, name).and_then(|e| e.class.clone()).unwrap_or_default()
    };
    let mut fams: BTreeMap<(String, String, String, u8), Family> = BTreeMap::new();
    for j in robot.joints.iter().filter(|j| motor_driven(cx, j) && !robot.turns_a_wheel(j.id)) {
        let (key, label) = match cx.facts(&j.name).and_then(|f| f.motor) {
            Some(m) => (format!("spec {m}"), format!("the spec's motor `{m}`")),
            None => {
                let Some((l, _)) = joint_torque_limit(robot, j.id).filter(|(l, _)| *l > 0.0) else {
                    continue;
                };
                let unit = if j.jtype == JointType::Slide { "N" } else { "N·m" };
                (
                    format!("limit {l:.6e}"),
                    format!("equal force limits of {} {unit}", fmt_num(l, 4)),
                )
            }
        };
        let act = robot
            .actuators_on_joint(j.id)
            .first()
            .map(|a| class(ElemKind::Actuator, a.id, &a.name))
            .unwrap_or_default();
        let jclass = class(ElemKind::Joint, j.id, &j.name);
        let ty = (j.jtype == JointType::Slide) as u8;
        fams.entry((key, jclass, act, ty))
            .or_insert_with(|| Family { label, joints: Vec::new() })
            .joints
            .push(j.id);
    }
    fams.into_values().collect()
}
