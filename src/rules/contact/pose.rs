//! The pose the static foot rules judge a robot's feet at: the keyframe when the model has one;
//! else qpos0 — unless qpos0 places limited joints past their stops (a URDF whose zero pose
//! bends the knees through their end stops, as Cassie's), a pose the robot cannot take. Then
//! the file gives no stance: qpos0 may be the stance drawn with the stops wrong, or the nearest
//! pose the robot can take — qpos0 with those joints moved to their nearest stop — may be.
//! The rules judge both and report what holds at both, worded at the clamped pose (`toe-tilt`
//! names "qpos0 clamped into the joint ranges"): a sole flat at either may be flat in the
//! stance. A keyframe is judged as written: it is the pose the author chose, and
//! `keyframe-state` reports it when it lies outside the ranges.

use crate::finding::Finding;
use crate::model::pose_state;
use crate::model::{JointType, Robot};
use crate::probe::stance::RANGE_TOLERANCE;

/// The static foot rules: they judge the feet's geometry at one pose.
pub const FOOT_RULES: &[&str] = &[
    "toe-tilt",
    "foot-collision-geometry",
    "links-without-collision",
    "torsional-friction-length",
];

/// qpos0 with every limited hinge or slide it places past its range by more than
/// [`RANGE_TOLERANCE`] of the range (`keyframe-state`'s and the stance runs' `in_range` test)
/// moved to its nearest stop, and how many moved.
pub fn clamped_qpos0(robot: &Robot) -> (Vec<f64>, usize) {
    let mut q = robot.mj.qpos0().to_vec();
    let mut moved = 0;
    for j in &robot.joints {
        if !j.limited || !matches!(j.jtype, JointType::Hinge | JointType::Slide) {
            continue;
        }
        let Some(x) = q.get_mut(j.qposadr) else { continue };
        let (lo, hi) = (j.range[0].min(j.range[1]), j.range[0].max(j.range[1]));
        let past = (lo - *x).max(*x - hi);
        if past > RANGE_TOLERANCE * (hi - lo) {
            *x = x.max(lo).min(hi);
            moved += 1;
        }
    }
    (q, moved)
}

/// The robot at the second pose the static foot rules judge when the loaded one is no pose of
/// the robot: a model with no keyframe whose qpos0 places joints past their stops, at
/// [`clamped_qpos0`]. `None` when the loaded pose (the keyframe, or qpos0 within the ranges)
/// is the only one to judge.
pub fn foot_rules_robot(robot: &Robot) -> Option<Robot> {
    if robot.key.key.is_some() {
        return None;
    }
    let (q, moved) = clamped_qpos0(robot);
    if moved == 0 {
        return None;
    }
    let mut copy = robot.clone();
    copy.key = pose_state(&copy.mj, &q, moved);
    Some(copy)
}

/// The findings of a foot rule at the clamped pose (`at_clamped`) that it also made at qpos0
/// (`at_qpos0`): the same rule at the same place on the same element.
pub fn at_both(at_qpos0: Vec<Finding>, at_clamped: Vec<Finding>) -> Vec<Finding> {
    at_clamped
        .into_iter()
        .filter(|f| {
            at_qpos0.iter().any(|g| {
                g.rule == f.rule && g.primary == f.primary && g.element_loc == f.element_loc
            })
        })
        .collect()
}

/// How a foot finding names the pose it judged: "keyframe `stand`", "qpos0", or "qpos0 clamped
/// into the joint ranges (no keyframe; qpos0 places 6 joints past their stops, and the finding
/// holds there too)" ([`at_both`]).
pub fn pose_word(robot: &Robot) -> String {
    match &robot.key.key_name {
        Some(k) if !k.is_empty() => format!("keyframe `{k}`"),
        Some(_) => "the keyframe".into(),
        None if robot.key.clamped > 0 => format!(
            "qpos0 clamped into the joint ranges (no keyframe; qpos0 places {} joint{} past {} stops, and the finding holds there too)",
            robot.key.clamped,
            if robot.key.clamped == 1 { "" } else { "s" },
            if robot.key.clamped == 1 { "its" } else { "their" }
        ),
        None => "qpos0".into(),
    }
}
