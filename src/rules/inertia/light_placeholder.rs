//! `inertia-exceeds-geometry`'s light case: a link whose stated mass is less than its own
//! geometry could weigh in any material a robot part is made of — less than the lightest solid
//! foam filling the shape and less than the thinnest closed shell covering it. A placeholder
//! mass (CyberDog2's 1 g head behind two boxes of 0.34 l), fused or moving.

use crate::finding::{Finding, Subject};
use crate::model::source::{Loc, XNode};
use crate::model::{Format, GeomType, Robot};
use crate::rules::Context;
use crate::rules::geometry::oversized_collision::{joint_span, primitive_extent, primitive_volume};
use crate::util::fmt_num;

/// One shape of a link: what it is, its volume (m³) and surface area (m²).
pub(super) struct Shape {
    pub(super) what: String,
    pub(super) volume: f64,
    pub(super) area: f64,
    /// Largest dimension, m.
    pub(super) extent: f64,
}

/// A link's stated mass, where it is written, its colliding and its drawn shapes, and the body
/// it ends up in.
struct Part {
    name: String,
    mass: f64,
    at: Loc,
    collision: Vec<Shape>,
    visual: Vec<Shape>,
    body: usize,
}

/// Volume, area and largest extent of a compiled mesh (its faces, in the mesh's compiled
/// scale; the extent along its principal axes).
pub(super) fn mesh_measure(robot: &Robot, mesh: usize) -> Option<(f64, f64, f64)> {
    let m = &robot.mj;
    let vadr = usize::try_from(*m.mesh_vertadr().get(mesh)?).ok()?;
    let fadr = usize::try_from(*m.mesh_faceadr().get(mesh)?).ok()?;
    let fnum = usize::try_from(*m.mesh_facenum().get(mesh)?).ok()?;
    let (verts, faces) = (m.mesh_vert(), m.mesh_face());
    let (mut v6, mut a2) = (0.0, 0.0);
    for f in faces.get(fadr..fadr + fnum)? {
        let p = |k: usize| -> Option<[f64; 3]> {
            let i = vadr + usize::try_from(f[k]).ok()?;
            verts.get(i).map(|v| v.map(f64::from))
        };
        let (a, b, c) = (p(0)?, p(1)?, p(2)?);
        v6 += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
            + a[2] * (b[0] * c[1] - b[1] * c[0]);
        let (u, w) = ([0, 1, 2].map(|k| b[k] - a[k]), [0, 1, 2].map(|k| c[k] - a[k]));
        let x = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]];
        a2 += (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
    }
    let vnum = usize::try_from(*m.mesh_vertnum().get(mesh)?).ok()?;
    let pts = verts.get(vadr..vadr + vnum)?;
    let extent = (0..3)
        .map(|k| {
            let (lo, hi) = pts.iter().fold((f64::MAX, f64::MIN), |(lo, hi), v| {
                (lo.min(f64::from(v[k])), hi.max(f64::from(v[k])))
            });
            hi - lo
        })
        .fold(0.0, f64::max);
    let (v, a) = ((v6 / 6.0).abs(), a2 / 2.0);
    (v.is_finite() && v > 0.0 && a > 0.0).then_some((v, a, extent))
}

/// Surface area of a primitive of compiled size `s` (m²).
fn primitive_area(gtype: GeomType, s: [f64; 3]) -> Option<f64> {
    use std::f64::consts::PI;
    Some(match gtype {
        GeomType::Sphere => 4.0 * PI * s[0] * s[0],
        GeomType::Capsule => 4.0 * PI * s[0] * s[0] + 2.0 * PI * s[0] * 2.0 * s[1],
        GeomType::Cylinder => 2.0 * PI * s[0] * s[0] + 2.0 * PI * s[0] * 2.0 * s[1],
        GeomType::Box => 8.0 * (s[0] * s[1] + s[1] * s[2] + s[2] * s[0]),
        // An ellipsoid's area lies between its inscribed and circumscribed spheres'.
        GeomType::Ellipsoid => 4.0 * PI * s[0].min(s[1]).min(s[2]).powi(2),
        _ => return None,
    })
}

fn mm(x: f64) -> String {
    fmt_num(x * 1000.0, 3)
}

/// A compiled geom as a [`Shape`].
pub(super) fn geom_shape(robot: &Robot, g: usize) -> Option<Shape> {
    let geom = robot.geoms.get(g)?;
    if geom.gtype == GeomType::Mesh {
        let k = usize::try_from(geom.mesh).ok()?;
        let (volume, area, extent) = mesh_measure(robot, k)?;
        let name = robot.meshes.get(k).map_or("", String::as_str);
        return Some(Shape { what: format!("mesh `{name}`"), volume, area, extent });
    }
    let s = geom.size;
    Some(Shape {
        what: describe(geom.gtype, s),
        volume: primitive_volume(geom.gtype, s)?,
        area: primitive_area(geom.gtype, s)?,
        extent: primitive_extent(geom.gtype, s)?,
    })
}

