use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::source::XNode;
use crate::model::{Format, GeomType};
use crate::rules::inertia::inertial_overridden::stated_inertials;
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds a moving body of an MJCF robot that states no `<inertial>` while another body of
    /// the same rigid part — welded to it, no joint between (MuJoCo's `body_weldid`) — states
    /// the part's, and whose whole compiled mass MuJoCo took from its geoms at the default
    /// density, 1000 kg/m³: none of the body's geoms writes a `mass` or a `density`, itself or
    /// through its `<default class>`. The geoms' mass then comes on top of the part's stated
    /// one. Also a floating base (a body on a free joint) in the same state while every other
    /// moving body states its `<inertial>`: the file has its parts' masses (a CAD export) and
    /// leaves the heaviest part to water's density, a solid of its shapes (Stompy Pro's torso
    /// from its meshes; a hollow shell of CAD shapes weighs a fraction of that, a stand-in box
    /// several times it). Reported when it is at least `min_fraction` of the robot's (the
    /// moving bodies'), with the mass, the geoms it came from and the body that states the
    /// part's. Not judged:
    /// a body that states an `<inertial>`, a body one of whose geoms sets `mass` or `density`
    /// (the writer chose the geoms' mass), a body on a joint of its own whose part states no
    /// mass elsewhere (a foot or hand that takes its mass from its shapes: the modeller's
    /// choice), bodies welded to the world (furniture, a fixed base's mount), and
    /// `<compiler inertiafromgeom>` `"true"` (rule `inertial-overridden`) or `"false"`.
    ///
    /// In a URDF, the moving links that state no `<inertial>` (nor does any link a fixed joint
    /// fuses into the same body), reported together with the mass MuJoCo made up for each when
    /// they hold at least `min_fraction` of the robot's mass: the URDF specification makes such
    /// a link massless, MuJoCo's importer fills its collision geoms (visual ones are discarded)
    /// with water (myCobot 280: no link states one). Links welded to the world are not judged.
    ///
    /// ## Why is this bad?
    /// With `inertiafromgeom="auto"` (the default) MuJoCo uses each stated `<inertial>` and
    /// infers the others from the geoms, visual geoms included, at the density of water. A body
    /// left without its `<inertial>` — a URDF-to-MJCF export's `floating_base_link` carrying a
    /// collision box that stands for the torso — weighs as much water as its shapes hold: a
    /// 0.2 × 0.14 × 0.42 m box adds 11.8 kg to a 36 kg humanoid that is already complete. Gravity
    /// loads, the centre of mass and the base's inertia then differ from the hardware's, and a
    /// policy trained on it learns a heavier robot. MuJoCo XML reference,
    /// `compiler/inertiafromgeom` ("auto": inferred only when the body has no inertial element)
    /// and `geom/density` (default 1000).
    ///
    /// ## How it is confirmed
    /// Static: the compiled `body_mass` against the effective `mass`/`density` attributes of
    /// the body's geoms and the `<inertial>` elements the file states. A fact of the file.
    ///
    /// ## How to fix
    /// State the body's `<inertial>` (the part's measured or CAD mass, or a small placeholder
    /// for a frame that carries none), or give its collision and visual geoms `mass="0"` /
    /// `density="0"` (usually in their `<default class>`) when another body already carries the
    /// part's mass.
    pub DefaultDensityMass {
        id: "default-density-mass",
        group: "inertia",
        level: Severity::Warning,
        probe: None,
        options: [
            opt("min_fraction", 0.01, "fraction", Domain::NON_NEGATIVE, "share of the robot's mass (its moving bodies') below which a body's default-density mass is not reported: a marker sphere's few grams"),
        ],
    }
}

/// The `inertiafromgeom` value MuJoCo applies (the last `<compiler>` that sets it), if set.
fn inertiafromgeom(tree: &XNode) -> Option<&str> {
    tree.children_tagged("compiler").filter_map(|c| c.get("inertiafromgeom")).last().map(str::trim)
}

