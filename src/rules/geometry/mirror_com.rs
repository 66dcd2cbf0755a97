//! The centre-of-mass and pose comparisons of `mirror-asymmetry` (split from the rule's file):
//! a mirror pair's stated centres of mass at the reference pose, and whether the pair is posed
//! as mirror images there at all.

use crate::finding::{Finding, Subject};
use crate::model::Robot;
use crate::model::mjcf::ElemKind;
use crate::model::source::Loc;
use crate::rules::Context;
use crate::util::fmt_num;

use super::mirror_asymmetry::Pair;

/// Body origins and centres of mass in the world at the reference pose (qpos0), where a
/// mirror-symmetric model is posed symmetrically.
pub(super) struct Pose {
    pub(super) xpos: Vec<[f64; 3]>,
    pub(super) xipos: Vec<[f64; 3]>,
    /// Row-major body orientation.
    pub(super) xmat: Vec<[f64; 9]>,
    /// Row-major orientation of each body's principal axes of inertia (its columns).
    pub(super) ximat: Vec<[f64; 9]>,
    pub(super) geom_xpos: Vec<[f64; 3]>,
    pub(super) xanchor: Vec<[f64; 3]>,
    pub(super) xaxis: Vec<[f64; 3]>,
    pub(super) site_xpos: Vec<[f64; 3]>,
    /// Row-major site orientation.
    pub(super) site_xmat: Vec<[f64; 9]>,
}

pub(super) fn reference_pose(robot: &Robot) -> Pose {
    let mut d = mujoco_rs::prelude::MjData::new(&robot.mj);
    d.forward();
    Pose {
        xpos: d.xpos().to_vec(),
        xipos: d.xipos().to_vec(),
        xmat: d.xmat().to_vec(),
        ximat: d.ximat().to_vec(),
        geom_xpos: d.geom_xpos().to_vec(),
        xanchor: d.xanchor().to_vec(),
        xaxis: d.xaxis().to_vec(),
        site_xpos: d.site_xpos().to_vec(),
        site_xmat: d.site_xmat().to_vec(),
    }
}

/// The limb roots of a mirror pair: walking up both bodies' parents together while they
/// differ, the last two distinct ancestors (the pair itself when the two hang on one body, as a
/// gripper's fingers do). Their origins, mounted on one common body, are placed mirror-
/// symmetrically even when a pair further down is not: a hip-roll bracket mounted turned 180°
/// puts its axis ahead of the hip on one side and behind it on the other.
pub(super) fn limb_roots(robot: &Robot, l: usize, r: usize) -> (usize, usize) {
    let parent = |b: usize| robot.bodies.get(b).map_or(0, |x| x.parent);
    let (mut a, mut b) = (l, r);
    for _ in 0..robot.bodies.len() {
        let (pa, pb) = (parent(a), parent(b));
        if pa == pb || pa == 0 || pb == 0 || pa == a || pb == b {
            break;
        }
        (a, b) = (pa, pb);
    }
    (a, b)
}

/// Whether body `b` draws or collides through a mirrored mesh (a `scale` with an odd number of
/// negative factors): the file says the part is the mirror image of another.
fn mirrored_mesh(robot: &Robot, b: usize) -> bool {
    let scale = robot.mj.mesh_scale();
    robot.geoms.iter().filter(|g| g.body == b && g.mesh >= 0).any(|g| {
        scale.get(g.mesh as usize).is_some_and(|s| s.iter().filter(|x| **x < 0.0).count() % 2 == 1)
    })
}

/// Where the file writes body `name`'s `<inertial pos>` (the centre of mass).
pub(super) fn com_loc(robot: &Robot, name: &str) -> Option<Loc> {
    let mut found = None;
    robot.tree.walk(&mut |n: &crate::model::source::XNode| {
        if found.is_none()
            && (n.tag == "body" || n.tag == "link")
            && n.name() == Some(name)
            && let Some(i) = n.children_tagged("inertial").next()
        {
            found = Some(
                i.attr("pos")
                    .or(i.children_tagged("origin").next().and_then(|o| o.attr("xyz")))
                    .map_or(i.loc, |a| a.loc),
            );
        }
    });
    found
}

pub(super) fn v_sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(super) fn v_dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(super) fn v_norm(a: [f64; 3]) -> f64 {
    v_dot(a, a).sqrt()
}