/// "box 76×60×40 mm" for a primitive of compiled size `s`.
fn describe(gtype: GeomType, s: [f64; 3]) -> String {
    match gtype {
        GeomType::Box => format!("box {}×{}×{} mm", mm(2.0 * s[0]), mm(2.0 * s[1]), mm(2.0 * s[2])),
        GeomType::Sphere => format!("sphere r {} mm", mm(s[0])),
        GeomType::Cylinder => format!("cylinder r {} × {} mm", mm(s[0]), mm(2.0 * s[1])),
        GeomType::Capsule => format!("capsule r {} × {} mm", mm(s[0]), mm(2.0 * s[1])),
        _ => format!("ellipsoid {}×{}×{} mm", mm(2.0 * s[0]), mm(2.0 * s[1]), mm(2.0 * s[2])),
    }
}

/// A URDF `<geometry>` as a [`Shape`]: primitives from their written sizes, meshes from the
/// compiled mesh of the file's stem (MuJoCo's importer names its meshes so).
fn urdf_shape(robot: &Robot, geometry: &XNode) -> Option<Shape> {
    let num = |n: &XNode, a: &str| n.get(a).and_then(|v| v.trim().parse::<f64>().ok());
    let child = geometry.children.iter().find(|c| !c.tag.is_empty())?;
    let (size, gtype) = match child.tag.as_str() {
        "box" => {
            let v: Vec<f64> =
                child.get("size")?.split_whitespace().filter_map(|x| x.parse().ok()).collect();
            ([*v.first()? / 2.0, *v.get(1)? / 2.0, *v.get(2)? / 2.0], GeomType::Box)
        }
        "cylinder" => {
            ([num(child, "radius")?, num(child, "length")? / 2.0, 0.0], GeomType::Cylinder)
        }
        "sphere" => ([num(child, "radius")?, 0.0, 0.0], GeomType::Sphere),
        "mesh" => {
            let file = child.get("filename")?;
            let stem = std::path::Path::new(file).file_stem()?.to_str()?;
            let k = robot.meshes.iter().position(|n| n == stem)?;
            let (volume, area, extent) = mesh_measure(robot, k)?;
            return Some(Shape { what: format!("mesh `{stem}`"), volume, area, extent });
        }
        _ => return None,
    };
    Some(Shape {
        what: describe(gtype, size),
        volume: primitive_volume(gtype, size)?,
        area: primitive_area(gtype, size)?,
        extent: primitive_extent(gtype, size)?,
    })
}

/// The URDF links that state a mass, with their shapes; the body each ends in (its own, or
/// the one it is fused into through fixed joints).
fn urdf_parts(robot: &Robot) -> Vec<Part> {
    let fixed_parent = |name: &str| {
        robot
            .tree
            .children_tagged("joint")
            .filter(|j| j.get("type") == Some("fixed"))
            .find(|j| j.children_tagged("child").next().and_then(|c| c.get("link")) == Some(name))
            .and_then(|j| j.children_tagged("parent").next().and_then(|c| c.get("link")))
            .map(str::to_string)
    };
    let mut out = Vec::new();
    for link in robot.tree.children_tagged("link") {
        let Some(name) = link.get("name") else { continue };
        let Some(mass_node) =
            link.children_tagged("inertial").next().and_then(|i| i.children_tagged("mass").next())
        else {
            continue;
        };
        let Some(mass) = mass_node.get("value").and_then(|v| v.trim().parse::<f64>().ok()) else {
            continue;
        };
        let shapes = |tag: &str| -> Vec<Shape> {
            link.children_tagged(tag)
                .filter_map(|c| c.children_tagged("geometry").next())
                .filter_map(|g| urdf_shape(robot, g))
                .collect()
        };
        let mut at = name.to_string();
        let mut body = None;
        for _ in 0..robot.bodies.len() {
            if let Some(b) = robot.bodies.iter().find(|b| b.name == at) {
                body = Some(b.id);
                break;
            }
            match fixed_parent(&at) {
                Some(p) => at = p,
                None => break,
            }
        }
        out.push(Part {
            name: name.to_string(),
            mass,
            at: mass_node.attr("value").map_or(mass_node.loc, |a| a.loc),
            collision: shapes("collision"),
            visual: shapes("visual"),
            body: body.unwrap_or(0),
        });
    }
    out
}

/// The MJCF bodies not fixed to the world that state their `<inertial>` mass, with their geoms.
fn mjcf_parts(robot: &Robot) -> Vec<Part> {
    let mut out = Vec::new();
    for b in robot.bodies.iter().filter(|b| b.id != 0 && b.weld != 0) {
        if b.name.is_empty() {
            continue;
        }
        let mut at = None;
        robot.tree.walk(&mut |n: &XNode| {
            if at.is_none()
                && n.tag == "body"
                && n.name() == Some(b.name.as_str())
                && let Some(i) = n.children_tagged("inertial").next()
            {
                at = i.attr("mass").map(|a| a.loc);
            }
        });
        let Some(at) = at else { continue };
        let shapes = |collide: bool| -> Vec<Shape> {
            robot
                .geoms
                .iter()
                .filter(|g| g.body == b.id && g.collides() == collide)
                .filter_map(|g| geom_shape(robot, g.id))
                .collect()
        };
        out.push(Part {
            name: b.name.clone(),
            mass: b.mass,
            at,
            collision: shapes(true),
            visual: shapes(false),
            body: b.id,
        });
    }
    out
}

