use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::source::{Loc, XNode};
use crate::model::{Format, GeomType, JointType, Robot};
use crate::rules::geometry::oversized_weight::{geom_mass_stated, mass_from_geoms, overload};
use crate::rules::{Context, Domain, Rule, RuleMeta, in_subtree, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds a colliding primitive (sphere, capsule, cylinder, box, ellipsoid) of a moving link
    /// that is larger than the robot itself and heavier than the link could be: its largest
    /// dimension exceeds the span of the robot's joints (the greatest distance between two
    /// joint anchors of its kinematic tree at the keyframe, hinges, slides and balls; a
    /// floating base's coordinates are not joints of the robot), and the primitive, filled
    /// with the lightest material a robot part is made of (`min_density`, 10 kg/m³ by
    /// default: rigid foam, or a closed 1 mm plastic shell half a metre across), would weigh
    /// more than the link. Says by how much on both counts. Typical causes: a length written in
    /// millimetres where MuJoCo and URDF read metres, a placeholder shape left by an exporter (a
    /// 2 m cylinder of radius 1 m on a 27 kg waist). The root link of a URDF (which MuJoCo's
    /// importer fuses into the world body) is judged with its `<inertial>` mass. Not judged:
    /// the world body of an MJCF (a floor, a terrain, a scene's fixed objects), bodies fixed to
    /// the world, kinematic trees with fewer than two joints (a scene's objects, a door),
    /// wheels (their shape is round about a hinge that turns without end), meshes (see
    /// `mesh-scale`). A large light bumper or shell within the robot's span and a heavy chassis
    /// larger than its few joints' span are not reported.
    ///
    /// A link whose mass MuJoCo computes from its geoms (no `<inertial>`, or `<compiler
    /// inertiafromgeom="true">`: 1000 kg/m³ by default) weighs what its shape gives, so the
    /// mass test cannot fail; it is judged by its weight instead: the largest gravity torque
    /// of the subtree it hangs in, over the range of each hinge that carries it (from the link
    /// up to its tree's top), against that hinge's actuator effort limit (`forcerange`, or a
    /// `<motor>`'s ctrlrange × gain, × the moment arm, capped by the joint's
    /// `actuatorfrcrange`). A floating base is tilted on its legs:
    /// its own weight about each hinge between it and a foot (not a wheel), against every
    /// such actuated hinge's limit projected on that axis (more than the legs can give). A
    /// geom that states its own `mass` is judged by the mass test only. A 2 m cylinder at 1000 kg/m³
    /// weighs 6.3 t; no joint of a robot built around a link holds that. Not judged this way:
    /// joints without an actuator or with an unlimited one, models that close a chain with a
    /// `connect` or `weld` equality (the joints share the load).
    ///
    /// ## Why is this bad?
    /// Collision geometry decides where the robot touches the world and itself. A shape larger
    /// than the whole robot makes contacts where the robot is not: it rests on the floor
    /// instead of the feet, hits tables it never reaches, and collides with the robot's own
    /// limbs in every pose, so contact forces and a policy trained on them have nothing to do
    /// with the real machine.
    ///
    /// ## How it is confirmed
    /// Static: the compiled shape's size, the joint anchors at the keyframe (or qpos0) and the
    /// body masses (a URDF root link's `<inertial><mass>`); for a link whose mass comes from
    /// its geoms, the subtree masses and centres of mass at the keyframe, the joints' axes and
    /// ranges, and the actuators' force limits and gears.
    ///
    /// ## How to fix
    /// Write the shape's size in metres as the link's real extent (a millimetre value divided
    /// by 1000), or replace the placeholder by primitives (or a convex mesh) that cover the
    /// link's visual geometry.
    pub OversizedCollisionPrimitive {
        id: "oversized-collision-primitive",
        group: "geometry",
        level: Severity::Warning,
        probe: None,
        options: [
            opt("min_density", 10.0, "kg/m³", Domain::POSITIVE, "the lightest a robot part is: a primitive that would weigh more than its link even at this density is not the link's shape"),
        ],
    }
}

