use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::Format;
use crate::model::source::XNode;
use crate::rules::{Context, Rule, RuleMeta};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds an MJCF whose `<compiler inertiafromgeom="true">` (in a URDF, the same element
    /// inside its `<mujoco>` extension, which MuJoCo reads) discards the `<inertial>`
    /// elements its bodies (links) state: MuJoCo then takes every body's mass and inertia from its
    /// geoms (at their `density`, 1000 kg/m³ unless set; only the geoms of
    /// `inertiagrouprange`), whatever the file states. A body is reported when its compiled
    /// mass differs from the `mass` its `<inertial>` states in the digits written (a stated
    /// `6.1575` kg is matched by 6.15745–6.15755 kg). A body none of whose geoms lies in
    /// `inertiagrouprange` keeps its stated `<inertial>` (MuJoCo has nothing to infer from) and
    /// is not reported. `inertiafromgeom="auto"` (MuJoCo's default) and `"false"` use each
    /// stated `<inertial>` and are not judged, nor are bodies that state none.
    ///
    /// ## Why is this bad?
    /// The `<inertial>` values are the measured or CAD mass properties; the geoms are drawn
    /// or collision shapes at an assumed uniform density. With `"true"` the simulated robot
    /// has the shapes' masses — hollow visual shells, heavy solid primitives, every part at one
    /// density — so gravity loads, the centre
    /// of mass and every joint's inertia differ from the hardware's, and a policy trained on
    /// it meets a different robot. MuJoCo XML reference, `compiler/inertiafromgeom`: "true"
    /// infers the inertia "overriding any values specified with the inertial element".
    ///
    /// ## How it is confirmed
    /// Static: the stated `<inertial mass>` against the compiled `body_mass`. A fact of the
    /// file.
    ///
    /// ## How to fix
    /// Remove `inertiafromgeom="true"` (the default `"auto"` uses each stated `<inertial>`
    /// and infers only the bodies that have none), or delete the `<inertial>` elements that
    /// the geoms are meant to replace.
    pub InertialOverridden {
        id: "inertial-overridden",
        group: "inertia",
        level: Severity::Warning,
        probe: None,
        options: [],
    }
}

/// Half a unit in the last digit written of a decimal number (`6.1575` → 5e-5, `2` → 0.5,
/// `1.5e-3` → 5e-5): how far a value may lie from the text and still be what it states.
fn half_last_digit(text: &str) -> f64 {
    let t = text.trim();
    let (mant, exp) = match t.find(['e', 'E']) {
        Some(i) => (&t[..i], t[i + 1..].parse::<i32>().unwrap_or(0)),
        None => (t, 0),
    };
    let decimals = mant.find('.').map_or(0, |i| mant.len() - i - 1) as i32;
    0.5 * 10f64.powi(exp - decimals)
}

/// The `<compiler>` element whose `inertiafromgeom` MuJoCo applies (the last one that sets
/// it, includes expanded), when it is `"true"`.
fn inertia_from_geom(tree: &XNode, format: Format) -> Option<&XNode> {
    let mut last: Option<&XNode> = None;
    // A URDF's compiler options are in its `<mujoco>` extension element, which MuJoCo reads.
    let compilers: Vec<&XNode> = match format {
        Format::Mjcf => tree.children_tagged("compiler").collect(),
        Format::Urdf => {
            tree.children_tagged("mujoco").flat_map(|m| m.children_tagged("compiler")).collect()
        }
    };
    for c in compilers {
        if c.get("inertiafromgeom").is_some() {
            last = Some(c);
        }
    }
    last.filter(|c| c.get("inertiafromgeom").map(str::trim) == Some("true"))
}

/// Bodies in MuJoCo's compiled order (pre-order over the `<worldbody>` sections, frames
/// flattened), each with its `<inertial>` if it states one: (compiled id, body, inertial).
pub(crate) fn stated_inertials(tree: &XNode) -> Vec<(usize, &XNode, Option<&XNode>)> {
    fn visit<'a>(
        n: &'a XNode,
        next: &mut usize,
        out: &mut Vec<(usize, &'a XNode, Option<&'a XNode>)>,
    ) {
        for c in &n.children {
            match c.tag.as_str() {
                "body" => {
                    *next += 1;
                    out.push((*next, c, c.children_tagged("inertial").next()));
                    visit(c, next, out);
                }
                "frame" => visit(c, next, out),
                _ => {}
            }
        }
    }
    let mut out = Vec::new();
    let mut next = 0;
    for w in tree.children_tagged("worldbody") {
        visit(w, &mut next, &mut out);
    }
    out
}

