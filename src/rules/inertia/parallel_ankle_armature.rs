use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::{Joint, Robot, Transmission};
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::spec::{JointFacts, Spec, v};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// A joint driven by N motors together (spec `count = N > 1`, e.g. ankle pitch and roll
    /// through a parallel RSU linkage, or detected: N tendon actuators reaching the joint) sees
    /// the reflected inertia of all N rotors, so its armature must be N × rotor_inertia × gear².
    /// Reports such joints that carry a different value (typically one motor's), and single-motor
    /// joints that carry a doubled value: twice their own family's, or the parallel family's
    /// N-motor value copied onto them.
    ///
    /// Without a spec (for joints the spec gives no motor family, or one without rotor_inertia and
    /// gear_ratio) it detects reuse of the model's
    /// own doubled values: a value that is exactly 2 × another value the model gives actuated
    /// joints (within `exact_tolerance`) is a two-motor value. Reported on passive joints (no
    /// actuator, or `passive = true` in the spec) that carry it — e.g. passive neck joints with
    /// 0.0565056 = 2 × 0.0282528, the parallel ankle's value — and on single-motor joints that
    /// carry it while the model shows elsewhere which joints really are two-motor ones (two
    /// tendon actuators reach them, or both joints of one ankle carry the doubled value: the
    /// parallel RSU ankle, whose two motors drive pitch and roll together; an ankle whose other
    /// joint carries a different value has one motor per axis). A passive joint that joint equalities tie to an actuated joint
    /// carrying the same value (the linked fingers of a coupled gripper) carries its driver's
    /// value and is not reported. Armature is the effective value (joint + actuator·gear² +
    /// tendon).
    ///
    /// ## Why is this bad?
    /// Armature strongly affects closed-loop behaviour (Asimov system identification §2). Halving a parallel ankle's
    /// reflected inertia makes it twice as lively in simulation as on hardware; copying the
    /// doubled ankle value onto a single-motor joint makes that joint artificially sluggish.
    ///
    /// ## How it is confirmed
    /// Static: compiled `dof_armature` against the spec's motor families and counts.
    ///
    /// ## How to fix
    /// Set armature = count × rotor_inertia × gear_ratio² for the joint's own family.
    pub ParallelAnkleArmature {
        id: "parallel-ankle-armature",
        group: "inertia",
        level: Severity::Error,
        probe: None,
        options: [
            opt("tolerance", 0.05, "fraction", Domain::NON_NEGATIVE, "relative tolerance when comparing armature values"),
            opt("exact_tolerance", 1e-4, "fraction", Domain::NON_NEGATIVE, "without a spec: relative tolerance of an exact doubling (a copied value)"),
        ],
    }
}

#[derive(Debug, Clone, PartialEq)]
pub enum Issue {
    /// An N-motor joint whose armature is not N × single.
    Parallel { n: u32, detected: bool, single: f64, expected: f64, carries_single: bool },
    /// A single-motor joint carrying twice its own family's value.
    DoubledOwn { single: f64 },
    /// A single-motor joint carrying another (parallel) family's N-motor value.
    Reused { family: String, n: u32, value: f64, single: f64 },
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * b.abs().max(1e-12)
}

fn single_value(spec: &Spec, family: &str) -> Option<f64> {
    let m = spec.motor(family)?;
    let (ri, g) = (v(&m.rotor_inertia)?, v(&m.gear_ratio)?);
    Some(ri * g * g)
}

/// Number of tendon-transmission actuators reaching joint `j` (a parallel linkage drives each
/// of its joints through several).
pub fn tendon_motor_count(robot: &Robot, j: usize) -> u32 {
    robot.actuators_on_joint(j).iter().filter(|a| a.trn == Transmission::Tendon).count() as u32
}

