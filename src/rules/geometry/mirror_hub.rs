//! The centre of mass of a body on the mirror plane (split from `mirror-asymmetry`): a body
//! with no side that carries mirror pairs — a trunk, a pelvis — whose own centre of mass lies
//! off the plane its limbs mirror across (Darwin-OP's trunk, 38.7 mm right of the centre line).

use crate::finding::{Finding, Subject};
use crate::model::Format;
use crate::model::mirror::mirror_in;
use crate::model::mjcf::ElemKind;
use crate::rules::Context;
use crate::util::fmt_num;

use super::mirror_asymmetry::Pair;
use super::mirror_com::{Pose, com_loc, limb_roots, mirror_plane, v_dot, v_norm, v_sub};

/// Angle within which the mirror planes of the pairs one body carries must agree for them to
/// define one plane (deg): CAD exports place mirrored limbs' roots within hundredths of a
/// degree; a limb root placed off (a hip bracket 75 mm off its mirror) tilts its pair's plane
/// by degrees, and the body's plane is then not known.
const PLANE_AGREEMENT_DEG: f64 = 5.0;

/// The link a hub stands for and the centre of mass its own `<inertial>` states, in the world
/// at the reference pose: (name, centre of mass). An MJCF body's compiled centre of mass. A
/// URDF link's own `<inertial><origin xyz>` in its link frame (the compiled body's frame), so
/// links MuJoCo's importer fuses into it (a payload written as its own fixed link) are not
/// counted; the world body (hub 0) of a URDF is the root link and the links fixed to it, which
/// the importer fuses into the world: the heaviest of them with no side marker (Darwin-OP's
/// `MP_BODY`, fixed 0.35 m above its massless `base_link`), placed by the fixed joints'
/// origins. `None` when the file states no inertial.
fn own_com(cx: &Context, pose: &Pose, b: usize) -> Option<(String, [f64; 3])> {
    let robot = cx.robot;
    if robot.format != Format::Urdf {
        let name = robot.body_name(b);
        com_loc(robot, name)?;
        return (b != 0).then(|| pose.xipos.get(b).map(|c| (name.to_string(), *c)))?;
    }
    let com_in = |name: &str, o: [f64; 3], m: [f64; 9]| -> Option<(f64, [f64; 3])> {
        let link = robot.tree.children_tagged("link").find(|l| l.name() == Some(name))?;
        let inertial = link.children_tagged("inertial").next()?;
        let mass = inertial.children_tagged("mass").next().and_then(|x| x.get("value"));
        let mass = mass.and_then(crate::model::c_number).unwrap_or(0.0);
        let origin = inertial.children_tagged("origin").next();
        let p = triple(origin.and_then(|o| o.get("xyz")))?;
        Some((mass, [0, 1, 2].map(|i| o[i] + (0..3).map(|k| m[3 * i + k] * p[k]).sum::<f64>())))
    };
    if b != 0 {
        let name = robot.body_name(b);
        let (o, m) = (*pose.xpos.get(b)?, *pose.xmat.get(b)?);
        return com_in(name, o, m).map(|(_, c)| (name.to_string(), c));
    }
    // The root link and the links fixed to it, with their frames (the root's is the world's).
    let root = crate::rules::contact::welded_legged_base::root_link(robot)?.name()?.to_string();
    let mut group: Vec<(String, [f64; 3], [f64; 9])> =
        vec![(root, [0.0; 3], [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0])];
    let mut i = 0;
    while i < group.len() && group.len() <= robot.bodies.len() + 64 {
        let (parent, o, m) = group[i].clone();
        for j in robot.tree.children_tagged("joint").filter(|j| j.get("type") == Some("fixed")) {
            let (Some(p), Some(c)) = (
                j.children_tagged("parent").next().and_then(|x| x.get("link")),
                j.children_tagged("child").next().and_then(|x| x.get("link")),
            ) else {
                continue;
            };
            if p != parent || group.iter().any(|g| g.0 == c) {
                continue;
            }
            let origin = j.children_tagged("origin").next();
            let (Some(xyz), Some(rpy)) = (
                triple(origin.and_then(|x| x.get("xyz"))),
                triple(origin.and_then(|x| x.get("rpy"))),
            ) else {
                continue;
            };
            let r = rpy_matrix(rpy);
            let o2 = [0, 1, 2].map(|a| o[a] + (0..3).map(|k| m[3 * a + k] * xyz[k]).sum::<f64>());
            let m2: [f64; 9] = std::array::from_fn(|e| {
                let (a, c) = (e / 3, e % 3);
                (0..3).map(|k| m[3 * a + k] * r[3 * k + c]).sum()
            });
            group.push((c.to_string(), o2, m2));
        }
        i += 1;
    }
    let exists = |x: &str| robot.tree.children_tagged("link").any(|l| l.name() == Some(x));
    group
        .iter()
        .filter(|g| mirror_in(&g.0, cx.spec, exists).is_none())
        .filter_map(|g| com_in(&g.0, g.1, g.2).map(|(mass, c)| (mass, g.0.clone(), c)))
        .filter(|x| x.0 > 0.0)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, name, c)| (name, c))
}

