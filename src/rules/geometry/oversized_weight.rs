//! The weight test of `oversized-collision-primitive` for a link whose mass MuJoCo computes from
//! its geoms (no `<inertial>`): the mass grows with the shape, so the shape cannot be judged by
//! it; the actuators can. Holding the link against gravity needs a torque at the joints that
//! carry it which their effort limits must give.
//!
//! The gravity torque of a mass M at offset r from a hinge's anchor, about its unit axis a,
//! when the joint turns by θ from the keyframe: with u = r − (r·a)a (the offset across the
//! axis) and v = a × u, τ(θ) = M (cos θ g·v − sin θ g·u). Its largest magnitude over the
//! joint's range (the whole turn for an unlimited hinge) is what the actuators must hold.

use mujoco_rs::prelude::*;

use crate::model::source::XNode;
use crate::model::{ActuatorKind, Format, JointType, Robot};
use crate::rules::in_subtree;

/// Steps per radian at which the gravity torque is evaluated over a joint's range (besides its
/// ends): 0.01 rad, where cos θ of the extremum is missed by less than 5e-5.
const STEPS_PER_RAD: f64 = 100.0;

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// The largest gravity torque (N·m) of mass `m` at `com` about hinge `j` (anchor, axis at the
/// keyframe) over the joint's range from the keyframe position `q`.
pub fn worst_gravity_torque(robot: &Robot, j: usize, m: f64, com: [f64; 3]) -> Option<f64> {
    let joint = robot.joints.get(j)?;
    let p = *robot.key.joint_xanchor.get(j)?;
    let a = *robot.key.joint_xaxis.get(j)?;
    let q = *robot.key.qpos.get(joint.qposadr)?;
    let g = robot.opt.gravity;
    let r = [com[0] - p[0], com[1] - p[1], com[2] - p[2]];
    let along = dot(r, a);
    let u = [r[0] - along * a[0], r[1] - along * a[1], r[2] - along * a[2]];
    let v = cross(a, u);
    let (gv, gu) = (dot(g, v), dot(g, u));
    let tau = |t: f64| (m * (t.cos() * gv - t.sin() * gu)).abs();
    let (lo, hi) = if joint.limited && joint.range[0] < joint.range[1] {
        (joint.range[0] - q, joint.range[1] - q)
    } else {
        (-std::f64::consts::PI, std::f64::consts::PI)
    };
    let n = ((hi - lo) * STEPS_PER_RAD).ceil().clamp(1.0, 1e5) as usize;
    let worst = (0..=n).map(|k| tau(lo + (hi - lo) * k as f64 / n as f64)).fold(0.0, f64::max);
    worst.is_finite().then_some(worst)
}

/// The torque (N·m) the actuators of hinge `j` can hold it with: each one's force limit
/// (`forcerange`, or a `<motor>`'s ctrlrange × gain) × its moment arm at the joint, summed, and
/// no more than the joint's own `actuatorfrcrange`. `None` for a joint no actuator drives, or
/// one an actuator drives without a limit and the joint sets none.
pub fn effort_limit(robot: &Robot, j: usize) -> Option<f64> {
    let acts = robot.actuators_on_joint(j);
    if acts.is_empty() {
        return None;
    }
    let mut sum = Some(0.0);
    for a in acts {
        let force = if a.forcelimited {
            Some(a.forcerange[0].abs().max(a.forcerange[1].abs()))
        } else if matches!(a.kind, ActuatorKind::Motor) && a.ctrllimited {
            Some(a.gainprm[0].abs() * a.ctrlrange[0].abs().max(a.ctrlrange[1].abs()))
        } else {
            None
        };
        let arm = robot.moment_at_joint(a, j).map(f64::abs);
        sum = sum.zip(force).zip(arm).map(|((s, f), r)| s + f * r);
    }
    let joint = robot
        .mj
        .jnt_actfrclimited()
        .get(j)
        .copied()
        .unwrap_or(false)
        .then(|| {
            let r = robot.mj.jnt_actfrcrange().as_flattened();
            Some(r.get(2 * j)?.abs().max(r.get(2 * j + 1)?.abs()))
        })
        .flatten();
    let limit = match (sum, joint) {
        (Some(s), Some(l)) => s.min(l),
        (Some(s), None) => s,
        (None, Some(l)) => l,
        (None, None) => return None,
    };
    (limit.is_finite() && limit > 0.0).then_some(limit)
}

/// Whether a body's mass is MuJoCo's sum over its geoms (no `<inertial>` on its element, or
/// `<compiler inertiafromgeom="true">`). `false` when its element is not found.
pub fn mass_from_geoms(robot: &Robot, body: usize) -> bool {
    let name = robot.body_name(body);
    match robot.format {
        Format::Urdf => robot
            .tree
            .children_tagged("link")
            .find(|l| l.get("name") == Some(name))
            .is_some_and(|l| l.children_tagged("inertial").next().is_none()),
        Format::Mjcf => {
            let forced = robot
                .tree
                .children_tagged("compiler")
                .filter_map(|c| c.get("inertiafromgeom"))
                .last()
                .is_some_and(|v| v.trim() == "true");
            let mut bodies: Vec<&XNode> = Vec::new();
            fn visit<'a>(n: &'a XNode, out: &mut Vec<&'a XNode>) {
                for c in &n.children {
                    match c.tag.as_str() {
                        "body" => {
                            out.push(c);
                            visit(c, out);
                        }
                        "frame" => visit(c, out),
                        _ => {}
                    }
                }
            }
            for w in robot.tree.children_tagged("worldbody") {
                visit(w, &mut bodies);
            }
            // Compiled bodies follow the file's pre-order; a name that disagrees means the
            // order was not MuJoCo's: say nothing.
            let Some(el) = body.checked_sub(1).and_then(|i| bodies.get(i)) else { return false };
            if el.get("name").unwrap_or("") != name {
                return false;
            }
            forced || el.children_tagged("inertial").next().is_none()
        }
    }
}

