//! Where `mirror-asymmetry` compares places: the centres of mass and the collision geoms of a
//! mirror pair of bodies, reflected across the pair's mirror plane at the reference pose.

use crate::finding::{Finding, Subject};
use crate::model::Robot;
use crate::model::mjcf::ElemKind;
use crate::model::source::Loc;
use crate::rules::Context;
use crate::util::fmt_num;

use super::mirror_asymmetry::{Pair, SIZE_NOISE, colliders};

/// Body origins and centres of mass in the world at the reference pose (qpos0), where a
/// mirror-symmetric model is posed symmetrically.
pub(super) struct Pose {
    xpos: Vec<[f64; 3]>,
    xipos: Vec<[f64; 3]>,
    /// Row-major body orientation.
    xmat: Vec<[f64; 9]>,
    geom_xpos: Vec<[f64; 3]>,
}

pub(super) fn reference_pose(robot: &Robot) -> Pose {
    let mut d = mujoco_rs::prelude::MjData::new(&robot.mj);
    d.forward();
    Pose {
        xpos: d.xpos().to_vec(),
        xipos: d.xipos().to_vec(),
        xmat: d.xmat().to_vec(),
        geom_xpos: d.geom_xpos().to_vec(),
    }
}

/// The limb roots of a mirror pair: walking up both bodies' parents together while they
/// differ, the last two distinct ancestors (the pair itself when the two hang on one body, as a
/// gripper's fingers do). Their origins, mounted on one common body, are placed mirror-
/// symmetrically even when a pair further down is not: a hip-roll bracket mounted turned 180°
/// puts its axis ahead of the hip on one side and behind it on the other.
fn limb_roots(robot: &Robot, l: usize, r: usize) -> (usize, usize) {
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
fn com_loc(robot: &Robot, name: &str) -> Option<Loc> {
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

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// The mirror plane of pair `p` at the reference pose, as its unit normal and offset along it:
/// halfway between the pair's limb roots ([`limb_roots`]), else between its own origins;
/// origins that coincide define none.
fn mirror_plane(robot: &Robot, pose: &Pose, p: &Pair) -> Option<([f64; 3], f64)> {
    let (ol, or) = (*pose.xpos.get(p.left.0)?, *pose.xpos.get(p.right.0)?);
    let (ra, rb) = limb_roots(robot, p.left.0, p.right.0);
    let (pa, pb) = (*pose.xpos.get(ra)?, *pose.xpos.get(rb)?);
    let (pa, pb) = if norm(sub(pa, pb)) > 1e-6 { (pa, pb) } else { (ol, or) };
    let gap = sub(pa, pb);
    if !(norm(gap) > 1e-6) {
        return None;
    }
    let n = gap.map(|x| x / norm(gap));
    Some((n, dot([0, 1, 2].map(|k| (pa[k] + pb[k]) / 2.0), n)))
}

/// A mirror pair whose collision geoms match one to one in type and size but not in place: at
/// the reference pose, a right geom's offset from its body's origin, reflected across the
/// pair's mirror plane, lies farther than `place_tolerance` (or `geom_tolerance` of the geom's
/// bounding radius) from the offset of every left geom of its type and size — and the same
/// holds with the offset carried into the left body's frame unreflected (one part mounted
/// turned on both sides, or frames whose convention differs: a body frame turned 180° about
/// its axis with the geom placed accordingly, fits one of the two). Offsets from each body's
/// own origin, so a pair whose origins are themselves misplaced is judged on its geoms alone.
pub(super) fn geoms_misplaced(cx: &Context, p: &Pair, pose: &Option<Pose>) -> Option<Finding> {
    let robot = cx.robot;
    let pose = pose.as_ref()?;
    let (n, _) = mirror_plane(robot, pose, p)?;
    let gtol = cx.opt("geom_tolerance");
    let ptol = cx.opt("place_tolerance");
    let (l, r) = (p.left.0, p.right.0);
    let (ol, or) = (*pose.xpos.get(l)?, *pose.xpos.get(r)?);
    let (ml, mr) = (*pose.xmat.get(l)?, *pose.xmat.get(r)?);
    let (gl, gr) = (colliders(robot, l), colliders(robot, r));
    if gl.is_empty() {
        return None;
    }
    let offset = |g: usize, o: [f64; 3]| pose.geom_xpos.get(g).map(|x| sub(*x, o));
    let reflect = |v: [f64; 3]| {
        let h = dot(v, n);
        [v[0] - 2.0 * h * n[0], v[1] - 2.0 * h * n[1], v[2] - 2.0 * h * n[2]]
    };
    // A right offset in the world → the left body's frame, the same local coordinates.
    let turn = |v: [f64; 3]| {
        let local = [0, 1, 2].map(|k| (0..3).map(|i| mr[3 * i + k] * v[i]).sum::<f64>());
        [0, 1, 2].map(|i| (0..3).map(|k| ml[3 * i + k] * local[k]).sum::<f64>())
    };
    let close = |x: f64, y: f64| (x - y).abs() <= SIZE_NOISE.max(gtol * x.abs().max(y.abs()));
    let partners = |g: usize| -> Vec<usize> {
        let a = &robot.geoms[g];
        gl.iter()
            .copied()
            .filter(|&h| {
                let b = &robot.geoms[h];
                b.gtype == a.gtype && (0..3).all(|k| close(a.size[k], b.size[k]))
            })
            .collect()
    };
    // For each right geom: its tolerance, and its distance to the nearest partner under `map`.
    let miss = |map: &dyn Fn([f64; 3]) -> [f64; 3], g: usize| -> Option<(f64, usize)> {
        let v = map(offset(g, or)?);
        partners(g)
            .into_iter()
            .filter_map(|h| Some((norm(sub(v, offset(h, ol)?)), h)))
            .min_by(|a, b| a.0.total_cmp(&b.0))
    };
    let allowed = |g: usize| ptol.max(gtol * robot.geoms[g].rbound.max(0.0));
    let fits = |map: &dyn Fn([f64; 3]) -> [f64; 3]| {
        gr.iter().all(|&g| miss(map, g).is_some_and(|(d, _)| d <= allowed(g)))
    };
    if fits(&reflect) || fits(&turn) {
        return None;
    }
    // The right geom farthest from its mirror place, and the partner nearest it.
    let (g, d, h) = gr
        .iter()
        .filter_map(|&g| miss(&reflect, g).map(|(d, h)| (g, d, h)))
        .filter(|&(g, d, _)| d > allowed(g))
        .max_by(|a, b| (a.1 - allowed(a.0)).total_cmp(&(b.1 - allowed(b.0))))?;
    let mm = |x: f64| fmt_num(1000.0 * x, 3);
    let gname = |id: usize| {
        let name = &robot.geoms[id].name;
        if name.is_empty() { format!("#{id}") } else { format!("`{name}`") }
    };
    let msg = format!(
        "body `{}`'s collision geom {} is not at the mirror image of `{}`'s {}: reflected across the mirror plane of its limb, it lies {} mm from it",
        p.right.1,
        gname(g),
        p.left.1,
        gname(h),
        mm(d)
    );
    let hloc = robot.elem_loc(ElemKind::Geom, h, &robot.geoms[h].name);
    Some(
        cx.at_elem(ElemKind::Geom, g, &robot.geoms[g].name, msg)
            .label(format!("{} mm off the mirror place", mm(d)))
            .secondary(hloc, format!("mirror `{}`'s geom", p.left.1))
            .note(format!(
                "the two bodies' collision geoms match in type and size, but at the reference pose (qpos0) this one's place relative to its body, mirrored, lies {} mm from its partner's, beyond {} mm (place_tolerance, or geom_tolerance of its size); as the same part turned into the other body's frame it does not fit either: one side's shape was moved or mistyped, so that foot or limb touches the ground or the body {} mm away from where the other side's does",
                mm(d),
                mm(allowed(g)),
                mm(d)
            ))
            .help("place the geom at the mirror image of its partner's place (in a URDF the `xyz` of its collision `<origin>`, in MJCF its `pos`), or where the body's visual is")
            .subject(Subject::Geom(g))
            .measured(d, "m")
            .expected(allowed(g), "m")
            .with("place_mismatch", d),
    )
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
