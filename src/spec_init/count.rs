//! The `count` of a joint in the spec template: how many motors drive it.

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
