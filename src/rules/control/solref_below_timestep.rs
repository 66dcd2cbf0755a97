use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::Robot;
use crate::model::contact::{contact, contacts_disabled, takes_part};
use crate::model::mjcf::ElemKind;
use crate::model::source::{Loc, XNode};
use crate::rules::{Context, Rule, RuleMeta, display_name};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds constraints whose `solref` time constant (standard form: both numbers positive) is
    /// below twice the timestep. With MuJoCo's `refsafe` flag on (the default), the solver uses
    /// max(solref[0], 2 × timestep) for every active constraint (`getsolparam` in
    /// `engine_core_constraint.c`; the MJCF reference, `option/flag refsafe`), so such a
    /// constraint is softer than the file says. Read from the compiled model (`opt.timestep` and
    /// the compiled solref arrays, after default classes), for every constraint MuJoCo can make:
    /// - contacts between two geoms that may touch (the masks, `<exclude>` and weld/parent
    ///   filters let them): the solref MuJoCo combines for the pair (the higher-`priority`
    ///   geom's, else the `solmix`-weighted mean; `model::contact`), reported on each geom whose
    ///   own solref is below the bound, naming a partner;
    /// - explicit `<contact><pair>`s: their `solref` and `solreffriction`;
    /// - with `<flag override="enable"/>`, every contact uses `<option o_solref>` instead;
    /// - joint limits (`solreflimit` of a limited joint) and joint dry friction
    ///   (`solreffriction` of a joint with `frictionloss`);
    /// - equality constraints (`solref`);
    /// - tendon limits and tendon friction (`solreflimit`, `solreffriction`).
    ///
    /// Not reported: direct solref (negative numbers: stiffness and damping given directly,
    /// which refsafe leaves alone), mixed-sign solref (MuJoCo replaces it with the default and
    /// warns itself), `<flag refsafe="disable"/>`, constraint kinds the model disables with
    /// `<flag>` (contact, limit, equality, frictionloss, constraint), and flex contacts.
    ///
    /// ## Why is this bad?
    /// The reference stiffness of a constraint is proportional to 1 / timeconst² and its damping
    /// to 1 / timeconst: a contact written as solref 0.002 at a 0.005 s timestep is simulated as
    /// 0.01, 25 times less stiff, and sinks and bounces accordingly. The file no longer says what
    /// the simulation does: a foot contact or a joint stop tuned (or fitted) in the file is not
    /// the one the policy trains on, and the same file behaves differently at another timestep.
    ///
    /// ## How it is confirmed
    /// Static: MuJoCo's own rule applied to the compiled values; nothing a simulation of the
    /// model could measure differs from it.
    ///
    /// ## How to fix
    /// Write the time constant MuJoCo actually uses (≥ 2 × timestep), or lower the timestep
    /// until the intended one is at least twice it. A stiffer constraint than that bound needs
    /// a smaller timestep (or the direct, negative solref form, which refsafe does not touch).
    pub SolrefBelowTimestep {
        id: "solref-below-timestep",
        group: "control",
        level: Severity::Warning,
        probe: None,
        options: [],
    }
}

/// MuJoCo's disable bits (`mjtDisableBit`, mjtype.h of MuJoCo 3.17).
const DSBL_CONSTRAINT: i32 = 1;
const DSBL_EQUALITY: i32 = 1 << 1;
const DSBL_FRICTIONLOSS: i32 = 1 << 2;
const DSBL_LIMIT: i32 = 1 << 3;
const DSBL_REFSAFE: i32 = 1 << 12;
/// `mjENBL_OVERRIDE`: contacts take `opt.o_solref` (and friction, solimp, margin).
const ENBL_OVERRIDE: i32 = 1;
/// MuJoCo's refsafe floor, in timesteps: solref[0] ≥ 2 × timestep.
const REFSAFE_STEPS: f64 = 2.0;

/// The time constant MuJoCo uses instead of `solref`'s, when refsafe raises it.
fn raised(solref: [f64; 2], floor: f64) -> Option<f64> {
    (solref[0] > 0.0 && solref[1] > 0.0 && solref[0] < floor).then_some(floor)
}

struct Bound {
    dt: f64,
    floor: f64,
}