/// Three numbers written in a URDF attribute; an absent one is zero, as URDF reads it.
fn triple(v: Option<&str>) -> Option<[f64; 3]> {
    let Some(v) = v else { return Some([0.0; 3]) };
    let x: Vec<f64> = v.split_whitespace().filter_map(crate::model::c_number).collect();
    Some([*x.first()?, *x.get(1)?, *x.get(2)?])
}

/// A URDF `rpy` as a row-major rotation: Rz(yaw)·Ry(pitch)·Rx(roll).
fn rpy_matrix([r, p, y]: [f64; 3]) -> [f64; 9] {
    let (sr, cr, sp, cp, sy, cy) = (r.sin(), r.cos(), p.sin(), p.cos(), y.sin(), y.cos());
    [
        cy * cp,
        cy * sp * sr - sy * cr,
        cy * sp * cr + sy * sr,
        sy * cp,
        sy * sp * sr + cy * cr,
        sy * sp * cr - cy * sr,
        -sp,
        cp * sr,
        cp * cr,
    ]
}

/// Bodies with no side (no side marker in the name, in no mirror pair) that carry mirror pairs
/// — the pair's limb roots ([`limb_roots`]) both hang from the body — and whose own stated
/// centre of mass lies off the plane those pairs mirror across by more than `com_tolerance` and
/// `plane_com_fraction` of the half spacing of the widest pair's limb roots. The plane is the
/// widest pair's; every pair the body carries must mirror across it (normals within
/// [`PLANE_AGREEMENT_DEG`], midpoints within `com_tolerance`), else the body is not judged.
pub(super) fn hub_com_off(
    cx: &Context,
    body_pairs: &[(usize, usize)],
    pose: &Option<Pose>,
) -> Vec<Finding> {
    let robot = cx.robot;
    let Some(pose) = pose.as_ref() else { return Vec::new() };
    let paired = |b: usize| body_pairs.iter().any(|&(l, r)| l == b || r == b);
    let exists = |x: &str| robot.bodies.iter().any(|o| o.name == x);
    let parent = |b: usize| robot.bodies.get(b).map_or(0, |x| x.parent);
    // Each pair's hub (the body both limb roots hang from) with the pair's plane and the half
    // spacing of its limb roots.
    let mut planes: Vec<Carried> = Vec::new();
    for &(l, r) in body_pairs {
        let (ra, rb) = limb_roots(robot, l, r);
        let hub = parent(ra);
        if hub != parent(rb) || ra == rb {
            continue;
        }
        let p = Pair {
            kind: ElemKind::Body,
            left: (l, robot.body_name(l)),
            right: (r, robot.body_name(r)),
        };
        let (Some((n, off)), Some(pa), Some(pb)) =
            (mirror_plane(robot, pose, &p), pose.xpos.get(ra), pose.xpos.get(rb))
        else {
            continue;
        };
        planes.push(Carried { hub, l, r, n, off, half: v_norm(v_sub(*pa, *pb)) / 2.0 });
    }
    let (tol, fraction) = (cx.opt("com_tolerance"), cx.opt("plane_com_fraction"));
    let mut hubs: Vec<usize> = planes.iter().map(|p| p.hub).collect();
    hubs.sort_unstable();
    hubs.dedup();
    // The robot's base: a floating base, or a legged URDF's root (the world body the importer
    // fused it into). A hub is judged when it is the base or hangs from it through bodies
    // with no side (a torso over a waist joint): the middle of a robot that stands on its
    // limbs, not a gripper's palm between its fingers.
    let mut bases = crate::rules::contact::feet::floating_bases(robot);
    if robot.format == Format::Urdf
        && crate::rules::contact::welded_legged_base::urdf_legs(robot).is_some()
    {
        bases.push(0);
    }
    let sided = |b: usize| paired(b) || mirror_in(robot.body_name(b), cx.spec, exists).is_some();
    let on_base = |hub: usize| {
        let mut b = hub;
        for _ in 0..=robot.bodies.len() {
            if bases.contains(&b) {
                return true;
            }
            if b == 0 || sided(b) {
                return false;
            }
            b = parent(b);
        }
        false
    };
    let mut out = Vec::new();
    for hub in hubs {
        if !on_base(hub) {
            continue;
        }
        let name = robot.body_name(hub);
        let world = hub == 0 && robot.format == Format::Urdf;
        if !world
            && (hub == 0
                || paired(hub)
                || name.is_empty()
                || mirror_in(name, cx.spec, exists).is_some()
                || !(robot.bodies[hub].mass > 0.0))
        {
            continue;
        }
        let mine: Vec<&Carried> = planes.iter().filter(|p| p.hub == hub).collect();
        let Some(widest) = mine.iter().copied().max_by(|a, b| a.half.total_cmp(&b.half)) else {
            continue;
        };
        let (n, off, half) = (widest.n, widest.off, widest.half);
        // Every pair the body carries mirrors across the widest pair's plane (a plane and its
        // opposite normal are one plane).
        let agree = mine.iter().all(|p| {
            let c = v_dot(p.n, n);
            c.abs() >= PLANE_AGREEMENT_DEG.to_radians().cos()
                && (p.off * c.signum() - off).abs() <= tol
        });
        if !agree {
            continue;
        }
        let Some((link, com)) = own_com(cx, pose, hub) else { continue };
        let dist = v_dot(com, n) - off;
        let allowed = tol.max(fraction * half);
        if !(dist.abs() > allowed) {
            continue;
        }
        out.push(finding(cx, hub, &link, &mine, dist, allowed, half));
    }
    out
}

