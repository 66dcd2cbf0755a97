use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::source::{Loc, XNode};
use crate::model::{GeomType, JointType, Robot};
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds a floating base (a body with a free joint) whose rotational inertia is the same
    /// about every axis — a placeholder such as a sphere's or a cube's — while the body's own
    /// shape in the file is far from round. The shape is the bounding box, in the body's frame,
    /// of its geoms (every geom but planes, as compiled: primitives and mesh bounding boxes) and
    /// of the points where its child bodies attach. A uniform solid of that box would have
    /// principal moments that differ by at least `min_ratio`; a body with no geoms and no
    /// children gives no evidence and is not judged. Only a compiled inertia whose three moments
    /// agree within `isotropy_tolerance` counts as a placeholder: a measured inertia is never
    /// exactly isotropic.
    ///
    /// ## Why is this bad?
    /// The base carries most of a legged robot's mass; its inertia sets how fast it pitches and
    /// rolls under the legs' forces. A trunk that is long and flat has a much larger pitch and
    /// yaw inertia than roll inertia; an isotropic guess gets at least one of them wrong by the
    /// ratio reported, so the simulated body pitches or rolls too easily or too sluggishly and a
    /// policy's balance does not transfer. MuJoCo XML reference, `body/inertial`: diaginertia is
    /// the principal moments in the inertial frame.
    ///
    /// ## How it is confirmed
    /// Static: compiled `body_inertia` and the compiled geoms' and child bodies' positions; no
    /// simulation measures whether an inertia is a placeholder.
    ///
    /// ## How to fix
    /// Use the inertia the CAD or the manufacturer's URDF gives for the assembled base (with
    /// `quat` or `fullinertia` for its axes), or remove `<inertial>` so MuJoCo computes it from
    /// collision geoms that match the body's shape.
    pub IsotropicBaseInertia {
        id: "isotropic-base-inertia",
        group: "inertia",
        level: Severity::Warning,
        probe: None,
        options: [
            opt("isotropy_tolerance", 0.001, "fraction", Domain::NON_NEGATIVE, "relative spread of the three moments below which an inertia counts as isotropic"),
            opt("min_ratio", 3.0, "ratio", Domain::AT_LEAST_ONE, "largest / smallest moment of a uniform solid of the body's extents from which the body counts as not round"),
        ],
    }
}

/// Rotates `v` by the unit quaternion `q` (w, x, y, z).
fn rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let [w, x, y, z] = q;
    let t = [2.0 * (y * v[2] - z * v[1]), 2.0 * (z * v[0] - x * v[2]), 2.0 * (x * v[1] - y * v[0])];
    [
        v[0] + w * t[0] + (y * t[2] - z * t[1]),
        v[1] + w * t[1] + (z * t[0] - x * t[2]),
        v[2] + w * t[2] + (x * t[1] - y * t[0]),
    ]
}

/// Full extents (x, y, z) in body `b`'s frame of its non-plane geoms' bounding boxes and its
/// children's attachment points; `None` without any of them.
pub fn body_extents(robot: &Robot, b: usize) -> Option<[f64; 3]> {
    extents_of(robot, b, false)
}

/// As [`body_extents`]; with `origin`, the body's own origin (where its joints sit) counts as
/// one more point of it.
pub fn extents_of(robot: &Robot, b: usize, origin: bool) -> Option<[f64; 3]> {
    let m = &robot.mj;
    let (aabb, gpos, gquat) = (m.geom_aabb(), m.geom_pos(), m.geom_quat());
    let mut pts: Vec<[f64; 3]> = if origin { vec![[0.0; 3]] } else { Vec::new() };
    for g in robot.geoms.iter().filter(|g| g.body == b && g.gtype != GeomType::Plane) {
        let (Some(bb), Some(p), Some(q)) = (aabb.get(g.id), gpos.get(g.id), gquat.get(g.id)) else {
            continue;
        };
        for corner in 0..8 {
            let s = |i: usize| if corner >> i & 1 == 1 { 1.0 } else { -1.0 };
            let local = [bb[0] + s(0) * bb[3], bb[1] + s(1) * bb[4], bb[2] + s(2) * bb[5]];
            let r = rotate(*q, local);
            pts.push([r[0] + p[0], r[1] + p[1], r[2] + p[2]]);
        }
    }
    let bpos = m.body_pos();
    for c in robot.bodies.iter().filter(|c| c.id != 0 && c.parent == b) {
        if let Some(p) = bpos.get(c.id) {
            pts.push(*p);
        }
    }
    if pts.len() < 2 {
        return None;
    }
    let mut e = [0.0; 3];
    for (i, ei) in e.iter_mut().enumerate() {
        let lo = pts.iter().map(|p| p[i]).fold(f64::INFINITY, f64::min);
        let hi = pts.iter().map(|p| p[i]).fold(f64::NEG_INFINITY, f64::max);
        *ei = hi - lo;
    }
    e.iter().all(|x| x.is_finite()).then_some(e)
}

