//! Which bodies are feet and which side they are on. Shared by the contact rules and
//! `collision-visual-mismatch`; left/right names mirror by [`crate::model::mirror`].
//!
//! Foot bodies come from the spec's `robot.foot_bodies` globs; without them, from body names
//! containing `foot`, `ankle_roll`, `toe` or `sole`; failing that, the leaf bodies whose
//! collision geoms reach within 3 cm of the robot's lowest collision point at the keyframe.
//! Each matched body that has no matched ancestor is a foot root; its descendants (and any
//! other matched body on the same side, e.g. a separately matched toe) are its toe bodies.
//!
//! Only a floating-base robot has feet (unless the spec names them): a fixed-base arm or a
//! test rig gets no foot rules. Each foot is classified by its ground geoms (the collision
//! geoms whose lowest point at the keyframe is within [`GROUND_WINDOW`] of the foot's lowest):
//! a **point foot** touches down through spheres whose lowest points lie within
//! [`POINT_SPREAD`] of each other (the quadruped's foot sphere; flat-foot rules do not apply); a
//! **wheel** touches down through a sphere, cylinder or ellipsoid on a body turned by an
//! unlimited hinge (no foot rules apply); anything else is a **flat foot**.

pub use crate::model::mirror::{Side, side_of};
use crate::model::{GeomType, Robot};
use crate::rules::geometry::shapes::Placed;
use crate::spec::Spec;

/// How far above the foot's lowest point a geom may reach and still touch the ground, m.
pub const GROUND_WINDOW: f64 = 0.01;
/// Largest horizontal spread of the contact points of a point foot, m.
pub const POINT_SPREAD: f64 = 0.02;

/// The robot family a foot belongs to, by how it touches the ground.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FootKind {
    /// A sole or a set of contacts that spans a support polygon (humanoids).
    Flat,
    /// One small contact region through spheres (point-foot quadrupeds).
    Point,
    /// A rolling wheel.
    Wheel,
}

#[derive(Debug, Clone)]
pub struct Foot {
    pub kind: FootKind,
    /// The collision geoms that touch the ground (within [`GROUND_WINDOW`] of the lowest).
    pub ground: Vec<usize>,
    pub side: Option<Side>,
    /// The foot body (subject of findings).
    pub root: usize,
    /// Toe bodies: the root's descendants and other matched bodies on the same side.
    pub toes: Vec<usize>,
    /// Collision geoms (non-plane) of the root and its toes.
    pub geoms: Vec<usize>,
}

impl Foot {
    pub fn is_toe_geom(&self, robot: &Robot, g: usize) -> bool {
        self.toes.contains(&robot.geoms[g].body)
    }
    pub fn label(&self, robot: &Robot) -> String {
        match self.side {
            Some(s) => format!("{} foot ({})", s.word(), robot.body_name(self.root)),
            None => format!("foot {}", robot.body_name(self.root)),
        }
    }
}

fn is_ancestor(robot: &Robot, anc: usize, mut b: usize) -> bool {
    while b != 0 {
        b = robot.bodies[b].parent;
        if b == anc {
            return true;
        }
    }
    false
}

fn contact_geoms(robot: &Robot, body: usize) -> impl Iterator<Item = usize> + '_ {
    robot
        .geoms
        .iter()
        .filter(move |g| {
            g.body == body
                && crate::model::contact::takes_part(robot, g.id)
                && !matches!(g.gtype, GeomType::Plane | GeomType::Hfield)
        })
        .map(|g| g.id)
}