/// `v` reflected through the plane through the origin with unit normal `n`.
pub(super) fn v_reflect(v: [f64; 3], n: [f64; 3]) -> [f64; 3] {
    let h = v_dot(v, n);
    [v[0] - 2.0 * h * n[0], v[1] - 2.0 * h * n[1], v[2] - 2.0 * h * n[2]]
}

/// A world vector of the right body (frame `mr`, row-major) turned into the left body's frame
/// (`ml`) with the same local coordinates: the same part mounted the same way on both sides.
pub(super) fn v_turn(v: [f64; 3], ml: &[f64; 9], mr: &[f64; 9]) -> [f64; 3] {
    let local = [0, 1, 2].map(|k| (0..3).map(|i| mr[3 * i + k] * v[i]).sum::<f64>());
    [0, 1, 2].map(|i| (0..3).map(|k| ml[3 * i + k] * local[k]).sum::<f64>())
}

/// The mirror plane of pair `p` at the reference pose, as its unit normal and offset along it:
/// halfway between the pair's limb roots ([`limb_roots`]), else between its own origins;
/// origins that coincide define none.
pub(super) fn mirror_plane(robot: &Robot, pose: &Pose, p: &Pair) -> Option<([f64; 3], f64)> {
    let (ol, or) = (*pose.xpos.get(p.left.0)?, *pose.xpos.get(p.right.0)?);
    let (ra, rb) = limb_roots(robot, p.left.0, p.right.0);
    let (pa, pb) = (*pose.xpos.get(ra)?, *pose.xpos.get(rb)?);
    let (pa, pb) = if v_norm(v_sub(pa, pb)) > 1e-6 { (pa, pb) } else { (ol, or) };
    let gap = v_sub(pa, pb);
    if !(v_norm(gap) > 1e-6) {
        return None;
    }
    let n = gap.map(|x| x / v_norm(gap));
    Some((n, v_dot([0, 1, 2].map(|k| (pa[k] + pb[k]) / 2.0), n)))
}