/// A URDF's links with their `<inertial>`, as (compiled body id, link, inertial): only links
/// MuJoCo compiled into a body of their own name and into which no other link was fused (every
/// child link is a body too), so the compiled mass is the link's alone. A root link welded to
/// the world (fused into it) is not judged.
fn urdf_inertials(robot: &crate::model::Robot) -> Vec<(usize, &XNode, Option<&XNode>)> {
    let tree = &robot.tree;
    let body = |name: &str| robot.bodies.iter().find(|b| b.id != 0 && b.name == name);
    tree.children_tagged("link")
        .filter_map(|l| {
            let name = l.get("name")?;
            let b = body(name)?;
            let children_kept = tree
                .children_tagged("joint")
                .filter(|j| j.children_tagged("parent").any(|p| p.get("link") == Some(name)))
                .filter_map(|j| j.children_tagged("child").next()?.get("link"))
                .all(|c| body(c).is_some());
            children_kept.then(|| (b.id, l, l.children_tagged("inertial").next()))
        })
        .collect()
}

/// The mass an `<inertial>` states, as written: MJCF's `mass` attribute, URDF's `<mass value>`.
fn stated_mass(inertial: &XNode, format: Format) -> Option<&str> {
    match format {
        Format::Mjcf => inertial.get("mass"),
        Format::Urdf => inertial.children_tagged("mass").next()?.get("value"),
    }
}

impl Rule for InertialOverridden {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let Some(compiler) = inertia_from_geom(&robot.tree, robot.format) else { return };
        // (compiled body, stated mass, compiled mass, the <inertial>'s mass attribute)
        let mut off: Vec<(usize, f64, f64, &XNode)> = Vec::new();
        let stated_list = match robot.format {
            Format::Mjcf => stated_inertials(&robot.tree),
            Format::Urdf => urdf_inertials(robot),
        };
        for (id, body, inertial) in stated_list {
            let Some(inertial) = inertial else { continue };
            let Some(b) = robot.bodies.get(id) else { continue };
            // The compiled body must be this element (a name that disagrees means the order
            // was not MuJoCo's: judge nothing rather than the wrong body).
            if body.name().is_some_and(|n| n != b.name) {
                return;
            }
            let Some(text) = stated_mass(inertial, robot.format) else { continue };
            let Ok(stated) = text.trim().parse::<f64>() else { continue };
            if (b.mass - stated).abs() > half_last_digit(text) {
                off.push((id, stated, b.mass, inertial));
            }
        }
        if off.is_empty() {
            return;
        }
        // The largest discrepancies first.
        off.sort_by(|a, b| (b.1 - b.2).abs().total_cmp(&(a.1 - a.2).abs()).then(a.0.cmp(&b.0)));
        let name = |id: usize| {
            let n = &robot.bodies[id].name;
            if n.is_empty() { format!("no. {id}") } else { format!("`{n}`") }
        };
        let shown: Vec<String> = off
            .iter()
            .take(3)
            .map(|&(id, s, c, _)| {
                format!("{} states {} kg and weighs {} kg", name(id), fmt_num(s, 4), fmt_num(c, 4))
            })
            .collect();
        let more =
            if off.len() > 3 { format!(", … ({} bodies)", off.len()) } else { String::new() };
        let groups = compiler
            .get("inertiagrouprange")
            .map(|g| format!(" of groups {}", g.split_whitespace().collect::<Vec<_>>().join("–")))
            .unwrap_or_default();
        let msg = format!(
            "<compiler inertiafromgeom=\"true\"> discards the <inertial> of {} {} and takes mass and inertia from the geoms{groups}: {}{more}",
            off.len(),
            if off.len() == 1 { "body" } else { "bodies" },
            shown.join("; ")
        );
        let loc = compiler.attr("inertiafromgeom").map_or(compiler.loc, |a| a.loc);
        let (stated_sum, compiled_sum) =
            off.iter().fold((0.0, 0.0), |(s, c), &(_, st, co, _)| (s + st, c + co));
        let mut f = cx.finding(msg, loc).label("overrides every <inertial>");
        for &(id, s, c, inertial) in off.iter().take(3) {
            f = f.secondary(
                inertial.loc,
                format!("{} weighs {} kg, not {} kg", name(id), fmt_num(c, 4), fmt_num(s, 4)),
            );
        }
        let (id0, ..) = off[0];
        out.push(
            f.note("with inertiafromgeom=\"true\" MuJoCo infers every body's mass and inertia from its geoms at their density, overriding the values of each <inertial> element")
                .help("remove inertiafromgeom=\"true\" (the default \"auto\" uses each stated <inertial> and infers only bodies without one), or delete the <inertial> elements the geoms are meant to replace")
                .subject(Subject::Body(id0))
                .measured(compiled_sum, "kg")
                .expected(stated_sum, "kg")
                .with("bodies", off.len() as f64),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_unit_of_the_last_written_digit() {
        assert_eq!(half_last_digit("2"), 0.5);
        assert!((half_last_digit("6.1575") - 5e-5).abs() < 1e-15);
        assert!((half_last_digit("1.5e-3") - 5e-5).abs() < 1e-15);
        assert!((half_last_digit(" 0.10 ") - 5e-3).abs() < 1e-15);
    }
}
