use std::collections::BTreeMap;

use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::contact::takes_part;
use crate::model::mjcf::ElemKind;
use crate::model::{Format, GeomType};
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// For every colliding geom of a body not fixed to the world (the robot's, not a floor's or
    /// the scenery's), reads the distance at which its contacts start to act, `margin` − `gap`,
    /// and reports it when it exceeds both `max_distance` and `max_size_fraction` × the geom's
    /// smallest half-size (a sphere's, capsule's or cylinder's radius, a box's or ellipsoid's
    /// smallest half-extent, a mesh's bounding radius). The geoms that take their margin from
    /// one attribute (a `<default class>`) are reported together. Not judged: a model whose
    /// `<option><flag override="enable">` replaces every margin by `o_margin`, URDFs (no
    /// margin), geoms that take part in no contact.
    ///
    /// The semantics relied on (MuJoCo XML reference, `geom/margin` and `geom/gap`; `mjContact`
    /// in the API reference): collision detection includes a contact when the geoms' distance
    /// is below `margin` (of a geom pair, the larger of the two geoms' margins, likewise the
    /// gaps; a `<pair>` states its own); contacts with distance between `margin` − `gap` and
    /// `margin` are inactive, and the active ones (`includemargin` = `margin` − `gap`) are
    /// constraints whose reference distance is that margin: the solver pushes the geoms apart
    /// as soon as they are closer than `margin` − `gap`, and rests them that far apart.
    ///
    /// ## Why is this bad?
    /// A margin without a matching gap makes every contact act before the surfaces touch: the
    /// gym Ant's `margin="0.01"` kept on a hexapod whose feet are 20 mm capsules stands it 10 mm
    /// above its floor, and grasps, foot placement and self-collisions all act at a distance a
    /// real part never does. `margin` with an equal `gap` (contacts detected early for sensing
    /// or a smooth solver, made active only at touch) is the usual intent.
    ///
    /// ## How it is confirmed
    /// Static: compiled `geom_margin`, `geom_gap` and `geom_size`. A fact of the file.
    ///
    /// ## How to fix
    /// Remove the `margin` (MuJoCo's default 0), or set `gap` equal to it so contacts are
    /// detected early but act only at touch; keep a positive margin − gap only as small as the
    /// contact's softness asks (a millimetre or less).
    pub ContactMargin {
        id: "contact-margin",
        group: "contact",
        level: Severity::Warning,
        probe: None,
        options: [
            opt("max_distance", 0.002, "m", Domain::NON_NEGATIVE, "largest margin − gap judged a contact's softness, not a distance: twice the width of MuJoCo's default solimp (0.001 m), over which a contact's impedance already acts"),
            opt("max_size_fraction", 0.1, "fraction", Domain::NON_NEGATIVE, "largest margin − gap as a share of the geom's smallest half-size: a 20 mm foot standing 2 mm off its floor is a tenth of its radius, visible in every pose"),
        ],
    }
}

/// The smallest half-size of a geom of compiled size `s` (m); a mesh's bounding radius.
fn half_size(gtype: GeomType, s: [f64; 3], rbound: f64) -> f64 {
    match gtype {
        GeomType::Sphere | GeomType::Capsule | GeomType::Cylinder => s[0],
        GeomType::Box | GeomType::Ellipsoid => s[0].min(s[1]).min(s[2]),
        _ => rbound,
    }
}

/// A geom judged: (geom, its active distance margin − gap in m, its smallest half-size in m).
type Judged = (usize, f64, f64);

