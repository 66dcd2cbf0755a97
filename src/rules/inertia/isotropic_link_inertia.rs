use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::{JointType, Robot};
use crate::rules::inertia::isotropic_base_inertia::{extents_of, inertia_loc};
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds moving links (not the floating base: `isotropic-base-inertia` judges that) whose
    /// written inertia is the same about every axis while the link is far from round: a
    /// placeholder such as `diaginertia="1 1 1"` on a 10 kg suspension link, or one value
    /// copied onto several links. Only inertias the file states (`<inertial>`) are judged;
    /// MuJoCo's own inertia from geoms is never a placeholder. An inertia counts as isotropic
    /// when its three principal moments agree within `isotropy_tolerance` (a measured inertia
    /// never does). The link's shape is the bounding box, in its frame, of its geoms (as
    /// compiled), its origin (where its joint sits) and the points where its child bodies
    /// attach; a uniform solid of that box must have principal moments that differ by at least
    /// `min_ratio` — a link with no geoms and no child off its origin gives no evidence and is
    /// not judged. Links that carry the same isotropic value are reported together.
    ///
    /// ## Why is this bad?
    /// A link's inertia sets how its joint, and every joint that carries it, accelerates. A
    /// long link has a small moment about its long axis and large ones across it; one
    /// isotropic guess gets at least one of them wrong by the ratio reported, often by orders
    /// of magnitude when the value is a round placeholder (1 kg·m² on a 10 kg part is a
    /// radius of gyration of 0.32 m). Joint accelerations, gains and contact responses
    /// learned on it do not transfer. MuJoCo XML reference, `body/inertial`.
    ///
    /// ## How it is confirmed
    /// Static: compiled `body_inertia`, the body's `<inertial>` and the compiled geoms' and
    /// child bodies' positions; no simulation measures whether an inertia is a placeholder.
    ///
    /// ## How to fix
    /// Use the link's inertia from CAD or the manufacturer's URDF (with `quat` or
    /// `fullinertia`), or remove `<inertial>` so MuJoCo computes it from geoms of the link's
    /// shape.
    pub IsotropicLinkInertia {
        id: "isotropic-link-inertia",
        group: "inertia",
        level: Severity::Warning,
        probe: None,
        options: [
            opt("isotropy_tolerance", 0.001, "fraction", Domain::NON_NEGATIVE, "relative spread of the three moments below which an inertia counts as isotropic"),
            opt("min_ratio", 3.0, "ratio", Domain::AT_LEAST_ONE, "largest / smallest moment of a uniform solid of the link's extents from which the link counts as not round"),
        ],
    }
}

/// A link with an isotropic inertia: (body, its extents in m, the extents' moment ratio).
type Placeholder = (usize, [f64; 3], f64);

impl Rule for IsotropicLinkInertia {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let inertia = robot.mj.body_inertia();
        let (tol, min_ratio) = (cx.opt("isotropy_tolerance"), cx.opt("min_ratio"));
        let bases: Vec<usize> =
            robot.joints.iter().filter(|j| j.jtype == JointType::Free).map(|j| j.body).collect();
        // (moment, [(body, extents, ratio)]), in body order.
        let mut groups: Vec<(f64, Vec<Placeholder>)> = Vec::new();
        for b in robot.bodies.iter().filter(|b| b.id != 0 && b.weld != 0 && b.mass > 0.0) {
            if bases.contains(&b.id) || inertia_loc(robot, &b.name).is_none() {
                continue;
            }
            let Some(i) = inertia.get(b.id) else { continue };
            let (lo, hi) =
                (i.iter().copied().fold(f64::INFINITY, f64::min), i[0].max(i[1]).max(i[2]));
            if !(lo > 0.0) || (hi - lo) > tol * hi {
                continue;
            }
            let Some(e) = extents_of(robot, b.id, true) else { continue };
            let sq = e.map(|x| x * x);
            let box_m = [sq[1] + sq[2], sq[0] + sq[2], sq[0] + sq[1]];
            let bmax = box_m.iter().copied().fold(0.0, f64::max);
            let bmin = box_m.iter().copied().fold(f64::INFINITY, f64::min);
            if !(bmax > 0.0) {
                continue; // no extent: no evidence of a shape
            }
            let ratio = if bmin > 0.0 { bmax / bmin } else { f64::INFINITY };
            if !(ratio >= min_ratio) {
                continue;
            }
            match groups.iter_mut().find(|g| (g.0 - hi).abs() <= tol * hi) {
                Some(g) => g.1.push((b.id, e, ratio)),
                None => groups.push((hi, vec![(b.id, e, ratio)])),
            }
        }
        for (moment, links) in groups {
            out.push(report(cx, moment, &links));
        }
    }
}

