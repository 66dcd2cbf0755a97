//! What the stance probes (`stance-settle`, `foot-slide`) share: the ground the robot stands on,
//! the robot's weight and base at the keyframe before a run, and the stance preconditions every
//! verdict of theirs records (a floor, a finite run, a free base, the feet loaded, the base
//! upright), each probe saying in its own words when it measured them.

use crate::model::{GeomType, JointType, Robot};
use crate::rules::control::non_earth_gravity as gravity;

/// Smallest share of the robot's weight the floor must carry for a stance verdict.
pub const MIN_SUPPORT: f64 = 0.5;
/// Largest base tilt (degrees from the keyframe) of a robot that still counts as upright.
pub const MAX_TILT_DEG: f64 = 30.0;
/// Largest base drop, as a fraction of the base's keyframe height, of an upright robot (at
/// least [`MIN_DROP_ALLOWED`]: a small model settling onto its feet drops a few centimetres).
pub const MAX_DROP: f64 = 0.5;
/// The drop any robot may show while settling, m.
pub const MIN_DROP_ALLOWED: f64 = 0.1;

/// A geom the robot can stand on, taking part in contacts (by its masks, or named by an
/// explicit `<contact><pair>`): a plane or height field on the world body or on a body welded
/// to it (a scene's `<body name="floor">` with no joint: MuJoCo allows these types only on
/// static bodies), or a box on the world body.
pub fn is_ground(robot: &Robot, g: usize) -> bool {
    robot.geoms.get(g).is_some_and(|x| {
        let on_static = robot.bodies.get(x.body).is_some_and(|b| b.weld == 0);
        crate::model::contact::takes_part(robot, g)
            && match x.gtype {
                GeomType::Plane | GeomType::Hfield => on_static,
                GeomType::Box => x.body == 0,
                _ => false,
            }
    })
}

/// Each geom's body for the stance runs, with the bodies welded to the world (a static floor
/// body) as the world (0): their contacts are the ground's, not the robot's.
pub fn ground_side_bodies(robot: &Robot, geom_body: &[i32]) -> Vec<i32> {
    geom_body
        .iter()
        .map(
            |&b| {
                if robot.bodies.get(b.max(0) as usize).is_some_and(|x| x.weld == 0) { 0 } else { b }
            },
        )
        .collect()
}

/// What a stance run knows before it steps.
#[derive(Debug, Clone)]
pub struct Start {
    /// The world body has a geom to stand on ([`is_ground`]).
    pub floor: bool,
    /// The robot has a free joint.
    pub free_base: bool,
    /// With no free joint, the base floats on coordinates of its own (three slides and a ball:
    /// [`Robot::floating_bodies`]), which the stance runs do not read.
    pub base_coordinates: bool,
    /// The robot's weight, N.
    pub weight: f64,
    /// Keyframe height of the (first) free joint's body, m; `None` without a free joint.
    pub base_z0: Option<f64>,
    /// The gravity MuJoCo applies (zero when disabled), m/s².
    pub gravity: [f64; 3],
    /// The floor's outward normal in the world frame (+z without a floor).
    pub floor_normal: [f64; 3],
    /// How many colliding geoms of the robot the keyframe places entirely under a floor plane
    /// they can touch, and the deepest one's depth (m): see [`buried`].
    pub buried: (usize, f64),
    /// Joints the keyframe places outside their range: see [`out_of_range`].
    pub out_of_range: OutOfRange,
}

impl Start {
    /// The run's figures before it runs: floor, base, weight and keyframe height known, the
    /// measured ones zero.
    pub fn figures(&self) -> Figures {
        Figures {
            floated: None,
            floor: self.floor,
            free_base: self.free_base,
            base_coordinates: self.base_coordinates,
            weight: self.weight,
            base_height: self.base_z0.unwrap_or(0.0),
            gravity: self.gravity,
            floor_normal: self.floor_normal,
            buried: self.buried,
            out_of_range: self.out_of_range.clone(),
            ..Default::default()
        }
    }
}

