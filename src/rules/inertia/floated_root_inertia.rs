//! `inertia-exceeds-geometry` on the root link of a legged URDF that MuJoCo's importer welds
//! to the world: the importer fuses that link (and the links fixed to it) into the world body,
//! so the compiled model has no body whose inertia could be judged, while the foot rules and
//! the stance probes float it ([`crate::rules::contact::welded_legged_base`]). It is judged on
//! the floated copy the stance probes stand ([`crate::model::floated`]): MuJoCo's own parse of
//! the file with a free joint on the root link, where the root and its fixed links compile to
//! one moving body.

use crate::finding::{Finding, Subject};
use crate::model::floated::{Float, floated_copy};
use crate::model::{GeomType, Robot};
use crate::rules::Context;
use crate::rules::contact::welded_legged_base::{is_welded_legged, root_link};
use crate::rules::inertia::isotropic_base_inertia::inertia_loc;
use crate::util::fmt_num;

/// A body's largest principal moment, the reach R of its geoms from its centre of mass (each
/// geom's bounding sphere; planes and height fields left out) and the bound m·R² on that
/// moment; `None` for a body without such geoms.
pub fn moment_and_bound(robot: &Robot, b: usize) -> Option<(f64, f64, f64)> {
    let m = &robot.mj;
    let (inertia, ipos, gpos) = (m.body_inertia(), m.body_ipos(), m.geom_pos());
    let (i, c) = (inertia.get(b)?, ipos.get(b)?);
    let r = robot
        .geoms
        .iter()
        .filter(|g| g.body == b && !matches!(g.gtype, GeomType::Plane | GeomType::Hfield))
        .filter_map(|g| {
            let p = gpos.get(g.id)?;
            let d = ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2)).sqrt();
            (g.rbound > 0.0).then_some(d + g.rbound)
        })
        .fold(None, |acc: Option<f64>, r| Some(acc.map_or(r, |a| a.max(r))))?;
    let top = i[0].max(i[1]).max(i[2]);
    Some((top, r, robot.bodies.get(b)?.mass * r * r))
}

/// The root link's finding, when its floated body's largest moment exceeds m·R².
pub fn floated_root(cx: &Context) -> Option<Finding> {
    let robot = cx.robot;
    if !is_welded_legged(robot) {
        return None;
    }
    let root = root_link(robot)?.get("name")?.to_string();
    let copy = floated_copy(robot, cx.sources, &Float::RootLink(root.clone()), None).ok()?;
    let body = copy.robot.bodies.iter().find(|b| copy.robot.body_name(b.id) == root)?;
    let mass = body.mass;
    let (top, r, bound) = moment_and_bound(&copy.robot, body.id)?;
    if !(mass > 0.0 && top > bound && bound.is_finite()) {
        return None;
    }
    // The links MuJoCo fused into the root body: the root and the links fixed to it, through
    // fixed joints. The finding points at the heaviest one's stated inertia.
    let mut group = vec![root.clone()];
    let mut k = 0;
    while k < group.len() {
        for j in robot.tree.children_tagged("joint").filter(|j| j.get("type") == Some("fixed")) {
            let parent = j.children_tagged("parent").next().and_then(|p| p.get("link"));
            let child = j.children_tagged("child").next().and_then(|c| c.get("link"));
            if let (Some(p), Some(c)) = (parent, child)
                && p == group[k]
                && !group.iter().any(|g| g == c)
            {
                group.push(c.to_string());
            }
        }
        k += 1;
    }
    let stated = |name: &str| -> f64 {
        robot
            .tree
            .children_tagged("link")
            .find(|l| l.get("name") == Some(name))
            .and_then(|l| l.children_tagged("inertial").next())
            .and_then(|i| i.children_tagged("mass").next())
            .and_then(|m| m.get("value"))
            .and_then(|v| v.trim().parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    let heaviest = group
        .iter()
        .max_by(|a, b| stated(a).total_cmp(&stated(b)))
        .cloned()
        .unwrap_or_else(|| root.clone());
    let loc = inertia_loc(robot, &heaviest).unwrap_or_else(|| robot.root_loc());
    let fused: Vec<String> = group.iter().skip(1).map(|n| format!("`{n}`")).collect();
    let with = if fused.is_empty() {
        String::new()
    } else {
        format!(
            " with the link{} fixed to it ({})",
            if fused.len() == 1 { "" } else { "s" },
            fused.join(", ")
        )
    };
    let msg = format!(
        "root link `{root}`{with}, which MuJoCo's importer welds to the world and the legged robot floats on, has a principal moment of inertia {} kg·m², but its mass {} kg within {} m of its centre of mass (its geoms' reach) allows at most {} kg·m² (m·R²): {}× too large",
        fmt_num(top, 4),
        fmt_num(mass, 4),
        fmt_num(r, 3),
        fmt_num(bound, 3),
        fmt_num(top / bound, 3)
    );
    Some(
        cx.finding(msg, loc)
            .element(format!("link `{heaviest}`"), loc)
            .label("more than the part's geometry allows")
            .note(format!(
                "radius of gyration √(I/m) = {} m on a part that reaches {} m from its centre of mass: a placeholder or a unit slip. MuJoCo fuses a URDF's welded root into the world, so it is judged as the floated copy of the stance probes compiles it (a free joint on `{root}`)",
                fmt_num((top / mass).sqrt(), 3),
                fmt_num(r, 3)
            ))
            .help("use the trunk's inertia from CAD or the manufacturer's URDF")
            .subject(Subject::Model)
            .measured(top, "kg·m²")
            .expected(bound, "kg·m²"),
    )
}
