use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::{Format, JointType, Robot};
use crate::rules::contact::feet::GROUND_WINDOW;
use crate::rules::geometry::shapes::Placed;
use crate::rules::{Context, Rule, RuleMeta};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// In a URDF with no floating joint, finds a kinematic tree that looks like legs: two or more
    /// chains, each leaving the root link (or a body every chain passes through that hangs from
    /// the root link by one joint: a waist, whose pelvis carries the legs) through a joint of its
    /// own, below the top quarter of that body's colliding height (an arm leaves a torso at its
    /// top: a humanoid upper body's hands hanging below the torso are no feet), and ending, two or more hinge/slide joints further out, in a leaf link (not a wheel;
    /// no link below it collides: a shank may carry an open linkage's rod) whose collision
    /// geometry reaches the robot's lowest point (within 1 cm) at qpos0 below the root link's
    /// frame or below the joint the chain leaves the root through (a root frame at the ground
    /// under the trunk, a ROS `base_footprint`: Darwin-OP's `base_link`, 0.35 m below the body
    /// it is fixed to, is not where the legs hang from), two
    /// of which swing side by side (each has a hinge whose axis lies within 45° of the line
    /// between the two feet, as hip pitch and knee axes do; a gripper's fingers close on each
    /// other about axes across that line, so a palm with two two-joint fingers below it is no
    /// robot with legs). A chain through a link named as a hand's digit (`finger`, `thumb`,
    /// `gripper`) is no leg: a manipulator's fingers hanging from a stage above its root link
    /// (TriFinger's three fingers, fixed 0.29 m up, their tips below the root's frame) stand
    /// like legs, and their tips are no feet.
    /// Says that MuJoCo's importer welded the root to the world and that the foot rules
    /// (`toe-tilt`, `foot-collision-geometry`, `links-without-collision`,
    /// `torsional-friction-length`, and the foot soles of `collision-visual-mismatch`) judged
    /// those feet as if the root link floated: they take it (the world body the importer fused
    /// it into, with every link welded to it) as the floating base, at its pose in the file. The
    /// stance probes run on a floated copy: a free joint on the root link, a floor plane under
    /// the lowest foot, every joint held at qpos0 (MuJoCo loads no actuator from a URDF), each
    /// said in the verdict (`docs/probes.md`). A
    /// fixed-base arm (its chain ends above its base, or in one chain of fingers) and a wheeled
    /// base (its lowest links are wheels) are not reported, and their links are never taken
    /// for feet.
    ///
    /// ## Why is this bad?
    /// MuJoCo's URDF importer adds no free joint: the root link is fixed where the file puts it,
    /// so a legged robot loaded from its URDF hangs from its trunk, its feet never carry its
    /// weight, and nothing a stance or walking run would show (feet sliding, sinking, tipping)
    /// happens. The static geometry of the feet is the same welded or floating (qpos0 is the
    /// file's pose either way), so the foot rules judge it; a simulation of the robot standing
    /// needs the robot floated above a floor, which a URDF cannot say.
    ///
    /// ## How it is confirmed
    /// Static: the compiled tree (no free joint, the chains and their joints) and the leaf
    /// links' collision geometry at qpos0. Information, not a defect of the file: a URDF cannot
    /// say its base floats.
    ///
    /// ## How to fix
    /// Nothing to fix in the URDF. To simulate the robot standing with its own actuators and
    /// floor (rather than the probes' floated copy): an MJCF wrapper that attaches the URDF under a body with a `<freejoint/>` above a floor (`<mujoco><asset><model
    /// name="robot" file="robot.urdf"/></asset><worldbody><geom type="plane" size="0 0
    /// 1"/><body pos="0 0 H"><freejoint/><attach model="robot" prefix=""/></body></worldbody></mujoco>`,
    /// H the standing height), and lint the wrapper.
    pub WeldedLeggedBase {
        id: "welded-legged-base",
        group: "contact",
        level: Severity::Info,
        probe: None,
        options: [],
    }
}