/// The feet of the model, left before right.
pub fn feet(robot: &Robot, spec: Option<&Spec>) -> Vec<Foot> {
    let n = robot.bodies.len();
    let globs = spec.map(|s| s.foot_matchers()).unwrap_or_default();
    // A spec that sets `foot_bodies` (even to []) is authoritative.
    let from_spec = spec.is_some_and(|s| s.robot.foot_bodies.is_some());
    let mut matched: Vec<usize> = if from_spec {
        (1..n).filter(|&b| globs.iter().any(|m| m.is_match(robot.body_name(b)))).collect()
    } else {
        (1..n)
            .filter(|&b| {
                let l = robot.body_name(b).to_lowercase();
                ["foot", "ankle_roll", "toe", "sole"].iter().any(|k| l.contains(k))
            })
            .collect()
    };
    // Only a floating-base robot (a legged one) has feet to guess at: a fixed-base arm or a
    // test rig does not.
    let floating = robot.joints.iter().any(|j| j.jtype == crate::model::JointType::Free);
    if !floating && !from_spec {
        return Vec::new();
    }
    if matched.is_empty() && !from_spec && floating {
        // Leaf bodies whose collision geoms touch down.
        let lowest = |b: usize| {
            contact_geoms(robot, b)
                .map(|g| Placed::of(robot, g).lowest()[2])
                .fold(f64::INFINITY, f64::min)
        };
        let zmin = (1..n).map(lowest).fold(f64::INFINITY, f64::min);
        matched = (1..n)
            .filter(|&b| {
                !robot.bodies.iter().any(|c| c.id != 0 && c.parent == b) && lowest(b) <= zmin + 0.03
            })
            .collect();
    }
    let roots: Vec<usize> = matched
        .iter()
        .copied()
        .filter(|&b| !matched.iter().any(|&a| a != b && is_ancestor(robot, a, b)))
        .collect();
    let mut out: Vec<Foot> = Vec::new();
    for &root in &roots {
        let side = crate::model::mirror::mirror_in(robot.body_name(root), spec, |n| {
            robot.bodies.iter().any(|b| b.name == n)
        })
        .map(|(s, _)| s);
        let toes: Vec<usize> = (1..n).filter(|&b| is_ancestor(robot, root, b)).collect();
        // A second root on the same side (a separately matched toe) joins the first.
        if let Some(f) = out.iter_mut().find(|f| side.is_some() && f.side == side) {
            let toe_named = robot.body_name(root).to_lowercase().contains("toe");
            if toe_named {
                f.toes.push(root);
                f.toes.extend(toes);
                continue;
            }
        }
        out.push(Foot {
            kind: FootKind::Flat,
            ground: Vec::new(),
            side,
            root,
            toes,
            geoms: Vec::new(),
        });
    }
    for f in &mut out {
        let mut bodies = vec![f.root];
        bodies.extend(f.toes.iter().copied());
        f.geoms = bodies.iter().flat_map(|&b| contact_geoms(robot, b)).collect();
        f.geoms.sort();
        let low: Vec<(usize, [f64; 3])> =
            f.geoms.iter().map(|&g| (g, Placed::of(robot, g).lowest())).collect();
        let zmin = low.iter().map(|x| x.1[2]).fold(f64::INFINITY, f64::min);
        let ground: Vec<(usize, [f64; 3])> =
            low.into_iter().filter(|x| x.1[2] <= zmin + GROUND_WINDOW).collect();
        f.ground = ground.iter().map(|x| x.0).collect();
        let spread = ground
            .iter()
            .flat_map(|a| ground.iter().map(move |b| (a.1[0] - b.1[0]).hypot(a.1[1] - b.1[1])))
            .fold(0.0, f64::max);
        let wheel = ground.iter().any(|&(g, _)| {
            let geom = &robot.geoms[g];
            matches!(geom.gtype, GeomType::Sphere | GeomType::Cylinder | GeomType::Ellipsoid)
                && robot.joints.iter().any(|j| {
                    j.body == geom.body && j.jtype == crate::model::JointType::Hinge && !j.limited
                })
        });
        let spheres = !ground.is_empty()
            && ground.iter().all(|&(g, _)| robot.geoms[g].gtype == GeomType::Sphere);
        f.kind = if wheel {
            FootKind::Wheel
        } else if spheres && spread <= POINT_SPREAD {
            FootKind::Point
        } else {
            FootKind::Flat
        };
    }
    out.retain(|f| !f.geoms.is_empty());
    out.sort_by_key(|f| (f.side.map(|s| s as u8).unwrap_or(2), f.root));
    out
}