/// Volume of a primitive of compiled size `s` (m³); `None` for meshes, planes, height fields.
pub fn primitive_volume(gtype: GeomType, s: [f64; 3]) -> Option<f64> {
    use std::f64::consts::PI;
    Some(match gtype {
        GeomType::Sphere => 4.0 / 3.0 * PI * s[0].powi(3),
        GeomType::Capsule => PI * s[0] * s[0] * 2.0 * s[1] + 4.0 / 3.0 * PI * s[0].powi(3),
        GeomType::Cylinder => PI * s[0] * s[0] * 2.0 * s[1],
        GeomType::Box => 8.0 * s[0] * s[1] * s[2],
        GeomType::Ellipsoid => 4.0 / 3.0 * PI * s[0] * s[1] * s[2],
        _ => return None,
    })
}

/// Largest full dimension of a primitive of compiled size `s` (m).
pub fn primitive_extent(gtype: GeomType, s: [f64; 3]) -> Option<f64> {
    Some(match gtype {
        GeomType::Sphere => 2.0 * s[0],
        GeomType::Capsule => 2.0 * (s[0] + s[1]),
        GeomType::Cylinder => 2.0 * s[0].max(s[1]),
        GeomType::Box | GeomType::Ellipsoid => 2.0 * s[0].max(s[1]).max(s[2]),
        _ => return None,
    })
}

/// The body below the world that carries `b` (0 for the world body).
pub fn top_of(robot: &Robot, mut b: usize) -> usize {
    for _ in 0..robot.bodies.len() {
        match robot.bodies.get(b) {
            Some(x) if x.parent != 0 && b != 0 => b = x.parent,
            _ => break,
        }
    }
    b
}

/// The greatest distance between two anchors of the hinge, slide and ball joints of the tree
/// below `top` (0: every tree) at the keyframe, base coordinates excepted, and how many anchors.
pub fn joint_span(robot: &Robot, top: usize) -> (f64, usize) {
    let pts: Vec<[f64; 3]> = robot
        .joints
        .iter()
        .filter(|j| j.jtype != JointType::Free && !robot.is_base_coordinate(j.id))
        .filter(|j| in_subtree(robot, top, j.body))
        .filter_map(|j| robot.key.joint_xanchor.get(j.id).copied())
        .collect();
    let mut span: f64 = 0.0;
    for (i, a) in pts.iter().enumerate() {
        for b in &pts[i + 1..] {
            let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            span = span.max(d);
        }
    }
    (span, pts.len())
}

/// A `<link>`'s `<inertial><mass>` (kg).
fn link_mass(link: &XNode) -> Option<f64> {
    link.children_tagged("inertial")
        .flat_map(|i| i.children_tagged("mass"))
        .filter_map(|m| m.get("value")?.trim().parse::<f64>().ok())
        .find(|m| m.is_finite() && *m >= 0.0)
}

/// The URDF `<collision>` shape element that compiled to geom `g` (same type and size), in the
/// link named like the geom's body when there is one: (link, shape element).
fn urdf_shape(robot: &Robot, g: usize) -> Option<(&XNode, &XNode)> {
    let geom = robot.geoms.get(g)?;
    let num = |n: &XNode, a: &str| n.get(a).and_then(|v| v.trim().parse::<f64>().ok());
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * (1.0 + a.abs());
    let matches = |shape: &XNode| -> bool {
        let s = geom.size;
        match (shape.tag.as_str(), geom.gtype) {
            ("sphere", GeomType::Sphere) => num(shape, "radius").is_some_and(|r| close(r, s[0])),
            ("cylinder", GeomType::Cylinder) | ("capsule", GeomType::Capsule) => {
                num(shape, "radius").is_some_and(|r| close(r, s[0]))
                    && num(shape, "length").is_some_and(|l| close(l / 2.0, s[1]))
            }
            ("box", GeomType::Box) => shape.get("size").is_some_and(|v| {
                let x: Vec<f64> =
                    v.split_whitespace().filter_map(|t| t.parse::<f64>().ok()).collect();
                x.len() == 3 && (0..3).all(|k| close(x[k] / 2.0, s[k]))
            }),
            _ => false,
        }
    };
    let mut found = None;
    for link in robot.tree.children_tagged("link") {
        for c in link.children_tagged("collision") {
            for shape in c.children_tagged("geometry").flat_map(|x| x.children.iter()) {
                if matches(shape) {
                    if link.get("name") == Some(robot.body_name(geom.body)) {
                        return Some((link, shape));
                    }
                    found = found.or(Some((link, shape)));
                }
            }
        }
    }
    found
}

