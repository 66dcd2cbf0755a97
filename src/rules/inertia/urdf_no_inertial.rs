//! `default-density-mass`'s URDF case: moving links that state no `<inertial>`. The URDF
//! specification makes a link without one massless (zero mass, zero inertia); MuJoCo's importer
//! leaves such a body to `inertiafromgeom="auto"` and infers its mass and inertia from its
//! geoms — the `<collision>` ones (a URDF's `<visual>` geoms are discarded unless the file's
//! `<mujoco><compiler discardvisual="false">` keeps them) — filled solid at the default
//! density, 1000 kg/m³: a mass the file never states (myCobot 280's eight links).

use crate::finding::{Finding, Subject};
use crate::model::source::XNode;
use crate::model::{Format, GeomType};
use crate::rules::Context;
use crate::util::fmt_num;

/// The `inertiafromgeom` the file's `<mujoco><compiler>` sets, if any.
fn inertiafromgeom(root: &XNode) -> Option<&str> {
    root.children_tagged("mujoco")
        .flat_map(|m| m.children_tagged("compiler"))
        .filter_map(|c| c.get("inertiafromgeom"))
        .last()
        .map(str::trim)
}

/// One moving body whose URDF links state no `<inertial>`.
struct Weighed {
    body: usize,
    /// The link the body is named after and the links fixed to it that MuJoCo fused into it.
    links: Vec<String>,
    geoms: usize,
}

/// The finding for the moving bodies of a URDF whose links (the body's own and every link
/// fused into it by a fixed joint) state no `<inertial>` and which MuJoCo weighed from their
/// geoms at 1000 kg/m³, together at least `min_fraction` of the robot's moving mass.
pub(super) fn urdf_no_inertial(cx: &Context, min_fraction: f64) -> Option<Finding> {
    let robot = cx.robot;
    if robot.format != Format::Urdf || inertiafromgeom(&robot.tree).is_some_and(|v| v != "auto") {
        return None;
    }
    let links: Vec<&XNode> = robot.tree.children_tagged("link").collect();
    let link = |name: &str| links.iter().copied().find(|l| l.get("name") == Some(name));
    let has_body = |name: &str| robot.bodies.iter().any(|b| b.name == name);
    // The links a fixed joint hangs below `name` that have no body of their own (fused).
    let fused_below = |name: &str| -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        let mut todo = vec![name.to_string()];
        while let Some(p) = todo.pop() {
            for j in robot.tree.children_tagged("joint").filter(|j| j.get("type") == Some("fixed"))
            {
                let parent = j.children_tagged("parent").next().and_then(|c| c.get("link"));
                let child = j.children_tagged("child").next().and_then(|c| c.get("link"));
                if let (Some(pa), Some(c)) = (parent, child)
                    && pa == p
                    && !has_body(c)
                    && !out.iter().any(|o| o == c)
                {
                    out.push(c.to_string());
                    todo.push(c.to_string());
                }
            }
        }
        out
    };
    let moving = |id: usize| robot.bodies.get(id).is_some_and(|b| b.id != 0 && b.weld != 0);
    let robot_mass: f64 = robot.bodies.iter().filter(|b| moving(b.id)).map(|b| b.mass).sum();
    if !(robot_mass > 0.0) {
        return None;
    }
    let mut hits: Vec<Weighed> = Vec::new();
    for b in robot.bodies.iter().filter(|b| moving(b.id)) {
        if link(&b.name).is_none() {
            continue;
        }
        let mut names = vec![b.name.clone()];
        names.extend(fused_below(&b.name));
        let stated = names
            .iter()
            .any(|n| link(n).is_some_and(|l| l.children_tagged("inertial").next().is_some()));
        let geoms = robot
            .geoms
            .iter()
            .filter(|g| g.body == b.id && !matches!(g.gtype, GeomType::Plane | GeomType::Hfield))
            .count();
        if stated || geoms == 0 || !(b.mass > 0.0) {
            continue;
        }
        hits.push(Weighed { body: b.id, links: names, geoms });
    }
    let made_up: f64 = hits.iter().map(|h| robot.bodies[h.body].mass).sum();
    if hits.is_empty() || made_up < min_fraction * robot_mass {
        return None;
    }
    let n = hits.len();
    let all = (made_up - robot_mass).abs() <= 1e-9 * robot_mass;
    let list: Vec<String> = hits
        .iter()
        .map(|h| {
            let fused = if h.links.len() > 1 {
                format!(" (with {})", h.links[1..].join(", "))
            } else {
                String::new()
            };
            format!(
                "`{}`{fused} {} kg from {} geom{}",
                h.links[0],
                fmt_num(robot.bodies[h.body].mass, 4),
                h.geoms,
                if h.geoms == 1 { "" } else { "s" }
            )
        })
        .collect();
    let shown = if n > 6 {
        format!("{}; and {} more", list[..6].join("; "), n - 6)
    } else {
        list.join("; ")
    };
    let whole = if all {
        format!("{} kg, all the mass of its moving links, is MuJoCo's", fmt_num(made_up, 4))
    } else {
        format!(
            "{} kg of the robot's {} kg ({} %) is MuJoCo's",
            fmt_num(made_up, 4),
            fmt_num(robot_mass, 4),
            fmt_num(made_up / robot_mass * 100.0, 3)
        )
    };
    let msg = format!(
        "{n} moving link{} state{} no <inertial>: MuJoCo weighs each as a solid of water, its collision geoms filled at the default density 1000 kg/m³ — {shown}; {whole}, not the file's",
        if n == 1 { "" } else { "s" },
        if n == 1 { "s" } else { "" }
    );
    let first = &hits[0];
    let at = |name: &str| {
        link(name).map(|l| l.attr("name").map_or(l.loc, |a| a.loc)).unwrap_or(robot.tree.loc)
    };
    let mut f = cx
        .finding(msg, at(&first.links[0]))
        .element(format!("link `{}`", first.links[0]), at(&first.links[0]))
        .label("no <inertial>: weighed as water");
    for h in hits.iter().skip(1).take(3) {
        f = f.secondary(at(&h.links[0]), format!("also `{}`", h.links[0]));
    }
    Some(
        f.note("a URDF link without <inertial> has zero mass and inertia by the URDF specification (ROS tools and Gazebo take it as massless); MuJoCo's importer infers it from the link's collision geoms instead (inertiafromgeom=\"auto\"; visual geoms are discarded), each filled solid at 1000 kg/m³: a CAD mesh is the outer surface of a part of plastic, metal and motors, and a stand-in shape is not the part at all, so that mass and inertia are no measurement of the link")
            .help("state each link's <inertial> (mass, origin at the centre of mass, inertia) from CAD or by weighing the parts; a frame that carries no part can state a small placeholder mass")
            .subject(Subject::Body(first.body))
            .measured(made_up, "kg")
            .expected(0.0, "kg")
            .with("links", n as f64)
            .with("robot_mass_kg", robot_mass),
    )
}