/// The leaves of `robot` that stand like feet (see the rule's docs), as (leaf, top-level link
/// of its chain), and how far below the root link's frame their lowest point is (m; negative
/// when the root frame lies at the ground below it). With
/// `wheel_legs`, a chain that ends in a wheel counts too when it has two or more other
/// hinge/slide joints above the wheel (a wheel-legged robot's hip and knee; a rover's steered
/// wheel has one).
/// The bodies from `b` up to the root link's child (the body hanging from the world), in order.
fn chain_up(robot: &Robot, b: usize) -> Vec<usize> {
    let mut path = vec![b];
    let mut x = b;
    for _ in 0..robot.bodies.len() {
        let p = robot.bodies[x].parent;
        if p == 0 {
            break;
        }
        path.push(p);
        x = p;
    }
    path
}

/// The hub the chains (leaf, [`chain_up`] path) leave: the body all of them pass through when
/// it is reached from the root link through one joint (a waist), else the root link (0).
fn waist_hub(robot: &Robot, chains: &[(usize, Vec<usize>)]) -> usize {
    let firsts: std::collections::BTreeSet<usize> =
        chains.iter().filter_map(|c| c.1.last().copied()).collect();
    match firsts.iter().next() {
        Some(&w)
            if firsts.len() == 1 && robot.joints.iter().filter(|j| j.body == w).count() == 1 =>
        {
            w
        }
        _ => 0,
    }
}

fn legs(robot: &Robot, wheel_legs: bool) -> (Vec<(usize, usize)>, f64) {
    let n = robot.bodies.len();
    let lowest_of = |b: usize| {
        robot
            .geoms
            .iter()
            .filter(|g| g.body == b && crate::model::contact::takes_part(robot, g.id))
            .filter(|g| {
                !matches!(g.gtype, crate::model::GeomType::Plane | crate::model::GeomType::Hfield)
            })
            .map(|g| Placed::of(robot, g.id).lowest()[2])
            .fold(f64::INFINITY, f64::min)
    };
    let lows: Vec<f64> = (0..n).map(lowest_of).collect();
    let zmin = lows.iter().copied().fold(f64::INFINITY, f64::min);
    // The root link's frame: the world origin, where the importer welds it.
    let root_z = robot.key.body_xpos.first().map_or(0.0, |p| p[2]);
    // Each foot-like leaf with its chain up to the world: the bodies from the leaf to the
    // root link's child, in order.
    let mut chains: Vec<(usize, Vec<usize>)> = Vec::new();
    for (b, &low) in lows.iter().enumerate().skip(1) {
        // A leaf of the colliding tree: no body below it collides (a shank may carry the rod
        // of an open knee linkage).
        if crate::rules::contact::feet::collides_below(robot, b) || low > zmin + GROUND_WINDOW {
            continue;
        }
        let path = chain_up(robot, b);
        // The leaf hangs below the root link's frame, or below the joint its chain leaves the
        // root through: a root frame at the ground under the trunk (a ROS `base_footprint`,
        // Darwin-OP's `base_link` 0.35 m below the body it is fixed to) is not where the
        // legs hang from.
        let top = path.last().copied().unwrap_or(b);
        let hip_z = robot
            .joints
            .iter()
            .filter(|j| j.body == top)
            .filter_map(|j| robot.key.joint_xanchor.get(j.id).map(|a| a[2]))
            .fold(f64::NEG_INFINITY, f64::max);
        if !(low < root_z || low < hip_z) {
            continue;
        }
        chains.push((b, path));
    }
    // The hub the legs leave: the root link, or a body reached from it through one joint (a
    // waist) when every chain passes through that body.
    let hub = waist_hub(robot, &chains);
    let height = hub_height(robot, hub);
    let mut out = Vec::new();
    for (leaf, path) in chains {
        let below: Vec<usize> = path.iter().copied().take_while(|&x| x != hub).collect();
        let Some(&top) = below.last() else { continue };
        // A hand's digit is no leg, however it hangs: a chain through a link named as one.
        if below.iter().any(|&b| is_digit_name(robot.body_name(b))) {
            continue;
        }
        // An arm hanging below the body: it leaves through the top of the body.
        if let (Some((lo, hi)), Some(exit)) = (height, exit_anchor(robot, top))
            && exit[2] > lo + ARM_EXIT_HEIGHT * (hi - lo)
        {
            continue;
        }
        let (mut joints, mut wheel) = (0usize, false);
        for j in robot.joints.iter().filter(|j| below.contains(&j.body)) {
            if robot.is_wheel(j.id) {
                wheel = true;
            } else if matches!(j.jtype, JointType::Hinge | JointType::Slide) {
                joints += 1;
            }
        }
        if joints >= 2 && (!wheel || wheel_legs) {
            out.push((leaf, top));
        }
    }
    (out, root_z - zmin)
}