impl Bound {
    /// "… time constant 0.002 s is below 2 × timestep (0.01 s): MuJoCo (refsafe) uses 0.01 s".
    fn sentence(&self, what: &str, attr: &str, tc: f64) -> String {
        format!(
            "{what}: {attr} time constant {} s is below 2 × timestep (2 × {} = {} s); MuJoCo (refsafe) uses {} s, {}× less stiff than the file says",
            fmt_num(tc, 4),
            fmt_num(self.dt, 4),
            fmt_num(self.floor, 4),
            fmt_num(self.floor, 4),
            fmt_num((self.floor / tc).powi(2), 3),
        )
    }
    fn finish(&self, f: Finding, tc: f64) -> Finding {
        self.finish_noted(f, tc, "")
    }
    fn finish_noted(&self, f: Finding, tc: f64, before: &str) -> Finding {
        f.label(format!("timeconst {} s < {} s", fmt_num(tc, 4), fmt_num(self.floor, 4)))
            .note(format!("{before}refsafe (on by default) makes the solver use max(solref[0], 2·timestep) for every constraint in the standard (positive) solref form; the reference stiffness scales as 1/timeconst², the damping as 1/timeconst"))
            .help(format!(
                "write a time constant ≥ {} s (what MuJoCo uses now), or lower the timestep to ≤ {} s to get the stiffness the file asks for",
                fmt_num(self.floor, 4),
                fmt_num(tc / REFSAFE_STEPS, 4)
            ))
            .measured(tc, "s")
            .expected(self.floor, "s")
            .with("effective_timeconst_s", self.floor)
    }
}

/// The `<option o_solref>` attribute (or the `<option>` element) of an MJCF file.
fn option_loc(robot: &Robot) -> Loc {
    let mut found = None;
    robot.tree.walk(&mut |n: &XNode| {
        if found.is_none() && n.tag == "option" {
            found = Some(n.attr("o_solref").map_or(n.loc, |a| a.loc));
        }
    });
    found.unwrap_or_else(|| robot.root_loc())
}

