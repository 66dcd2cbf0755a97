use std::collections::BTreeMap;

use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mirror::mirror_in;
use crate::model::mjcf::ElemKind;
use crate::model::{GeomType, Robot};
use crate::rules::inertia::isotropic_base_inertia::inertia_loc;
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};

use super::copied_mass::copied_masses;
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Reports a body whose compiled inertial — mass, centre of mass, principal axes and
    /// principal moments — is bit for bit that of another body although the two bodies share no
    /// geometry: no mesh of the same shape and no primitive geom of the same type and size. Bodies
    /// that are the same part (the legs of a quadruped built from one thigh mesh, or one
    /// module repeated) share a mesh or a primitive and are not reported; neither are bodies
    /// without any geom (camera and sensor frames), whose part cannot be told. Left and right
    /// halves of a part (paired by name as in `mirror-asymmetry`, which compares them) are not
    /// reported either: a mirrored part whose centre of mass lies on the plane of symmetry has
    /// the same inertial on both sides. Needs no spec and no
    /// threshold on the inertial: ten numbers agreeing to the last digit across two different
    /// parts are a copy, not a coincidence. Meshes are compared by content, not by asset: two
    /// files of one part (vertex count and extents in the mesh's principal frame agreeing to
    /// float noise, 1e-6 m) are one part.
    ///
    /// Also reports one mass copied over parts of different sizes: a compiled mass that, to
    /// the last digit, `copied_mass_min_bodies` (3) or more bodies with geometry of one robot
    /// (a URDF; an MJCF kinematic tree) share, together `copied_mass_share` (10 %) or more of
    /// that robot's mass, while their parts differ in size by `size_factor` (1.5) or more — the
    /// largest over the smallest of their radii of gyration about their principal axis of
    /// largest moment (√(I_max / m)), or of their extents (the cube root of the summed
    /// bounding-box volumes of their colliding geoms or of their other geoms, whichever is
    /// larger: a foot drawn as a box that collides through tip spheres is the box's size). Two
    /// robots of one scene are not compared. The KUKA LWR URDF's 2.0 kg on all
    /// seven links, radii of gyration 0.05–0.41 m; the Mini Pupper's 25 g on all 24 leg
    /// links. Parts that are one part (a mirrored pair, a hexapod's six legs, a modular arm's
    /// identical segments) have one size, and a group whose bodies all have one compiled
    /// inertial is the exact case above. A length 1.5× another's is a part 3.4× the volume
    /// (2.25× the moment at one mass): not one part made to a tolerance. Below the share, a
    /// copied mass moves little of the robot (sensor frames' 1 g).
    ///
    /// ## Why is this bad?
    /// An `<inertial>` block pasted from the body above (a common URDF/MJCF export or hand-edit
    /// slip) puts the wrong mass at the wrong place: its centre of mass sits where the other
    /// part's was, often outside the body, and the moments belong to another shape. The
    /// simulated robot's mass distribution — the trunk's pitch inertia, the load a joint
    /// carries, where the whole-body centre of mass lies — then differs from the hardware,
    /// and a balance policy trained on it leans or pitches on the real robot.
    ///
    /// ## How it is confirmed
    /// Static comparison of the compiled `body_mass`, `body_ipos`, `body_iquat` and
    /// `body_inertia`, and of the bodies' geoms (`geom_type`, `geom_size`, `geom_dataid`,
    /// `geom_aabb`).
    ///
    /// ## How to fix
    /// Take the body's own inertial from CAD or the manufacturer's URDF; if the two bodies
    /// really are one part, give them the same mesh or collision geometry.
    pub CopiedInertial {
        id: "copied-inertial",
        group: "inertia",
        level: Severity::Warning,
        probe: None,
        options: [
            opt("size_factor", 1.5, "ratio", Domain::AT_LEAST_ONE, "largest / smallest size (radius of gyration, or cube root of the collision bounding volume) of bodies sharing one mass from which they are different parts"),
            opt("copied_mass_min_bodies", 3.0, "bodies", Domain::AT_LEAST_ONE, "fewest bodies sharing one mass for the copied-mass case to judge them"),
            opt("copied_mass_share", 0.1, "fraction", Domain::FRACTION, "smallest share of the robot's mass the bodies sharing one mass carry for the copied-mass case to judge them"),
        ],
    }
}

/// The compiled inertial of body `b` as exact bit patterns (mass, COM, principal axes, moments).
fn key(robot: &Robot, b: usize) -> Option<[u64; 11]> {
    let m = &robot.mj;
    let mass = *m.body_mass().get(b)?;
    if !(mass > 0.0) {
        return None;
    }
    let (p, q, i) = (m.body_ipos().get(b)?, m.body_iquat().get(b)?, m.body_inertia().get(b)?);
    let v = [mass, p[0], p[1], p[2], q[0], q[1], q[2], q[3], i[0], i[1], i[2]];
    Some(v.map(|x| (x + 0.0).to_bits()))
}

/// Two compiled meshes whose vertex extents agree to this many metres on every axis (and that have
/// as many vertices) are one part exported twice: float noise only. MuJoCo stores a mesh's
/// vertices in its own principal frame, so the same part from two files compiles to the same
/// numbers.
const SAME_MESH_M: f64 = 1e-6;

