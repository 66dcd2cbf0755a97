//! A floated copy of a robot whose base cannot stand as the file writes it, for the stance
//! probes: a legged URDF (MuJoCo's importer welds its root link to the world) gets a free joint
//! on its root link; a base written as three slides and a ball gets one free joint in place of
//! those four, at the same pose. When the model has no floor, the copy gets a plane under the
//! lowest point of the robot: also a robot that floats as written (an MJCF robot file whose
//! floor is in the scene that includes it), which gets nothing else. The copy is re-parsed from the file with MuJoCo's own parser
//! (mjSpec) and compiled like the model; the probes read their results back into the model's
//! body, geom and joint ids through the maps below.

use mujoco_rs::prelude::*;

use super::source::SourceMap;
use super::{JointType, Robot, extract::extract, key_state, mj};

/// How the copy floats the base.
#[derive(Debug, Clone, PartialEq)]
pub enum Float {
    /// A free joint added on the URDF's root link (named).
    RootLink(String),
    /// The base body's slide and ball joints replaced by one free joint (body id in the model).
    SlideBall(usize),
    /// Nothing to float: the robot has a free joint at body (id in the model), and the copy only
    /// adds the floor it lacks (a robot file whose scene is another file).
    FloorOnly(usize),
}

/// The copy and how its ids map back to the model's.
pub struct FloatedCopy {
    pub robot: Robot,
    /// Name of the body that carries the added free joint (`None`: the robot floats as
    /// written, [`Float::FloorOnly`]).
    pub base_name: Option<String>,
    /// Height of the floor plane the copy added, m (`None`: the model has its own floor).
    pub floor_z: Option<f64>,
    /// Joints the copy holds at qpos0 by an added joint equality (a URDF's, which has no
    /// actuators in MuJoCo).
    pub held: usize,
    /// The copy's body id → the model's (the URDF root link → 0, the world it was fused into).
    pub body_map: Vec<Option<usize>>,
    /// The copy's geom id → the model's (`None` for the added floor).
    pub geom_map: Vec<Option<usize>>,
    /// The copy's joint id → the model's (`None` for the added free joint).
    pub joint_map: Vec<Option<usize>>,
}

/// Name of the floor geom the copy adds.
pub const FLOOR_NAME: &str = "modellint_added_floor";

/// Builds the floated copy of `robot` (parsed again from its file, `sources` holding it), with a
/// floor plane at `floor_z` when given. The error says why no copy could be built.
pub fn floated_copy(
    robot: &Robot,
    sources: &SourceMap,
    how: &Float,
    floor_z: Option<f64>,
) -> Result<FloatedCopy, String> {
    let file = robot.tree.loc.file;
    let resolved = if robot.format == super::Format::Urdf {
        super::urdf_packages::resolved_copy(sources, file).map_err(|e| e.to_string())?
    } else {
        None
    };
    let path = resolved.clone().unwrap_or_else(|| robot.path.clone());
    let spec = MjSpec::from_xml(&path).map_err(|e| format!("MuJoCo could not parse it: {e}"));
    if let Some(t) = &resolved {
        let _ = std::fs::remove_file(t);
    }
    let mut spec = spec?;
    let base_name = match how {
        Float::RootLink(name) => {
            let body = spec.body_mut(name).ok_or_else(|| {
                format!("the root link `{name}` is not a body of the parsed model")
            })?;
            body.add_free_joint();
            name.clone()
        }
        Float::SlideBall(b) => {
            let name = robot.body_name(*b).to_string();
            if name.is_empty() {
                return Err("the base body has no name, so the copy cannot find it in MuJoCo's parse of the file".into());
            }
            let body = spec
                .body_mut(&name)
                .ok_or_else(|| format!("no body `{name}` in the parsed model"))?;
            mj::replace_joints_by_free(body)?;
            name
        }
        Float::FloorOnly(b) => robot.body_name(*b).to_string(),
    };
    // A URDF has no actuators in MuJoCo: nothing would hold the pose a driven robot holds with
    // its position targets, so the copy holds each hinge and slide at qpos0.
    let mut held = 0;
    if robot.format == super::Format::Urdf && robot.actuators.is_empty() {
        for j in robot.joints.iter().filter(|j| j.is_scalar() && !j.name.is_empty()) {
            mj::hold_joint(&mut spec, &j.name);
            held += 1;
        }
    }
    if let Some(z) = floor_z {
        mj::add_floor(spec.world_body_mut(), FLOOR_NAME, z, contact_bits(robot));
    } else if matches!(how, Float::FloorOnly(_)) {
        return Err("the robot floats and the model has a floor: nothing to add".into());
    }
    let m = spec.compile().map_err(|e| format!("MuJoCo could not compile it: {e}"))?;
    let mut copy = extract(&robot.path, robot.format, robot.tree.clone(), robot.src.clone(), m);
    let body_map = map_bodies(robot, &copy, &base_name, how)?;
    let geom_map = map_geoms(robot, &copy, &body_map)?;
    let joint_map = map_joints(robot, &copy, how, &base_name)?;
    let key = robot.key.key;
    if let (Float::SlideBall(b), Some(k)) = (how, key) {
        // The free joint's keyframe pose is the base body's world pose at the model's keyframe.
        let free = copy.joints.iter().find(|j| j.jtype == JointType::Free).map(|j| j.qposadr);
        let pose = mj::body_pose_at_key(&robot.mj, k, *b);
        if let (Some(adr), Some(pose)) = (free, pose) {
            mj::set_key_qpos(&mut copy.mj, k, adr, &pose);
        }
    }
    copy.key = key_state(&copy.mj, key, &copy.keys);
    let base_name = (!matches!(how, Float::FloorOnly(_))).then_some(base_name);
    Ok(FloatedCopy { robot: copy, base_name, floor_z, held, body_map, geom_map, joint_map })
}