/// Name parts of a hand's digits (any case): a link named with one is a finger, never a leg.
pub const DIGIT_NAME_PARTS: [&str; 3] = ["finger", "thumb", "gripper"];

/// Whether a link's name names a hand's digit ([`DIGIT_NAME_PARTS`]).
fn is_digit_name(name: &str) -> bool {
    let l = name.to_lowercase();
    DIGIT_NAME_PARTS.iter().any(|p| l.contains(p))
}

/// Whether two of the `legs` (as (leaf, top of chain)) swing side by side, as legs do: each
/// has a hinge whose axis at qpos0 lies nearer the line between the two leaves than across it
/// (within 45°). A biped's or quadruped's hip pitch and knee axes point from one leg to the
/// other (the legs swing fore and aft beside each other); a gripper's fingers close on each
/// other, about axes across the line between their tips, so two fingers of two joints each
/// hanging below a palm are no legs.
fn side_by_side(robot: &Robot, legs: &[(usize, usize)]) -> bool {
    let axes = |leaf: usize, top: usize| -> Vec<[f64; 3]> {
        let mut chain = vec![leaf];
        let mut b = leaf;
        while b != top && b != 0 {
            b = robot.bodies[b].parent;
            chain.push(b);
        }
        robot
            .joints
            .iter()
            .filter(|j| j.jtype == JointType::Hinge && chain.contains(&j.body))
            .filter(|j| !robot.is_wheel(j.id))
            .filter_map(|j| robot.key.joint_xaxis.get(j.id).copied())
            .collect()
    };
    let at = |b: usize| robot.key.body_xpos.get(b).copied().unwrap_or([0.0; 3]);
    let along = |axes: &[[f64; 3]], d: [f64; 3]| {
        axes.iter().any(|a| {
            let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
            n > 0.0
                && (a[0] * d[0] + a[1] * d[1] + a[2] * d[2]).abs() / n
                    >= std::f64::consts::FRAC_1_SQRT_2
        })
    };
    legs.iter().enumerate().any(|(i, &(la, ta))| {
        legs.iter().skip(i + 1).filter(|l| l.1 != ta).any(|&(lb, tb)| {
            let (pa, pb) = (at(la), at(lb));
            let d = [pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]];
            let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            if !(n > 1e-9) {
                return false;
            }
            let d = d.map(|x| x / n);
            along(&axes(la, ta), d) && along(&axes(lb, tb), d)
        })
    })
}

/// The legs of a URDF that MuJoCo's importer welded to the world (no free joint) and whose
/// tree is legs — two or more chains leaving the root, each ending in a foot-like leaf (see
/// the rule's docs) — as in [`legs`]; `None` for any other model (an MJCF, a floating URDF, a
/// fixed-base arm, a wheeled base).
fn welded_legs(robot: &Robot) -> Option<(Vec<(usize, usize)>, f64)> {
    if robot.format != Format::Urdf || robot.joints.iter().any(|j| j.jtype == JointType::Free) {
        return None;
    }
    let (legs, depth) = legs(robot, false);
    let mut tops: Vec<usize> = legs.iter().map(|l| l.1).collect();
    tops.sort_unstable();
    tops.dedup();
    (tops.len() >= 2 && side_by_side(robot, &legs)).then_some((legs, depth))
}

