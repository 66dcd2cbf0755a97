//! `inertia-exceeds-geometry`'s light case for MJCF bodies that state no mass: MuJoCo fills
//! their geoms at the `density` the file writes, and a density below any solid's (the gym Ant's
//! `density="5"` kept on a Trossen hexapod: a 0.21 kg robot) weighs each part as the light
//! placeholder case's stated masses are weighed — against the lighter of a solid of the
//! lightest foam and a closed shell of the thinnest cover of its largest shape.

use std::collections::BTreeMap;

use crate::finding::{Finding, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::source::Loc;
use crate::model::{Format, GeomType};
use crate::rules::Context;
use crate::rules::geometry::oversized_collision::joint_span;
use crate::rules::inertia::inertial_overridden::stated_inertials;
use crate::rules::inertia::light_placeholder::{Shape, floor, geom_shape};
use crate::util::fmt_num;

/// MuJoCo's default geom density (kg/m³): water.
const DEFAULT_DENSITY: f64 = 1000.0;

/// One body weighed from its geoms' density: its name, compiled mass, summed geom volume and
/// the floor of its largest shape.
struct Weighed {
    body: usize,
    mass: f64,
    volume: f64,
    shape: Shape,
    bound: f64,
}

/// MJCF bodies not fixed to the world whose compiled mass MuJoCo took from their geoms' written
/// or inherited `density` (no `<inertial>`, or `inertiafromgeom="true"`; no geom of the body
/// writes a `mass`) and that weigh less than their largest shape's floor: the lighter of a
/// solid of `density` and a shell of `areal`. Reported once per `density` value the geoms take
/// (a `<default class>`'s reaches every body of the class). Not judged: `inertiafromgeom=
/// "false"`, geoms with `shellinertia` (their density is per area), geoms outside the
/// compiler's `inertiagrouprange` or of density 0 (they carry no mass), planes and height
/// fields, shapes larger than the robot's joint span (a unit slip), models with fewer than two
/// joints.
pub(super) fn light_from_density(cx: &Context, density: f64, areal: f64) -> Vec<Finding> {
    let robot = cx.robot;
    if robot.format != Format::Mjcf {
        return Vec::new();
    }
    let compiler = |attr: &str| {
        robot.tree.children_tagged("compiler").filter_map(|c| c.get(attr)).last().map(str::trim)
    };
    let from_geoms_always = match compiler("inertiafromgeom") {
        Some("false") => return Vec::new(),
        Some("true") => true,
        _ => false,
    };
    let groups: Vec<i32> = compiler("inertiagrouprange")
        .map(|v| v.split_whitespace().filter_map(|x| x.parse().ok()).collect())
        .unwrap_or_default();
    let (glo, ghi) = match groups.as_slice() {
        [a, b] => (*a, *b),
        _ => (0, 5),
    };
    let (span, anchors) = joint_span(robot, 0);
    if anchors < 2 {
        return Vec::new();
    }
    let stated = stated_inertials(&robot.tree);
    let in_order = stated.iter().all(|(id, b, _)| {
        robot.bodies.get(*id).is_some_and(|c| b.name().is_none_or(|n| n == c.name))
    });
    if !in_order {
        return Vec::new();
    }
    // density attribute's location → (its value, the bodies it makes too light)
    let mut by_source: BTreeMap<(usize, usize, usize), (usize, Vec<Weighed>)> = BTreeMap::new();
    for (id, _, inertial) in &stated {
        let id = *id;
        let Some(b) = robot.bodies.get(id) else { continue };
        if b.id == 0 || b.weld == 0 || !(b.mass > 0.0) || (inertial.is_some() && !from_geoms_always)
        {
            continue;
        }
        let mut carriers = Vec::new();
        let mut judged = true;
        for g in robot.geoms.iter().filter(|g| g.body == id) {
            if matches!(g.gtype, GeomType::Plane | GeomType::Hfield) {
                continue;
            }
            let Some(e) = robot.elem(ElemKind::Geom, g.id, &g.name) else {
                judged = false;
                break;
            };
            let attr = |a: &str| e.attrs.get(a).map(|o| o.value.trim());
            if attr("shellinertia") == Some("true") || attr("mass").is_some() {
                judged = false; // a mass per area, or a mass the writer states
                break;
            }
            let rho = match attr("density") {
                Some(v) => match v.parse::<f64>() {
                    Ok(x) => x,
                    Err(_) => {
                        judged = false;
                        break;
                    }
                },
                None => DEFAULT_DENSITY,
            };
            if rho > 0.0 && (glo..=ghi).contains(&g.group) {
                carriers.push(g.id);
            }
        }
        if !judged || carriers.is_empty() {
            continue;
        }
        let shapes: Vec<Shape> = carriers.iter().filter_map(|&g| geom_shape(robot, g)).collect();
        if shapes.len() != carriers.len() || shapes.iter().any(|s| s.extent > span) {
            continue;
        }
        let volume: f64 = shapes.iter().map(|s| s.volume).sum();
        let Some((k, bound)) = shapes
            .iter()
            .enumerate()
            .map(|(k, s)| (k, floor(s, density, areal)))
            .max_by(|a, b| a.1.total_cmp(&b.1))
        else {
            continue;
        };
        if !(b.mass < bound) {
            continue;
        }
        let g0 = &robot.geoms[carriers[k]];
        let (loc, _) = robot.attr_loc(ElemKind::Geom, g0.id, &g0.name, "density");
        let shape = shapes.into_iter().nth(k).expect("k indexes shapes");
        let entry = by_source.entry((loc.file, loc.start, loc.end)).or_insert((g0.id, Vec::new()));
        entry.1.push(Weighed { body: id, mass: b.mass, volume, shape, bound });
    }
    let mut out = Vec::new();
    for (_, (gid, parts)) in by_source {
        out.push(report(cx, gid, &parts, density, areal));
    }
    out
}

fn report(cx: &Context, gid: usize, parts: &[Weighed], density: f64, areal: f64) -> Finding {
    let robot = cx.robot;
    let g = &robot.geoms[gid];
    let written = robot
        .elem(ElemKind::Geom, gid, &g.name)
        .and_then(|e| e.attrs.get("density").map(|o| o.value.trim().to_string()));
    let gram = |x: f64| fmt_num(x * 1000.0, 3);
    let label = |id: usize| {
        let b = &robot.bodies[id];
        if b.name.is_empty() {
            format!("an unnamed body under `{}`", robot.body_name(b.parent))
        } else {
            format!("body `{}`", b.name)
        }
    };
    // The body furthest under its floor leads.
    let lead = parts
        .iter()
        .max_by(|a, b| (a.bound / a.mass).total_cmp(&(b.bound / b.mass)))
        .expect("a group holds a body");
    let mass: f64 = parts.iter().map(|p| p.mass).sum();
    let volume: f64 = parts.iter().map(|p| p.volume).sum();
    let (robot_mass, _) = robot.mass_split();
    let n = parts.len();
    let density_text = match &written {
        Some(v) => format!("density {v} kg/m³"),
        None => format!("the default density {} kg/m³", fmt_num(DEFAULT_DENSITY, 4)),
    };
    let msg = format!(
        "{n} bod{} weigh{} from {} geoms at {density_text} (no <inertial>): {} g over {} l, an effective {} kg/m³, less than any material a robot part is made of; {} weighs {} g, its {} ({} l, {} cm²) at least {} g as a solid of the lightest foam or a closed shell of the thinnest cover — {}× lighter; the robot weighs {} kg",
        if n == 1 { "y" } else { "ies" },
        if n == 1 { "s" } else { "" },
        if n == 1 { "its" } else { "their" },
        gram(mass),
        fmt_num(volume * 1000.0, 3),
        fmt_num(mass / volume, 3),
        label(lead.body),
        gram(lead.mass),
        lead.shape.what,
        fmt_num(lead.shape.volume * 1000.0, 3),
        fmt_num(lead.shape.area * 1e4, 3),
        gram(lead.bound),
        fmt_num(lead.bound / lead.mass, 3),
        fmt_num(robot_mass, 4)
    );
    let mut f = match written {
        Some(_) => cx.at_attr(ElemKind::Geom, gid, &g.name, "density", msg),
        None => cx.at_elem(ElemKind::Geom, gid, &g.name, msg),
    }
    .label(format!("{} g", gram(lead.mass)));
    let mut shown: Vec<Loc> = Vec::new();
    for p in parts.iter().filter(|p| p.body != lead.body).take(3) {
        let b = &robot.bodies[p.body];
        let loc = robot.elem_loc(ElemKind::Body, b.id, &b.name);
        if !shown.contains(&loc) {
            shown.push(loc);
            f = f.secondary(
                loc,
                format!("{} {} g, floor {} g", label(b.id), gram(p.mass), gram(p.bound)),
            );
        }
    }
    f.note(format!(
        "with no <inertial> MuJoCo weighs a body as solids of its geoms' density; a part of any real material weighs at least the lighter of its largest shape filled with foam of min_density {} kg/m³ and a closed shell of min_areal_density {} kg/m² (0.3 mm of plastic); these bodies weigh less, so the joints carrying them, the gravity load and the contact forces belong to a model of the robot, not the robot",
        fmt_num(density, 3),
        fmt_num(areal, 3)
    ))
    .help("write the parts' masses (an <inertial> per body, or mass=\"…\" on their geoms) or the density of what they are made of (printed PLA ~1240 kg/m³ solid, ~300–600 kg/m³ at typical infill; aluminium 2700 kg/m³)")
    .subject(Subject::Body(lead.body))
    .measured(lead.mass, "kg")
    .expected(lead.bound, "kg")
    .with("bodies", n as f64)
    .with("effective_density", mass / volume)
}
