use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::{JointType, Robot};
use crate::rules::{Context, Rule, RuleMeta, in_subtree};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Reports a hinge or slide joint of an actuated robot that nothing holds: no actuator
    /// drives it (on the joint or through a tendon), no spring (`stiffness` 0), no joint or
    /// tendon equality couples it, no fixed tendon includes it, no spatial tendon is attached
    /// beyond it, and it closes no loop (no `connect`/`weld` equality joins a body beyond it to
    /// one before it). Examples: a gripper's fingertip joints that the real linkage couples to
    /// the gripper motor, written as free hinges; a suspension slide with damping and a range
    /// but no spring. Not reported: wheels ([`Robot::is_wheel`]) and a hinge carrying a wheel
    /// further out (a caster swivel, a rocker-bogie: they turn freely by design); a floating or
    /// planar base's coordinates; joints of a kinematic tree with no actuator at all (a door or
    /// an object of the scene; `missing-actuators` reports a robot with none). Needs no spec and
    /// no threshold: it reads what the compiled model connects to the joint.
    ///
    /// ## Why is this bad?
    /// Nothing restores such a joint: gravity, contact and the motion of the rest of the robot
    /// decide where it sits, damping only slows it, dry friction only holds it against small
    /// loads, and its range stops (if any) end up carrying the load. A suspension without a
    /// spring rests on its stop and transmits every impact through it; a fingertip without its
    /// coupling flops or stays wherever contact left it, so grasps learned in simulation do not
    /// transfer.
    ///
    /// ## How it is confirmed
    /// Static: the compiled model's actuators, tendons, equalities and joint stiffness.
    ///
    /// ## How to fix
    /// Give the joint what holds it on the real robot: a coupling to the driven joint
    /// (`<equality><joint joint1=... joint2=... polycoef=.../>` or a fixed tendon), a spring
    /// (`stiffness`, `springref`, with `damping`), or an actuator. A joint that is rigid on the
    /// real robot should be removed.
    pub FreePassiveJoint {
        id: "free-passive-joint",
        group: "mapping",
        level: Severity::Warning,
        probe: None,
        options: [],
    }
}
/// The body just below the world that carries `b` (its kinematic tree).
fn tree_root(robot: &Robot, mut b: usize) -> usize {
    for _ in 0..=robot.bodies.len() {
        match robot.bodies.get(b) {
            Some(x) if x.parent != 0 && b != 0 => b = x.parent,
            _ => return b,
        }
    }
    b
}

/// What holds joint `j` besides stiffness: an actuator, a tendon, an equality or a closed loop.
fn held(robot: &Robot, j: usize) -> bool {
    let joint = &robot.joints[j];
    if !robot.actuators_on_joint(j).is_empty() {
        return true;
    }
    let m = &robot.mj;
    let (wt, wo) = (m.wrap_type(), m.wrap_objid());
    let site_body = m.site_bodyid();
    let geom_body = m.geom_bodyid();
    for (w, &t) in wt.iter().enumerate() {
        let (t, o) = (t as i32, wo.get(w).copied().unwrap_or(-1));
        let Ok(o) = usize::try_from(o) else { continue };
        let beyond = |b: Option<&i32>| {
            b.and_then(|&b| usize::try_from(b).ok())
                .is_some_and(|b| in_subtree(robot, joint.body, b))
        };
        // 1: a joint in a fixed tendon; 3: a site, 4/5: a wrapping geom of a spatial tendon.
        let touches = match t {
            1 => o == j,
            3 => beyond(site_body.get(o)),
            4 | 5 => beyond(geom_body.get(o)),
            _ => false,
        };
        if touches {
            return true;
        }
    }
    robot.equalities.iter().any(|e| match e.etype {
        // connect / weld between bodies: a loop through the joint when one end lies beyond it.
        0 | 1 => {
            let side = |o: i32| usize::try_from(o).is_ok_and(|b| in_subtree(robot, joint.body, b));
            side(e.obj1) != side(e.obj2)
        }
        2 => e.obj1 == j as i32 || e.obj2 == j as i32,
        _ => false,
    })
}

impl Rule for FreePassiveJoint {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        if robot.actuators.is_empty() {
            return;
        }
        // Kinematic trees that carry an actuated joint: the robot's, not the scene's objects.
        let actuated_trees: Vec<usize> = robot
            .joints
            .iter()
            .filter(|j| !robot.actuators_on_joint(j.id).is_empty())
            .map(|j| tree_root(robot, j.body))
            .collect();
        for j in robot.joints.iter().filter(|j| j.is_scalar()) {
            if j.stiffness != 0.0
                || j.body == 0
                || !actuated_trees.contains(&tree_root(robot, j.body))
                || robot.is_wheel(j.id)
                || robot.is_base_coordinate(j.id)
                || held(robot, j.id)
            {
                continue;
            }
            // A hinge that carries a wheel (a caster's swivel, a bogie) turns freely by design.
            if j.jtype == JointType::Hinge
                && robot.joints.iter().any(|w| {
                    w.id != j.id && in_subtree(robot, j.body, w.body) && robot.is_wheel(w.id)
                })
            {
                continue;
            }
            let slide = j.jtype == JointType::Slide;
            let (unit, dunit, funit) =
                if slide { ("m", "N·s/m", "N") } else { ("rad", "N·m·s/rad", "N·m") };
            let mut has = Vec::new();
            if j.damping > 0.0 {
                has.push(format!("damping {} {dunit}", fmt_num(j.damping, 4)));
            }
            if j.frictionloss > 0.0 {
                has.push(format!("frictionloss {} {funit}", fmt_num(j.frictionloss, 4)));
            }
            if j.limited {
                has.push(format!(
                    "range [{}, {}] {unit}",
                    fmt_num(j.range[0], 4),
                    fmt_num(j.range[1], 4)
                ));
            }
            let only = if has.is_empty() {
                "nothing else either: it swings freely".to_string()
            } else {
                format!("only {}", has.join(", "))
            };
            // An unnamed joint by its number among its body's joints (from 1, file order).
            let label = if j.name.is_empty() {
                let no = robot.joints[..j.id].iter().filter(|x| x.body == j.body).count() + 1;
                format!("no. {no} of body `{}`", robot.body_name(j.body))
            } else {
                format!("`{}`", j.name)
            };
            let msg = format!(
                "{} joint {label} is held by nothing: no actuator, no spring (stiffness 0), no coupling (equality, tendon or closed loop); {only}",
                if slide { "slide" } else { "hinge" },
            );
            let f = cx
                .at_elem(ElemKind::Joint, j.id, &j.name, msg)
                .label("no actuator, spring or coupling")
                .note(if j.limited {
                    "nothing restores the joint: gravity, contact and the rest of the robot's motion decide where it sits, damping only slows it and dry friction only holds it against small loads, so it ends up on its range stops"
                } else {
                    "nothing restores the joint: gravity, contact and the rest of the robot's motion decide where it sits; damping only slows it and dry friction only holds it against small loads"
                })
                .help("give it what holds it on the real robot: a coupling to the driven joint (<equality><joint .../> or a fixed tendon), a spring (stiffness with damping), or an actuator; remove the joint if the real part is rigid")
                .subject(Subject::Joint(j.id));
            out.push(f);
        }
    }
}