pub fn start(robot: &Robot) -> Start {
    let g = gravity::effective_gravity(robot);
    let gmag = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
    let free = robot.joints.iter().find(|j| j.jtype == JointType::Free);
    Start {
        floor: (0..robot.geoms.len()).any(|g| is_ground(robot, g)),
        free_base: free.is_some(),
        base_coordinates: free.is_none() && !robot.floating_bodies().is_empty(),
        weight: robot.bodies.iter().map(|b| b.mass).sum::<f64>() * gmag,
        base_z0: free.map(|j| robot.key.qpos.get(j.qposadr + 2).copied().unwrap_or(0.0)),
        gravity: g,
        floor_normal: gravity::floor(robot).map_or([0.0, 0.0, 1.0], |f| f.1),
        buried: buried(robot),
        out_of_range: out_of_range(robot),
    }
}

/// How far past its range a joint may start, as a share of the range: `keyframe-state`'s
/// default `tolerance` (a pose written to a few digits).
pub const RANGE_TOLERANCE: f64 = 0.02;

/// The limited hinges and slides the keyframe (or qpos0) places outside their range by more
/// than [`RANGE_TOLERANCE`] of it: how many, and the farthest one.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct OutOfRange {
    /// The pose the run starts from, as the detail names it: "the keyframe" or "the default
    /// pose qpos0 (no keyframe)" (`keyframe-state`'s words).
    pub pose: &'static str,
    pub count: usize,
    /// The farthest joint: name, position, range, distance past it (rad or m).
    pub worst: Option<(String, f64, [f64; 2], f64)>,
}

/// `keyframe-state`'s range test on the pose a stance run starts from: the joint-limit
/// constraints throw such joints back at the first step, so the robot does not stand in the
/// pose the run means to judge (a URDF copy holds them there against their stops).
pub fn out_of_range(robot: &Robot) -> OutOfRange {
    let pose = if robot.key.key.is_some() {
        "the keyframe"
    } else {
        "the default pose qpos0 (no keyframe)"
    };
    let mut r = OutOfRange { pose, ..OutOfRange::default() };
    for j in &robot.joints {
        if !j.limited || !matches!(j.jtype, JointType::Hinge | JointType::Slide) {
            continue;
        }
        let Some(&x) = robot.key.qpos.get(j.qposadr) else { continue };
        let past = (j.range[0] - x).max(x - j.range[1]);
        if past <= RANGE_TOLERANCE * (j.range[1] - j.range[0]).abs() {
            continue;
        }
        r.count += 1;
        if r.worst.as_ref().is_none_or(|w| past > w.3) {
            r.worst = Some((j.name.clone(), x, j.range, past));
        }
    }
    r
}

/// The colliding geoms of bodies not fixed to the world that the keyframe (the pose a stance
/// run starts from) places entirely under a floor plane they can touch — their bounding
/// sphere below the plane's surface, `keyframe-state`'s test —: how many, and the deepest
/// one's depth (m). MuJoCo's plane is a half-space: a robot started inside it is pushed out
/// or falls through, and stands on nothing either way.
pub fn buried(robot: &Robot) -> (usize, f64) {
    let (xpos, xmat) = (&robot.key.geom_xpos, &robot.key.geom_xmat);
    let buried = crate::model::contact::buried_under_planes(robot, xpos, xmat);
    (buried.len(), buried.iter().map(|b| b.2).fold(0.0, f64::max))
}

/// The largest drop of a base at keyframe height `base_height` that still counts as upright, m.
pub fn max_drop(base_height: f64) -> f64 {
    (MAX_DROP * base_height).max(MIN_DROP_ALLOWED)
}

/// What a stance run did to a model whose base cannot stand as written ([`super::float`]).
#[derive(Debug, Clone, PartialEq)]
pub enum Floated {
    /// It ran on a floated copy: a free joint added at body `base` (`None`: the robot floats
    /// as written), a floor plane at `floor_z` (m) when the model has none, and `held` joints
    /// (a URDF's, which has no actuators in MuJoCo) held at qpos0 by added joint equalities.
    Copy { base: Option<String>, floor_z: Option<f64>, held: usize },
    /// No floated copy could be built (why): it ran on the model as written.
    Failed(String),
}