/// A mirror pair whose stated centres of mass are not mirror images: the right body's centre of
/// mass reflected across the pair's mirror plane (halfway between its limb roots) lies farther from the
/// left's than `com_tolerance`, and than `com_fraction` of their offsets from the origins.
pub(super) fn com_differs(cx: &Context, p: &Pair, pose: &Option<Pose>) -> Option<Finding> {
    let robot = cx.robot;
    let pose = pose.as_ref()?;
    // Stated inertials only: a centre of mass MuJoCo computes from the geoms follows the
    // collision geometry, compared on its own.
    let loc = com_loc(robot, p.right.1)?;
    let lloc = com_loc(robot, p.left.1)?;
    let (ol, or) = (*pose.xpos.get(p.left.0)?, *pose.xpos.get(p.right.0)?);
    let (cl, cr) = (*pose.xipos.get(p.left.0)?, *pose.xipos.get(p.right.0)?);
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let norm = |a: [f64; 3]| dot(a, a).sqrt();
    let (n, off) = mirror_plane(robot, pose, p)?;
    let reflect = |g: [f64; 3]| {
        let h = dot(g, n) - off;
        [g[0] - 2.0 * h * n[0], g[1] - 2.0 * h * n[1], g[2] - 2.0 * h * n[2]]
    };
    let reflected = reflect(cr);
    let miss = norm(sub(reflected, cl));
    let reach = (norm(sub(cl, ol)) + norm(sub(cr, or))) / 2.0;
    let allowed = cx.opt("com_tolerance").max(cx.opt("com_fraction") * reach);
    if !(miss > allowed) {
        return None;
    }
    // The same part on hinges whose zeros differ: its centre of mass and the bodies it carries
    // all turned by one angle about its own hinge from their mirror images. Reported as that turn
    // where it starts; the bodies below a turned pair inherit it and are not reported.
    let (plane, tol) = (Plane { n, off }, cx.opt("pose_tolerance"));
    if let Some(t) = turned_pair(robot, pose, p.left.0, p.right.0, plane, allowed, tol) {
        return Some(turned(cx, p, &t, tol));
    }
    if turned_above(robot, pose, p, plane, allowed, tol) {
        return None;
    }
    // One part mounted on both sides (a gripper turned 180°) is no mirror image: its centre of
    // mass follows the rotation between the two body frames. Unless one side's mesh is the
    // mirrored copy of the other's, a centre of mass that fits that rotation is not reported.
    let (ml, mr) = (*pose.xmat.get(p.left.0)?, *pose.xmat.get(p.right.0)?);
    let local_l = [0, 1, 2].map(|k| (0..3).map(|i| ml[3 * i + k] * (cl[i] - ol[i])).sum::<f64>());
    let rotated =
        [0, 1, 2].map(|i| or[i] + (0..3).map(|k| mr[3 * i + k] * local_l[k]).sum::<f64>());
    let miss_rotated = norm(sub(rotated, cr));
    // The geoms say which: each right geom's centre at the reflection of a left geom's centre
    // (a mirrored part), or at its image under the frames' rotation (the same part).
    let geoms = |b: usize| -> Vec<[f64; 3]> {
        robot
            .geoms
            .iter()
            .filter(|g| g.body == b)
            .filter_map(|g| pose.geom_xpos.get(g.id).copied())
            .collect()
    };
    let (gl, gr) = (geoms(p.left.0), geoms(p.right.0));
    let fits = |map: &dyn Fn([f64; 3]) -> [f64; 3]| {
        !gl.is_empty()
            && gl.len() == gr.len()
            && gr.iter().all(|&g| gl.iter().any(|&h| norm(sub(map(g), h)) <= allowed))
    };
    // Right world point → left world point under the rotation between the two body frames.
    let unrotate = |g: [f64; 3]| {
        let local = [0, 1, 2].map(|k| (0..3).map(|i| mr[3 * i + k] * (g[i] - or[i])).sum::<f64>());
        [0, 1, 2].map(|i| ol[i] + (0..3).map(|k| ml[3 * i + k] * local[k]).sum::<f64>())
    };
    let mirrored = mirrored_mesh(robot, p.left.0) != mirrored_mesh(robot, p.right.0)
        || (fits(&reflect) && !fits(&unrotate));
    if !mirrored && !(miss_rotated > allowed) {
        return None;
    }
    let mm = |x: f64| fmt_num(1000.0 * x, 3);
    let local =
        |b: usize| {
            robot.mj.body_ipos().get(b).map(|v| {
                format!("({}, {}, {})", fmt_num(v[0], 4), fmt_num(v[1], 4), fmt_num(v[2], 4))
            })
        };
    let (lr, ll) = (local(p.right.0)?, local(p.left.0)?);
    let msg = format!(
        "body `{}`'s centre of mass {lr} m is not the mirror image of `{}`'s ({ll} m): reflected across the mirror plane of its limb, it lies {} mm from it",
        p.right.1,
        p.left.1,
        mm(miss)
    );
    let rloc = robot.elem_loc(ElemKind::Body, p.right.0, p.right.1);
    Some(
        cx.finding(msg, loc)
            .element(format!("body {}", p.right.1), rloc)
            .label(format!("centre of mass {lr} m"))
            .secondary(lloc, format!("mirror `{}` has {ll} m", p.left.1))
            .note(format!(
                "at the reference pose (qpos0) the two bodies' origins are mirror images; their centres of mass are {} mm apart once mirrored, beyond {} mm (com_tolerance, or com_fraction of their {} mm offset from the origins); {}: one side's inertial was copied from the other without flipping the lateral coordinate, so one limb swings and loads differently and the policy learns the asymmetry",
                mm(miss),
                mm(allowed),
                mm(reach),
                if mirrored {
                    "the two parts' geoms are mirror images (a mirrored mesh, or geoms at mirrored places), so the centre of mass must be mirrored too".to_string()
                } else {
                    format!("as one part turned into the other's frame they are {} mm apart too", mm(miss_rotated))
                }
            ))
            .help("mirror the centre of mass of the copied side (negate its lateral coordinate in the body's frame), or take both inertials from the CAD of each part")
            .subject(Subject::Body(p.right.0))
            .measured(miss, "m")
            .expected(allowed, "m")
            .with("com_mismatch", miss),
    )
}

/// Whether a pair of ancestors of pair `p` (walking up both bodies' parents while they differ)
/// is one part turned about its hinge ([`turned_pair`]): the bodies below inherit the turn.
fn turned_above(
    robot: &Robot,
    pose: &Pose,
    p: &Pair,
    plane: Plane,
    allowed: f64,
    tol: f64,
) -> bool {
    let parent = |b: usize| robot.bodies.get(b).map_or(0, |x| x.parent);
    let (mut a, mut b) = (parent(p.left.0), parent(p.right.0));
    while a != b && a != 0 && b != 0 {
        if turned_pair(robot, pose, a, b, plane, allowed, tol).is_some() {
            return true;
        }
        (a, b) = (parent(a), parent(b));
    }
    false
}