impl Rule for ContactMargin {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        if robot.format != Format::Mjcf {
            return;
        }
        let overridden = robot.tree.children_tagged("option").any(|o| {
            o.children_tagged("flag").any(|f| f.get("override").map(str::trim) == Some("enable"))
        });
        if overridden {
            return;
        }
        let (dmax, fmax) = (cx.opt("max_distance"), cx.opt("max_size_fraction"));
        let m = &robot.mj;
        let (margin, gap) = (m.geom_margin(), m.geom_gap());
        // margin attribute's location → [(geom, active distance, half size)]
        let mut groups: BTreeMap<(usize, usize, usize), Vec<Judged>> = BTreeMap::new();
        for g in &robot.geoms {
            let moving = robot.bodies.get(g.body).is_some_and(|b| b.id != 0 && b.weld != 0);
            if !moving || !takes_part(robot, g.id) {
                continue;
            }
            let (Some(&mg), Some(&gp)) = (margin.get(g.id), gap.get(g.id)) else { continue };
            let active = mg - gp;
            let half = half_size(g.gtype, g.size, g.rbound);
            if !(active > dmax) || !(half > 0.0) || !(active > fmax * half) {
                continue;
            }
            let (loc, class) = robot.attr_loc(ElemKind::Geom, g.id, &g.name, "margin");
            let key = if class.is_some() {
                (loc.file, loc.start, loc.end)
            } else {
                (usize::MAX, g.id, 0)
            };
            groups.entry(key).or_default().push((g.id, active, half));
        }
        for (_, mut gs) in groups {
            // The geom the distance is the largest share of leads.
            gs.sort_by(|a, b| (b.1 / b.2).total_cmp(&(a.1 / a.2)));
            out.push(report(cx, &gs));
        }
    }
}

fn report(cx: &Context, gs: &[Judged]) -> Finding {
    let robot = cx.robot;
    let (g0, active, half) = gs[0];
    let geom = &robot.geoms[g0];
    let m = &robot.mj;
    let (mg, gp) = (m.geom_margin()[g0], m.geom_gap()[g0]);
    let mm = |x: f64| fmt_num(x * 1000.0, 3);
    let n = gs.len();
    let name = |g: usize| {
        let x = &robot.geoms[g];
        if x.name.is_empty() {
            format!("geom {}", robot.unnamed_geom(g))
        } else {
            format!("`{}`", x.name)
        }
    };
    let who = if n == 1 {
        name(g0)
    } else {
        let names: Vec<String> = gs.iter().take(5).map(|x| name(x.0)).collect();
        let more = if n > 5 { format!(", … ({n} geoms)") } else { String::new() };
        format!("{n} colliding geoms ({}{more})", names.join(", "))
    };
    let largest = gs.iter().map(|x| x.2).fold(0.0, f64::max);
    let msg = format!(
        "margin {} − gap {} on {who}: {} contacts push from {} mm before the surfaces touch, {}× the {} mm half-size of {}{}",
        fmt_num(mg, 4),
        fmt_num(gp, 4),
        if n == 1 { "its" } else { "their" },
        mm(active),
        fmt_num(active / half, 3),
        mm(half),
        name(g0),
        if n > 1 && largest > half {
            format!(" ({}× the largest, {} mm)", fmt_num(active / largest, 3), mm(largest))
        } else {
            String::new()
        }
    );
    let mut f = cx
        .at_attr(ElemKind::Geom, g0, &geom.name, "margin", msg)
        .label(format!("acts {} mm away", mm(active)));
    for &(g, ..) in gs.iter().skip(1).take(3) {
        let x = &robot.geoms[g];
        f = f.secondary(robot.elem_loc(ElemKind::Geom, g, &x.name), "the same margin");
    }
    f.note(format!(
        "MuJoCo includes a contact when the geoms are closer than margin and makes it active when closer than margin − gap, where the solver pushes them apart and rests them: {} mm here, above max_distance {} mm and max_size_fraction {} of the geom's size, so feet stand, fingers grasp and links collide that far from the surfaces they draw",
        mm(active),
        mm(cx.opt("max_distance")),
        fmt_num(cx.opt("max_size_fraction"), 3)
    ))
    .help(format!(
        "remove margin (MuJoCo's default 0) or set gap=\"{}\" equal to it, so contacts are detected early but act only at touch",
        fmt_num(mg, 4)
    ))
    .subject(Subject::Geom(g0))
    .measured(active, "m")
    .expected(cx.opt("max_distance"), "m")
    .with("geoms", n as f64)
    .with("half_size", half)
}
