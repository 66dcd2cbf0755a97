//! The model a stance run simulates. A robot with a free joint stands as it is on the model's
//! floor, or on a copy with a floor added when the model has none (a robot file). A legged URDF
//! (MuJoCo's importer welds its root link to the world) and a base of three slides and a ball
//! stand on a floated copy ([`crate::model::floated`]): a free joint on the root link, or in
//! place of the base's four joints at the same pose, and a floor plane under the robot's lowest
//! point when the model has none. The run's results are read back into the model's ids, and its
//! figures say what the copy added ([`super::stance::Floated`]).

use std::collections::BTreeMap;

use super::stance::Floated;
use crate::lint::Loaded;
use crate::model::floated::{Float, FloatedCopy, floated_copy};
use crate::model::{GeomType, JointType, Robot};

/// What a stance run simulates.
pub enum StanceModel {
    /// The model itself (it has a free joint, or nothing to float).
    Own,
    /// The floated copy.
    Copy(Box<FloatedCopy>),
    /// No copy could be built: why.
    Failed(String),
}

/// How the model's base must be floated for a stance run, if at all: a robot with a free
/// joint stands as it is when the model has a floor, and on a copy with a floor added when not.
pub fn needs_float(robot: &Robot) -> Option<Float> {
    if let Some(free) = robot.joints.iter().find(|j| j.jtype == JointType::Free) {
        let floor = (0..robot.geoms.len()).any(|g| super::stance::is_ground(robot, g));
        return (!floor).then_some(Float::FloorOnly(free.body));
    }
    if crate::rules::contact::welded_legged_base::is_welded_legged(robot) {
        let root = crate::rules::contact::welded_legged_base::root_link(robot)?;
        return Some(Float::RootLink(root.get("name").unwrap_or("").to_string()));
    }
    robot.floating_bodies().first().map(|&b| Float::SlideBall(b))
}

/// The lowest point of the robot's colliding geoms at the keyframe (planes and height fields
/// are floors, not robot), m.
fn lowest_point(robot: &Robot) -> f64 {
    let z = robot
        .geoms
        .iter()
        .filter(|g| crate::model::contact::takes_part(robot, g.id))
        .filter(|g| !matches!(g.gtype, GeomType::Plane | GeomType::Hfield))
        .map(|g| crate::rules::geometry::shapes::Placed::of(robot, g.id).lowest()[2])
        .fold(f64::INFINITY, f64::min);
    if z.is_finite() { z } else { 0.0 }
}

/// The model the stance runs on `l` simulate: built by the first run that asks (`stance-settle`
/// or `foot-slide`, which may run at once: the second waits) and shared by every later one of
/// the lint. Each run makes its own `MjData`, so sharing the model shares no state.
pub fn stance_model(l: &Loaded) -> &StanceModel {
    l.stance.get_or_init(|| build(l))
}

/// The model a stance run on `l` simulates, built afresh.
fn build(l: &Loaded) -> StanceModel {
    let robot = &l.robot;
    let Some(how) = needs_float(robot) else { return StanceModel::Own };
    // A URDF's world geoms are its root link's, never a floor.
    let has_floor = matches!(how, Float::SlideBall(_))
        && (0..robot.geoms.len()).any(|g| super::stance::is_ground(robot, g));
    // (Float::FloorOnly: chosen only when the model has no floor.)
    let floor = (!has_floor).then(|| lowest_point(robot));
    match floated_copy(robot, &l.sources, &how, floor) {
        Ok(c) => StanceModel::Copy(Box::new(c)),
        Err(e) => StanceModel::Failed(e),
    }
}

impl StanceModel {
    /// What the stance figures record about the model run.
    pub fn floated(&self) -> Option<Floated> {
        match self {
            StanceModel::Own => None,
            StanceModel::Copy(c) => {
                Some(Floated::Copy { base: c.base_name.clone(), floor_z: c.floor_z, held: c.held })
            }
            StanceModel::Failed(e) => Some(Floated::Failed(e.clone())),
        }
    }
}

/// `per` keyed by the copy's ids, keyed by the model's (`map`: copy id → model id; an id with
/// no counterpart is dropped).
pub fn remap<T>(per: BTreeMap<usize, T>, map: &[Option<usize>]) -> BTreeMap<usize, T> {
    per.into_iter().filter_map(|(k, v)| Some((map.get(k).copied().flatten()?, v))).collect()
}