/// The parallel-drive armature problem of a joint, if any (shared with `armature-mismatch`,
/// which leaves these joints to this rule).
pub fn parallel_issue(
    cx: &Context,
    spec: &Spec,
    j: &Joint,
    facts: &JointFacts,
    tol: f64,
) -> Option<Issue> {
    let fam = facts.motor.as_deref()?;
    if facts.passive {
        return None;
    }
    let single = single_value(spec, fam)?;
    let detected = tendon_motor_count(cx.robot, j.id);
    let n = facts.count.max(if facts.count == 1 && detected >= 2 { detected } else { 1 });
    let a = j.armature;
    if n > 1 {
        let expected = single * n as f64;
        if close(a, expected, tol) {
            return None;
        }
        return Some(Issue::Parallel {
            n,
            detected: facts.count == 1,
            single,
            expected,
            carries_single: close(a, single, tol),
        });
    }
    if !(a > 0.0) || close(a, single, tol) {
        return None;
    }
    // One value copy-pasted onto every actuated joint is `armature-mismatch`'s uniform finding,
    // not a doubling, even when it happens to be twice some family's value.
    let uniform = cx
        .robot
        .joints
        .iter()
        .filter(|o| {
            o.is_scalar() && spec.joint(&o.name).is_some_and(|f| f.motor.is_some() && !f.passive)
        })
        .all(|o| o.armature == a);
    if !uniform && close(a, 2.0 * single, tol) {
        return Some(Issue::DoubledOwn { single });
    }
    for other in &cx.robot.joints {
        let Some(of) = spec.joint(&other.name) else { continue };
        let (Some(ofam), true) = (of.motor.as_deref(), of.count > 1) else { continue };
        let Some(os) = single_value(spec, ofam) else { continue };
        let value = os * of.count as f64;
        if close(a, value, tol) {
            return Some(Issue::Reused { family: ofam.to_string(), n: of.count, value, single });
        }
    }
    None
}

impl Rule for ParallelAnkleArmature {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        doubled_without_spec(cx, out);
        let Some(spec) = cx.spec else { return };
        let tol = cx.opt("tolerance");
        for j in cx.robot.joints.iter().filter(|j| j.is_scalar()) {
            let Some(facts) = spec.joint(&j.name) else { continue };
            let Some(issue) = parallel_issue(cx, spec, j, &facts, tol) else { continue };
            let fam = facts.motor.clone().unwrap_or_default();
            let a = j.armature;
            let (msg, expected, note) = match &issue {
                Issue::Parallel { n, detected, single, expected, carries_single } => (
                    format!(
                        "joint `{}` is driven by {n} `{fam}` motors{} but its armature {} kg·m² {}; expected {n} × {} = {} kg·m²",
                        j.name,
                        if *detected {
                            format!(
                                " (the model reaches it through {n} tendon actuators; the spec says count = 1)"
                            )
                        } else {
                            String::new()
                        },
                        fmt_num(a, 4),
                        if *carries_single {
                            "is one motor's reflected inertia"
                        } else {
                            "is not their combined reflected inertia"
                        },
                        fmt_num(*single, 4),
                        fmt_num(*expected, 4)
                    ),
                    *expected,
                    "every motor of a parallel linkage reflects its rotor inertia onto the joint; with one motor's value the simulated joint is far livelier than the hardware (Asimov system identification §2: the ankle value is doubled for the two RSU motors)",
                ),
                Issue::DoubledOwn { single } => (
                    format!(
                        "single-motor joint `{}` carries armature {} kg·m², twice its `{fam}` family's reflected inertia {} kg·m²",
                        j.name,
                        fmt_num(a, 4),
                        fmt_num(*single, 4)
                    ),
                    *single,
                    "doubling belongs to joints driven by two motors through a parallel linkage; on a single-motor joint it makes the simulated joint twice as sluggish as the hardware",
                ),
                Issue::Reused { family, n, value, single } => (
                    format!(
                        "single-motor joint `{}` carries armature {} kg·m², the {n}-motor value of the parallel `{family}` family ({} kg·m²), not its own `{fam}` value {} kg·m²",
                        j.name,
                        fmt_num(a, 4),
                        fmt_num(*value, 4),
                        fmt_num(*single, 4)
                    ),
                    *single,
                    "a value copied from the parallel ankle carries that linkage's doubled inertia onto a joint that has one motor",
                ),
            };
            let mut f = cx
                .at_attr(ElemKind::Joint, j.id, &j.name, "armature", msg)
                .label(format!("armature {} kg·m²", fmt_num(a, 4)))
                .note(note)
                .help(format!(
                    "set armature=\"{}\" (count × rotor_inertia × gear_ratio²)",
                    fmt_num(expected, 6)
                ))
                .subject(Subject::Joint(j.id))
                .measured(a, "kg·m²")
                .expected(expected, "kg·m²")
                .with("armature", a)
                .with("expected_armature", expected);
            if let Some(l) = facts.motor_loc {
                f = f.secondary(l, format!("spec motor family `{fam}` (count = {})", facts.count));
            }
            out.push(f);
        }
    }
}