/// The figures of one run that the stance preconditions judge, held by every stance probe's
/// output (`Settle::stance`, `Slide::stance`).
#[derive(Debug, Clone, Default)]
pub struct Figures {
    /// The run was on a floated copy, or no copy could be built.
    pub floated: Option<Floated>,
    /// The world body has a colliding plane, height field or box.
    pub floor: bool,
    /// The run did not stay finite.
    pub diverged: bool,
    /// The robot has a free joint.
    pub free_base: bool,
    /// See [`Start::base_coordinates`].
    pub base_coordinates: bool,
    /// The robot's weight, N.
    pub weight: f64,
    /// Mean total normal force of the robot's contacts with world geoms while loaded, N.
    pub support_load: f64,
    /// Tilt of the base from its keyframe orientation when judged, degrees.
    pub base_tilt_deg: f64,
    /// Keyframe base height minus the judged one, m (positive: the base fell).
    pub base_drop: f64,
    /// Keyframe height of the base, m.
    pub base_height: f64,
    /// The gravity the run applies, m/s².
    pub gravity: [f64; 3],
    /// The floor's outward normal in the world frame.
    pub floor_normal: [f64; 3],
    /// Colliding robot geoms the keyframe places under the floor, and the deepest depth (m).
    pub buried: (usize, f64),
    /// Joints the keyframe places outside their range.
    pub out_of_range: OutOfRange,
}

/// How a probe words its preconditions: the run's finite / diverged sentences, why a fixed base
/// fails it, when the load was measured ("after 1 s standing") and when the base was judged
/// upright ("" or "after the push ").
pub struct Words {
    pub finite: &'static str,
    pub diverged: &'static str,
    pub fixed_base: &'static str,
    pub loaded_when: &'static str,
    pub upright_when: &'static str,
}

/// Why a stance run does not test a base written as three slides and a ball: it floats, but the
/// runs place, push and read a free joint's base only.
const BASE_COORDINATES: &str = "the base floats on slides and a ball, which the stance runs do not read (they need a free joint)";

/// The stance preconditions of a run, in order: floor, gravity, above_floor, in_range,
/// settled, free_base, feet_loaded, upright.
pub fn preconditions(f: &Figures, w: &Words) -> super::Preconditions {
    let share = if f.weight > 0.0 { f.support_load / f.weight } else { 0.0 };
    let max_drop = max_drop(f.base_height);
    let n = crate::util::fmt_num;
    let off = gravity::off_earth(f.gravity, f.floor_normal);
    let g = f.gravity;
    let gmag = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
    let gravity_detail = match &off {
        None => format!("gravity is Earth's: {} m/s² towards the floor", n(gmag, 4)),
        Some(s) => format!(
            "{s}, not Earth's ({}–{} m/s² towards the floor): nothing pulls the robot onto its feet, so standing does not load them",
            n(gravity::EARTH_G_MIN, 3),
            n(gravity::EARTH_G_MAX, 3)
        ),
    };
    super::Preconditions::new()
        .check(
            "floor",
            f.floor,
            if let Some(Floated::Copy { floor_z: Some(z), base, .. }) = &f.floated {
                format!(
                    "the model has no floor: the {} has a plane added at z = {} m, under the robot's lowest point",
                    if base.is_some() { "floated copy" } else { "copy" },
                    n(*z, 4)
                )
            } else if f.floor {
                "the model has a floor".to_string()
            } else {
                "the model has no floor (no colliding plane or height field on the world or a static body, nor box on the world body): lint the scene that includes the robot".to_string()
            },
        )
        .check("gravity", off.is_none(), gravity_detail)
        .check(
            "above_floor",
            f.buried.0 == 0,
            if f.buried.0 == 0 {
                format!(
                    "{} places no colliding geom of the robot under the floor",
                    start_pose(&f.out_of_range)
                )
            } else {
                format!(
                    "{} places {} colliding geom{} of the robot entirely under the floor (the deepest {} m below its surface, `keyframe-state`): the robot starts inside the floor and stands on nothing",
                    start_pose(&f.out_of_range),
                    f.buried.0,
                    if f.buried.0 == 1 { "" } else { "s" },
                    n(f.buried.1, 3)
                )
            },
        )
        .check("in_range", f.out_of_range.count == 0, in_range_detail(&f.out_of_range))
        .check("settled", !f.diverged, if f.diverged { w.diverged } else { w.finite })
        .check(
            "free_base",
            f.free_base,
            match &f.floated {
                Some(Floated::Copy { base: Some(base), .. }) => {
                    format!("probed on a floated copy: free joint added at `{base}`")
                }
                Some(Floated::Copy { base: None, .. }) => "the base is free-floating".to_string(),
                Some(Floated::Failed(why)) => format!(
                    "{}; no floated copy could be built: {why}",
                    if f.base_coordinates { BASE_COORDINATES } else { w.fixed_base }
                ),
                None if f.free_base => "the base is free-floating".to_string(),
                None if f.base_coordinates => BASE_COORDINATES.to_string(),
                None => w.fixed_base.to_string(),
            },
        )
        .check(
            "feet_loaded",
            share >= MIN_SUPPORT,
            format!(
                "the floor carries {} % of the robot's weight {} (need ≥ {} %)",
                n(100.0 * share, 3),
                w.loaded_when,
                n(100.0 * MIN_SUPPORT, 3)
            ),
        )
        .check(
            "upright",
            f.base_tilt_deg <= MAX_TILT_DEG && f.base_drop <= max_drop,
            format!(
                "{}the base tilted {}° and dropped {} m (upright: ≤ {}°, ≤ {} m)",
                w.upright_when,
                n(f.base_tilt_deg, 3),
                n(f.base_drop, 3),
                n(MAX_TILT_DEG, 3),
                n(max_drop, 3)
            ),
        )
}

