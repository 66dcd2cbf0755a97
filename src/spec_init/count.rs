//! Which joints the spec template calls actuated and passive, and the `count` of a joint: how
//! many motors drive it.

use crate::model::Robot;
use crate::rules::inertia::parallel_ankle_armature::tendon_motor_count;

/// The `count = N` line of a joint group (a joint, or a left/right pair). Two or more tendon
/// actuators reaching every joint of the group are a parallel linkage the model shows (each
/// motor reflects its rotor inertia onto the joint, as `parallel-ankle-armature` counts them):
/// that number. Otherwise 1, and for an ankle, how to tell whether two motors drive it, which
/// a serial pitch/roll cross with one actuator per joint cannot show.
pub(super) fn count_line(robot: &Robot, group: &[&str]) -> String {
    let n = group
        .iter()
        .filter_map(|name| robot.joints.iter().find(|j| j.name == *name))
        .map(|j| tendon_motor_count(robot, j.id))
        .min()
        .unwrap_or(0);
    if n >= 2 {
        return format!(
            "count = {n}  # {n} tendon actuators drive this joint in the model: a parallel linkage"
        );
    }
    if group.iter().any(|n| n.to_ascii_lowercase().contains("ankle")) {
        return "count = 1  # one actuator in the model; 2 if two motors in the shank drive this \
                ankle through rods (a parallel RSU linkage; the datasheet tells)"
            .to_string();
    }
    "count = 1  # motors driving the joint (one actuator in the model)".to_string()
}

/// Scalar joints reached by at least one actuator.
pub(super) fn actuated(robot: &Robot) -> Vec<usize> {
    robot
        .joints
        .iter()
        .filter(|j| j.is_scalar() && !robot.actuators_on_joint(j.id).is_empty())
        .map(|j| j.id)
        .collect()
}

/// MuJoCo's `mjEQ_JOINT`: `joint1 = poly(joint2)`, or a constant with no `joint2`.
const EQ_JOINT: i32 = 2;

/// Scalar joints no actuator reaches and no joint equality ties to an actuated joint (or holds
/// at a constant): a URDF `<mimic>` joint (MJCF `<equality><joint>`) follows its leader's motor
/// and has no spring of its own, so it is not passive.
pub(super) fn passive(robot: &Robot) -> Vec<usize> {
    let driven = |j: usize| !robot.actuators_on_joint(j).is_empty();
    let coupled = |j: usize| {
        robot.equalities.iter().filter(|e| e.etype == EQ_JOINT).any(|e| {
            let other = if e.obj1 == j as i32 {
                e.obj2
            } else if e.obj2 == j as i32 {
                e.obj1
            } else {
                return false;
            };
            other < 0 || driven(other as usize)
        })
    };
    robot
        .joints
        .iter()
        .filter(|j| j.is_scalar() && !driven(j.id) && !coupled(j.id))
        .map(|j| j.id)
        .collect()
}