/// The contact bits an added floor needs to touch every geom of the robot that collides.
fn contact_bits(robot: &Robot) -> i32 {
    robot.geoms.iter().filter(|g| g.collides()).fold(0, |acc, g| acc | g.contype | g.conaffinity)
}

fn map_bodies(
    robot: &Robot,
    copy: &Robot,
    base: &str,
    how: &Float,
) -> Result<Vec<Option<usize>>, String> {
    let mut out = Vec::with_capacity(copy.bodies.len());
    for (i, b) in copy.bodies.iter().enumerate() {
        let to = if i == 0 || (matches!(how, Float::RootLink(_)) && b.name == base) {
            Some(0)
        } else if !b.name.is_empty() {
            robot.bodies.iter().find(|x| x.name == b.name).map(|x| x.id)
        } else if copy.bodies.len() == robot.bodies.len() {
            Some(i)
        } else {
            None
        };
        if to.is_none() {
            return Err(format!("the copy's body {i} `{}` is not one of the model's", b.name));
        }
        out.push(to);
    }
    Ok(out)
}

fn map_geoms(
    robot: &Robot,
    copy: &Robot,
    bodies: &[Option<usize>],
) -> Result<Vec<Option<usize>>, String> {
    let mut out = vec![None; copy.geoms.len()];
    let mut next = 0usize;
    for g in &copy.geoms {
        if g.name == FLOOR_NAME {
            continue;
        }
        let o = robot.geoms.get(next).ok_or("the copy has more geoms than the model")?;
        let same = o.gtype == g.gtype
            && bodies.get(g.body).copied().flatten() == Some(o.body)
            && o.size.iter().zip(g.size).all(|(a, b)| (a - b).abs() <= 1e-9 * (1.0 + a.abs()));
        if !same {
            return Err(format!("the copy's geom {} does not match the model's geom {next}", g.id));
        }
        out[g.id] = Some(next);
        next += 1;
    }
    if next != robot.geoms.len() {
        return Err("the copy has fewer geoms than the model".into());
    }
    Ok(out)
}

fn map_joints(
    robot: &Robot,
    copy: &Robot,
    how: &Float,
    base: &str,
) -> Result<Vec<Option<usize>>, String> {
    let added = |j: &super::Joint| {
        j.jtype == JointType::Free
            && copy.body_name(j.body) == base
            && !matches!(how, Float::FloorOnly(_))
    };
    let kept: Vec<usize> = robot
        .joints
        .iter()
        .filter(|j| !matches!(how, Float::SlideBall(b) if j.body == *b))
        .map(|j| j.id)
        .collect();
    let mut out = vec![None; copy.joints.len()];
    let mut it = kept.iter();
    for j in copy.joints.iter().filter(|j| !added(j)) {
        let o = it.next().ok_or("the copy has more joints than the model")?;
        if robot.joints[*o].jtype != j.jtype || robot.joints[*o].name != j.name {
            return Err(format!("the copy's joint `{}` does not match the model's", j.name));
        }
        out[j.id] = Some(*o);
    }
    if it.next().is_some() {
        return Err("the copy has fewer joints than the model".into());
    }
    Ok(out)
}
