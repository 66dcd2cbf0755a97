//! `effort-limit-mismatch`'s URDF case: a joint whose `<dynamics damping>` takes its whole
//! `<limit effort>` below the `<limit velocity>` the same file states.

use crate::finding::{Finding, Subject};
use crate::model::Format;
use crate::model::source::XNode;
use crate::rules::Context;
use crate::util::fmt_num;

/// A positive finite number written as `attr` on `node`, with its location.
fn positive(node: Option<&XNode>, attr: &str) -> Option<(f64, crate::model::source::Loc)> {
    let a = node?.attr(attr)?;
    a.value.trim().parse::<f64>().ok().filter(|v| v.is_finite() && *v > 0.0).map(|v| (v, a.loc))
}

/// In a URDF, each hinge or slide joint whose `<dynamics damping>` × `<limit velocity>` exceeds
/// its `<limit effort>`, as the spec's case judges a motor's `velocity_limit`: at the effort the file gives the motor, the
/// damping stops the joint at effort / damping, short of the velocity the file also gives it.
/// A joint with no positive effort or velocity (a passive one, `effort="0" velocity="0"`) or no
/// damping is not judged; neither is one a spec gives a motor family, whose `velocity_limit`
/// the actuated-joint case judges.
pub fn urdf_damping_caps_speed(cx: &Context, out: &mut Vec<Finding>) {
    let robot = cx.robot;
    if robot.format != Format::Urdf {
        return;
    }
    for x in robot.tree.children_tagged("joint") {
        let Some(name) = x.get("name") else { continue };
        let Some(j) = robot.joint(name).filter(|j| j.is_scalar()) else { continue };
        if cx.facts(name).is_some_and(|f| f.motor.is_some()) {
            continue;
        }
        let limit = x.children_tagged("limit").next();
        let dynamics = x.children_tagged("dynamics").next();
        let (Some((effort, _)), Some((velocity, v_at)), Some((damping, d_at))) =
            (positive(limit, "effort"), positive(limit, "velocity"), positive(dynamics, "damping"))
        else {
            continue;
        };
        if damping * velocity <= effort {
            continue;
        }
        let slide = j.jtype == crate::model::JointType::Slide;
        let (unit, vel, dunit) =
            if slide { ("N", "m/s", "N·s/m") } else { ("N·m", "rad/s", "N·m·s/rad") };
        let terminal = effort / damping;
        let msg = format!(
            "joint `{name}` damping {} {dunit} takes its whole effort {} {unit} at {} {vel}: it cannot reach the velocity limit {} {vel} the same file gives it",
            fmt_num(damping, 4),
            fmt_num(effort, 4),
            fmt_num(terminal, 3),
            fmt_num(velocity, 4)
        );
        let f = cx
            .finding(msg, d_at)
            .element(format!("joint `{name}`"), d_at)
            .label(format!(
                "{} × {} {vel} = {} {unit} of damping at the velocity limit",
                fmt_num(damping, 4),
                fmt_num(velocity, 4),
                fmt_num(damping * velocity, 4)
            ))
            .secondary(v_at, format!("velocity limit, {} {vel}", fmt_num(velocity, 4)))
            .note("MuJoCo's URDF importer makes <dynamics damping> the joint's passive damping (Gazebo applies it too): it opposes every motion with damping × speed, so with the whole effort the simulated joint stops accelerating at effort / damping; a policy learns a robot slower than the one the file's velocity limit describes (a motor's back-EMF is already in its speed–torque curve, not a second damping on top)")
            .help(format!(
                "lower the damping below {} {dunit} (effort / velocity: the joint's identified viscous friction, if known), or state the velocity the joint reaches",
                fmt_num(effort / velocity, 3)
            ))
            .subject(Subject::Joint(j.id))
            .measured(terminal, vel)
            .expected(velocity, vel)
            .with("damping", damping)
            .with("force_limit", effort)
            .with("terminal_speed", terminal)
            .with("velocity_limit", velocity);
        out.push(f);
    }
}