impl Rule for OversizedCollisionPrimitive {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let rho = cx.opt("min_density");
        let urdf = robot.format == Format::Urdf;
        for g in &robot.geoms {
            if !crate::model::contact::takes_part(robot, g.id) {
                continue;
            }
            let (Some(volume), Some(extent)) =
                (primitive_volume(g.gtype, g.size), primitive_extent(g.gtype, g.size))
            else {
                continue;
            };
            let body = g.body;
            // An MJCF's world body holds the scene; a URDF's holds its root link.
            if body == 0 && !urdf {
                continue;
            }
            if body != 0 && robot.bodies.get(body).is_none_or(|b| b.weld == 0) {
                continue;
            }
            if robot.joints.iter().any(|j| j.body == body && robot.is_wheel(j.id)) {
                continue;
            }
            // A URDF's trees all hang from its root link, fused into the world body.
            let top = if urdf { 0 } else { top_of(robot, body) };
            let (span, anchors) = joint_span(robot, top);
            if anchors < 2 || extent <= span {
                continue;
            }
            let shape = if urdf { urdf_shape(robot, g.id) } else { None };
            let (link_name, link_m) = if body == 0 {
                let Some((link, _)) = shape else { continue };
                let Some(m) = link_mass(link) else { continue };
                (link.get("name").unwrap_or("").to_string(), m)
            } else {
                (robot.body_name(body).to_string(), robot.bodies[body].mass)
            };
            let least = volume * rho;
            let kind = format!("{:?}", g.gtype).to_lowercase();
            let named = if g.name.is_empty() { String::new() } else { format!(" `{}`", g.name) };
            let head = format!(
                "collision {kind}{named} of link `{link_name}` is {} m across, {}× the {} m spanned by the robot's joints",
                fmt_num(extent, 3),
                fmt_num(extent / span, 3),
                fmt_num(span, 3),
            );
            // The mass test; for a link whose mass MuJoCo sums from its geoms (which grows
            // with the shape), the weight test at the joints that hold it.
            let weight = if least > link_m && link_m > 0.0 {
                None
            } else if body != 0 && mass_from_geoms(robot, body) && !geom_mass_stated(robot, g.id) {
                match overload(robot, body) {
                    Some(o) => Some(o),
                    None => continue,
                }
            } else {
                continue;
            };
            let msg = match &weight {
                None => format!(
                    "{head}, and at {} kg/m³ (lighter than any robot part) its {} m³ would weigh {} kg, {}× the link's {} kg",
                    fmt_num(rho, 3),
                    fmt_num(volume, 3),
                    fmt_num(least, 3),
                    fmt_num(least / link_m, 3),
                    fmt_num(link_m, 3),
                ),
                Some(o) => format!(
                    "{head}; the link's mass, which MuJoCo computes from its geoms (no <inertial>), is {} kg, and {} over the range of joint `{}` needs {} N·m, {}× the {} N·m {}",
                    fmt_num(link_m, 3),
                    if o.trunk { "tilting it on the legs" } else { "holding it against gravity" },
                    crate::rules::display_name(&robot.joints[o.joint].name, o.joint),
                    fmt_num(o.need, 3),
                    fmt_num(o.need / o.limit, 3),
                    fmt_num(o.limit, 3),
                    if o.trunk {
                        "the legs' actuated joints give about that axis together"
                    } else {
                        "its actuators give"
                    },
                ),
            };
            let mut f = match shape {
                Some((_, s)) => {
                    let at: Loc = s.attrs.first().map_or(s.loc, |a| a.loc);
                    cx.finding(msg, at).element(format!("link `{link_name}`"), s.loc)
                }
                None => cx.at_attr(ElemKind::Geom, g.id, &g.name, "size", msg),
            };
            f = f
                .label("larger than the robot")
                .note("a size written in millimetres where metres are read, or a placeholder shape: the link collides where the robot is not")
                .help("write the shape's size in metres as the link's real extent, or cover the link's visual geometry with primitives or a convex mesh")
                .subject(Subject::Geom(g.id))
                .measured(extent, "m")
                .expected(span, "m")
                .with("span", span)
                .with("volume", volume)
                .with("least_mass", least)
                .with("link_mass", link_m);
            if let Some(o) = &weight {
                f = f.with("need_torque", o.need).with("effort_limit", o.limit);
            }
            out.push(f);
        }
    }
}