/// The model compiles with `balanceinertia="true"` (the last `<compiler>` that sets it: the
/// MJCF's own, or the one in a URDF's `<mujoco>` block). MuJoCo then replaces every inertia
/// that breaks the triangle inequality (A + B ≥ C) by the mean of its moments about every axis:
/// an isotropic inertia the compiler made, from a tensor no body can have.
pub fn balances_inertia(robot: &Robot) -> bool {
    let top = robot.tree.children_tagged("compiler");
    let urdf = robot.tree.children_tagged("mujoco").flat_map(|m| m.children_tagged("compiler"));
    top.chain(urdf).filter_map(|c| c.get("balanceinertia")).last().map(str::trim) == Some("true")
}

/// The words a finding of isotropic inertia adds under `balanceinertia="true"`.
pub const BALANCED: &str = "; the model compiles with `balanceinertia=\"true\"`, which makes any tensor breaking A + B ≥ C isotropic (the mean of its moments): where the stated tensor breaks it, the isotropy is the compiler's and the tensor written is one no body can have";

fn report(cx: &Context, moment: f64, links: &[Placeholder]) -> Finding {
    let robot = cx.robot;
    let (b0, e, ratio) = links[0];
    let name = robot.body_name(b0);
    let mass = robot.bodies[b0].mass;
    let ratio_s = |r: f64| if r.is_finite() { fmt_num(r, 2) } else { "∞".into() };
    let msg = if links.len() == 1 {
        format!(
            "link `{name}` has the same inertia {} kg·m² about every axis (mass {} kg, radius of gyration {} m), but it spans {} × {} × {} m: a uniform solid of that shape has moments differing {}×",
            fmt_num(moment, 4),
            fmt_num(mass, 4),
            fmt_num((moment / mass).sqrt(), 3),
            fmt_num(e[0], 3),
            fmt_num(e[1], 3),
            fmt_num(e[2], 3),
            ratio_s(ratio)
        )
    } else {
        let names: Vec<String> = links
            .iter()
            .map(|&(b, _, r)| {
                format!(
                    "{} ({} kg, {}×)",
                    robot.body_name(b),
                    fmt_num(robot.bodies[b].mass, 4),
                    ratio_s(r)
                )
            })
            .collect();
        format!(
            "{} links carry the same isotropic inertia {} kg·m² while none of them is round (a uniform solid of each one's extents has moments differing by the factor given): {}",
            links.len(),
            fmt_num(moment, 4),
            names.join(", ")
        )
    };
    let balanced = balances_inertia(robot);
    let msg = if balanced { format!("{msg}{BALANCED}") } else { msg };
    let eloc = robot.elem_loc(ElemKind::Body, b0, name);
    let loc = inertia_loc(robot, name).unwrap_or(eloc);
    let mut f = cx
        .finding(msg, loc)
        .element(format!("body {name}"), eloc)
        .label("isotropic: a sphere's or a cube's inertia");
    for &(b, _, _) in links.iter().skip(1).take(3) {
        let n = robot.body_name(b);
        f = f.secondary(
            inertia_loc(robot, n).unwrap_or_else(|| robot.elem_loc(ElemKind::Body, b, n)),
            "the same isotropic value",
        );
    }
    f = f.note("extents from the link's geoms (as compiled), its origin and the points where its child bodies attach; a measured inertia of a long link has moments across it several times the one along it")
        .help(if balanced {
            "state a physical tensor (A + B ≥ C: the link's inertia from CAD, with quat or fullinertia) so that balanceinertia leaves it as written, or drop <inertial> so MuJoCo computes it from geoms of the link's shape"
        } else {
            "use the link's inertia from CAD or the manufacturer's URDF (with quat or fullinertia), or drop <inertial> so MuJoCo computes it from geoms of the link's shape"
        })
        .subject(Subject::Body(b0))
        .measured(1.0, "ratio")
        .with("links", links.len() as f64);
    if ratio.is_finite() { f.expected(ratio, "ratio") } else { f }
}