/// The least mass a shape can have: the lighter of a solid of `density` and a closed shell of
/// `areal` density.
pub(super) fn floor(s: &Shape, density: f64, areal: f64) -> f64 {
    (density * s.volume).min(areal * s.area)
}

/// Links lighter than their own geometry allows: the mass is below the floor of the link's
/// largest shape (the lighter of a solid of `min_density` and a shell of `min_areal_density`),
/// taken over the colliding shapes and over the drawn ones, whichever set gives the lower
/// floor when both exist. Links without shapes (a fused frame, a sensor mount) and massless
/// links are not judged, nor shapes larger than the robot's joint span (a length in
/// millimetres: `mesh-scale`'s and `oversized-collision-primitive`'s), nor models with fewer
/// than two joints (no robot size to tell such a slip by).
pub(super) fn light_placeholders(cx: &Context, density: f64, areal: f64) -> Vec<Finding> {
    let robot = cx.robot;
    let parts = match robot.format {
        Format::Urdf => urdf_parts(robot),
        _ => mjcf_parts(robot),
    };
    // A shape larger than the robot's joint span is a unit slip (`mesh-scale`,
    // `oversized-collision-primitive`), whatever the link weighs.
    // Without two joints there is no robot size to tell a unit slip by: not judged.
    let (span, anchors) = joint_span(robot, 0);
    if anchors < 2 {
        return Vec::new();
    }
    let fits = |s: &Shape| s.extent <= span;
    let mut out = Vec::new();
    for mut p in parts {
        if !(p.mass > 0.0) {
            continue;
        }
        p.collision.retain(|s| fits(s));
        p.visual.retain(|s| fits(s));
        let largest = |v: &[Shape]| -> Option<(usize, f64)> {
            v.iter()
                .enumerate()
                .map(|(i, s)| (i, floor(s, density, areal)))
                .max_by(|a, b| a.1.total_cmp(&b.1))
        };
        let (c, v) = (largest(&p.collision), largest(&p.visual));
        let (shape, bound) = match (c, v) {
            (Some(c), Some(v)) if v.1 < c.1 => (&p.visual[v.0], v.1),
            (Some(c), _) => (&p.collision[c.0], c.1),
            (None, Some(v)) => (&p.visual[v.0], v.1),
            (None, None) => continue,
        };
        if !(p.mass < bound) {
            continue;
        }
        let g = |x: f64| fmt_num(x * 1000.0, 3);
        let kind = if robot.format == Format::Urdf { "link" } else { "body" };
        let msg = format!(
            "{kind} `{}` weighs {} g, less than its own geometry could in any material: its {} ({} l, {} cm²) is at least {} g as a solid of the lightest foam or a closed shell of the thinnest cover — {}× lighter",
            p.name,
            g(p.mass),
            shape.what,
            fmt_num(shape.volume * 1000.0, 3),
            fmt_num(shape.area * 1e4, 3),
            g(bound),
            fmt_num(bound / p.mass, 3)
        );
        out.push(
            cx.finding(msg, p.at)
                .label(format!("{} g", g(p.mass)))
                .note(format!(
                    "a part of {} l and {} cm² weighs at least {} g filled with foam of min_density {} kg/m³ or {} g as a closed shell of min_areal_density {} kg/m² (0.3 mm of plastic), whichever is lighter; {} g is neither: a placeholder mass (a default of the exporter or a value typed to make the solver accept the link), and the link's inertia and the load on the joints carrying it follow it",
                    fmt_num(shape.volume * 1000.0, 3),
                    fmt_num(shape.area * 1e4, 3),
                    g(density * shape.volume),
                    fmt_num(density, 3),
                    g(areal * shape.area),
                    fmt_num(areal, 3),
                    g(p.mass)
                ))
                .help("weigh the part or take its mass from CAD (with its inertia); a marker or frame that has no mass of its own should carry no drawn or colliding shape of that size")
                .subject(Subject::Body(p.body))
                .measured(p.mass, "kg")
                .expected(bound, "kg"),
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn primitive_areas() {
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
        assert!(close(primitive_area(GeomType::Box, [0.5, 1.0, 1.5]).unwrap(), 22.0));
        let pi = std::f64::consts::PI;
        assert!(close(primitive_area(GeomType::Sphere, [1.0, 0.0, 0.0]).unwrap(), 4.0 * pi));
        assert!(close(primitive_area(GeomType::Cylinder, [1.0, 1.0, 0.0]).unwrap(), 6.0 * pi));
        assert!(close(primitive_area(GeomType::Capsule, [1.0, 1.0, 0.0]).unwrap(), 8.0 * pi));
    }
}