/// What identifies a body's part: its meshes (vertex count and extents in the mesh's principal
/// frame) and its primitive geoms (type and size).
enum Part {
    Mesh(usize, [f64; 3]),
    Primitive(GeomType, [u64; 3]),
}

impl PartialEq for Part {
    fn eq(&self, o: &Part) -> bool {
        match (self, o) {
            (Part::Mesh(n, e), Part::Mesh(m, f)) => {
                n == m && (0..3).all(|k| (e[k] - f[k]).abs() <= SAME_MESH_M)
            }
            (Part::Primitive(t, s), Part::Primitive(u, r)) => t == u && s == r,
            _ => false,
        }
    }
}

fn mesh_part(robot: &Robot, mesh: usize) -> Option<Part> {
    let m = &robot.mj;
    let (a, n) = (*m.mesh_vertadr().get(mesh)?, *m.mesh_vertnum().get(mesh)?);
    let (a, n) = (usize::try_from(a).ok()?, usize::try_from(n).ok()?);
    let vert = m.mesh_vert().get(a..a + n)?;
    let mut e = [0.0; 3];
    for (k, ek) in e.iter_mut().enumerate() {
        let lo = vert.iter().map(|v| f64::from(v[k])).fold(f64::INFINITY, f64::min);
        let hi = vert.iter().map(|v| f64::from(v[k])).fold(f64::NEG_INFINITY, f64::max);
        *ek = hi - lo;
    }
    Some(Part::Mesh(n, e))
}

fn parts(robot: &Robot, b: usize) -> Vec<Part> {
    robot
        .geoms
        .iter()
        .filter(|g| g.body == b)
        .filter_map(|g| match usize::try_from(g.mesh) {
            Ok(mesh) if g.gtype == GeomType::Mesh => mesh_part(robot, mesh),
            _ => Some(Part::Primitive(g.gtype, g.size.map(|x| (x + 0.0).to_bits()))),
        })
        .collect()
}

impl Rule for CopiedInertial {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let mut groups: BTreeMap<[u64; 11], Vec<usize>> = BTreeMap::new();
        for b in robot.bodies.iter().filter(|b| b.id != 0) {
            if let Some(k) = key(robot, b.id) {
                groups.entry(k).or_default().push(b.id);
            }
        }
        for ids in groups.values().filter(|v| v.len() > 1) {
            let ps: Vec<Vec<Part>> = ids.iter().map(|&b| parts(robot, b)).collect();
            for (k, &b) in ids.iter().enumerate() {
                if ps[k].is_empty() {
                    continue;
                }
                let shares = |j: usize| ps[j].iter().any(|p| ps[k].contains(p));
                // A repeat of an earlier body's part, or no earlier body with geometry: nothing
                // to report here.
                if (0..k).any(shares) {
                    continue;
                }
                // Left and right halves of a part whose centre of mass lies on the plane of
                // symmetry have one inertial: the mirror pair is mirror-asymmetry's to compare.
                let name = robot.body_name(b);
                let mirror = mirror_in(name, cx.spec, |n| robot.bodies.iter().any(|x| x.name == n))
                    .map(|(_, m)| m);
                let Some(a) = (0..k)
                    .find(|&j| {
                        !ps[j].is_empty() && mirror.as_deref() != Some(robot.body_name(ids[j]))
                    })
                    .map(|j| ids[j])
                else {
                    continue;
                };
                out.push(finding(cx, a, b));
            }
        }
        out.extend(copied_masses(
            cx,
            cx.opt("size_factor"),
            cx.opt("copied_mass_min_bodies"),
            cx.opt("copied_mass_share"),
            |a, b| key(robot, a).is_some() && key(robot, a) == key(robot, b),
        ));
    }
}

fn finding(cx: &Context, a: usize, b: usize) -> Finding {
    let robot = cx.robot;
    let m = &robot.mj;
    let (an, bn) = (robot.body_name(a), robot.body_name(b));
    let mass = m.body_mass()[b];
    let p = m.body_ipos()[b];
    let i = m.body_inertia()[b];
    let v3 =
        |v: [f64; 3]| format!("({}, {}, {})", fmt_num(v[0], 4), fmt_num(v[1], 4), fmt_num(v[2], 4));
    let msg = format!(
        "body `{bn}` has exactly the inertial of body `{an}` (mass {} kg, centre of mass {} m, principal moments {} kg·m²) though the two share no geometry",
        fmt_num(mass, 4),
        v3(p),
        v3(i)
    );
    let (aloc, bloc) =
        (robot.elem_loc(ElemKind::Body, a, an), robot.elem_loc(ElemKind::Body, b, bn));
    let loc = inertia_loc(robot, bn).unwrap_or(bloc);
    let src = inertia_loc(robot, an).unwrap_or(aloc);
    cx.finding(msg, loc)
        .element(format!("body {bn}"), bloc)
        .label("the same ten numbers as another part's")
        .secondary(src, format!("body `{an}`'s inertial"))
        .note("mass, centre of mass, principal axes and moments agree to the last digit while the bodies have no mesh and no primitive geom in common: an inertial block copied from another body, which puts that part's mass distribution on this one")
        .help(format!("give `{bn}` its own inertial from CAD or the manufacturer's URDF (or, if the two really are one part, the same geometry)"))
        .subject(Subject::Body(b))
        .measured(mass, "kg")
}