/// Whether geom `g` states its own `mass` (on its element or through a default class): its
/// link's mass then does not grow with the shape, and the mass test judges it. Unknown (the
/// element not found) counts as stated; a URDF collision has no mass of its own.
pub fn geom_mass_stated(robot: &Robot, g: usize) -> bool {
    if robot.format == Format::Urdf {
        return false;
    }
    let name = robot.geoms.get(g).map_or("", |x| x.name.as_str());
    robot
        .elem(crate::model::mjcf::ElemKind::Geom, g, name)
        .is_none_or(|e| e.attrs.contains_key("mass"))
}

/// The joint that cannot hold a link: (joint, torque needed, torque available), N·m.
pub struct Overload {
    pub joint: usize,
    pub need: f64,
    pub limit: f64,
    /// A floating base tilted on its legs (the limit is every actuated leg hinge's about the
    /// axis).
    pub trunk: bool,
}

/// The weight test for the link of body `body` (mass from its geoms): the hinge that carries
/// it (one on the path from the link to its tree's top, holding the whole subtree below it)
/// or, for a floating base, the joints of the legs tilting it (each hinge between the base and
/// a foot that is not a wheel, with every such actuated hinge's limit projected on its axis:
/// an upper bound on what the legs give),
/// whose actuators fall furthest short of the link's worst gravity torque over the joint's
/// range. `None` when every such joint can hold it, none has a known limit, or the model
/// closes a chain with an equality.
pub fn overload(robot: &Robot, body: usize) -> Option<Overload> {
    // A closed chain (a `connect` or `weld` equality) shares the load between joints.
    if robot.equalities.iter().any(|e| e.etype == 0 || e.etype == 1) {
        return None;
    }
    let mut d = MjData::new(&robot.mj);
    if let Some(k) = robot.key.key {
        let _ = d.reset_keyframe(k);
    }
    d.forward();
    let subtree_com = d.subtree_com().to_vec();
    let xipos = d.xipos().to_vec();
    let subtree_mass = robot.mj.body_subtreemass();
    let weld = robot.bodies.get(body)?.weld;
    let hinges =
        |b: usize| robot.joints.iter().filter(move |j| j.body == b && j.jtype == JointType::Hinge);
    let mut worst: Option<Overload> = None;
    let trunk = robot.floating_bodies().contains(&weld);
    let mut keep = |joint: usize, need: f64, limit: f64| {
        if need > limit && worst.as_ref().is_none_or(|w| need / limit > w.need / w.limit) {
            worst = Some(Overload { joint, need, limit, trunk });
        }
    };
    if trunk {
        // The trunk: the bodies welded to the floating base, tilted on the legs.
        let (mut m, mut c) = (0.0, [0.0; 3]);
        for b in robot.bodies.iter().filter(|b| b.weld == weld) {
            let x = *xipos.get(b.id)?;
            m += b.mass;
            for k in 0..3 {
                c[k] += b.mass * x[k];
            }
        }
        if m <= 0.0 {
            return None;
        }
        let com = c.map(|x| x / m);
        // The legs: the hinges between the base and each foot that is not a wheel.
        let mut tree: Vec<usize> = Vec::new();
        for foot in crate::rules::contact::feet::feet(robot, None) {
            if foot.kind == crate::rules::contact::feet::FootKind::Wheel
                || !in_subtree(robot, weld, foot.root)
            {
                continue;
            }
            let mut b = foot.root;
            for _ in 0..robot.bodies.len() {
                if b == 0 || robot.bodies[b].weld == weld {
                    break;
                }
                for j in hinges(b) {
                    if !robot.is_base_coordinate(j.id) && !tree.contains(&j.id) {
                        tree.push(j.id);
                    }
                }
                b = robot.bodies[b].parent;
            }
        }
        tree.sort_unstable();
        let limits: Vec<(usize, f64)> =
            tree.iter().filter_map(|&j| Some((j, effort_limit(robot, j)?))).collect();
        for &j in &tree {
            let Some(&a) = robot.key.joint_xaxis.get(j) else { continue };
            let limit: f64 = limits
                .iter()
                .filter_map(|&(k, l)| Some(l * dot(a, *robot.key.joint_xaxis.get(k)?).abs()))
                .sum();
            if let Some(need) = worst_gravity_torque(robot, j, m, com)
                && limit > 0.0
            {
                keep(j, need, limit);
            }
        }
    } else {
        let mut b = body;
        for _ in 0..robot.bodies.len() {
            if b == 0 {
                break;
            }
            for j in hinges(b) {
                if robot.is_wheel(j.id) {
                    continue;
                }
                let (Some(limit), Some(&m), Some(&c)) =
                    (effort_limit(robot, j.id), subtree_mass.get(b), subtree_com.get(b))
                else {
                    continue;
                };
                if let Some(need) = worst_gravity_torque(robot, j.id, m, c) {
                    keep(j.id, need, limit);
                }
            }
            if robot.floating_bodies().contains(&b) {
                break;
            }
            b = robot.bodies[b].parent;
        }
    }
    worst
}
