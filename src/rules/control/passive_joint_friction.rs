use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::{JointType, Robot};
use crate::rules::geometry::oversized_weight::worst_gravity_torque;
use crate::rules::inertia::passive_joint_armature::{class_sources, driven};
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds a motor's `frictionloss` inherited by joints no motor drives, larger than every
    /// load of the joint's own: a hinge or slide with no actuator (on the joint, on a tendon
    /// that moves it, or through a joint equality to an actuated joint: the drive test of
    /// `passive-joint-armature`) that takes its `frictionloss` from the same `<default class>`
    /// attribute as actuated joints do, where that friction exceeds `load_factor` × the
    /// largest torque (force, for a slide) its own loads can put on it:
    /// - the gravity of everything it carries (its body's subtree mass at the subtree's centre
    ///   of mass, the worst over the joint's range, from the keyframe; a slide: the mass × the
    ///   gravity along its axis);
    /// - its spring, `stiffness` × the farthest the range lies from `springref`.
    ///
    /// The gripper knuckles, followers and spring links of a linkage under the arm's class, a
    /// passive toe or a free finger. Not reported: a frictionloss written on the joint itself
    /// or in a class no actuated joint uses (a deliberate value: a brake, a detent, a measured
    /// bearing); a friction its own loads overcome; wheels (the ground turns them: a round
    /// colliding geom about the axis at the end of its chain, on a joint with no range or one of
    /// 2π or more); joints that
    /// a spec marks passive with a motor family.
    ///
    /// ## Why is this bad?
    /// `frictionloss` is dry friction: MuJoCo holds the joint still until the generalised force
    /// on it exceeds the value. A motor's frictionloss stands for its gearbox; a passive joint
    /// has none. When the friction exceeds what the joint's own weight and spring can exert,
    /// the joint never moves on its own: a spring link that should return stays where it was
    /// left, a knuckle hangs at any angle, and only the coupling to a driven joint moves it — a
    /// load added to the driver on every closing. MuJoCo XML reference, `joint/frictionloss`.
    ///
    /// ## How it is confirmed
    /// Static: where each joint's compiled `frictionloss` is written (the attribute and the
    /// class it inherits from), the actuators' transmissions and the equalities; the subtree's
    /// mass and centre of mass at the keyframe; `stiffness`, `springref` and the range.
    ///
    /// ## How to fix
    /// Set `frictionloss="0"` on the passive joints (or give them a class of their own without
    /// the motors' friction); keep a value only where a measured bearing or a detent needs
    /// one, written on the joint.
    pub PassiveJointFriction {
        id: "passive-joint-friction",
        group: "control",
        level: Severity::Warning,
        probe: None,
        options: [opt(
            "load_factor",
            1.0,
            "",
            Domain::POSITIVE,
            "how many times the largest torque of the joint's own loads (gravity of what it carries, its spring) the inherited frictionloss must exceed: 1 = the joint never moves on its own"
        )],
    }
}

/// One passive joint whose inherited friction its own loads cannot overcome: (joint, the
/// largest gravity torque, the largest spring torque).
type Held = (usize, f64, f64);

/// The largest torque (force, for a slide) of joint `j`'s own loads: gravity of its subtree,
/// the worst over its range; its spring at the end of the range farthest from `springref`.
fn own_loads(robot: &Robot, j: usize, mass: &[f64], com: &[[f64; 3]]) -> Option<(f64, f64)> {
    let joint = robot.joints.get(j)?;
    let (m, c) = (*mass.get(joint.body)?, *com.get(joint.body)?);
    let gravity = match joint.jtype {
        JointType::Hinge => worst_gravity_torque(robot, j, m, c)?,
        JointType::Slide => {
            let a = robot.key.joint_xaxis.get(j)?;
            let g = robot.opt.gravity;
            (m * (a[0] * g[0] + a[1] * g[1] + a[2] * g[2])).abs()
        }
        _ => return None,
    };
    let far = if joint.limited {
        (joint.range[0] - joint.springref).abs().max((joint.range[1] - joint.springref).abs())
    } else {
        std::f64::consts::PI
    };
    Some((gravity, joint.stiffness * far))
}

