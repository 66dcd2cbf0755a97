use std::collections::BTreeMap;

use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::rules::{Context, Rule, RuleMeta};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds a `<default class>` geom `mass` that several geoms of one body inherit, when the
    /// body's compiled mass shows MuJoCo counted it once per geom (the body weighs at least the
    /// class mass times the number of geoms inheriting it). Geoms that write their own `mass`
    /// or `density`, and bodies whose `<inertial>` states the mass, are not judged.
    ///
    /// ## Why is this bad?
    /// MuJoCo sums the masses of a body's geoms when it infers the body's inertia from them
    /// (`compiler/inertiafromgeom`), visual geoms included unless `inertiagrouprange` leaves
    /// their group out. A class meant to give a part its mass (`<default class="fingertip"><geom
    /// mass="0.02"/>`) that both the part's visual and collision geoms use, or several collision
    /// primitives of one link, gives the body that mass once per geom: a fingertip twice as heavy,
    /// a link N times as heavy, with the gravity load and inertia to match. MuJoCo XML reference,
    /// `geom/mass` and `compiler/inertiafromgeom`.
    ///
    /// ## How it is confirmed
    /// Static: the effective attributes of the geoms (their own and their classes'), checked
    /// against the compiled `body_mass`. A fact of the file.
    ///
    /// ## How to fix
    /// Give the mass once: keep the class `mass` on one geom of the body (the collision geom) and
    /// set `mass="0"` on the others (or a visual class with `mass="0"`), or state the body's
    /// `<inertial>`.
    pub RepeatedClassMass {
        id: "repeated-class-mass",
        group: "inertia",
        level: Severity::Warning,
        probe: None,
        options: [],
    }
}

impl Rule for RepeatedClassMass {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        // (body, class) → the geoms of the body that inherit `mass` from the class, and the mass.
        let mut groups: BTreeMap<(usize, String), (Vec<usize>, f64)> = BTreeMap::new();
        for g in &robot.geoms {
            let Some(e) = robot.elem(ElemKind::Geom, g.id, &g.name) else { continue };
            let Some(m) = e.attrs.get("mass") else { continue };
            let Some(class) = &m.class else { continue };
            if e.attrs.get("density").is_some_and(|d| d.class.is_none()) {
                continue;
            }
            let Ok(mass) = m.value.trim().parse::<f64>() else { continue };
            if !(mass > 0.0) {
                continue;
            }
            let entry = groups.entry((g.body, class.clone())).or_insert((Vec::new(), mass));
            if entry.1 == mass {
                entry.0.push(g.id);
            }
        }
        for ((body, class), (geoms, mass)) in groups {
            let n = geoms.len();
            let Some(b) = robot.bodies.get(body) else { continue };
            // MuJoCo counted the class mass once per geom: the body weighs at least n × mass
            // (a relative margin for the compiler's rounding).
            if n < 2 || b.mass < n as f64 * mass * (1.0 - 1e-9) {
                continue;
            }
            let first = &robot.geoms[geoms[0]];
            let msg = format!(
                "body `{}` has {n} geoms that inherit mass {} kg from <default class=\"{class}\">: MuJoCo counts it {n} times (the body weighs {} kg)",
                b.name,
                fmt_num(mass, 4),
                fmt_num(b.mass, 4)
            );
            let mut f = cx
                .at_attr(ElemKind::Geom, first.id, &first.name, "mass", msg)
                .label(format!("class mass {} kg", fmt_num(mass, 4)));
            for &g in &geoms[1..] {
                let geom = &robot.geoms[g];
                let loc = robot.elem_loc(ElemKind::Geom, g, &geom.name);
                f = f.secondary(loc, format!("also inherits mass {} kg", fmt_num(mass, 4)));
            }
            let f = f
                .note("MuJoCo sums the masses of a body's geoms to infer its mass and inertia, visual geoms included; a class mass on N geoms of one body is N times that mass")
                .help(format!(
                    "keep the class mass on one geom of `{}` and give the others mass=\"0\" (or a visual class with mass=\"0\"), or state the body's <inertial>",
                    b.name
                ))
                .subject(Subject::Body(body))
                .measured(b.mass, "kg")
                .expected(b.mass - (n - 1) as f64 * mass, "kg")
                .with("geoms", n as f64);
            out.push(f);
        }
    }
}