/// "probed on a floated copy: free joint added at `trunk`; floor added at z = -0.69 m" when the
/// run was on a floated copy, for a verdict's note ("probed on a copy with a floor added at z =
/// -0.69 m (the model has none)" when the robot floats as written).
pub fn copy_note(f: &Figures) -> Option<String> {
    let Some(Floated::Copy { base, floor_z, held }) = &f.floated else { return None };
    let Some(base) = base else {
        let z = (*floor_z)?;
        return Some(format!(
            "probed on a copy with a floor added at z = {} m (the model has none; lint the scene for its own floor)",
            crate::util::fmt_num(z, 4)
        ));
    };
    let floor = floor_z
        .map(|z| format!("; floor added at z = {} m", crate::util::fmt_num(z, 4)))
        .unwrap_or_default();
    let held = match held {
        0 => String::new(),
        n => format!("; its {n} joints held at qpos0 (the URDF has no actuators)"),
    };
    Some(format!("probed on a floated copy: free joint added at `{base}`{floor}{held}"))
}

/// `v` with [`copy_note`] appended to its note (and to an inconclusive verdict's reason).
pub fn tag_copy(mut v: super::Verdict, f: &Figures) -> super::Verdict {
    if let Some(c) = copy_note(f) {
        v.note = format!("{} ({c})", v.note);
        if let super::Status::Inconclusive(r) = &mut v.status {
            *r = format!("{r} ({c})");
        }
    }
    v
}

/// The height of the floor plane a floated copy added, m.
pub fn floor_added(f: &Figures) -> Option<f64> {
    match &f.floated {
        Some(Floated::Copy { floor_z, .. }) => *floor_z,
        _ => None,
    }
}

/// The pose a stance run starts from, in the preconditions' words ("the keyframe", "the default
/// pose qpos0 (no keyframe)"); "the keyframe" for figures made without a start.
fn start_pose(r: &OutOfRange) -> &'static str {
    if r.pose.is_empty() { "the keyframe" } else { r.pose }
}