/// A wheel, which the ground turns: [`Robot::turns_a_wheel`]'s shape on a joint that can turn
/// a whole revolution (no range, or one of 2π or more).
fn is_wheel(robot: &Robot, j: usize) -> bool {
    let x = &robot.joints[j];
    (!x.limited || (x.range[1] - x.range[0]).abs() >= std::f64::consts::TAU)
        && robot.turns_a_wheel(j)
}

impl Rule for PassiveJointFriction {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let factor = cx.opt("load_factor");
        let source =
            |j: usize| robot.attr_loc(ElemKind::Joint, j, &robot.joints[j].name, "frictionloss");
        let motor_sources = class_sources(robot, |j| j.frictionloss > 0.0, source);
        if motor_sources.is_empty() {
            return;
        }
        let mut d = mujoco_rs::prelude::MjData::new(&robot.mj);
        if let Some(k) = robot.key.key {
            let _ = d.reset_keyframe(k);
        }
        d.forward();
        let com = d.subtree_com().to_vec();
        let mass = robot.mj.body_subtreemass().to_vec();
        // Passive joints grouped by the class attribute they inherit.
        let mut groups: Vec<(crate::model::source::Loc, String, Vec<Held>)> = Vec::new();
        for j in robot.joints.iter().filter(|j| j.is_scalar() && j.frictionloss > 0.0) {
            if driven(robot, j.id)
                || is_wheel(robot, j.id)
                || cx.facts(&j.name).is_some_and(|f| f.motor.is_some())
            {
                continue;
            }
            let (loc, class) = source(j.id);
            let Some(class) = class else { continue };
            if !motor_sources.contains(&loc) {
                continue;
            }
            let Some((g, s)) = own_loads(robot, j.id, &mass, &com) else { continue };
            if j.frictionloss <= factor * (g + s) {
                continue;
            }
            match groups.iter_mut().find(|x| x.0 == loc) {
                Some(x) => x.2.push((j.id, g, s)),
                None => groups.push((loc, class, vec![(j.id, g, s)])),
            }
        }
        for (_, class, joints) in groups {
            out.push(report(cx, &class, &joints));
        }
    }
}

fn report(cx: &Context, class: &str, joints: &[Held]) -> Finding {
    let robot = cx.robot;
    let first = &robot.joints[joints[0].0];
    let value = first.frictionloss;
    let u = |j: usize| if robot.joints[j].jtype == JointType::Slide { "N" } else { "N·m" };
    let n = joints.len();
    let names: Vec<String> = joints
        .iter()
        .map(|&(j, g, s)| {
            let spring =
                if s > 0.0 { format!(", spring {}", fmt_num(s, 3)) } else { String::new() };
            format!("{} (gravity {}{spring} {})", robot.joints[j].name, fmt_num(g, 3), u(j))
        })
        .collect();
    let shown = if names.len() > 6 {
        format!("{}, … ({n} joints)", names[..6].join(", "))
    } else {
        names.join(", ")
    };
    let most = joints.iter().map(|&(_, g, s)| g + s).fold(0.0, f64::max);
    let msg = format!(
        "frictionloss {} {} from <default class=\"{class}\">, the actuated joints' value, holds {n} joint{} no actuator drives against every load of their own: {shown}",
        fmt_num(value, 4),
        u(first.id),
        if n == 1 { "" } else { "s" }
    );
    let mut f = cx
        .at_attr(ElemKind::Joint, first.id, &first.name, "frictionloss", msg)
        .label("no motor drives this joint");
    for &(j, _, _) in joints.iter().skip(1).take(3) {
        let jt = &robot.joints[j];
        f = f.secondary(robot.elem_loc(ElemKind::Joint, j, &jt.name), "no motor either");
    }
    f.note("frictionloss is dry friction: the joint stays still until the force on it exceeds the value; a motor's stands for its gearbox, and a passive joint whose own weight and spring cannot exceed it never moves on its own — only a coupling drags it, loading the driver")
        .help("set frictionloss=\"0\" on the passive joints (or give them a class of their own); keep a value only where a measured bearing or a detent needs one, written on the joint")
        .subject(Subject::Joint(first.id))
        .measured(value, u(first.id))
        .expected(most, u(first.id))
        .with("joints", n as f64)
}
