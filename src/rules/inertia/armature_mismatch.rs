use std::collections::BTreeMap;

use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::describe_parts;
use crate::model::mjcf::ElemKind;
use crate::rules::inertia::drive_family::{GROUP_MIN, motor_driven};
use crate::rules::inertia::parallel_ankle_armature::parallel_issue;
use crate::rules::limits::effort_limit_mismatch::joint_torque_limit;
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::spec::v;
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// For every joint the spec says a motor drives, compares the compiled `armature` with the
    /// reflected rotor inertia rotor_inertia × gear_ratio² × count of its motor family. Reports
    /// zero armature (error) and values off by more than `tolerance` (joints that share the value
    /// through one `<default class>` and family are reported together). Also reports, once, an
    /// armature that is identical on every actuated joint while the spec's families expect
    /// different values — the sign of one number copy-pasted everywhere. Without a spec, one
    /// armature on every actuated hinge is reported when their force limits span `effort_spread`
    /// × or more; between √(1 + `tolerance`) × and that, as info; in a model whose joints do
    /// not all share one value, one value shared by three or more actuated hinges (the arms
    /// that keep a `<default>`'s armature while the legs set their own) is reported when their
    /// force limits span `effort_spread` × or more: peak torque scales with the
    /// gear and reflected inertia with its square, so a gear stage of r× needs armatures r²×
    /// apart, while a software derating of one motor keeps one value right. A model that
    /// drives any actuated hinge through a tendon (a tendon-driven hand: the motors sit in the
    /// forearm, not at the joints) is not judged without a spec; a joint that a joint equality
    /// couples to others (a gripper's linked fingers) carries its linkage's armature and is left
    /// out of the comparison. Joints driven by
    /// several motors (count > 1) are left to `parallel-ankle-armature`.
    ///
    /// With or without a spec (for the joints whose motor it does not name), an actuated hinge
    /// or slide whose armature exceeds `max_link_ratio` × the inertia the joint moves — the
    /// diagonal of the joint-space inertia at the standing keyframe or qpos0 (the joint's
    /// subtree about its axis; its mass along a slide) less the armature — is reported; joints
    /// that share the value through one `<default class>` together. Armature is gear² × the
    /// rotor's inertia: a gear-288 servo (Dynamixel XC330-M288, ~1.6e-8 kg·m² rotor) reflects
    /// ~1.3e-3 kg·m², 10–100× a light finger link and ~2e3× the lightest part it can turn (its
    /// horn and a bracket, ~3 g at 15 mm, 7e-7 kg·m²); 10⁴× is beyond any drive (the gym Ant's
    /// `armature="1"` kept on a hexapod whose leg links have 1e-7–1e-3 kg·m²).
    ///
    /// ## Why is this bad?
    /// Armature here is the reflected inertia of motor and gearbox seen at the joint (Asimov system identification
    /// §2). It often dominates the link inertia of distal joints and sets their closed-loop
    /// bandwidth and damping; a wrong value trains the policy on a joint that accelerates
    /// differently from the hardware.
    ///
    /// ## How it is confirmed
    /// Static: compiled `dof_armature` + `actuator_armature`·gear² + tendon armature against the
    /// spec's motor families, or against the spread of the model's own force limits.
    ///
    /// ## How to fix
    /// Set each joint's armature to rotor_inertia × gear_ratio² × count of its motor, e.g. one
    /// `<default class>` per motor family.
    pub ArmatureMismatch {
        id: "armature-mismatch",
        group: "inertia",
        level: Severity::Warning,
        probe: None,
        options: [
            opt("tolerance", 0.05, "fraction", Domain::NON_NEGATIVE, "allowed relative difference from the expected reflected inertia"),
            opt("max_link_ratio", 1e4, "ratio", Domain::AT_LEAST_ONE, "largest armature as a multiple of the inertia the joint moves (its subtree about its axis, armature left out) that a real drive reflects: a gear-288 hobby servo on the lightest part it turns is ~2e3×"),
            opt("effort_spread", 5.0, "ratio", Domain::AT_LEAST_ONE, "without a spec: largest / smallest force limit from which one shared armature value is a warning (above √(1 + tolerance) it is info)"),
        ],
    }
}

struct Entry {
    joint: usize,
    expected: f64,
    family: String,
}