/// The legs of a URDF robot, wheel-legs included (a wheel at the end of a hip and a knee), as
/// the leaf of each; `None` unless two or more legs leave the root (or a one-joint waist) at
/// separate links: a fixed-base arm, a gripper's one chain of fingers, a wheeled base.
///
/// A robot whose pose at qpos0 hides its legs (Qmini's zero is each leg folded up behind its
/// hip, the feet above the hips) is told by its structure instead ([`legs_by_structure`]).
pub fn urdf_legs(robot: &Robot) -> Option<Vec<usize>> {
    if robot.format != Format::Urdf {
        return None;
    }
    let found = |legs: &[(usize, usize)]| {
        let mut tops: Vec<usize> = legs.iter().map(|l| l.1).collect();
        tops.sort_unstable();
        tops.dedup();
        (tops.len() >= 2 && side_by_side(robot, legs)).then(|| legs.iter().map(|l| l.0).collect())
    };
    found(&legs(robot, true).0).or_else(|| found(&legs_by_structure(robot)))
}

/// The hub's colliding height at qpos0: the lowest and highest points of its colliding geoms
/// (m); `None` when it has none.
fn hub_height(robot: &Robot, hub: usize) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for g in robot.geoms.iter().filter(|g| {
        g.body == hub
            && crate::model::contact::takes_part(robot, g.id)
            && !matches!(g.gtype, crate::model::GeomType::Plane | crate::model::GeomType::Hfield)
    }) {
        let p = Placed::of(robot, g.id);
        lo = lo.min(p.lowest()[2]);
        hi = hi.max(p.support([0.0, 0.0, 1.0])[2]);
    }
    (hi > lo).then_some((lo, hi))
}

/// Where a chain leaves the hub: the anchor of the joint on its first body, at qpos0.
fn exit_anchor(robot: &Robot, top: usize) -> Option<[f64; 3]> {
    let j = robot.joints.iter().find(|j| j.body == top)?;
    robot.key.joint_xanchor.get(j.id).copied()
}

/// The share of the hub's colliding height above which a chain leaves it as an arm, not a leg,
/// whatever its pose: shoulders sit at the top of a torso (a humanoid upper body's hands hang
/// below its torso at qpos0), hips low on a pelvis or at mid-height on a quadruped's trunk.
const ARM_EXIT_HEIGHT: f64 = 0.75;

/// The share of the hub's colliding height below which a chain must leave it to be a leg
/// told by structure: legs leave a body through its lower half (a biped's hips under the
/// pelvis, a quadruped's at the trunk's bottom), arms through its upper half (shoulders at the
/// top of a torso, a head's neck on it).
const LEG_EXIT_HEIGHT: f64 = 0.5;

/// Legs told by the tree's structure whatever the pose at qpos0: two or more chains from the
/// root link (or a one-joint waist every chain passes through, as in [`legs`]) to leaves of
/// the colliding tree (contact-capable ends), each with two or more hinge/slide joints and no
/// wheel, that leave the hub through a joint whose anchor lies in the lower half
/// ([`LEG_EXIT_HEIGHT`]) of the hub's colliding geometry, and are long enough, stretched
/// straight, to reach below the hub's lowest point. The positions are the root's own frame
/// (the root does not move with the joints); the chain's length is the sum of the distances
/// between its joints' anchors and from the last anchor to the farthest point of its end's
/// colliding geoms, which no joint angle changes. A humanoid upper body's arms leave the torso
/// at its top, so they are no legs.
fn legs_by_structure(robot: &Robot) -> Vec<(usize, usize)> {
    use crate::model::contact::takes_part;
    let n = robot.bodies.len();
    let colliding = |b: usize| {
        robot.geoms.iter().filter(move |g| {
            g.body == b
                && takes_part(robot, g.id)
                && !matches!(
                    g.gtype,
                    crate::model::GeomType::Plane | crate::model::GeomType::Hfield
                )
        })
    };
    let mut chains: Vec<(usize, Vec<usize>)> = Vec::new();
    for b in 1..n {
        if colliding(b).next().is_none() || crate::rules::contact::feet::collides_below(robot, b) {
            continue;
        }
        let path = chain_up(robot, b);
        chains.push((b, path));
    }
    let hub = waist_hub(robot, &chains);
    let Some((lo, hi)) = hub_height(robot, hub) else { return Vec::new() };
    let exit_below = lo + LEG_EXIT_HEIGHT * (hi - lo);
    let anchor = |j: usize| robot.key.joint_xanchor.get(j).copied();
    let dist = |a: [f64; 3], b: [f64; 3]| {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    };
    let mut out = Vec::new();
    for (leaf, path) in chains {
        let below: Vec<usize> = path.iter().copied().take_while(|&x| x != hub).collect();
        let Some(&top) = below.last() else { continue };
        let mut joints: Vec<usize> = robot
            .joints
            .iter()
            .filter(|j| below.contains(&j.body))
            .filter(|j| matches!(j.jtype, JointType::Hinge | JointType::Slide))
            .map(|j| j.id)
            .collect();
        if joints.len() < 2 || joints.iter().any(|&j| robot.is_wheel(j)) {
            continue;
        }
        // Top down: the body order of the tree, ancestors first.
        joints.sort_by_key(|&j| (robot.joints[j].body, j));
        let Some(exit) = exit_anchor(robot, top) else { continue };
        if !(exit[2] < exit_below) {
            continue;
        }
        let pts: Vec<[f64; 3]> = joints.iter().filter_map(|&j| anchor(j)).collect();
        let Some(&last) = pts.last() else { continue };
        let mut length: f64 = pts.windows(2).map(|w| dist(w[0], w[1])).sum();
        length += dist(exit, pts[0]);
        let end = colliding(leaf)
            .map(|g| dist(last, robot.key.geom_xpos[g.id]) + g.rbound.max(0.0))
            .fold(0.0, f64::max);
        if exit[2] - (length + end) < lo {
            out.push((leaf, top));
        }
    }
    out
}

