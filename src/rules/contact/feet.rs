//! Which bodies are feet, which side they are on, and how left/right names mirror. Shared by
//! the contact rules and `mirror-asymmetry`.
//!
//! Foot bodies come from the spec's `robot.foot_bodies` globs; without them, from body names
//! containing `foot`, `ankle_roll`, `toe` or `sole`; failing that, the leaf bodies whose
//! collision geoms reach within 3 cm of the robot's lowest collision point at the keyframe.
//! Each matched body that has no matched ancestor is a foot root; its descendants (and any
//! other matched body on the same side, e.g. a separately matched toe) are its toe bodies.

use crate::model::{GeomType, Robot};
use crate::rules::geometry::shapes::Placed;
use crate::spec::Spec;

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Side {
    Left,
    Right,
}

impl Side {
    pub fn word(self) -> &'static str {
        match self {
            Side::Left => "left",
            Side::Right => "right",
        }
    }
}

/// Left/right marker pairs to try, the spec's first.
pub fn markers(spec: Option<&Spec>) -> Vec<(String, String)> {
    let mut v = Vec::new();
    if let Some(s) = spec {
        if let (Some(l), Some(r)) = (&s.robot.left, &s.robot.right) {
            v.push((l.clone(), r.clone()));
        }
    }
    for (l, r) in LEG_PREFIXES {
        v.push((l.to_string(), r.to_string()));
    }
    for (l, r) in [
        ("left_", "right_"),
        ("Left_", "Right_"),
        ("_left", "_right"),
        ("_Left", "_Right"),
        ("l_", "r_"),
        ("L_", "R_"),
        ("_l", "_r"),
        ("_L", "_R"),
        ("Left", "Right"),
        ("left", "right"),
    ] {
        v.push((l.to_string(), r.to_string()));
    }
    v
}

/// Quadruped leg prefixes: front/rear (or fore/hind) left ↔ right. Only ever a name's prefix.
const LEG_PREFIXES: [(&str, &str); 8] = [
    ("FL_", "FR_"),
    ("RL_", "RR_"),
    ("fl_", "fr_"),
    ("rl_", "rr_"),
    ("LF_", "RF_"),
    ("LH_", "RH_"),
    ("lf_", "rf_"),
    ("lh_", "rh_"),
];

/// Replace one marker occurrence: short markers (`l_`, `_l`) only as a prefix / suffix.
fn swap(name: &str, from: &str, to: &str) -> Option<String> {
    if LEG_PREFIXES.iter().any(|(l, r)| *l == from || *r == from) {
        return name.starts_with(from).then(|| format!("{to}{}", &name[from.len()..]));
    }
    let short = from.trim_matches('_').len() <= 1;
    if short {
        if from.ends_with('_') && name.starts_with(from) {
            return Some(format!("{to}{}", &name[from.len()..]));
        }
        if from.starts_with('_') && name.ends_with(from) {
            return Some(format!("{}{to}", &name[..name.len() - from.len()]));
        }
        return None;
    }
    name.contains(from).then(|| name.replacen(from, to, 1))
}

/// Side of a name and its mirrored counterpart, by the first marker pair that applies.
pub fn mirror(name: &str, spec: Option<&Spec>) -> Option<(Side, String)> {
    for (l, r) in markers(spec) {
        if let Some(m) = swap(name, &l, &r) {
            return Some((Side::Left, m));
        }
        if let Some(m) = swap(name, &r, &l) {
            return Some((Side::Right, m));
        }
    }
    None
}

pub fn side_of(name: &str, spec: Option<&Spec>) -> Option<Side> {
    mirror(name, spec).map(|(s, _)| s)
}

#[derive(Debug, Clone)]
pub struct Foot {
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
            g.body == body && g.collides() && !matches!(g.gtype, GeomType::Plane | GeomType::Hfield)
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
        let side = side_of(robot.body_name(root), spec);
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
        out.push(Foot { side, root, toes, geoms: Vec::new() });
    }
    for f in &mut out {
        let mut bodies = vec![f.root];
        bodies.extend(f.toes.iter().copied());
        f.geoms = bodies.iter().flat_map(|&b| contact_geoms(robot, b)).collect();
        f.geoms.sort();
    }
    out.retain(|f| !f.geoms.is_empty());
    out.sort_by_key(|f| (f.side.map(|s| s as u8).unwrap_or(2), f.root));
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn mirror_names() {
        assert_eq!(mirror("left_knee", None), Some((Side::Left, "right_knee".into())));
        assert_eq!(mirror("Hip_Pitch_Right", None), Some((Side::Right, "Hip_Pitch_Left".into())));
        assert_eq!(mirror("l_ankle", None), Some((Side::Left, "r_ankle".into())));
        assert_eq!(mirror("ankle_r", None), Some((Side::Right, "ankle_l".into())));
        assert_eq!(mirror("torso", None), None);
        assert_eq!(mirror("wheel_rl", None), None);
        assert_eq!(mirror("FL_calf", None), Some((Side::Left, "FR_calf".into())));
        assert_eq!(mirror("RR_hip", None), Some((Side::Right, "RL_hip".into())));
        assert_eq!(mirror("LH_KFE", None), Some((Side::Left, "RH_KFE".into())));
        assert_eq!(mirror("HALF_link", None), None);
    }
}