/// Whether mirror pair `p` is posed as mirror images at the reference pose as far as its
/// centres of mass tell: neither it nor a pair of its ancestors is one part turned about its
/// hinge (joints whose zeros differ, reported by [`com_differs`]), judged with the same
/// distance allowance as [`com_differs`].
pub(super) fn posed_mirrored(cx: &Context, p: &Pair, pose: &Pose) -> bool {
    let robot = cx.robot;
    let Some((n, off)) = mirror_plane(robot, pose, p) else { return false };
    let (Some(ol), Some(or), Some(cl), Some(cr)) = (
        pose.xpos.get(p.left.0),
        pose.xpos.get(p.right.0),
        pose.xipos.get(p.left.0),
        pose.xipos.get(p.right.0),
    ) else {
        return false;
    };
    let reach = (v_norm(v_sub(*cl, *ol)) + v_norm(v_sub(*cr, *or))) / 2.0;
    let allowed = cx.opt("com_tolerance").max(cx.opt("com_fraction") * reach);
    let (plane, tol) = (Plane { n, off }, cx.opt("pose_tolerance"));
    turned_pair(robot, pose, p.left.0, p.right.0, plane, allowed, tol).is_none()
        && !turned_above(robot, pose, p, plane, allowed, tol)
}

/// A mirror plane: unit normal `n`, at `off` along it from the origin.
#[derive(Clone, Copy)]
struct Plane {
    n: [f64; 3],
    off: f64,
}

impl Plane {
    fn reflect(&self, g: [f64; 3]) -> [f64; 3] {
        let n = self.n;
        let h = g[0] * n[0] + g[1] * n[1] + g[2] * n[2] - self.off;
        [g[0] - 2.0 * h * n[0], g[1] - 2.0 * h * n[1], g[2] - 2.0 * h * n[2]]
    }
}

/// Mirror a direction across the plane of unit normal `n`.
fn reflect_dir(v: [f64; 3], n: [f64; 3]) -> [f64; 3] {
    let h = v[0] * n[0] + v[1] * n[1] + v[2] * n[2];
    [v[0] - 2.0 * h * n[0], v[1] - 2.0 * h * n[1], v[2] - 2.0 * h * n[2]]
}

/// A mirror pair whose centres of mass differ by a turn about each body's own hinge.
struct Turn {
    /// The left and right joints.
    joints: (usize, usize),
    /// The turn, degrees.
    deg: f64,
    /// The centres of mass' distance from the joint axis and coordinate along it, metres.
    radial: f64,
    axial: f64,
}