impl Rule for ArmatureMismatch {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        super::armature_over_link::armature_over_link(cx, cx.opt("max_link_ratio"), out);
        let Some(spec) = cx.spec else {
            uniform_without_spec(cx, out);
            return;
        };
        let tol = cx.opt("tolerance");
        let robot = cx.robot;
        let mut actuated: Vec<(usize, f64, String)> = Vec::new();
        // (default-class span or joint id, family, zero?) → joints
        let mut groups: BTreeMap<(usize, usize, usize, String, bool), Vec<Entry>> = BTreeMap::new();
        for j in robot.joints.iter().filter(|j| j.is_scalar()) {
            let Some(facts) = spec.joint(&j.name) else { continue };
            let Some(fam) = facts.motor.clone() else { continue };
            if facts.passive {
                continue;
            }
            let Some(expected) = spec.expected_armature(&facts) else { continue };
            // rotor_inertia = 0 means "unknown" (e.g. a hobby servo): nothing to compare against.
            if !(expected > 0.0) {
                continue;
            }
            actuated.push((j.id, expected, fam.clone()));
            if facts.count > 1 || parallel_issue(cx, spec, j, &facts, tol).is_some() {
                continue;
            }
            let a = j.armature;
            let zero = !(a > 0.0);
            if !zero && (a - expected).abs() <= tol * expected {
                continue;
            }
            let (loc, class) = robot.attr_loc(ElemKind::Joint, j.id, &j.name, "armature");
            let key = if class.is_some() {
                (loc.file, loc.start, loc.end, fam.clone(), zero)
            } else {
                (usize::MAX, j.id, 0, fam.clone(), zero)
            };
            groups.entry(key).or_default().push(Entry { joint: j.id, expected, family: fam });
        }
        for ((.., zero), es) in groups {
            let first = &robot.joints[es[0].joint];
            let (a, e, fam) = (first.armature, es[0].expected, es[0].family.as_str());
            let m = spec.motor(fam);
            let (ri, g) = (
                m.and_then(|m| v(&m.rotor_inertia)).unwrap_or(f64::NAN),
                m.and_then(|m| v(&m.gear_ratio)).unwrap_or(f64::NAN),
            );
            let ri_s = if ri.abs() < 1e-3 { format!("{ri:e}") } else { fmt_num(ri, 4) };
            let formula = format!("{ri_s} × {}² = {} kg·m²", fmt_num(g, 4), fmt_num(e, 4));
            let who = if es.len() == 1 {
                format!("joint `{}`", first.name)
            } else {
                let names: Vec<&str> =
                    es.iter().map(|x| robot.joints[x.joint].name.as_str()).collect();
                format!("{} `{fam}` joints ({})", es.len(), names.join(", "))
            };
            let msg = if zero {
                format!(
                    "{who} {} no armature, but the `{fam}` motor reflects rotor_inertia × gear² = {formula}",
                    if es.len() == 1 { "has" } else { "have" }
                )
            } else {
                format!(
                    "armature {} kg·m² on {who} is {}% {} the `{fam}` motor's reflected inertia {formula}",
                    fmt_num(a, 4),
                    fmt_num(((a - e) / e).abs() * 100.0, 3),
                    if a < e { "below" } else { "above" }
                )
            };
            let mut f = crate::rules::inertia::at_armature(cx, first, msg)
                .label(format!("armature {} kg·m²", fmt_num(a, 4)))
                .note("armature stands for the motor and gearbox inertia reflected to the joint (Asimov system identification §2); it sets how fast the joint accelerates under the PD controller, so a wrong value trains the policy on a joint unlike the hardware")
                .help(format!("set armature=\"{}\" for the `{fam}` joints (rotor_inertia × gear_ratio² × count)", fmt_num(e, 6)))
                .subject(Subject::Joint(first.id))
                .measured(a, "kg·m²")
                .expected(e, "kg·m²")
                .with("armature", a)
                .with("expected_armature", e);
            if zero && cx.level == cx.meta.default_level {
                f.severity = Severity::Error;
            }
            if first.armature_elsewhere() {
                f.note = Some(format!(
                    "{} — effective armature {} kg·m² = {}",
                    f.note.unwrap_or_default(),
                    fmt_num(a, 4),
                    describe_parts(robot, &first.armature_parts, "armature")
                ));
            }
            if let Some(l) = spec.joint(&first.name).and_then(|x| x.motor_loc) {
                f = f.secondary(l, format!("spec motor family `{fam}`"));
            }
            out.push(f);
        }
        // Copy-paste sign: one value everywhere while the families differ.
        if actuated.len() >= 2 {
            let a0 = robot.joints[actuated[0].0].armature;
            let same = actuated.iter().all(|(j, ..)| {
                (robot.joints[*j].armature - a0).abs() <= 1e-9 * a0.abs().max(1e-12)
            });
            let mut fams: BTreeMap<&str, f64> = BTreeMap::new();
            for (_, e, fam) in &actuated {
                fams.entry(fam.as_str()).or_insert(*e);
            }
            let mut vals: Vec<f64> = fams.values().copied().collect();
            vals.sort_by(f64::total_cmp);
            let distinct = vals.windows(2).any(|w| (w[1] - w[0]).abs() > tol * w[1]);
            if same && fams.len() >= 2 && distinct {
                let j = &robot.joints[actuated[0].0];
                let list: Vec<String> =
                    fams.iter().map(|(k, e)| format!("{k} {}", fmt_num(*e, 4))).collect();
                let f = cx
                    .at_attr(
                        ElemKind::Joint,
                        j.id,
                        &j.name,
                        "armature",
                        format!(
                            "every one of the {} actuated joints has the same armature {} kg·m², but the spec's {} motor families expect different values (kg·m²: {})",
                            actuated.len(),
                            fmt_num(a0, 4),
                            fams.len(),
                            list.join(", ")
                        ),
                    )
                    .label("one value for every motor")
                    .note("one number everywhere is the sign of a copy-pasted placeholder rather than per-family reflected inertia")
                    .help("give each motor family its own default class with armature = rotor_inertia × gear_ratio² × count")
                    .subject(Subject::Model)
                    .with("armature", a0);
                out.push(f);
            }
        }
        if actuated.len() < 2 {
            uniform_without_spec(cx, out);
        }
    }
}

