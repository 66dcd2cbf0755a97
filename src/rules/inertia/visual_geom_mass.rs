use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::source::XNode;
use crate::model::{Format, GeomType, Robot};
use crate::rules::geometry::oversized_collision::primitive_volume;
use crate::rules::inertia::inertial_overridden::stated_inertials;
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds a moving body of an MJCF model whose mass MuJoCo takes from its geoms (it states
    /// no `<inertial>`, or `<compiler inertiafromgeom="true">`) and which counts a visual-only
    /// copy of a colliding geom: a geom that never collides (contype = conaffinity = 0) of the
    /// same type, size and mesh at the same place in the body as one that collides, counted in
    /// the mass (its group within `inertiagrouprange`, its `mass` or `density` not 0). Each
    /// copied shape then weighs twice. The mass the copies add is MuJoCo's body mass split
    /// over the geoms by their volume × density (primitives' volumes, meshes' from their
    /// compiled faces), used when that split sums to the compiled mass within
    /// `mass_agreement`, or half the body's mass when every counted geom of it is one of such a
    /// pair; reported when it is at least `min_fraction` of the robot's (its moving bodies').
    /// A visual copy with its own class `mass` is `repeated-class-mass`'s; a body that states
    /// its `<inertial>` is not judged (MuJoCo ignores its geoms' mass). URDF links are not
    /// judged (the importer gives every link its `<inertial>`).
    ///
    /// ## Why is this bad?
    /// With `inertiafromgeom="auto"` (the default) a body with no `<inertial>` weighs what its
    /// geoms weigh, visual ones included unless their group lies outside `inertiagrouprange` or
    /// their `density`/`mass` is 0; a geom with neither weighs 1000 kg/m³ of its volume. An
    /// export that writes each part twice — once to draw (`class="visualgeom"`, contype 0), once
    /// to collide — without `density="0"` on the visual class doubles the part: Stompy Pro's
    /// torso counts its ten meshes twice. Gravity load, centre of mass and base inertia then
    /// differ from the hardware's. MuJoCo XML reference, `compiler/inertiafromgeom`,
    /// `compiler/inertiagrouprange` and `geom/density`.
    ///
    /// ## How it is confirmed
    /// Static: the compiled geoms (type, size, mesh, place, contype, conaffinity, group), their
    /// effective `mass`/`density` attributes and the compiled `body_mass`. A fact of the file.
    ///
    /// ## How to fix
    /// Give the visual class `density="0"` (or `mass="0"`), or leave its group out of
    /// `inertiagrouprange`, or state the body's `<inertial>` (its CAD mass).
    pub VisualGeomMass {
        id: "visual-geom-mass",
        group: "inertia",
        level: Severity::Warning,
        probe: None,
        options: [
            opt("min_fraction", 0.01, "fraction", Domain::NON_NEGATIVE, "share of the robot's mass (its moving bodies') below which the copies' mass is not reported: a marker's few grams"),
            opt("mass_agreement", 0.02, "fraction", Domain::NON_NEGATIVE, "relative difference tolerated between the compiled body mass and the sum of its geoms' volume × density before that split is trusted (MuJoCo's mesh volume differs from the faces' for open or shell meshes)"),
        ],
    }
}

/// The `<compiler>` value of `attr` MuJoCo applies (the last that sets it).
fn compiler(tree: &XNode, attr: &str) -> Option<String> {
    tree.children_tagged("compiler")
        .filter_map(|c| c.get(attr))
        .last()
        .map(|s| s.trim().to_string())
}

/// Volume of a compiled mesh (m³): the divergence theorem over its faces
/// (`light_placeholder::mesh_measure`, which also gives its area and extent).
fn mesh_volume(robot: &Robot, mesh: usize) -> Option<f64> {
    super::light_placeholder::mesh_measure(robot, mesh).map(|(v, _, _)| v)
}

/// A geom's weight in the body's mass: `Mass(m)` for a written mass, `Density(d)` otherwise
/// (its own or its class's `density`, else MuJoCo's default 1000 kg/m³).
#[derive(Clone, Copy, PartialEq)]
enum Weight {
    Mass(f64),
    Density(f64),
}

fn weight(robot: &Robot, g: usize) -> Option<Weight> {
    let geom = robot.geoms.get(g)?;
    let e = robot.elem(ElemKind::Geom, g, &geom.name)?;
    let num = |k: &str| e.attrs.get(k).and_then(|a| a.value.trim().parse::<f64>().ok());
    Some(match (num("mass"), num("density")) {
        (Some(m), _) => Weight::Mass(m),
        (None, Some(d)) => Weight::Density(d),
        (None, None) => Weight::Density(1000.0),
    })
}

/// Geom `g`'s mass by volume × density, if its volume is known.
fn geom_mass(robot: &Robot, g: usize, w: Weight) -> Option<f64> {
    match w {
        Weight::Mass(m) => Some(m),
        Weight::Density(d) => {
            let geom = robot.geoms.get(g)?;
            let v = match geom.gtype {
                GeomType::Mesh => mesh_volume(robot, usize::try_from(geom.mesh).ok()?)?,
                t => primitive_volume(t, geom.size)?,
            };
            Some(d * v)
        }
    }
}

