//! Where `mirror-asymmetry` compares the sites that sensors read across the mirror plane: a
//! mirror pair of sensor sites must have one type and size, mirrored places on their bodies and
//! mirrored orientations, judged as the collision geoms' places are (`mirror_places`).

use crate::finding::{Finding, Subject};
use crate::model::mirror::mirror_in;
use crate::model::mjcf::ElemKind;
use crate::rules::Context;
use crate::util::fmt_num;

use super::mirror_asymmetry::{Pair, SIZE_NOISE, pairs};
use super::mirror_com::{
    Pose, mirror_plane, reference_pose, v_dot as dot, v_norm as norm, v_reflect, v_turn,
};

/// MuJoCo's `mjOBJ_SITE`: a sensor's object or reference frame is a site.
const OBJ_SITE: i32 = 6;

/// The size entries a site type uses (`mjGEOM_SPHERE` 2 … `mjGEOM_BOX` 6): a sphere its radius,
/// a capsule or cylinder radius and half-length, an ellipsoid or box three half-sizes.
fn used_sizes(t: i32) -> usize {
    match t {
        2 => 1,
        3 | 5 => 2,
        _ => 3,
    }
}

const TYPE_NAMES: [&str; 7] =
    ["plane", "hfield", "sphere", "capsule", "ellipsoid", "cylinder", "box"];

/// A site's bounding radius from its type and size, m.
fn bound(t: i32, s: [f64; 3]) -> f64 {
    match t {
        2 => s[0],
        3 => s[0] + s[1],
        5 => s[0].hypot(s[1]),
        _ => norm(s),
    }
}

/// The axes of a site whose direction its shape shows (columns of its frame): none for a
/// sphere, the long axis of a capsule or cylinder, and each box or ellipsoid axis whose half-size
/// differs from the other two beyond `close` (two equal half-sizes make their axes one shape).
fn shown_axes(t: i32, s: [f64; 3], close: &dyn Fn(f64, f64) -> bool) -> Vec<usize> {
    match t {
        2 => vec![],
        3 | 5 => vec![2],
        _ => (0..3).filter(|&k| (0..3).all(|i| i == k || !close(s[k], s[i]))).collect(),
    }
}

fn col(m: [f64; 9], k: usize) -> [f64; 3] {
    [m[k], m[3 + k], m[6 + k]]
}

/// Every site a sensor reads: its object, or the frame it is measured in.
fn sensed_sites(cx: &Context) -> Vec<bool> {
    let m = &cx.robot.mj;
    let mut v = vec![false; m.site_bodyid().len()];
    let (ot, oid, rt, rid) =
        (m.sensor_objtype(), m.sensor_objid(), m.sensor_reftype(), m.sensor_refid());
    for i in 0..ot.len() {
        for (t, id) in [(ot[i] as i32, oid[i]), (rt[i] as i32, rid[i])] {
            if t == OBJ_SITE
                && let Some(s) = usize::try_from(id).ok().and_then(|s| v.get_mut(s))
            {
                *s = true;
            }
        }
    }
    v
}

/// The sensor pairs of sites: by their names' side markers, then, for sites whose names carry
/// none, the one sensed site on each body of a body pair.
fn site_pairs(
    cx: &Context,
    body_pairs: &[(usize, usize)],
    names: &[String],
) -> Vec<(usize, usize)> {
    let body = cx.robot.mj.site_bodyid();
    let mut v = pairs(names, cx);
    let unmarked =
        |s: usize| mirror_in(&names[s], cx.spec, |x| names.iter().any(|y| y == x)).is_none();
    for &(bl, br) in body_pairs {
        let on = |b: usize| -> Vec<usize> {
            (0..names.len())
                .filter(|&s| !names[s].is_empty() && body[s] as usize == b && unmarked(s))
                .filter(|&s| !v.iter().any(|&(l, r)| l == s || r == s))
                .collect()
        };
        if let ([l], [r]) = (on(bl).as_slice(), on(br).as_slice()) {
            v.push((*l, *r));
        }
    }
    v
}

/// One comparison of a right site with its left partner under one map of the right side onto
/// the left (the mirror reflection, or the same part turned into the other body's frame): the
/// distance of the places and the largest angle between the shown axes' lines, degrees.
fn compare(
    vl: [f64; 3],
    vr: [f64; 3],
    axes: &[([f64; 3], [f64; 3])],
    map: &dyn Fn([f64; 3]) -> [f64; 3],
) -> (f64, f64) {
    let d = norm(super::mirror_com::v_sub(map(vr), vl));
    let deg = axes
        .iter()
        .map(|&(al, ar)| dot(map(ar), al).abs().min(1.0).acos().to_degrees())
        .fold(0.0, f64::max);
    (d, deg)
}

