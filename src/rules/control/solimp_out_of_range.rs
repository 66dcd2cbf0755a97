use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::contact::takes_part;
use crate::model::mjcf::ElemKind;
use crate::rules::{Context, Rule, RuleMeta};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds colliding geoms whose `solimp` impedance bounds, d0 = solimp[0] and
    /// dwidth = solimp[1], lie outside [0, 1] — e.g. `solimp="2 1 0.01"`. (0 and 1 themselves
    /// are clipped by 0.0001, which changes nothing a contact does, and are not reported.)
    /// MuJoCo clips both to [mjMINIMP, mjMAXIMP] = [0.0001, 0.9999] when it builds each
    /// contact (`getimpedance` in `engine_core_constraint.c`), silently. Read from the compiled
    /// `geom_solimp` (after default classes); one finding per value and class of geoms that take
    /// it.
    ///
    /// ## Why is this bad?
    /// The impedance is the fraction of the constraint force that acts (0: none, 1: all): a
    /// value of 2 is not a valid impedance, and the contact that runs has 0.9999, not what the
    /// file says. A tuned grip or foot contact is then not the one trained on, and the file reads
    /// as if a stiffer-than-rigid contact were possible. MuJoCo XML reference, "solimp".
    ///
    /// ## How it is confirmed
    /// Static: MuJoCo's own clipping applied to the compiled values; no simulation of the model
    /// measures anything else.
    ///
    /// ## How to fix
    /// Write impedances inside (0, 1): `solimp="0.95 0.99 0.001"` for a hard contact (MuJoCo's
    /// default is `0.9 0.95 0.001`); make a contact stiffer with `solref`, not with impedance.
    pub SolimpOutOfRange {
        id: "solimp-out-of-range",
        group: "control",
        level: Severity::Warning,
        probe: None,
        options: [],
    }
}

impl Rule for SolimpOutOfRange {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        // 0 and 1 are clipped by 0.0001, which changes nothing a contact does (Menagerie's
        // legged robots write `0.015 1 0.031` on purpose); beyond [0, 1] the value is no
        // impedance at all.
        let bad = |x: f64| !(0.0..=1.0).contains(&x);
        // Geoms grouped by where their solimp value is written (an inherited class value once).
        let mut groups: std::collections::BTreeMap<(usize, usize, usize), Vec<usize>> =
            std::collections::BTreeMap::new();
        for g in &robot.geoms {
            if !takes_part(robot, g.id) || !(bad(g.solimp[0]) || bad(g.solimp[1])) {
                continue;
            }
            let (loc, _) = robot.attr_loc(ElemKind::Geom, g.id, &g.name, "solimp");
            groups.entry((loc.file, loc.start, loc.end)).or_default().push(g.id);
        }
        for ids in groups.values() {
            let g = &robot.geoms[ids[0]];
            let mut shown: Vec<String> = ids.iter().take(4).map(|&i| robot.geom_ref(i)).collect();
            if ids.len() > 4 {
                shown.push(format!("and {} more", ids.len() - 4));
            }
            let msg = format!(
                "solimp ({}, {}, {}) of {} colliding geom{} ({}): impedance {} outside [0, 1]; MuJoCo clips it to 0.0001 … 0.9999 in every contact",
                fmt_num(g.solimp[0], 4),
                fmt_num(g.solimp[1], 4),
                fmt_num(g.solimp[2], 4),
                ids.len(),
                if ids.len() == 1 { "" } else { "s" },
                shown.join(", "),
                [g.solimp[0], g.solimp[1]]
                    .iter()
                    .filter(|x| bad(**x))
                    .map(|x| fmt_num(*x, 4))
                    .collect::<Vec<_>>()
                    .join(" and ")
            );
            let f = cx
                .at_attr(ElemKind::Geom, g.id, &g.name, "solimp", msg)
                .label("impedance outside [0, 1]")
                .note("an impedance is the fraction of the constraint force that acts: MuJoCo clips d0 and dwidth to 0.0001 … 0.9999, so the contact that runs is not the one written")
                .help("write impedances inside (0, 1), e.g. solimp=\"0.95 0.99 0.001\"; stiffen a contact with solref instead")
                .subject(Subject::Geom(g.id))
                .measured(g.solimp[0].max(g.solimp[1]), "")
                .with("geoms", ids.len() as f64);
            out.push(f);
        }
    }
}