/// Whether geoms `a` and `b` are one shape at one place of one body: the same type, mesh and
/// size, position and orientation as compiled (within 1 µm and 1e-6).
fn same_shape(robot: &Robot, a: usize, b: usize) -> bool {
    let (ga, gb) = (&robot.geoms[a], &robot.geoms[b]);
    let (pos, quat) = (robot.mj.geom_pos(), robot.mj.geom_quat());
    let close = |x: &[f64], y: &[f64]| x.iter().zip(y).all(|(p, q)| (p - q).abs() <= 1e-6);
    let (Some(pa), Some(pb), Some(qa), Some(qb)) =
        (pos.get(a), pos.get(b), quat.get(a), quat.get(b))
    else {
        return false;
    };
    let qn: Vec<f64> = qb.iter().map(|x| -x).collect();
    ga.body == gb.body
        && ga.gtype == gb.gtype
        && ga.mesh == gb.mesh
        && close(&ga.size, &gb.size)
        && close(pa, pb)
        && (close(qa, qb) || close(qa, &qn))
}

impl Rule for VisualGeomMass {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        if robot.format != Format::Mjcf {
            return;
        }
        let from_geom = compiler(&robot.tree, "inertiafromgeom");
        if from_geom.as_deref() == Some("false") {
            return;
        }
        let all = from_geom.as_deref() == Some("true");
        let groups: Vec<i32> = compiler(&robot.tree, "inertiagrouprange")
            .map(|s| s.split_whitespace().filter_map(|x| x.parse().ok()).collect())
            .unwrap_or_default();
        let (g0, g1) = match groups[..] {
            [a, b] => (a, b),
            _ => (0, 5),
        };
        let stated = stated_inertials(&robot.tree);
        let states = |id: usize| stated.iter().any(|(b, _, i)| *b == id && i.is_some());
        let moving = |id: usize| robot.bodies.get(id).is_some_and(|b| b.id != 0 && b.weld != 0);
        let robot_mass: f64 = robot.bodies.iter().filter(|b| moving(b.id)).map(|b| b.mass).sum();
        if !(robot_mass > 0.0) {
            return;
        }
        for b in robot.bodies.iter().filter(|b| moving(b.id) && b.mass > 0.0) {
            if !all && states(b.id) {
                continue;
            }
            // The geoms MuJoCo counts in the body's mass, with their weights.
            let counted: Vec<(usize, Weight)> = robot
                .geoms
                .iter()
                .filter(|g| g.body == b.id && (g0..=g1).contains(&g.group))
                .filter_map(|g| Some((g.id, weight(robot, g.id)?)))
                .filter(|(_, w)| match w {
                    Weight::Mass(x) | Weight::Density(x) => *x != 0.0,
                })
                .collect();
            // Visual-only copies of a colliding geom, each with its partner.
            let mut copies: Vec<(usize, usize)> = Vec::new();
            for &(c, wc) in &counted {
                if robot.geoms[c].collides() {
                    continue;
                }
                let partner = counted.iter().find(|&&(o, wo)| {
                    robot.geoms[o].collides()
                        && wo == wc
                        && !copies.iter().any(|p| p.1 == o)
                        && same_shape(robot, c, o)
                });
                if let Some(&(o, _)) = partner {
                    copies.push((c, o));
                }
            }
            if copies.is_empty() {
                continue;
            }
            let split: Option<Vec<f64>> =
                counted.iter().map(|&(g, w)| geom_mass(robot, g, w)).collect();
            let agree = cx.opt("mass_agreement");
            let copies_mass = match split {
                Some(m) if (m.iter().sum::<f64>() - b.mass).abs() <= agree * b.mass => {
                    let total: f64 = m.iter().sum();
                    let of = |g: usize| counted.iter().position(|c| c.0 == g).map_or(0.0, |k| m[k]);
                    copies.iter().map(|&(c, _)| of(c)).sum::<f64>() * b.mass / total
                }
                _ if counted.len() == 2 * copies.len() => b.mass / 2.0,
                _ => continue,
            };
            let share = copies_mass / robot_mass;
            if share < cx.opt("min_fraction") {
                continue;
            }
            let n = copies.len();
            let msg = format!(
                "body `{}` counts {n} visual-only geom{} (contype = conaffinity = 0) that repeat{} a colliding geom's shape and place in its mass: MuJoCo weighs each such shape twice, {} kg of the body's {} kg from the copies ({} % of the robot's {} kg)",
                b.name,
                if n == 1 { "" } else { "s" },
                if n == 1 { "s" } else { "" },
                fmt_num(copies_mass, 4),
                fmt_num(b.mass, 4),
                fmt_num(share * 100.0, 3),
                fmt_num(robot_mass, 4)
            );
            let first = copies[0].0;
            let gname = |g: usize| robot.geoms[g].name.clone();
            let mut f = cx
                .at_elem(ElemKind::Geom, first, &gname(first), msg)
                .element(format!("body {}", b.name), robot.elem_loc(ElemKind::Body, b.id, &b.name))
                .label("visual-only copy counted in the mass")
                .secondary(
                    robot.elem_loc(ElemKind::Geom, copies[0].1, &gname(copies[0].1)),
                    "the colliding geom it repeats",
                );
            for &(c, _) in copies.iter().skip(1).take(2) {
                f = f.secondary(robot.elem_loc(ElemKind::Geom, c, &gname(c)), "also a copy");
            }
            out.push(
                f.note(format!(
                    "the body states no <inertial>{}, so MuJoCo sums its geoms' masses, visual ones included (groups {g0}–{g1} of inertiagrouprange); a geom with no mass or density weighs 1000 kg/m³ of its volume, and a drawn copy of a colliding shape weighs it again",
                    if all { " that MuJoCo keeps (inertiafromgeom=\"true\")" } else { "" }
                ))
                .help("give the visual class density=\"0\" (or mass=\"0\"), or state the body's <inertial> from the CAD")
                .subject(Subject::Body(b.id))
                .measured(copies_mass, "kg")
                .expected(0.0, "kg")
                .with("body_mass_kg", b.mass)
                .with("copies", n as f64),
            );
        }
    }
}