/// Where the body's inertia is written: the `diaginertia`/`fullinertia` of its `<inertial>`
/// (MJCF) or the `<inertia>` of its link's `<inertial>` (URDF).
pub(crate) fn inertia_loc(robot: &Robot, name: &str) -> Option<Loc> {
    let mut found = None;
    robot.tree.walk(&mut |n: &XNode| {
        if found.is_some() || !(n.tag == "body" || n.tag == "link") || n.name() != Some(name) {
            return;
        }
        let Some(i) = n.children_tagged("inertial").next() else { return };
        found = ["diaginertia", "fullinertia"]
            .iter()
            .find_map(|a| i.attr(a).map(|a| a.loc))
            .or_else(|| i.children_tagged("inertia").next().map(|x| x.loc))
            .or(Some(i.loc));
    });
    found
}

impl Rule for IsotropicBaseInertia {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let inertia = robot.mj.body_inertia();
        let (tol, min_ratio) = (cx.opt("isotropy_tolerance"), cx.opt("min_ratio"));
        let mut bases: Vec<usize> =
            robot.joints.iter().filter(|j| j.jtype == JointType::Free).map(|j| j.body).collect();
        bases.dedup();
        for b in bases {
            let Some(i) = inertia.get(b) else { continue };
            let (lo, hi) =
                (i.iter().copied().fold(f64::INFINITY, f64::min), i[0].max(i[1]).max(i[2]));
            if !(lo > 0.0) || (hi - lo) > tol * hi {
                continue;
            }
            let Some(e) = body_extents(robot, b) else { continue };
            let sq = e.map(|x| x * x);
            let box_m = [sq[1] + sq[2], sq[0] + sq[2], sq[0] + sq[1]];
            let bmax = box_m.iter().copied().fold(0.0, f64::max);
            let bmin = box_m.iter().copied().fold(f64::INFINITY, f64::min);
            let ratio = if bmin > 0.0 { bmax / bmin } else { f64::INFINITY };
            if !(ratio >= min_ratio) {
                continue;
            }
            let name = robot.body_name(b);
            let msg = format!(
                "floating base `{name}` has the same inertia {} kg·m² about every axis, but the body spans {} × {} × {} m: a uniform solid of that shape has moments differing {}×",
                fmt_num(lo, 4),
                fmt_num(e[0], 3),
                fmt_num(e[1], 3),
                fmt_num(e[2], 3),
                if ratio.is_finite() { fmt_num(ratio, 2) } else { "∞".into() }
            );
            let balanced = super::isotropic_link_inertia::balances_inertia(robot);
            let msg = if balanced {
                format!("{msg}{}", super::isotropic_link_inertia::BALANCED)
            } else {
                msg
            };
            let eloc = robot.elem_loc(ElemKind::Body, b, name);
            let loc = inertia_loc(robot, name).unwrap_or(eloc);
            let f = cx
                .finding(msg, loc)
                .element(format!("body {name}"), eloc)
                .label("isotropic: a sphere's or a cube's inertia")
                .note("extents from the body's geoms (as compiled) and the points where its child bodies attach; a measured inertia of a long, flat trunk has pitch and yaw moments several times its roll moment")
                .help("use the assembled base's inertia from CAD or the manufacturer's URDF (with quat or fullinertia), or drop <inertial> so MuJoCo computes it from collision geoms of the body's shape")
                .subject(Subject::Body(b))
                .measured(1.0, "ratio")
                .expected(ratio, "ratio");
            out.push(f);
        }
    }
}
