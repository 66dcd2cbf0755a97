use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::{GeomType, JointType, Robot};
use crate::rules::geometry::shapes::Placed;
use crate::rules::{Context, Rule, RuleMeta, in_subtree};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds a limb written as a robot of its own: a kinematic tree on a free joint that
    /// carries actuated hinge or slide joints, is lighter than the model's main robot (the
    /// free tree with the most hinge and slide joints, then the heaviest) and starts inside the
    /// main robot's bounding box at the keyframe (or qpos0), or within a tenth of the robot's
    /// size (the box's diagonal) of it, with no `connect` or
    /// `weld` equality holding it to anything. A tree with no actuator (a passive limb, or
    /// one whose motors are missing), or one placed farther, up to the robot's own size from
    /// its box, is reported when it is shaped and named like one of the robot's limbs: two or
    /// more hinge or slide joints in series, no ball joint, fewer joints than the main robot,
    /// every joint named for a part of a limb (shoulder, elbow, wrist, hand, finger, hip,
    /// knee, ankle, thigh, calf, foot, head, neck, ...) and for one side (`left_…`, `r_…`,
    /// `…_L`, `FL_…`), in a robot that names its joints by side. An onshape-to-robot or CAD export writes
    /// detached assemblies this way (both arms as free bodies at the robot's frame). Not
    /// reported: scene objects (no actuated joint and no side in their names: boxes, balls, a
    /// door, a rope or cable on ball joints), a free payload, a second complete robot (as
    /// heavy as the first, or as many joints, or joints on both sides, or placed apart from
    /// it), a tree held by an equality.
    ///
    /// ## Why is this bad?
    /// The limb is not attached: at the first step it falls off the robot (or floats in it,
    /// with gravity off), its motors push against nothing, and the robot moves without the
    /// limb's mass and reach. Observations and actions of a policy name joints that are not
    /// where the robot has them.
    ///
    /// ## How it is confirmed
    /// Static: the compiled tree, its actuators and equalities, and the geometry's world
    /// bounding boxes at the keyframe (or qpos0).
    ///
    /// ## How to fix
    /// Move the limb's body inside the body it mounts on (the torso for an arm), at its
    /// mounting pose, and remove its `<freejoint/>`; or, when the attachment is a real
    /// closed chain, hold it with `<equality><weld body1="..." body2="..."/>`.
    pub DetachedLimb {
        id: "detached-limb",
        group: "mapping",
        level: Severity::Error,
        probe: None,
        options: [],
    }
}

/// A world bounding box: (min, max).
type Aabb = ([f64; 3], [f64; 3]);

/// Bounding box of the geoms and body origins of the tree below `top` at the keyframe.
fn bounds(robot: &Robot, top: usize) -> Option<Aabb> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let mut grow = |p: [f64; 3]| {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    };
    for b in robot.bodies.iter().filter(|b| b.id != 0 && in_subtree(robot, top, b.id)) {
        if let Some(p) = robot.key.body_xpos.get(b.id) {
            grow(*p);
        }
    }
    for g in robot.geoms.iter().filter(|g| g.body != 0 && in_subtree(robot, top, g.body)) {
        if matches!(g.gtype, GeomType::Plane | GeomType::Hfield | GeomType::Other | GeomType::Sdf) {
            continue;
        }
        if robot.key.geom_xpos.get(g.id).is_none() || robot.key.geom_xmat.get(g.id).is_none() {
            continue;
        }
        let p = Placed::of(robot, g.id);
        for k in 0..3 {
            for s in [-1.0, 1.0] {
                let mut d = [0.0; 3];
                d[k] = s;
                grow(p.support(d));
            }
        }
    }
    lo[0].is_finite().then_some((lo, hi))
}

/// How close a limb must start to the robot to count as one of its parts: this share of the
/// robot's own size (the diagonal of its bounding box). Two robots of a scene stand apart by
/// about their size; a limb exported at its mounting pose touches or nearly touches its robot.
const ADJACENT_SHARE: f64 = 0.1;

/// How close a limb named as one of the robot's own (see [`named_limb`]) must start, unactuated
/// or farther than [`ADJACENT_SHARE`]: within the robot's own size (this share of its box's
/// diagonal). An exporter places a detached arm at or beside its mount; a second robot or a
/// scene's object is not named after one side of the robot's body.
const NAMED_LIMB_SHARE: f64 = 1.0;

