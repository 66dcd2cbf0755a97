//! `copied-inertial`'s second case: one mass written on several bodies whose parts differ in
//! size (the KUKA LWR URDF's 2 kg on all seven links, from the flange's few centimetres to the
//! shoulder's 0.4 m).
use std::collections::BTreeMap;

use crate::finding::{Finding, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::source::{Loc, XNode};
use crate::model::{Format, Robot};
use crate::rules::Context;
use crate::util::fmt_num;

/// A body of a one-mass group: its id and its two sizes (m).
struct Sized {
    body: usize,
    /// Radius of gyration about the principal axis of largest moment, √(I_max / m).
    gyration: f64,
    /// Cube root of the summed bounding-box volumes of its colliding geoms or of its other
    /// geoms, whichever is larger (a foot drawn as a box and colliding through tip spheres is
    /// the box's size).
    extent: f64,
}

/// Where body `name`'s mass is written: URDF `<inertial><mass value>`, MJCF `<inertial mass>`.
fn mass_loc(robot: &Robot, name: &str) -> Option<Loc> {
    let mut found = None;
    robot.tree.walk(&mut |n: &XNode| {
        if found.is_some() || !(n.tag == "body" || n.tag == "link") || n.name() != Some(name) {
            return;
        }
        let Some(i) = n.children_tagged("inertial").next() else { return };
        found = i
            .attr("mass")
            .map(|a| a.loc)
            .or_else(|| {
                i.children_tagged("mass").next().and_then(|m| m.attr("value")).map(|a| a.loc)
            })
            .or(Some(i.loc));
    });
    found
}

fn sized(robot: &Robot, b: usize) -> Option<Sized> {
    let m = &robot.mj;
    let mass = *m.body_mass().get(b)?;
    let inertia = m.body_inertia().get(b)?;
    let aabb = m.geom_aabb();
    let own: Vec<usize> = robot.geoms.iter().filter(|g| g.body == b).map(|g| g.id).collect();
    if own.is_empty() || !(mass > 0.0) {
        return None;
    }
    let volume = |collides: bool| -> f64 {
        own.iter()
            .filter(|&&g| robot.geoms[g].collides() == collides)
            .filter_map(|&g| aabb.get(g))
            .map(|a| 8.0 * a[3] * a[4] * a[5])
            .sum()
    };
    let volume = volume(true).max(volume(false));
    let imax = inertia[0].max(inertia[1]).max(inertia[2]);
    Some(Sized { body: b, gyration: (imax / mass).sqrt(), extent: volume.cbrt() })
}

/// The largest ratio of one size over the group, with the bodies at its two ends (small, large).
fn spread(group: &[Sized], size: fn(&Sized) -> f64) -> Option<(f64, usize, usize)> {
    let lo = group.iter().filter(|s| size(s) > 0.0).min_by(|a, b| size(a).total_cmp(&size(b)))?;
    let hi = group.iter().max_by(|a, b| size(a).total_cmp(&size(b)))?;
    Some((size(hi) / size(lo), lo.body, hi.body))
}

/// The robot body `b` belongs to: a URDF is one robot (MuJoCo's importer hangs each chain of a
/// welded root from the world); in an MJCF, the kinematic tree (the body below the world).
fn robot_of(robot: &Robot, b: usize) -> usize {
    if robot.format == Format::Urdf {
        return 0;
    }
    let mut x = b;
    while let Some(p) = robot.bodies.get(x).map(|y| y.parent).filter(|&p| p != 0 && p != x) {
        x = p;
    }
    x
}

/// One finding per mass that at least `min_bodies` bodies with geometry of one robot state, carrying
/// `min_share` of the robot's mass or more, whose parts differ in size by `size_factor` or more
/// (radius of gyration or geometry extent). A group whose bodies all have one compiled inertial
/// is the exact copy's (reported per pair, or one part) and not judged here.
pub(super) fn copied_masses(
    cx: &Context,
    size_factor: f64,
    min_bodies: f64,
    min_share: f64,
    same_inertial: impl Fn(usize, usize) -> bool,
) -> Vec<Finding> {
    let robot = cx.robot;
    let mut totals: BTreeMap<usize, f64> = BTreeMap::new();
    let mut groups: BTreeMap<(usize, u64), Vec<Sized>> = BTreeMap::new();
    for b in robot.bodies.iter().filter(|b| b.id != 0) {
        let tree = robot_of(robot, b.id);
        *totals.entry(tree).or_default() += b.mass;
        if let Some(s) = sized(robot, b.id) {
            groups.entry((tree, (b.mass + 0.0).to_bits())).or_default().push(s);
        }
    }
    let mut out = Vec::new();
    for (&(tree, _), group) in &groups {
        let n = group.len();
        let mass = robot.bodies[group[0].body].mass;
        let total = totals.get(&tree).copied().unwrap_or(0.0);
        if (n as f64) < min_bodies || !(total > 0.0) || mass * n as f64 / total < min_share {
            continue;
        }
        if group.iter().all(|s| same_inertial(group[0].body, s.body)) {
            continue;
        }
        let Some(g) = spread(group, |s| s.gyration) else { continue };
        let Some(e) = spread(group, |s| s.extent) else { continue };
        let (ratio, lo, hi, what) = if g.0 >= e.0 {
            (g.0, g.1, g.2, "radius of gyration")
        } else {
            (e.0, e.1, e.2, "extent")
        };
        if !(ratio >= size_factor) {
            continue;
        }
        out.push(finding(cx, group, mass, total, (ratio, lo, hi, what), size_factor));
    }
    out
}

fn finding(
    cx: &Context,
    group: &[Sized],
    mass: f64,
    total: f64,
    (ratio, lo, hi, what): (f64, usize, usize, &str),
    size_factor: f64,
) -> Finding {
    let robot = cx.robot;
    let n = group.len();
    let size = |b: usize| {
        let s = group.iter().find(|s| s.body == b).expect("a group member");
        if what == "radius of gyration" { s.gyration } else { s.extent }
    };
    let first = group[0].body;
    let name = |b: usize| robot.body_name(b);
    let loc = |b: usize| {
        mass_loc(robot, name(b)).unwrap_or_else(|| robot.elem_loc(ElemKind::Body, b, name(b)))
    };
    let msg = format!(
        "{n} bodies state one mass, {} kg ({} % of the robot's {} kg), though their parts differ {}× in size: {what} {} m (`{}`) to {} m (`{}`)",
        fmt_num(mass, 4),
        fmt_num(100.0 * mass * n as f64 / total, 3),
        fmt_num(total, 4),
        fmt_num(ratio, 3),
        fmt_num(size(lo), 3),
        name(lo),
        fmt_num(size(hi), 3),
        name(hi)
    );
    let mut f = cx
        .finding(msg, loc(first))
        .element(
            format!("body {}", name(first)),
            robot.elem_loc(ElemKind::Body, first, name(first)),
        )
        .label(format!("{} kg, as on {} other bodies", fmt_num(mass, 4), n - 1));
    for b in [lo, hi].into_iter().filter(|&b| b != first) {
        f = f.secondary(loc(b), format!("`{}`: the same {} kg", name(b), fmt_num(mass, 4)));
    }
    f.note(format!(
        "masses taken from CAD or weighed differ from part to part; one value to the last digit on {n} parts whose {what} spans {}× (from {} up) is a value copied across the file, not the parts' masses: the robot's mass distribution, the load each joint carries and the whole-body centre of mass are the copy's",
        fmt_num(ratio, 3),
        fmt_num(size_factor, 3)
    ))
    .help("give each body its own mass from CAD or the manufacturer's data (or weigh the parts)")
    .subject(Subject::Body(first))
    .measured(ratio, "×")
    .expected(size_factor, "×")
    .with("bodies", n as f64)
}