/// Mirror pairs of sensor sites (a force-torque site, a touch site) whose type, size, place on
/// the body or orientation is not the mirror image of the partner's ([`sites_differ`]'s
/// comparisons), one finding per pair.
pub(super) fn sites_differ(
    cx: &Context,
    body_pairs: &[(usize, usize)],
    pose: &Option<Pose>,
) -> Vec<Finding> {
    let robot = cx.robot;
    let m = &robot.mj;
    let sensed = sensed_sites(cx);
    let names: Vec<String> = (0..sensed.len())
        .map(|s| {
            let name = robot.elem(ElemKind::Site, s, "").and_then(|e| e.name.clone());
            if sensed[s] { name.unwrap_or_default() } else { String::new() }
        })
        .collect();
    let sp = site_pairs(cx, body_pairs, &names);
    if sp.is_empty() {
        return vec![];
    }
    let own;
    let pose = match pose {
        Some(p) => p,
        None => {
            own = reference_pose(robot);
            &own
        }
    };
    let (gtol, ptol, atol) =
        (cx.opt("geom_tolerance"), cx.opt("place_tolerance"), cx.opt("axis_tolerance"));
    let close = |x: f64, y: f64| (x - y).abs() <= SIZE_NOISE.max(gtol * x.abs().max(y.abs()));
    let (sbody, stype, ssize) = (m.site_bodyid(), m.site_type(), m.site_size());
    let mut out = Vec::new();
    for (sl, sr) in sp {
        let (bl, br) = (sbody[sl].max(0) as usize, sbody[sr].max(0) as usize);
        // Two sites on one body have no limb roots to mirror across: not judged.
        if bl == br {
            continue;
        }
        let bp = Pair {
            kind: ElemKind::Body,
            left: (bl, &robot.bodies[bl].name),
            right: (br, &robot.bodies[br].name),
        };
        let Some((n, _)) = mirror_plane(robot, pose, &bp) else { continue };
        let (tl, tr) = (stype[sl] as i32, stype[sr] as i32);
        let (zl, zr) = (ssize[sl], ssize[sr]);
        let mut parts: Vec<String> = Vec::new();
        let shape = |t: i32, s: [f64; 3]| {
            let v: Vec<String> =
                s[..used_sizes(t)].iter().map(|x| fmt_num(1000.0 * x, 4)).collect();
            format!("{} {} mm", TYPE_NAMES.get(t as usize).unwrap_or(&"site"), v.join("/"))
        };
        if tl != tr || !(0..used_sizes(tl)).all(|k| close(zl[k], zr[k])) {
            parts.push(format!("it is a {} against its mirror's {}", shape(tr, zr), shape(tl, zl)));
        }
        let (Some(ol), Some(or), Some(ml), Some(mr)) =
            (pose.xpos.get(bl), pose.xpos.get(br), pose.xmat.get(bl), pose.xmat.get(br))
        else {
            continue;
        };
        let (Some(pl), Some(pr), Some(rl), Some(rr)) = (
            pose.site_xpos.get(sl),
            pose.site_xpos.get(sr),
            pose.site_xmat.get(sl),
            pose.site_xmat.get(sr),
        ) else {
            continue;
        };
        let sub = super::mirror_com::v_sub;
        let (vl, vr) = (sub(*pl, *ol), sub(*pr, *or));
        let axes: Vec<([f64; 3], [f64; 3])> = if tl == tr {
            shown_axes(tl, zl, &close).into_iter().map(|k| (col(*rl, k), col(*rr, k))).collect()
        } else {
            vec![]
        };
        let reflect = |v: [f64; 3]| v_reflect(v, n);
        // A right vector in the world → the left body's frame, the same local coordinates.
        let turn = |v: [f64; 3]| v_turn(v, ml, mr);
        let allowed = ptol.max(gtol * bound(tr, zr));
        let fits = |(d, deg): (f64, f64)| d <= allowed && deg <= atol;
        let (mirrored, turned) = (compare(vl, vr, &axes, &reflect), compare(vl, vr, &axes, &turn));
        if parts.is_empty() && (fits(mirrored) || fits(turned)) {
            continue;
        }
        let (d, deg) = mirrored;
        let mm = |x: f64| fmt_num(1000.0 * x, 3);
        if d > allowed {
            parts.push(format!("reflected across the mirror plane of its limb, it lies {} mm from its mirror's place", mm(d)));
        }
        if deg > atol {
            parts.push(format!(
                "its shape's axis is turned {}° from its mirror's, reflected",
                fmt_num(deg, 3)
            ));
        }
        if parts.is_empty() {
            continue;
        }
        let sensor_of = |site: &str| {
            robot
                .src
                .list(ElemKind::Sensor)
                .iter()
                .find(|e| e.attrs.values().any(|o| o.value == site))
                .map(|e| format!(" (read by {} `{}`)", e.tag, e.name.clone().unwrap_or_default()))
                .unwrap_or_default()
        };
        let msg = format!(
            "site `{}`{} is not the mirror image of `{}`: {}",
            names[sr],
            sensor_of(&names[sr]),
            names[sl],
            parts.join("; ")
        );
        let lloc = robot.elem_loc(ElemKind::Site, sl, &names[sl]);
        out.push(
            cx.at_elem(ElemKind::Site, sr, &names[sr], msg)
                .label("sensor site differs from its mirror's")
                .secondary(lloc, format!("mirror site `{}`{}", names[sl], sensor_of(&names[sl])))
                .note(format!(
                    "a sensor reads what happens at its site: a force-torque site moved along the limb measures a different moment, a touch site turned across the limb covers other contact points, so the two sides' readings differ for mirrored motions and a policy trained on them learns a side; compared at the reference pose (qpos0) with the place tolerance of collision geoms ({} mm: place_tolerance, or geom_tolerance of its size) and axis_tolerance ({}°), as mirror images or as one part turned into the other body's frame",
                    mm(allowed),
                    fmt_num(atol, 3)
                ))
                .help("give the site its mirror partner's type and size, and the mirror image of its place and axes (`pos`, `zaxis`/`quat`/`euler`)")
                .subject(Subject::Body(br))
                .measured(d, "m")
                .expected(allowed, "m"),
        );
    }
    out
}