/// The `in_range` precondition's detail.
fn in_range_detail(r: &OutOfRange) -> String {
    let n = crate::util::fmt_num;
    match &r.worst {
        None => format!("{} places every limited joint inside its range", start_pose(r)),
        Some((name, x, range, past)) => format!(
            "{} places {} joint{} outside {} range (`{name}` at {}, {} past [{}, {}], `keyframe-state`): the joint limits throw the robot out of the pose the run should stand in",
            start_pose(r),
            r.count,
            if r.count == 1 { "" } else { "s" },
            if r.count == 1 { "its" } else { "their" },
            n(*x, 4),
            n(*past, 3),
            n(range[0], 4),
            n(range[1], 4)
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The robot of `xml` (the replay tests' loader) and its temporary directory, removed.
    fn load_xml(tag: &str, xml: &str) -> Robot {
        let (robot, dir) = crate::sim2real::replay::tests::robot_from_xml(tag, xml);
        std::fs::remove_dir_all(dir).ok();
        robot
    }

    /// A knee limited to [0.2, 1.5] rad: qpos0 (0) lies 0.2 rad below it, 15 % of the range,
    /// beyond the 2 % tolerance; a keyframe at 0.6 rad lies inside.
    fn knee(key: &str) -> String {
        format!(
            r#"<mujoco><compiler angle="radian"/><worldbody>
            <geom type="plane" size="1 1 .1"/>
            <body pos="0 0 .5"><freejoint/><geom size=".05"/>
              <body><joint name="knee" axis="0 1 0" range="0.2 1.5"/><geom size=".03"/></body>
            </body></worldbody>{key}</mujoco>"#
        )
    }

    /// The detail names the pose the run starts from: qpos0 when the model has no keyframe.
    #[test]
    fn the_detail_names_the_default_pose_without_a_keyframe() {
        let r = out_of_range(&load_xml("stance-nokey", &knee("")));
        assert_eq!(r.count, 1, "{r:?}");
        let d = in_range_detail(&r);
        assert!(d.starts_with("the default pose qpos0 (no keyframe) places 1 joint"), "{d}");
        let key = r#"<keyframe><key name="stand" qpos="0 0 .5 1 0 0 0 0.6"/></keyframe>"#;
        let r = out_of_range(&load_xml("stance-key", &knee(key)));
        assert_eq!(r.count, 0, "{r:?}");
        let d = in_range_detail(&r);
        assert_eq!(d, "the keyframe places every limited joint inside its range");
    }

    /// `above_floor` names the same pose as `in_range`: qpos0 for a model without a keyframe,
    /// whether or not a geom starts under the floor.
    #[test]
    fn above_floor_names_the_start_pose() {
        let above = |r: &Robot| {
            let s = start(r);
            let p = preconditions(&s.figures(), &WORDS_FOR_TEST);
            p.list().iter().find(|p| p.name == "above_floor").map(|p| (p.met, p.detail.clone()))
        };
        let (met, d) = above(&load_xml("stance-above-nokey", &knee(""))).unwrap();
        assert!(met, "{d}");
        assert_eq!(
            d,
            "the default pose qpos0 (no keyframe) places no colliding geom of the robot under the floor"
        );
        // The base 0.4 m under the floor (its 5 cm sphere entirely below it).
        let key = r#"<keyframe><key name="stand" qpos="0 0 -.4 1 0 0 0 0.6"/></keyframe>"#;
        let (met, d) = above(&load_xml("stance-above-key", &knee(key))).unwrap();
        assert!(!met, "{d}");
        assert!(d.starts_with("the keyframe places 2 colliding geoms"), "{d}");
        let buried = knee("").replace(r#"<body pos="0 0 .5">"#, r#"<body pos="0 0 -.4">"#);
        let (met, d) = above(&load_xml("stance-above-buried", &buried)).unwrap();
        assert!(!met, "{d}");
        assert!(
            d.starts_with("the default pose qpos0 (no keyframe) places 2 colliding geoms"),
            "{d}"
        );
    }

    const WORDS_FOR_TEST: Words = Words {
        finite: "finite",
        diverged: "diverged",
        fixed_base: "fixed",
        loaded_when: "",
        upright_when: "",
    };
}