/// The side a free tree is named for when it is shaped and named like one of the robot's limbs:
/// two or more hinge/slide joints in series (one's body below the other's), no ball joint (a
/// rope or a cable), fewer hinge/slide joints than the main robot, every one of them named for
/// a limb (a part of the head, an arm or a leg: [`crate::model::region::from_name`]) and for
/// the same side (`left_…`, `r_…`, `…_L`, `FL_…`: [`crate::model::mirror::side_of`]), in a
/// model whose main robot names its own joints by side.
fn named_limb(
    robot: &Robot,
    spec: Option<&crate::spec::Spec>,
    t: &Tree,
    main: &Tree,
) -> Option<crate::model::mirror::Side> {
    use crate::model::mirror::side_of;
    if t.scalar < 2 || t.scalar >= main.scalar {
        return None;
    }
    let inside = |top: usize| robot.joints.iter().filter(move |j| in_subtree(robot, top, j.body));
    if inside(t.top).any(|j| j.jtype == JointType::Ball) {
        return None;
    }
    let scalar: Vec<&crate::model::Joint> = inside(t.top).filter(|j| j.is_scalar()).collect();
    let in_series = scalar
        .iter()
        .any(|a| scalar.iter().any(|b| b.body != a.body && in_subtree(robot, a.body, b.body)));
    let limb_named = scalar.iter().all(|j| {
        matches!(crate::model::region::from_name(&j.name), Some("arms" | "legs" | "head"))
    });
    if copied_segments(robot, &scalar) {
        return None;
    }
    let side = side_of(&scalar.first()?.name, spec)?;
    let one_side = scalar.iter().all(|j| side_of(&j.name, spec) == Some(side));
    let robot_sided = inside(main.top).any(|j| j.is_scalar() && side_of(&j.name, spec).is_some());
    (in_series && limb_named && one_side && robot_sided).then_some(side)
}

/// How far apart the masses of a chain's segments may be for them to be copies of one segment
/// (relative to the heaviest): a rope or strap cut into equal pieces.
const SEGMENT_MASS_SPREAD: f64 = 0.01;

/// Whether `joints` are a chain of copies of one segment, not a limb: every joint has one name
/// but for its number (`left_hand_strap_1` … `_4`, where a limb names each joint for its part:
/// shoulder, elbow, wrist), and the bodies they move have one mass (within
/// [`SEGMENT_MASS_SPREAD`]) — a strap, rope or chain of hinges.
fn copied_segments(robot: &Robot, joints: &[&crate::model::Joint]) -> bool {
    let stem = |n: &str| -> String {
        n.chars()
            .filter(|c| !c.is_ascii_digit())
            .collect::<String>()
            .trim_matches(['_', '-', '.'])
            .to_string()
    };
    let Some(first) = joints.first() else { return false };
    let s0 = stem(&first.name);
    if joints.len() < 2 || joints.iter().any(|j| stem(&j.name) != s0) {
        return false;
    }
    let masses: Vec<f64> =
        joints.iter().filter_map(|j| robot.bodies.get(j.body).map(|b| b.mass)).collect();
    let hi = masses.iter().copied().fold(0.0, f64::max);
    let lo = masses.iter().copied().fold(f64::INFINITY, f64::min);
    hi > 0.0 && hi - lo <= SEGMENT_MASS_SPREAD * hi
}

/// Whether box `a` overlaps box `b` grown by `margin` on every side.
fn overlap(a: &Aabb, b: &Aabb, margin: f64) -> bool {
    (0..3).all(|k| a.0[k] <= b.1[k] + margin && b.0[k] - margin <= a.1[k])
}

/// A free tree: its top body, its hinge/slide joints, the actuated ones, and its mass.
struct Tree {
    top: usize,
    scalar: usize,
    actuated: Vec<usize>,
    mass: f64,
}

fn free_trees(robot: &Robot) -> Vec<Tree> {
    robot
        .bodies
        .iter()
        .filter(|b| b.id != 0 && b.parent == 0)
        .filter(|b| robot.joints.iter().any(|j| j.body == b.id && j.jtype == JointType::Free))
        .map(|b| {
            let joints: Vec<usize> = robot
                .joints
                .iter()
                .filter(|j| j.is_scalar() && in_subtree(robot, b.id, j.body))
                .map(|j| j.id)
                .collect();
            let actuated = joints
                .iter()
                .copied()
                .filter(|&j| !robot.actuators_on_joint(j).is_empty())
                .collect();
            let mass =
                robot.bodies.iter().filter(|x| in_subtree(robot, b.id, x.id)).map(|x| x.mass).sum();
            Tree { top: b.id, scalar: joints.len(), actuated, mass }
        })
        .collect()
}