/// A mirror pair `l`, `r` (bodies) that is one part on hinges whose zeros differ: each hangs on
/// exactly one hinge, the two hinges' anchors are mirror images at the reference pose (within
/// `allowed`), and at least two of the body's points off the axis — its centre of mass, the
/// origins of the bodies it carries — lie at the same distance from the axis and place along it
/// (mirrored) as their mirror's, all turned about the axis by one angle (within the rule's
/// `pose_tolerance`) larger than that tolerance. Distance and place along the axis are
/// quantities of the body itself, whatever the pose; one point alone cannot tell a turned part
/// from a misplaced centre of mass.
fn turned_pair(
    robot: &Robot,
    pose: &Pose,
    l: usize,
    r: usize,
    plane: Plane,
    allowed: f64,
    tol: f64,
) -> Option<Turn> {
    use crate::model::JointType;
    let n = plane.n;
    let hinge = |b: usize| {
        let mut it = robot.joints.iter().filter(|j| j.body == b);
        match (it.next(), it.next()) {
            (Some(j), None) if j.jtype == JointType::Hinge => Some(j.id),
            _ => None,
        }
    };
    let (jl, jr) = (hinge(l)?, hinge(r)?);
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let unit = |a: [f64; 3]| {
        let len = dot(a, a).sqrt();
        (len > 1e-12).then(|| a.map(|x| x / len))
    };
    let (pl, pr) = (*pose.xanchor.get(jl)?, *pose.xanchor.get(jr)?);
    let miss = sub(plane.reflect(pr), pl);
    let (al, ar) = (unit(*pose.xaxis.get(jl)?)?, unit(reflect_dir(*pose.xaxis.get(jr)?, n))?);
    if dot(miss, miss).sqrt() > allowed || dot(al, ar).abs() < tol.to_radians().cos() {
        return None;
    }
    // Off-axis part and coordinate along the axis of a point relative to the left anchor; the
    // right one mirrored about its own anchor first.
    let split = |v: [f64; 3], a: [f64; 3]| {
        let h = dot(v, a);
        ([v[0] - h * a[0], v[1] - h * a[1], v[2] - h * a[2]], h)
    };
    let angle = |u: [f64; 3], w: [f64; 3]| {
        let c = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]];
        dot(c, al).atan2(dot(u, w)).to_degrees()
    };
    let children = |b: usize| -> Vec<usize> {
        robot.bodies.iter().filter(|c| c.parent == b && c.id != b).map(|c| c.id).collect()
    };
    let mut points = vec![(*pose.xipos.get(l)?, *pose.xipos.get(r)?)];
    let (cl, cr) = (children(l), children(r));
    if cl.len() == cr.len() {
        for (x, y) in cl.iter().zip(&cr) {
            points.push((*pose.xpos.get(*x)?, *pose.xpos.get(*y)?));
        }
    }
    let mut turns = Vec::new();
    let (mut radial, mut axial) = (0.0, 0.0);
    for (k, (ql, qr)) in points.iter().enumerate() {
        let (ul, hl) = split(sub(*ql, pl), al);
        let (ur, hr) = split(reflect_dir(sub(*qr, pr), n), al);
        let (rl, rr) = (dot(ul, ul).sqrt(), dot(ur, ur).sqrt());
        if !(rl > allowed && rr > allowed) {
            continue;
        }
        if (rl - rr).abs() > allowed || (hl - hr).abs() > allowed {
            return None;
        }
        if k == 0 {
            (radial, axial) = (rl, hl.abs());
        }
        turns.push(angle(ul, ur));
    }
    let first = *turns.first()?;
    let apart = |t: f64| ((t - first + 180.0).rem_euclid(360.0) - 180.0).abs();
    if turns.len() < 2 || first.abs() <= tol || turns.iter().any(|t| apart(*t) > tol) {
        return None;
    }
    Some(Turn { joints: (jl, jr), deg: first.abs(), radial, axial })
}

/// The finding for a pair turned about its own joint: the two joints' zeros differ.
fn turned(cx: &Context, p: &Pair, t: &Turn, tol_deg: f64) -> Finding {
    let robot = cx.robot;
    let (jl, jr) = (&robot.joints[t.joints.0], &robot.joints[t.joints.1]);
    let range = |j: &crate::model::Joint| {
        if j.limited {
            format!("[{}, {}]", fmt_num(j.range[0], 4), fmt_num(j.range[1], 4))
        } else {
            "no range".to_string()
        }
    };
    let deg = fmt_num(t.deg, 3);
    let msg = format!(
        "body `{}` is turned {deg}° about joint `{}` from the mirror image of `{}` at the reference pose (qpos0): the two joints' zeros differ",
        p.right.1, jr.name, p.left.1
    );
    let rloc = robot.elem_loc(ElemKind::Body, p.right.0, p.right.1);
    let lloc = robot.elem_loc(ElemKind::Body, p.left.0, p.left.1);
    cx.finding(msg, rloc)
        .element(format!("body {}", p.right.1), rloc)
        .label(format!("turned {deg}° about `{}`", jr.name))
        .secondary(lloc, format!("mirror `{}`", p.left.1))
        .note(format!(
            "the two bodies' centres of mass lie at the same distance from their joints' axes ({} mm) and place along them ({} mm), where a turn of {deg}° about the joint puts them: the part is the same on both sides, its joint's zero is not (what it carries turned by the same angle, beyond pose_tolerance {}°). A joint angle, range or keyframe written for one side then poses the other side {deg}° away: `{}` {} against `{}` {}; the bodies below inherit the turn and are not reported again",
            fmt_num(t.radial * 1000.0, 3),
            fmt_num(t.axial * 1000.0, 3),
            fmt_num(tol_deg, 3),
            jl.name,
            range(jl),
            jr.name,
            range(jr)
        ))
        .help("give both joints the same zero (turn one side's body frame, with its inertial and geoms, by the angle), or write that side's ranges and keyframes through the offset")
        .subject(Subject::Body(p.right.0))
        .measured(t.deg, "deg")
        .expected(tol_deg, "deg")
        .with("turn_deg", t.deg)
}