impl Rule for DefaultDensityMass {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        if robot.format == Format::Urdf {
            out.extend(super::urdf_no_inertial::urdf_no_inertial(cx, cx.opt("min_fraction")));
            return;
        }
        if robot.format != Format::Mjcf
            || matches!(inertiafromgeom(&robot.tree), Some("true" | "false"))
        {
            return;
        }
        let stated = stated_inertials(&robot.tree);
        // The stated list must be MuJoCo's body order (names agree): otherwise judge nothing.
        let in_order = stated.iter().all(|(id, b, _)| {
            robot.bodies.get(*id).is_some_and(|c| b.name().is_none_or(|n| n == c.name))
        });
        if !in_order {
            return;
        }
        let moving = |id: usize| robot.bodies.get(id).is_some_and(|b| b.id != 0 && b.weld != 0);
        let robot_mass: f64 = robot.bodies.iter().filter(|b| moving(b.id)).map(|b| b.mass).sum();
        let with_inertial: Vec<usize> =
            stated.iter().filter(|(id, _, i)| i.is_some() && moving(*id)).map(|s| s.0).collect();
        if with_inertial.is_empty() || robot_mass <= 0.0 {
            return;
        }
        for (id, _, inertial) in &stated {
            let id = *id;
            if inertial.is_some() || !moving(id) {
                continue;
            }
            let b = &robot.bodies[id];
            let geoms: Vec<&crate::model::Geom> = robot
                .geoms
                .iter()
                .filter(|g| g.body == id && !matches!(g.gtype, GeomType::Plane | GeomType::Hfield))
                .collect();
            // Every geom at the default density: none writes mass or density (own or class).
            let defaulted = |g: &crate::model::Geom| {
                robot.elem(ElemKind::Geom, g.id, &g.name).is_some_and(|e| {
                    !e.attrs.contains_key("mass") && !e.attrs.contains_key("density")
                })
            };
            if geoms.is_empty() || !geoms.iter().all(|g| defaulted(g)) {
                continue;
            }
            let share = b.mass / robot_mass;
            if !(b.mass > 0.0) || share < cx.opt("min_fraction") {
                continue;
            }
            // The part's mass is stated on another body welded to this one.
            let Some(&part) =
                with_inertial.iter().find(|&&o| o != id && robot.bodies[o].weld == b.weld)
            else {
                if let Some(f) = base_from_water(cx, id, &stated, robot_mass, geoms.len()) {
                    out.push(f);
                }
                continue;
            };
            let msg = format!(
                "body `{}` states no <inertial>, while `{}`, welded to it (no joint between), states its rigid part's: MuJoCo adds {} kg from its {} geom{} at the default density 1000 kg/m³ (no mass or density written), {} % of the robot's {} kg",
                b.name,
                robot.bodies[part].name,
                fmt_num(b.mass, 4),
                geoms.len(),
                if geoms.len() == 1 { "" } else { "s" },
                fmt_num(share * 100.0, 3),
                fmt_num(robot_mass, 4)
            );
            let mut f = cx.at_elem(ElemKind::Body, id, &b.name, msg).label("no <inertial>");
            f = f.secondary(
                robot.elem_loc(ElemKind::Body, part, &robot.bodies[part].name),
                "states the rigid part's mass",
            );
            for g in geoms.iter().take(3) {
                f = f.secondary(
                    robot.elem_loc(ElemKind::Geom, g.id, &g.name),
                    "weighed at 1000 kg/m³",
                );
            }
            out.push(
                f.note("with inertiafromgeom=\"auto\" MuJoCo infers a body's mass and inertia from its geoms, visual ones included, when the body states no <inertial>; a geom with no mass or density weighs as much water as its shape holds, and here it adds to a rigid part whose mass another body already states")
                    .help(format!(
                        "state the <inertial> of `{}` (or a small placeholder for a frame that carries no part), or give its geoms mass=\"0\" (in their default class) when another body carries the part's mass",
                        b.name
                    ))
                    .subject(Subject::Body(id))
                    .measured(b.mass, "kg")
                    .expected(0.0, "kg")
                    .with("robot_mass_kg", robot_mass)
                    .with("geoms", geoms.len() as f64),
            );
        }
    }
}

/// A floating base `id` weighed from its geoms at the default density while every other moving
/// body states its `<inertial>` (checked by the caller: no `<inertial>`, every geom defaulted).
fn base_from_water(
    cx: &Context,
    id: usize,
    stated: &[(usize, &XNode, Option<&XNode>)],
    robot_mass: f64,
    ngeoms: usize,
) -> Option<Finding> {
    let robot = cx.robot;
    let free =
        robot.joints.iter().any(|j| j.body == id && j.jtype == crate::model::JointType::Free);
    let moving = |o: usize| robot.bodies.get(o).is_some_and(|b| b.id != 0 && b.weld != 0);
    let others: Vec<&(usize, &XNode, Option<&XNode>)> =
        stated.iter().filter(|(o, _, _)| *o != id && moving(*o)).collect();
    if !free || others.is_empty() || others.iter().any(|(_, _, i)| i.is_none()) {
        return None;
    }
    let b = &robot.bodies[id];
    let rest = robot_mass - b.mass;
    let msg = format!(
        "floating base `{}` states no <inertial> while the robot's other {} moving bodies state theirs: MuJoCo weighs it {} kg from its {} geom{} at the default density 1000 kg/m³ (no mass or density written), {} % of the robot's {} kg against {} kg stated for all the rest",
        b.name,
        others.len(),
        fmt_num(b.mass, 4),
        ngeoms,
        if ngeoms == 1 { "" } else { "s" },
        fmt_num(b.mass / robot_mass * 100.0, 3),
        fmt_num(robot_mass, 4),
        fmt_num(rest, 4)
    );
    let f = cx
        .at_elem(ElemKind::Body, id, &b.name, msg)
        .label("no <inertial>: weighed as water")
        .note("with inertiafromgeom=\"auto\" MuJoCo infers a body's mass and inertia from its geoms, visual ones included, when it states no <inertial>; a geom with no mass or density weighs as much water as its shape holds: a solid of the base's shapes, which a hollow CAD shell is not, and a stand-in box is not the base's shape at all")
        .help(format!(
            "state the <inertial> of `{}` (the CAD mass, centre of mass and inertia of the base)",
            b.name
        ))
        .subject(Subject::Body(id))
        .measured(b.mass, "kg")
        .with("robot_mass_kg", robot_mass)
        .with("stated_rest_kg", rest)
        .with("geoms", ngeoms as f64);
    Some(f)
}
