//! `keyframe-state`'s floor check: how far the state a reset starts from places a floating-base
//! robot above (or into) the floor plane it stands on. The lowest point of each colliding geom
//! is its exact support point against the plane's normal (`shapes::Placed::support`: spheres,
//! capsules, cylinders, boxes, ellipsoids, mesh vertices), not a bounding sphere.

use crate::finding::{Finding, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::{GeomType, JointType, Robot, Transmission};
use crate::rules::Context;
use crate::rules::geometry::shapes::{Placed, V3, dot, mesh_world_vertices};
use crate::util::fmt_num;

/// How many hinges or slides a free body's subtree must hold to be a robot (legs, arms), not a
/// loose object of the scene (a box, a ball) that may rest on a table above the floor.
pub const MIN_ROBOT_JOINTS: usize = 2;

/// One pose a reset starts from: a keyframe (index, name, label) or qpos0 (`None`).
pub struct Start {
    pub key: Option<usize>,
    pub name: String,
    pub label: String,
}

/// The gap of one robot at one pose: lowest geom, the plane, signed height of the geom's lowest
/// point above the plane's surface (m; negative: into it).
struct Gap {
    geom: usize,
    plane: usize,
    height: f64,
}

/// The robot: of the free bodies whose subtrees hold at least [`MIN_ROBOT_JOINTS`] hinges or
/// slides, the one with the most joints an actuator drives, then the most joints (the first on a
/// tie), with its subtree's bodies. The other free trees are the scene's (a chair, a cabinet, a
/// loose limb `detached-limb` judges). None when an active connect or weld equality holds a
/// body to the world (a robot hung on a gantry does not drop).
fn main_robot(robot: &Robot) -> Option<(usize, Vec<usize>)> {
    let hung = robot.equalities.iter().any(|e| {
        (e.etype == 0 || e.etype == 1)
            && robot.mj.eq_active0().get(e.id).is_some_and(|&a| a)
            && (e.obj1 == 0 || e.obj2 == 0)
    });
    if hung {
        return None;
    }
    let under = |b: usize, root: usize| {
        let mut x = b;
        while x != 0 && x != root {
            x = robot.bodies[x].parent;
        }
        x == root
    };
    let driven = |j: usize| {
        robot.actuators.iter().any(|a| {
            matches!(a.trn, Transmission::Joint | Transmission::JointInParent)
                && a.target == j as i32
        })
    };
    let mut best: Option<((usize, usize), usize, Vec<usize>)> = None;
    for root in robot.joints.iter().filter(|j| j.jtype == JointType::Free).map(|j| j.body) {
        let bodies: Vec<usize> =
            robot.bodies.iter().map(|b| b.id).filter(|&b| b != 0 && under(b, root)).collect();
        let scalar: Vec<usize> = robot
            .joints
            .iter()
            .filter(|j| j.is_scalar() && bodies.contains(&j.body))
            .map(|j| j.id)
            .collect();
        if scalar.len() < MIN_ROBOT_JOINTS {
            continue;
        }
        let score = (scalar.iter().filter(|&&j| driven(j)).count(), scalar.len());
        if best.as_ref().is_none_or(|b| score > b.0) {
            best = Some((score, root, bodies));
        }
    }
    best.map(|(_, root, bodies)| (root, bodies))
}

/// The floor planes (of the world or welded to it) the geom touches, facing up against gravity.
fn planes(robot: &Robot, g: usize, up: V3, xmat: &[[f64; 9]]) -> Vec<usize> {
    crate::model::contact::ground_partners(robot, g)
        .into_iter()
        .map(|(p, _)| p)
        .filter(|&p| robot.geoms[p].gtype == GeomType::Plane)
        .filter(|&p| xmat.get(p).is_some_and(|x| dot([x[2], x[5], x[8]], up) > 0.5))
        .collect()
}

/// The lowest colliding geom of the robot `bodies` at the pose `(xpos, xmat)` against the floor
/// planes it touches; `None` when none of its geoms touches an upward floor plane.
fn gap(
    robot: &Robot,
    bodies: &[usize],
    up: V3,
    xpos: &[[f64; 3]],
    xmat: &[[f64; 9]],
) -> Option<Gap> {
    let mut best: Option<Gap> = None;
    for g in &robot.geoms {
        if !bodies.contains(&g.body)
            || matches!(
                g.gtype,
                GeomType::Plane | GeomType::Hfield | GeomType::Sdf | GeomType::Other
            )
            || !crate::model::contact::takes_part(robot, g.id)
        {
            continue;
        }
        let Some(shape) = placed(robot, g.id, xpos, xmat) else { continue };
        for p in planes(robot, g.id, up, xmat) {
            let x = &xmat[p];
            let n = [x[2], x[5], x[8]];
            let low = shape.support([-n[0], -n[1], -n[2]]);
            let o = xpos[p];
            let h = dot(n, [low[0] - o[0], low[1] - o[1], low[2] - o[2]]);
            if best.as_ref().is_none_or(|b| h < b.height) {
                best = Some(Gap { geom: g.id, plane: p, height: h });
            }
        }
    }
    best
}

/// Geom `g` placed at the pose, for its support points.
fn placed(robot: &Robot, g: usize, xpos: &[[f64; 3]], xmat: &[[f64; 9]]) -> Option<Placed> {
    let geom = robot.geoms.get(g)?;
    let (&pos, &mat) = (xpos.get(g)?, xmat.get(g)?);
    let verts = if geom.gtype == GeomType::Mesh {
        mesh_world_vertices(robot, geom.mesh, pos, &mat)
    } else {
        Vec::new()
    };
    Some(Placed { gtype: geom.gtype, size: geom.size, pos, mat, verts })
}

/// Gravity along −z within this angle, degrees, for a model with no floor to be judged against
/// the plane z = 0 (the ground a training scene adds to a legged robot's MJCF file).
const IMPLIED_FLOOR_TILT: f64 = 1.0;

/// A model with no floor at all — no plane or height field anywhere, the robot file a training
/// scene adds the ground to, at z = 0 by convention — under gravity along −z: the robot
/// `bodies`' colliding geom whose lowest point lies lowest, with its height above z = 0 (m).
/// `None` when the model has a floor (judged against it), or gravity is not along −z.
fn implied_floor_gap(
    robot: &Robot,
    bodies: &[usize],
    up: V3,
    xpos: &[[f64; 3]],
    xmat: &[[f64; 9]],
) -> Option<(usize, f64)> {
    if up[2] < IMPLIED_FLOOR_TILT.to_radians().cos()
        || robot.geoms.iter().any(|g| matches!(g.gtype, GeomType::Plane | GeomType::Hfield))
    {
        return None;
    }
    let mut best: Option<(usize, f64)> = None;
    for g in &robot.geoms {
        if !bodies.contains(&g.body)
            || matches!(g.gtype, GeomType::Sdf | GeomType::Other)
            || !crate::model::contact::takes_part(robot, g.id)
        {
            continue;
        }
        let Some(shape) = placed(robot, g.id, xpos, xmat) else { continue };
        let z = shape.support([0.0, 0.0, -1.0])[2];
        if best.is_none_or(|b| z < b.1) {
            best = Some((g.id, z));
        }
    }
    best
}

/// A world geom other than a plane that the robot may stand on above the floor (a platform, a
/// stair step, a box of terrain): a colliding non-plane geom fixed to the world whose bounding
/// sphere reaches above the plane by more than `drop`.
fn raised_ground(
    robot: &Robot,
    plane: usize,
    drop: f64,
    xpos: &[[f64; 3]],
    xmat: &[[f64; 9]],
) -> bool {
    let rbound = robot.mj.geom_rbound();
    let x = &xmat[plane];
    let (n, o) = ([x[2], x[5], x[8]], xpos[plane]);
    robot.geoms.iter().any(|g| {
        robot.bodies.get(g.body).is_some_and(|b| b.weld == 0)
            && g.gtype != GeomType::Plane
            && crate::model::contact::takes_part(robot, g.id)
            && xpos
                .get(g.id)
                .zip(rbound.get(g.id))
                .is_some_and(|(p, r)| dot(n, [p[0] - o[0], p[1] - o[1], p[2] - o[2]]) + r > drop)
    })
}

/// Reports each floating-base robot that every start pose leaves more than `drop` m above its
/// floor plane (one finding, at the first keyframe or at the free joint), and each start pose
/// that sinks its lowest geom more than `sink` m into the plane without burying a geom whole
/// (`buried` lists the poses `keyframe-state` already reports as buried).
pub fn check(
    cx: &Context,
    starts: &[Start],
    buried: &[bool],
    drop: f64,
    sink: f64,
    out: &mut Vec<Finding>,
) {
    let robot = cx.robot;
    let g = robot.opt.gravity;
    let gn = dot(g, g).sqrt();
    if gn < 1e-9 {
        return;
    }
    let up = [-g[0] / gn, -g[1] / gn, -g[2] / gn];
    let speed = |h: f64| (2.0 * gn * h).sqrt();
    let gname = |g: usize| {
        let n = &robot.geoms[g].name;
        if n.is_empty() { format!("geom {}", robot.unnamed_geom(g)) } else { format!("geom `{n}`") }
    };
    let pname = |p: usize| {
        let n = &robot.geoms[p].name;
        if n.is_empty() { "the floor plane".to_string() } else { format!("the floor plane `{n}`") }
    };
    let m = &robot.mj;
    if let Some((root, bodies)) = main_robot(robot) {
        let Some(free) = robot.joints.iter().find(|j| j.body == root && j.jtype == JointType::Free)
        else {
            return;
        };
        let mut gaps = Vec::new();
        for (i, s) in starts.iter().enumerate() {
            let mut d = mujoco_rs::prelude::MjData::new(m);
            if let Some(k) = s.key {
                let _ = d.reset_keyframe(k);
            }
            d.forward();
            if let Some((g, z)) =
                implied_floor_gap(robot, &bodies, up, d.geom_xpos(), d.geom_xmat())
                && z < -sink
            {
                let msg = format!(
                    "{} puts the robot's lowest colliding geom, {}, {} m below z = 0: the file has no floor, and the scene a training setup adds puts the ground at z = 0",
                    s.label,
                    gname(g),
                    fmt_num(-z, 3)
                );
                let f = match s.key {
                    Some(k) => cx.at_attr(ElemKind::Key, k, &s.name, "qpos", msg),
                    None => cx.at_elem(ElemKind::Joint, free.id, &free.name, msg),
                };
                out.push(
                    f.label("below z = 0")
                        .note("a robot file without a floor is placed in a scene whose ground plane is z = 0 (the convention of legged-robot MJCF files and the frameworks that load them): reset to this state, the robot starts that deep in the ground, and MuJoCo's contact throws it out at the first step")
                        .help("raise the base's `pos` (or the free joint's height in a keyframe) until the lowest foot is at z = 0, or set the base height your training code starts from in a keyframe")
                        .subject(Subject::Joint(free.id))
                        .measured(-z, "m"),
                );
            }
            let Some(gp) = gap(robot, &bodies, up, d.geom_xpos(), d.geom_xmat()) else { continue };
            let raised = raised_ground(robot, gp.plane, drop, d.geom_xpos(), d.geom_xmat());
            if gp.height < -sink && !buried.get(i).copied().unwrap_or(false) {
                let msg = format!(
                    "{} sinks the robot's lowest colliding geom, {}, {} m into {}",
                    s.label,
                    gname(gp.geom),
                    fmt_num(-gp.height, 3),
                    pname(gp.plane)
                );
                let f = match s.key {
                    Some(k) => cx.at_attr(ElemKind::Key, k, &s.name, "qpos", msg),
                    None => cx.at_elem(ElemKind::Joint, free.id, &free.name, msg),
                };
                out.push(
                    f.label("into the floor")
                        .note("MuJoCo's contact pushes the geom out of the plane at the first step with the force of that depth: every reset to this state starts with the robot thrown up")
                        .help("raise the base until the lowest foot touches the floor (lift it by the depth)")
                        .subject(Subject::Joint(free.id))
                        .measured(-gp.height, "m"),
                );
            }
            gaps.push((i, gp, raised));
        }
        // A robot that any start pose stands on the floor (or may stand on raised ground) is placed.
        if gaps.is_empty() || gaps.iter().any(|(_, gp, raised)| gp.height <= drop || *raised) {
            return;
        }
        let (i, gp, _) = &gaps[0];
        let s = &starts[*i];
        let which = if starts.len() > 1 {
            format!("none of the {} keyframes stands the robot on the floor: ", starts.len())
        } else {
            String::new()
        };
        let msg = format!(
            "{which}{} starts the robot's lowest colliding geom, {}, {} m above {}: every reset drops the robot (base `{}`) that height, landing at {} m/s",
            s.label,
            gname(gp.geom),
            fmt_num(gp.height, 3),
            pname(gp.plane),
            robot.bodies[root].name,
            fmt_num(speed(gp.height), 2)
        );
        let f = match s.key {
            Some(k) => cx.at_attr(ElemKind::Key, k, &s.name, "qpos", msg),
            None => cx.at_elem(ElemKind::Joint, free.id, &free.name, msg),
        };
        out.push(
            f.label("above the floor")
                .note("the robot falls at every reset and lands on its feet (or not) at the impact speed: episodes start with a fall the real robot never makes, and a controller's first steps are spent catching it")
                .help("add a keyframe (`<key name=\"home\" qpos=...>`) whose base height stands the feet on the floor, or lower the base's `pos` by the gap")
                .subject(Subject::Joint(free.id))
                .measured(gp.height, "m"),
        );
    }
}