impl Rule for SolrefBelowTimestep {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let m = &robot.mj;
        let flags = robot.opt.disableflags;
        let dt = robot.opt.timestep;
        if flags & (DSBL_REFSAFE | DSBL_CONSTRAINT) != 0 || !(dt > 0.0) {
            return;
        }
        let b = Bound { dt, floor: REFSAFE_STEPS * dt };
        let on = |bit: i32| flags & bit == 0;
        // Joint limits and joint dry friction.
        let (jl, jsr, dsr, dfl) =
            (m.jnt_limited(), m.jnt_solref(), m.dof_solref(), m.dof_frictionloss());
        for j in &robot.joints {
            let name = display_name(&j.name, j.id);
            let sr = jsr.get(j.id).copied().unwrap_or([0.0; 2]);
            if on(DSBL_LIMIT)
                && jl.get(j.id).copied().unwrap_or(false)
                && raised(sr, b.floor).is_some()
            {
                let msg = b.sentence(&format!("joint `{name}` limit"), "solreflimit", sr[0]);
                let f = cx.at_attr(ElemKind::Joint, j.id, &j.name, "solreflimit", msg);
                out.push(b.finish(f, sr[0]).subject(Subject::Joint(j.id)));
            }
            let fr = dfl.get(j.dofadr).copied().unwrap_or(0.0);
            let sr = dsr.get(j.dofadr).copied().unwrap_or([0.0; 2]);
            if on(DSBL_FRICTIONLOSS) && fr > 0.0 && raised(sr, b.floor).is_some() {
                let msg =
                    b.sentence(&format!("joint `{name}` dry friction"), "solreffriction", sr[0]);
                let f = cx.at_attr(ElemKind::Joint, j.id, &j.name, "solreffriction", msg);
                out.push(b.finish(f, sr[0]).subject(Subject::Joint(j.id)));
            }
        }
        // Equality constraints.
        let esr = m.eq_solref();
        for e in &robot.equalities {
            let sr = esr.get(e.id).copied().unwrap_or([0.0; 2]);
            if on(DSBL_EQUALITY) && raised(sr, b.floor).is_some() {
                let what = format!("equality `{}`", display_name(&e.name, e.id));
                let msg = b.sentence(&what, "solref", sr[0]);
                let f = cx.at_attr(ElemKind::Equality, e.id, &e.name, "solref", msg);
                out.push(b.finish(f, sr[0]).subject(Subject::Model));
            }
        }
        // Tendon limits and tendon friction.
        let (tl, tsl, tsf, tfl) = (
            m.tendon_limited(),
            m.tendon_solref_lim(),
            m.tendon_solref_fri(),
            m.tendon_frictionloss(),
        );
        for (t, tname) in robot.tendons.iter().enumerate() {
            let what = format!("tendon `{}`", display_name(tname, t));
            let sr = tsl.get(t).copied().unwrap_or([0.0; 2]);
            if on(DSBL_LIMIT)
                && tl.get(t).copied().unwrap_or(false)
                && raised(sr, b.floor).is_some()
            {
                let msg = b.sentence(&format!("{what} limit"), "solreflimit", sr[0]);
                let f = cx.at_attr(ElemKind::Tendon, t, tname, "solreflimit", msg);
                out.push(b.finish(f, sr[0]).subject(Subject::Model));
            }
            let sr = tsf.get(t).copied().unwrap_or([0.0; 2]);
            if on(DSBL_FRICTIONLOSS)
                && tfl.get(t).copied().unwrap_or(0.0) > 0.0
                && raised(sr, b.floor).is_some()
            {
                let msg = b.sentence(&format!("{what} dry friction"), "solreffriction", sr[0]);
                let f = cx.at_attr(ElemKind::Tendon, t, tname, "solreffriction", msg);
                out.push(b.finish(f, sr[0]).subject(Subject::Model));
            }
        }
        // Contacts.
        if contacts_disabled(robot) {
            return;
        }
        if m.ffi().opt.enableflags & ENBL_OVERRIDE != 0 {
            let sr = m.ffi().opt.o_solref;
            if raised(sr, b.floor).is_some() && robot.geoms.iter().any(|g| takes_part(robot, g.id))
            {
                let msg = b.sentence("every contact (contact override)", "o_solref", sr[0]);
                let f = cx.finding(msg, option_loc(robot));
                out.push(b.finish(f, sr[0]).subject(Subject::Model));
            }
            return;
        }
        let psf = m.pair_solreffriction();
        for p in &robot.pairs {
            let what = format!("contact pair {}", display_name(&p.name, p.id));
            if raised(p.solref, b.floor).is_some() {
                let msg = b.sentence(&what, "solref", p.solref[0]);
                let f = cx.at_attr(ElemKind::Pair, p.id, &p.name, "solref", msg);
                out.push(b.finish(f, p.solref[0]).subject(Subject::Model));
            }
            let sr = psf.get(p.id).copied().unwrap_or([0.0; 2]);
            if raised(sr, b.floor).is_some() {
                let msg = b.sentence(&format!("{what} friction"), "solreffriction", sr[0]);
                let f = cx.at_attr(ElemKind::Pair, p.id, &p.name, "solreffriction", msg);
                out.push(b.finish(f, sr[0]).subject(Subject::Model));
            }
        }
        // Dynamic contacts: a geom whose own time constant is below the bound, and the partners
        // whose combined contact with it MuJoCo would raise (explicit pairs are reported above).
        // Each contact is reported once, on the first of its two geoms (the world's, e.g. a
        // floor, come first).
        let mut seen: std::collections::BTreeSet<(usize, usize)> = Default::default();
        // (geom, the partner named, the contact's time constant, every partner), grouped by
        // the attribute that sets the geom's solref: geoms that inherit it from one `<default>`
        // are one finding there, where the fix is.
        type Entry = (usize, usize, f64, Vec<usize>);
        let mut groups: std::collections::BTreeMap<Loc, Vec<Entry>> = Default::default();
        for g in &robot.geoms {
            if raised(g.solref, b.floor).is_none() {
                continue;
            }
            let partners: Vec<(usize, f64)> = robot
                .geoms
                .iter()
                .filter(|o| {
                    o.id != g.id
                        && !seen.contains(&(g.id.min(o.id), g.id.max(o.id)))
                        && crate::model::contact::pair_of(robot, g.id, o.id).is_none()
                })
                .filter_map(|o| {
                    let c = contact(robot, g.id, o.id)?;
                    raised(c.solref, b.floor).map(|_| (o.id, c.solref[0]))
                })
                .collect();
            // Name the ground first (what a foot touches), then the lowest id.
            let Some(&(o, tc)) =
                partners.iter().min_by_key(|&&(o, _)| (robot.geoms[o].body != 0, o))
            else {
                continue;
            };
            seen.extend(partners.iter().map(|&(p, _)| (g.id.min(p), g.id.max(p))));
            let (loc, _) = robot.attr_loc(ElemKind::Geom, g.id, &g.name, "solref");
            let ids = partners.iter().map(|p| p.0).collect();
            groups.entry(loc).or_default().push((g.id, o, tc, ids));
        }
        for (loc, entries) in &groups {
            let (g, o, n) = (entries[0].0, entries[0].1, entries[0].3.len());
            // Every geom of the group's contacts that takes its solref from this attribute.
            let mut involved: std::collections::BTreeSet<usize> = Default::default();
            for e in entries {
                involved.insert(e.0);
                involved.extend(e.3.iter().copied().filter(|&p| {
                    let q = &robot.geoms[p];
                    robot.attr_loc(ElemKind::Geom, p, &q.name, "solref").0 == *loc
                }));
            }
            let tc = entries.iter().map(|e| e.2).fold(f64::INFINITY, f64::min);
            let geom = &robot.geoms[g];
            let gname = robot.geom_ref(g);
            let oname = robot.geom_ref(o);
            let what = if entries.len() == 1 {
                let more =
                    if n > 1 { format!(" (and {} more geoms)", n - 1) } else { String::new() };
                format!("geom {gname}'s contact with {oname}{more}")
            } else {
                let names: Vec<String> =
                    involved.iter().take(4).map(|&i| robot.geom_ref(i)).collect();
                let more = if involved.len() > 4 {
                    format!(" and {} more", involved.len() - 4)
                } else {
                    String::new()
                };
                format!(
                    "the contacts of {} geoms that take this solref ({}{more})",
                    involved.len(),
                    names.join(", ")
                )
            };
            let msg = b.sentence(&what, "combined solref", tc);
            let mut f = cx.at_attr(ElemKind::Geom, g, &geom.name, "solref", msg);
            let other = &robot.geoms[o];
            if entries.len() == 1 && raised(other.solref, b.floor).is_some() {
                let (loc, _) = robot.attr_loc(ElemKind::Geom, o, &other.name, "solref");
                f = f.secondary(
                    loc,
                    format!("{oname}'s own time constant {} s", fmt_num(other.solref[0], 4)),
                );
            }
            let before = format!(
                "the geom's own solref time constant is {} s; a contact's is the higher-priority geom's, else the solmix-weighted mean of the two; ",
                fmt_num(geom.solref[0], 4)
            );
            let f = b.finish_noted(f, tc, &before).subject(Subject::Geom(g));
            out.push(f.with("geoms", involved.len().max(1) as f64));
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::lint::{LintInput, load, run_rules};
    use mujoco_rs::prelude::MjData;

    /// MuJoCo itself decides what it uses: the damping of a constraint row it builds is
    /// B = 2 / (dmax · timeconst) (`efc_KBIP`), so the time constant the solver used is read
    /// back from the row and must be the finding's effective value, not the file's.
    #[test]
    fn effective_time_constant_is_the_one_mujoco_uses() {
        let input = LintInput {
            model: "fixtures/rules/solref-below-timestep/invalid.xml".into(),
            spec: None,
            config: None,
            select: vec!["solref-below-timestep".into()],
            ignore: vec![],
        };
        let loaded = load(&input).expect("fixture loads");
        let findings = run_rules(&loaded);
        let robot = &loaded.robot;
        let hip = robot.joint("hip").expect("hip").id;
        let foot = robot.geoms.iter().find(|g| g.name == "foot").expect("foot").id;
        let effective = |subject: crate::finding::Subject| {
            findings
                .iter()
                .find(|f| f.subject == subject)
                .and_then(|f| f.data.get("effective_timeconst_s").copied())
                .expect("a finding with the effective time constant")
        };
        let (limit_tc, contact_tc) = (
            effective(crate::finding::Subject::Joint(hip)),
            // The floor-foot contact is reported once, on the floor (geom 0).
            effective(crate::finding::Subject::Geom(0)),
        );
        let m = &robot.mj;
        // The rows MuJoCo builds at a state: (type, object id, K B I P).
        let rows_at = |base_z: f64, hip_q: f64| {
            let mut d = MjData::new(m);
            d.qpos_mut()[2] = base_z;
            d.qpos_mut()[robot.joints[hip].qposadr] = hip_q;
            d.forward();
            // SAFETY: forward() ran the whole pipeline, which fills efc_KBIP for all nefc rows.
            let kbip = unsafe { d.efc_kbip() }.to_vec();
            let rows: Vec<(i32, i32, [f64; 4])> = d
                .efc_type()
                .iter()
                .zip(d.efc_id())
                .zip(kbip)
                .map(|((&t, &id), k)| (t as i32, id, k))
                .collect();
            let contacts: Vec<(usize, usize, f64)> = d
                .contact()
                .iter()
                .map(|c| (c.geom1 as usize, c.geom2 as usize, c.solimp[1]))
                .collect();
            (rows, contacts)
        };
        // The hip past its upper stop (range ±1), high above the floor.
        let (rows, _) = rows_at(2.0, 1.05);
        let limit = rows.iter().find(|r| r.0 == 3 && r.1 == hip as i32).expect("hip limit row");
        let dmax = m.jnt_solimp()[hip][1];
        let used = 2.0 / (dmax * limit.2[1]);
        assert!((used - limit_tc).abs() < 1e-9, "MuJoCo used {used} s, finding says {limit_tc}");
        assert!((used - 0.004).abs() > 1e-3, "MuJoCo did not raise the file's 0.004 s");
        // Leg straight down, the foot's tip (0.08 m above the floor at base height 0.6) 1 cm in.
        let (rows, contacts) = rows_at(0.51, 0.0);
        let c = contacts.iter().position(|c| c.0 == foot || c.1 == foot);
        let c = c.expect("foot touches the floor");
        let row = rows.iter().find(|r| r.0 >= 5 && r.1 == c as i32).expect("contact row");
        let used = 2.0 / (contacts[c].2 * row.2[1]);
        assert!(
            (used - contact_tc).abs() < 1e-9,
            "MuJoCo used {used} s, finding says {contact_tc}"
        );
    }
}