/// Passive joint `j` is tied, through a chain of joint equalities (`<equality><joint>`), to an
/// actuated joint whose armature is `value` too: the follower of a coupled mechanism (a gripper's
/// or a hand's linked phalanges) that carries the value of the joint that drives it.
fn follows_driver(
    robot: &Robot,
    j: usize,
    value: f64,
    passive: &dyn Fn(&Joint) -> bool,
    same: &dyn Fn(f64, f64) -> bool,
) -> bool {
    const JOINT_EQUALITY: i32 = 2;
    let links: Vec<(usize, usize)> = robot
        .equalities
        .iter()
        .filter(|e| e.etype == JOINT_EQUALITY && e.obj1 >= 0 && e.obj2 >= 0)
        .map(|e| (e.obj1 as usize, e.obj2 as usize))
        .filter(|&(a, b)| a < robot.joints.len() && b < robot.joints.len())
        .collect();
    let mut seen = vec![j];
    let mut next = vec![j];
    while let Some(k) = next.pop() {
        for &(a, b) in &links {
            let o = if a == k {
                b
            } else if b == k {
                a
            } else {
                continue;
            };
            if seen.contains(&o) {
                continue;
            }
            let oj = &robot.joints[o];
            if !passive(oj) && same(oj.armature, value) {
                return true;
            }
            seen.push(o);
            next.push(o);
        }
    }
    false
}

fn is_ankle(robot: &Robot, j: usize) -> bool {
    robot.joints[j].name.to_lowercase().contains("ankle")
}

/// The other ankle joints of joint `j`'s ankle: ankle joints on its own body, its parent body or
/// a child body (pitch and roll of one foot).
fn ankle_partners(robot: &Robot, j: usize) -> Vec<usize> {
    let parent = robot.mj.body_parentid();
    let body = robot.joints[j].body;
    let near = |b: usize| {
        b == body
            || parent.get(body).is_some_and(|&p| p as usize == b)
            || parent.get(b).is_some_and(|&p| p as usize == body)
    };
    robot
        .joints
        .iter()
        .filter(|o| o.id != j && o.is_scalar() && is_ankle(robot, o.id) && near(o.body))
        .map(|o| o.id)
        .collect()
}