/// The copy-paste sign without a spec: one armature on every actuated hinge while their torque
/// limits span `effort_spread` × or more (warning), or more than √(1 + `tolerance`) × but less
/// than `effort_spread` × (info: a gear stage would need armatures spread² apart, a derating of
/// one motor would not). Slide joints (armature in kg, force limits in N, e.g. a gripper's
/// fingers) are not compared with hinges. A model that drives any of its actuated hinges through
/// a tendon (a tendon-driven hand) is not judged: its motors are not at the joints.
fn uniform_without_spec(cx: &Context, out: &mut Vec<Finding>) {
    let robot = cx.robot;
    let spread_min = cx.opt("effort_spread");
    // A joint that a joint equality couples to others drives (or follows) a linkage — a
    // gripper's linked fingers —: its armature is the linkage's, not one gear stage's, so it
    // takes no part in the comparison (`drive_family::motor_driven`).
    let joints: Vec<&crate::model::Joint> = robot
        .joints
        .iter()
        .filter(|j| {
            j.jtype == crate::model::JointType::Hinge
                && !robot.actuators_on_joint(j.id).is_empty()
                && motor_driven(cx, j)
        })
        .collect();
    if joints.len() < 3 {
        return;
    }
    // A hinge moved through a tendon (a tendon-driven hand's fingers) has no motor at the joint:
    // the motor sits elsewhere, so neither the joint's armature nor the actuators' force limits
    // follow one gear stage per joint, and the comparison below has nothing to stand on.
    let through_tendon = |j: &crate::model::Joint| {
        robot.actuators_on_joint(j.id).iter().any(|a| a.trn == crate::model::Transmission::Tendon)
    };
    if joints.iter().any(|j| through_tendon(j)) {
        return;
    }
    let a0 = joints[0].armature;
    if !(a0 > 0.0) || !joints.iter().all(|j| (j.armature - a0).abs() <= 1e-9 * a0) {
        shared_without_spec(cx, &joints, spread_min, out);
        return;
    }
    let Some(span) = TorqueSpan::of(robot, &joints).filter(|s| s.count >= 2) else {
        return;
    };
    let (lo, hi) = (span.lo, span.hi);
    let spread = hi / lo;
    // Torque ∝ gear and reflected inertia ∝ gear²: were the spread a gear stage of one motor,
    // the armatures would differ by spread², more than `tolerance` once spread > √(1+tolerance).
    // Below `effort_spread` it may also be a software derating of one motor, which keeps one
    // armature right: then the finding says both and is info.
    let geared_min = (1.0 + cx.opt("tolerance")).sqrt();
    if !(spread > geared_min) {
        return;
    }
    let derating_possible = spread < spread_min;
    let j = joints[0];
    let why = if derating_possible {
        format!(
            "reflected inertia is rotor_inertia × gear², peak torque ∝ gear: if the {}× is a gear stage, the joints' reflected inertias differ {}×; one value fits only if it is a software derating of one motor",
            fmt_num(spread, 3),
            fmt_num(spread * spread, 3)
        )
    } else {
        format!(
            "reflected inertia is rotor_inertia × gear², peak torque ∝ gear: motors {}× apart in torque cannot share one reflected inertia, so one number everywhere is a copy-pasted placeholder (Asimov system identification §1–2: leg joints use actuator families with different reflected inertia)",
            fmt_num(spread, 3)
        )
    };
    let mut f = crate::rules::inertia::at_armature(
            cx,
            j,
            format!(
                "every one of the {} actuated hinge joints has the same armature {} kg·m², while their torque limits span {}–{} N·m ({}×, `{}` to `{}`)",
                joints.len(),
                fmt_num(a0, 4),
                fmt_num(lo, 4),
                fmt_num(hi, 4),
                fmt_num(spread, 3),
                span.lo_joint,
                span.hi_joint
            ),
        )
        .label("one value for every motor")
        .note(format!(
            "{why}{}",
            if j.armature_elsewhere() { format!("; effective armature = {}", describe_parts(robot, &j.armature_parts, "armature")) } else { String::new() }
        ))
        .help("give each motor family its own default class with armature = rotor_inertia × gear_ratio² × count; a spec with the families lets this rule check each value")
        .subject(Subject::Model)
        .measured(spread, "ratio")
        .expected(if derating_possible { geared_min } else { spread_min }, "ratio")
        .with("armature", a0)
        .with("effort_spread", spread);
    if derating_possible && cx.level == cx.meta.default_level {
        f.severity = Severity::Info;
    }
    out.push(f);
}