/// Whether a `connect` or `weld` equality names a body of the tree below `top`.
fn held(robot: &Robot, top: usize) -> bool {
    let m = &robot.mj;
    let objtype = m.eq_objtype();
    robot.equalities.iter().filter(|e| e.etype == 0 || e.etype == 1).any(|e| {
        // Body-type objects only (MuJoCo ≥ 3.1 also welds sites: their bodies count).
        let body_of = |o: i32| -> Option<usize> {
            if o < 0 {
                return None;
            }
            match objtype.get(e.id).map(|&t| t as i32) {
                Some(6) => m.site_bodyid().get(o as usize).map(|&b| b.max(0) as usize),
                _ => Some(o as usize),
            }
        };
        [e.obj1, e.obj2]
            .into_iter()
            .filter_map(body_of)
            .any(|b| b != 0 && in_subtree(robot, top, b))
    })
}

impl Rule for DetachedLimb {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let trees = free_trees(robot);
        let Some(main) = trees.iter().max_by(|a, b| {
            a.scalar
                .cmp(&b.scalar)
                .then(a.mass.partial_cmp(&b.mass).unwrap_or(std::cmp::Ordering::Equal))
                .then(b.top.cmp(&a.top))
        }) else {
            return;
        };
        let Some(main_box) = bounds(robot, main.top) else { return };
        let diagonal = (0..3).map(|k| (main_box.1[k] - main_box.0[k]).powi(2)).sum::<f64>().sqrt();
        let margin = ADJACENT_SHARE * diagonal;
        for t in trees.iter().filter(|t| t.top != main.top) {
            if t.mass >= main.mass || held(robot, t.top) {
                continue;
            }
            let Some(b) = bounds(robot, t.top) else { continue };
            let adjacent = !t.actuated.is_empty() && overlap(&b, &main_box, margin);
            let named = named_limb(robot, cx.spec, t, main)
                .filter(|_| overlap(&b, &main_box, NAMED_LIMB_SHARE * diagonal));
            if !adjacent && named.is_none() {
                continue;
            }
            let Some(free) =
                robot.joints.iter().find(|j| j.body == t.top && j.jtype == JointType::Free)
            else {
                continue;
            };
            let quote =
                |j: usize| format!("`{}`", crate::rules::display_name(&robot.joints[j].name, j));
            let names: Vec<String> = t.actuated.iter().map(|&j| quote(j)).collect();
            let joints = if names.is_empty() {
                let all: Vec<String> = robot
                    .joints
                    .iter()
                    .filter(|j| j.is_scalar() && in_subtree(robot, t.top, j.body))
                    .map(|j| quote(j.id))
                    .collect();
                format!(
                    "with {} joints named for the robot's {} side ({}) and no actuator",
                    all.len(),
                    named.map_or("", |s| s.word()),
                    all.join(", ")
                )
            } else {
                format!(
                    "with {} actuated joint{} ({})",
                    names.len(),
                    if names.len() == 1 { "" } else { "s" },
                    names.join(", ")
                )
            };
            let d = robot.key.body_xpos.get(t.top).zip(robot.key.body_xpos.get(main.top)).map_or(
                0.0,
                |(a, b)| {
                    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
                },
            );
            let f = cx
                .at_elem(
                    ElemKind::Joint,
                    free.id,
                    &free.name,
                    format!(
                        "body `{}` ({} kg) floats on a free joint of its own, {joints}, at the robot `{}` ({} kg, {} m from its base): a limb not attached to the robot",
                        robot.body_name(t.top),
                        fmt_num(t.mass, 3),
                        robot.body_name(main.top),
                        fmt_num(main.mass, 3),
                        fmt_num(d, 3),
                    ),
                )
                .label("the limb's own free joint")
                .note("nothing holds the limb to the robot: it falls off (or floats inside it) at the first step, and the robot moves without its mass")
                .help(format!(
                    "move body `{}` inside the body it mounts on, at its mounting pose, and remove its free joint (or hold it with <equality><weld body1=... body2=.../>)",
                    robot.body_name(t.top)
                ))
                .subject(Subject::Body(t.top))
                .measured(t.mass, "kg")
                .expected(main.mass, "kg")
                .with("actuated", names.len() as f64)
                .with("distance", d);
            out.push(f);
        }
    }
}