/// A mirror pair carried by `hub`: its left and right bodies, its mirror plane (unit normal,
/// offset along it) and the half spacing of its limb roots (m).
struct Carried {
    hub: usize,
    l: usize,
    r: usize,
    n: [f64; 3],
    off: f64,
    half: f64,
}

fn finding(
    cx: &Context,
    hub: usize,
    name: &str,
    pairs: &[&Carried],
    dist: f64,
    allowed: f64,
    half: f64,
) -> Finding {
    let robot = cx.robot;
    let mm = |x: f64| fmt_num(1000.0 * x, 3);
    let mut names: Vec<String> = Vec::new();
    for p in pairs {
        let both = format!("`{}`/`{}`", robot.body_name(p.l), robot.body_name(p.r));
        if !names.contains(&both) {
            names.push(both);
        }
    }
    let shown = if names.len() > 3 {
        format!("{} and {} more", names[..3].join(", "), names.len() - 3)
    } else {
        names.join(", ")
    };
    let loc = com_loc(robot, name).unwrap_or_else(|| robot.root_loc());
    let bloc = if hub == 0 {
        let link = robot.tree.children_tagged("link").find(|l| l.name() == Some(name));
        link.map_or(loc, |l| l.attr("name").map_or(l.loc, |a| a.loc))
    } else {
        robot.elem_loc(ElemKind::Body, hub, name)
    };
    let kw = if robot.format == Format::Urdf { "link" } else { "body" };
    cx.finding(
        format!(
            "{kw} `{name}` carries mirror pairs ({shown}) but its own centre of mass lies {} mm off the plane they mirror across",
            mm(dist.abs())
        ),
        loc,
    )
    .element(format!("{kw} {name}"), bloc)
    .label(format!("centre of mass {} mm off the mirror plane", mm(dist.abs())))
    .note(format!(
        "the limbs this body carries are mirror images across one plane, so the body they hang from is the middle of a mirror-symmetric robot; its centre of mass lies {} mm to one side, {} % of the way from the plane to the widest pair's roots ({} mm), beyond {} mm (com_tolerance, or plane_com_fraction of that distance): an inertial copied from a CAD frame whose axes differ from the body's, or a coordinate's sign lost; limbs at that spacing would carry {} % of its weight on one side, and the policy learns to lean against a weight the real body does not have",
        mm(dist.abs()),
        fmt_num(100.0 * dist.abs() / half, 3),
        mm(half),
        mm(allowed),
        fmt_num(50.0 * (1.0 + (dist.abs() / half).min(1.0)), 3)
    ))
    .help("move the centre of mass onto the mirror plane (the lateral coordinate of the body's <inertial> in the body's frame), or take it from the CAD; a payload that really sits to one side is best written as its own body or link, with its own inertial")
    .subject(if hub == 0 { Subject::Model } else { Subject::Body(hub) })
    .measured(dist.abs(), "m")
    .expected(allowed, "m")
}