/// The positive torque limits of some joints: how many, the lowest and highest (N·m), and the
/// first joint carrying each.
struct TorqueSpan<'a> {
    count: usize,
    lo: f64,
    hi: f64,
    lo_joint: &'a str,
    hi_joint: &'a str,
}

impl<'a> TorqueSpan<'a> {
    fn of(robot: &'a crate::model::Robot, joints: &[&crate::model::Joint]) -> Option<Self> {
        let limits: Vec<(usize, f64)> = joints
            .iter()
            .filter_map(|j| joint_torque_limit(robot, j.id).map(|(l, _)| (j.id, l)))
            .filter(|(_, l)| *l > 0.0)
            .collect();
        let (lo, hi) = limits
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), (_, l)| (lo.min(*l), hi.max(*l)));
        let name = |l: f64| {
            limits
                .iter()
                .find(|(_, x)| *x == l)
                .map(|(j, _)| robot.joints[*j].name.as_str())
                .unwrap_or("")
        };
        (!limits.is_empty()).then(|| Self {
            count: limits.len(),
            lo,
            hi,
            lo_joint: name(lo),
            hi_joint: name(hi),
        })
    }
}

/// The copy-paste sign inside a model whose joints do not all share one value: one armature
/// (exactly equal, > 0, typically the top `<default>`'s that the joints without their own take)
/// on [`GROUP_MIN`] or more actuated hinges whose torque limits span `effort_spread` × or more
/// (warning only: within a group, a derating of one motor is no sign of anything). AzureLoong's
/// 14 arm joints keep the default 0.01 kg·m² on 80, 48 and 12.4 N·m motors while its legs,
/// waist and head set their own.
fn shared_without_spec(
    cx: &Context,
    joints: &[&crate::model::Joint],
    spread_min: f64,
    out: &mut Vec<Finding>,
) {
    let robot = cx.robot;
    let mut groups: BTreeMap<u64, Vec<&crate::model::Joint>> = BTreeMap::new();
    for j in joints.iter().filter(|j| j.armature > 0.0) {
        groups.entry(j.armature.to_bits()).or_default().push(j);
    }
    for group in groups.values().filter(|g| g.len() >= GROUP_MIN) {
        let Some(span) = TorqueSpan::of(robot, group).filter(|s| s.count >= GROUP_MIN) else {
            continue;
        };
        let (lo, hi) = (span.lo, span.hi);
        let spread = hi / lo;
        if !(spread >= spread_min) {
            continue;
        }
        let j = group[0];
        let a = j.armature;
        let names: Vec<&str> = group.iter().map(|j| j.name.as_str()).collect();
        let f = crate::rules::inertia::at_armature(
            cx,
            j,
            format!(
                "{} of the {} actuated hinge joints share the armature {} kg·m² ({}), while their torque limits span {}–{} N·m ({}×, `{}` to `{}`)",
                group.len(),
                joints.len(),
                fmt_num(a, 4),
                if names.len() > 6 {
                    format!("`{}`, … ({} joints)", names[..6].join("`, `"), names.len())
                } else {
                    format!("`{}`", names.join("`, `"))
                },
                fmt_num(lo, 4),
                fmt_num(hi, 4),
                fmt_num(spread, 3),
                span.lo_joint,
                span.hi_joint
            ),
        )
        .label("one value for motors of different sizes")
        .note(format!(
            "reflected inertia is rotor_inertia × gear², peak torque ∝ gear: motors {}× apart in torque cannot share one reflected inertia, so the shared number is a copied placeholder (often a `<default>` value the joints without their own inherit); the model's other joints have their own values",
            fmt_num(spread, 3)
        ))
        .help("give each motor family its own default class with armature = rotor_inertia × gear_ratio² × count; a spec with the families lets this rule check each value")
        .subject(Subject::Joint(j.id))
        .measured(spread, "ratio")
        .expected(spread_min, "ratio")
        .with("armature", a)
        .with("effort_spread", spread);
        out.push(f);
    }
}