/// Whether `robot` is a legged URDF that MuJoCo's importer welded to the world: the foot rules
/// judge its feet as if its root link floated ([`crate::rules::contact::feet::floating_bases`]).
pub fn is_welded_legged(robot: &Robot) -> bool {
    welded_legs(robot).is_some()
}

/// The URDF's root link: the `<link>` no `<joint>` has as its child.
pub fn root_link(robot: &Robot) -> Option<&crate::model::source::XNode> {
    robot.tree.children_tagged("link").find(|l| {
        let name = l.get("name").unwrap_or("");
        !robot
            .tree
            .children_tagged("joint")
            .any(|j| j.children_tagged("child").any(|c| c.get("link") == Some(name)))
    })
}

impl Rule for WeldedLeggedBase {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let Some((legs, depth)) = welded_legs(robot) else { return };
        let root = root_link(robot);
        let root_name = root.and_then(|l| l.get("name")).unwrap_or("");
        let at = root.map_or(robot.root_loc(), |l| l.attr("name").map_or(l.loc, |a| a.loc));
        let names: Vec<String> =
            legs.iter().map(|l| format!("`{}`", robot.body_name(l.0))).collect();
        let f = cx
            .finding(
                format!(
                    "MuJoCo's importer welds the root link `{root_name}` to the world, and the robot has {} legs ending in its lowest contacts ({}): the foot rules judged these feet as if `{root_name}` floated, and the stance probes stand a floated copy",
                    legs.len(),
                    names.join(", ")
                ),
                at,
            )
            .element(format!("link `{root_name}`"), at)
            .label("root link, fixed to the world by the importer; floated for the foot rules and the stance probes")
            .note(format!(
                "a URDF cannot say its base floats: loaded as it is, the robot never stands on its feet (their lowest point {} m {} the root link's frame at qpos0). The static foot rules (`toe-tilt`, `foot-collision-geometry`, `links-without-collision`, `torsional-friction-length`) take the root link as a floating base at its pose in the file; the stance probes run on a copy with a free joint on it, a floor under the lowest foot and the joints held at qpos0",
                fmt_num(depth.abs(), 3),
                if depth >= 0.0 { "below" } else { "above" }
            ))
            .help("to simulate it standing with its own actuators and floor: an MJCF wrapper that attaches the URDF under a body with a <freejoint/> above a floor (<body pos=\"0 0 H\"><freejoint/><attach model=\"robot\" prefix=\"\"/></body>), and lint the wrapper")
            .subject(Subject::Model)
            .measured(legs.len() as f64, "legs")
            .with("depth", depth);
        out.push(f);
    }
}