/// Reuse of the model's own doubled values, for joints the spec gives no motor family (or one
/// without rotor inertia and gear ratio).
fn doubled_without_spec(cx: &Context, out: &mut Vec<Finding>) {
    let robot = cx.robot;
    let etol = cx.opt("exact_tolerance");
    let scalar: Vec<&Joint> =
        robot.joints.iter().filter(|j| j.is_scalar() && j.armature > 0.0).collect();
    let passive = |j: &Joint| {
        robot.actuators_on_joint(j.id).is_empty() || cx.facts(&j.name).is_some_and(|f| f.passive)
    };
    // A family whose single-motor value the spec states (rotor inertia and gear ratio); a family
    // left as a placeholder (`modellint init-spec`) checks as if the spec were absent.
    let has_family = |j: &Joint| {
        cx.facts(&j.name).is_some_and(|f| {
            !f.passive
                && f.motor
                    .as_deref()
                    .is_some_and(|m| cx.spec.and_then(|s| single_value(s, m)).is_some())
        })
    };
    let same = |a: f64, b: f64| (a - b).abs() <= etol * a.abs().max(b.abs());
    // Distinct values carried by actuated joints, each with its joints.
    let mut bases: Vec<(f64, Vec<usize>)> = Vec::new();
    for j in scalar.iter().filter(|j| !passive(j)) {
        match bases.iter_mut().find(|(v, _)| same(*v, j.armature)) {
            Some((_, js)) => js.push(j.id),
            None => bases.push((j.armature, vec![j.id])),
        }
    }
    // value → (passive joints, single-motor joints) carrying 2 × some base.
    let mut hits: Vec<(f64, f64, Vec<usize>, Vec<usize>)> = Vec::new();
    for j in &scalar {
        if has_family(j) {
            continue;
        }
        let Some((base, _)) = bases.iter().find(|(b, _)| same(j.armature, 2.0 * b)) else {
            continue;
        };
        let entry = match hits.iter_mut().position(|h| same(h.0, j.armature)) {
            Some(i) => &mut hits[i],
            None => {
                hits.push((j.armature, *base, Vec::new(), Vec::new()));
                hits.last_mut().unwrap()
            }
        };
        if passive(j) {
            // A follower a joint equality ties to an actuated joint of the same armature (a
            // coupled gripper's or hand's passive joints) carries its driver's value, not a copy.
            if !follows_driver(robot, j.id, j.armature, &passive, &same) {
                entry.2.push(j.id);
            }
        } else {
            entry.3.push(j.id);
        }
    }
    let names = |ids: &[usize]| {
        ids.iter().map(|&i| format!("`{}`", robot.joints[i].name)).collect::<Vec<_>>().join(", ")
    };
    for (value, base, passive_ids, single_ids) in hits {
        let base_joints =
            &bases.iter().find(|(b, _)| same(*b, base)).map(|x| x.1.clone()).unwrap_or_default();
        // Single-motor joints count only when the model shows which joints are two-motor ones:
        // two tendon actuators reach them, or they are ankles (the parallel RSU ankle is the
        // design that doubles armature) carrying the doubled value — with the other DoF of the
        // same ankle: both motors of a parallel ankle drive its pitch and its roll, so an ankle
        // whose other joint carries a different value (one Dynamixel per axis, each its own
        // identified value, one happening to be twice the other's) is no parallel ankle.
        let parallel: Vec<usize> = single_ids
            .iter()
            .copied()
            .filter(|&i| {
                tendon_motor_count(robot, i) >= 2
                    || (is_ankle(robot, i)
                        && ankle_partners(robot, i)
                            .iter()
                            .all(|&o| same(robot.joints[o].armature, robot.joints[i].armature)))
            })
            .collect();
        let flagged_single: Vec<usize> = if parallel.is_empty() {
            Vec::new()
        } else {
            single_ids
                .iter()
                .copied()
                .filter(|i| !parallel.contains(i) && robot.actuators_on_joint(*i).len() == 1)
                .collect()
        };
        let legit: Vec<usize> =
            single_ids.iter().copied().filter(|i| !flagged_single.contains(i)).collect();
        for (ids, what) in [(passive_ids, "passive"), (flagged_single, "single-motor")] {
            if ids.is_empty() {
                continue;
            }
            let j = &robot.joints[ids[0]];
            let who = if ids.len() == 1 {
                format!("{what} joint `{}` carries", j.name)
            } else {
                format!("{} {what} joints ({}) carry", ids.len(), names(&ids))
            };
            let also = if legit.is_empty() {
                String::new()
            } else {
                format!(" (also on actuated {})", names(&legit))
            };
            let mut shown_base: Vec<usize> = base_joints.iter().copied().take(6).collect();
            shown_base.retain(|i| !ids.contains(i));
            let more = base_joints.len().saturating_sub(shown_base.len());
            let msg = format!(
                "{who} armature {} kg·m², exactly 2 × the {} kg·m² of {}{}{also}: a two-motor value on a joint {}",
                fmt_num(value, 6),
                fmt_num(base, 6),
                names(&shown_base),
                if more > 0 { format!(" and {more} more") } else { String::new() },
                if what == "passive" { "that has no motor" } else { "driven by one motor" }
            );
            let mut f = crate::rules::inertia::at_armature(cx, j, msg)
                .label(format!("armature {} = 2 × {}", fmt_num(value, 6), fmt_num(base, 6)))
                .note(format!(
                    "doubling belongs to joints driven by two motors through a parallel linkage (Asimov system identification §2: the ankle value is doubled for the two RSU motors); copied onto {} it makes the joint twice as sluggish as one motor would, or adds rotor inertia where there is no rotor{}",
                    if what == "passive" { "a passive joint" } else { "a single-motor joint" },
                    if j.armature_elsewhere() { format!("; effective armature = {}", crate::model::describe_parts(robot, &j.armature_parts, "armature")) } else { String::new() }
                ))
                .help(if what == "passive" {
                    "give a passive joint only what it really has (a small armature for its own transmission, or none) plus its spring and damping; add a spec with `passive = true` to confirm".to_string()
                } else {
                    format!("set armature=\"{}\" (one motor's reflected inertia), or give the joint its own family's value", fmt_num(base, 6))
                })
                .subject(Subject::Joint(j.id))
                .measured(value, "kg·m²")
                .expected(base, "kg·m²")
                .with("armature", value)
                .with("base_armature", base);
            // Inferred from the file alone: a warning, not the spec-backed error.
            if cx.level == cx.meta.default_level {
                f.severity = Severity::Warning;
            }
            if let Some(&b0) = base_joints.first() {
                let bj = &robot.joints[b0];
                let (loc, _) = robot.attr_loc(ElemKind::Joint, bj.id, &bj.name, "armature");
                f = f.secondary(loc, format!("`{}` has {} kg·m²", bj.name, fmt_num(base, 6)));
            }
            out.push(f);
        }
    }
}
