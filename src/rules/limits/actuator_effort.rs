//! The effort case of `placeholder-joint-limits` in an MJCF file (split from the rule's file):
//! the force bound of the actuators that drive a hinge or slide against the torque of the
//! robot's weight at the joint's reach (the Koch v1.0 arm's ±87 N·m on a 0.24 kg arm).

use crate::model::mjcf::ElemKind;
use crate::model::source::Loc;
use crate::model::{ActuatorKind, JointType, Robot};
use crate::rules::geometry::oversized_weight::effort_limit;
use crate::rules::{Context, display_name, in_subtree};
use crate::util::fmt_num;

use super::placeholder_joint_limits::subtree_reach;

/// The gravity the robot's weight is taken under (m/s², MuJoCo's default): the hardware's
/// motors are sized for its weight on Earth whatever gravity the file simulates (a gravity
/// scaled by mistake is `non-earth-gravity`'s finding, not the motors').
const EARTH_GRAVITY: f64 = 9.81;

/// One joint whose actuators' force bound exceeds `weight_multiple` × the weight torque.
pub(super) struct ActuatorEffort {
    pub(super) joint: usize,
    /// Where the binding bound is written: the joint's `actuatorfrcrange` when it caps the
    /// actuators, else the strongest actuator's `forcerange` (or a motor's `ctrlrange`).
    pub(super) at: Loc,
    /// Bound / weight torque.
    pub(super) ratio: f64,
    pub(super) detail: String,
    /// The mass of the kinematic tree the joint is in (kg).
    pub(super) mass: f64,
}

/// The mass of the kinematic tree body `b` is in: the subtree of its ancestor that hangs from
/// the world (scenery and other robots in the file are other trees).
fn tree_mass(robot: &Robot, b: usize) -> f64 {
    let mut top = b;
    for _ in 0..robot.bodies.len() {
        match robot.bodies.get(top) {
            Some(x) if x.parent != 0 && top != 0 => top = x.parent,
            _ => break,
        }
    }
    if top == 0 {
        return 0.0;
    }
    robot.bodies.iter().filter(|x| in_subtree(robot, top, x.id)).map(|x| x.mass).sum()
}

/// One actuator's own force bound at joint `j` (N·m or N) and the attribute that states it:
/// `forcerange` (the larger end in magnitude, so a bound in either direction is judged) × the
/// moment arm, or a `<motor>`'s `ctrlrange` × gain × the moment arm.
fn own_bound(robot: &Robot, a: &crate::model::Actuator, j: usize) -> Option<(f64, &'static str)> {
    let arm = robot.moment_at_joint(a, j)?.abs();
    let end = |r: [f64; 2]| r[0].abs().max(r[1].abs());
    if a.forcelimited {
        Some((end(a.forcerange) * arm, "forcerange"))
    } else if matches!(a.kind, ActuatorKind::Motor) && a.ctrllimited {
        Some((a.gainprm[0].abs() * end(a.ctrlrange) * arm, "ctrlrange"))
    } else {
        None
    }
}

/// The hinges and slides of an MJCF model whose actuators can apply more than `multiple` × the
/// torque of their tree's weight on Earth at the joint's reach (the force of that weight for a
/// slide):
/// [`effort_limit`]'s bound (each actuator's `forcerange`, or a `<motor>`'s ctrlrange × gain,
/// × its gear, summed, no more than the joint's `actuatorfrcrange`), compiled values.
pub(super) fn actuator_efforts(cx: &Context, multiple: f64) -> Vec<ActuatorEffort> {
    let robot = cx.robot;
    let g = EARTH_GRAVITY;
    let mut out = Vec::new();
    for j in robot.joints.iter().filter(|j| matches!(j.jtype, JointType::Hinge | JointType::Slide))
    {
        let Some(limit) = effort_limit(robot, j.id) else { continue };
        let slide = j.jtype == JointType::Slide;
        let reach = if slide { 1.0 } else { subtree_reach(robot, j.id) };
        let mass = tree_mass(robot, j.body);
        if !(reach > 0.0 && mass > 0.0) {
            continue;
        }
        let weight = mass * g * reach;
        let ratio = limit / weight;
        if !(ratio > multiple) {
            continue;
        }
        // The bound that binds: the strongest actuator's, unless the joint caps the sum.
        let acts = robot.actuators_on_joint(j.id);
        let strongest = acts
            .iter()
            .filter_map(|a| own_bound(robot, a, j.id).map(|(f, attr)| (*a, f, attr)))
            .max_by(|x, y| x.1.total_cmp(&y.1));
        let sum: f64 = acts.iter().filter_map(|a| own_bound(robot, a, j.id)).map(|b| b.0).sum();
        let unbounded = acts.iter().any(|a| own_bound(robot, a, j.id).is_none());
        let capped = strongest.is_none() || unbounded || limit < sum * (1.0 - 1e-9);
        let (tu, lever) = if slide {
            ("N", String::new())
        } else {
            ("N·m", format!(" at {} m", fmt_num(reach, 3)))
        };
        let (at, source) = match strongest.filter(|_| !capped) {
            Some((a, _, attr)) => (
                robot.attr_loc(ElemKind::Actuator, a.id, &a.name, attr).0,
                if attr == "ctrlrange" {
                    format!("motor `{}` ctrlrange × gear", display_name(&a.name, a.id))
                } else {
                    format!("actuator `{}` forcerange", display_name(&a.name, a.id))
                },
            ),
            None => (
                robot.attr_loc(ElemKind::Joint, j.id, &j.name, "actuatorfrcrange").0,
                "actuatorfrcrange".to_string(),
            ),
        };
        let per = if acts.len() > 1 && !capped { ", the actuators summed" } else { "" };
        out.push(ActuatorEffort {
            joint: j.id,
            at,
            ratio,
            detail: format!(
                "`{}` {} {tu} ({source}{per}) = {}× the robot's weight{lever} ({} {tu})",
                j.name,
                fmt_num(limit, 4),
                fmt_num(ratio, 3),
                fmt_num(weight, 3)
            ),
            mass,
        });
    }
    out
}
