use std::collections::BTreeMap;

use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::{ActuatorKind, Robot};
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::spec::v;
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// For every actuated hinge/slide joint, finds the largest torque the model lets the
    /// actuators apply: the actuator's `forcerange` (× gear), the joint's `actuatorfrcrange`, for
    /// a `<motor>` its `ctrlrange` × gain × gear, or for a voltage-driven `<dcmotor>` (MuJoCo
    /// 3.17) its stall torque K/R × V_max × gear — the tightest that applies. Reports joints
    /// with no force limit at all (error; a joint that several actuators drive, each of them
    /// bounded — a differential drive's two tendons on each wheel — is limited by their sum and
    /// not reported), a `<motor>` whose torque `ctrlrange` (× gain × gear)
    /// contradicts the same joint's `actuatorfrcrange` by more than `tolerance` (no spec needed:
    /// e.g. ±139 N·m of command on a joint clamped at ±60), an actuator's `forcerange` (× gear)
    /// that does (MuJoCo applies both, so one of them never acts: e.g. servos bounded at ±72 N·m
    /// on joints clamped at ±10) — an actuator bound below the joint's clamp by no more than
    /// `derating` (±30 N·m of command on a joint clamped at ±32.4: 7.4 % under it) is a command
    /// held under the motor's peak on purpose and is not reported; two or more actuators on one joint (a position, a velocity and
    /// a torque mode of one motor) whose force bounds at the joint differ by more than
    /// `tolerance` while no `actuatorfrcrange` bounds their sum (no spec needed: they cannot all
    /// be the motor's peak), and limits that differ from the spec's motor
    /// `peak_torque` by more than `tolerance`. When the spec gives a motor family's
    /// `velocity_limit` or `saturation_torque`, reports once per family (info) that MuJoCo cannot
    /// express the speed–torque curve, so the training stack must apply it; and a joint whose
    /// damping takes its whole force limit below that `velocity_limit` (damping × velocity
    /// limit > force limit: at full torque the simulated joint stops accelerating at force
    /// limit / damping, so it can never reach the motor's rated speed). In a URDF, which states
    /// both, a joint whose `<dynamics damping>` × `<limit velocity>` exceeds its `<limit
    /// effort>` (no spec needed: the Unitree Qmini's `damping="1"` on 20 N·m joints rated
    /// 30 rad/s stops them at 20 rad/s); a joint with no positive effort, velocity or damping,
    /// or with a spec motor family, is not judged there.
    ///
    /// ## Why is this bad?
    /// Effort limits are part of the identified actuator model (Asimov system identification §4). A joint without a
    /// limit, or with a higher one than the motor's peak, lets the policy learn motions that need
    /// torque the hardware cannot produce; a lower one hides real capability.
    ///
    /// ## How it is confirmed
    /// Static: compares compiled force limits with the spec.
    ///
    /// ## How to fix
    /// Set `actuatorfrcrange="-peak peak"` on the joint (or `forcerange` on the actuator) to the
    /// motor's peak torque; apply the speed–torque saturation in the training environment's
    /// actuator model.
    pub EffortLimitMismatch {
        id: "effort-limit-mismatch",
        group: "limits",
        level: Severity::Warning,
        probe: None,
        options: [
            opt("tolerance", 0.05, "fraction", Domain::NON_NEGATIVE, "allowed relative difference between two statements of one motor's force limit: the model's and the spec's peak_torque, or two actuators of one joint"),
            opt("derating", 0.2, "fraction", Domain::FRACTION_BELOW_ONE, "largest fraction by which an actuator's own bound (a motor's ctrlrange × gear, a forcerange × gear) may sit below its joint's actuatorfrcrange and be taken as a command held under the motor's peak on purpose (a derating margin), not a contradiction"),
        ],
    }
}

/// Where a joint's force limit comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LimitSource {
    Joint,
    ActuatorForce(usize),
    MotorCtrl(usize),
}

/// The tightest symmetric torque limit (max |bound|) the model applies to joint `j`.
pub fn joint_torque_limit(robot: &Robot, j: usize) -> Option<(f64, LimitSource)> {
    let lim = robot.mj.jnt_actfrclimited();
    let rng = robot.mj.jnt_actfrcrange().as_flattened();
    let mut best: Option<(f64, LimitSource)> = None;
    let mut take = |x: f64, s: LimitSource| {
        if x.is_finite() && best.is_none_or(|(b, _)| x < b) {
            best = Some((x, s));
        }
    };
    if lim.get(j).copied().unwrap_or(false) {
        take(rng[2 * j].abs().max(rng[2 * j + 1].abs()), LimitSource::Joint);
    }
    let acts = robot.actuators_on_joint(j);
    // Several actuators add up; only a single one gives a per-actuator bound here.
    if acts.len() == 1 {
        // Through a fixed tendon the joint sees the actuator's force × gear × its coefficient.
        let arm = robot.moment_at_joint(acts[0], j).unwrap_or(acts[0].gear);
        for (x, s) in actuator_bounds(acts[0], arm) {
            take(x, s);
        }
    }
    best
}

/// The force bounds one actuator puts on what it transmits (× its moment arm `arm`: gear, or
/// gear × tendon coefficient at a joint): its `forcerange`, a `<motor>`'s ctrlrange × gain, a
/// voltage-driven `<dcmotor>`'s stall torque.
fn actuator_bounds(a: &crate::model::Actuator, arm: f64) -> Vec<(f64, LimitSource)> {
    let g = arm.abs();
    let mut v = Vec::new();
    if a.forcelimited {
        v.push((
            g * a.forcerange[0].abs().max(a.forcerange[1].abs()),
            LimitSource::ActuatorForce(a.id),
        ));
    }
    if a.kind == ActuatorKind::Motor && a.ctrllimited {
        v.push((
            g * a.gainprm[0].abs() * a.ctrlrange[0].abs().max(a.ctrlrange[1].abs()),
            LimitSource::MotorCtrl(a.id),
        ));
    }
    if let ActuatorKind::DcMotor { resistance, k, voltage: true } = a.kind
        && a.ctrllimited
        && resistance > 0.0
    {
        v.push((
            g * (k / resistance).abs() * a.ctrlrange[0].abs().max(a.ctrlrange[1].abs()),
            LimitSource::MotorCtrl(a.id),
        ));
    }
    v.retain(|x| x.0.is_finite());
    v
}

/// Every actuator on joint `j` bounds its force: the joint's torque is bounded (by their sum
/// through the transmissions, e.g. a differential drive's two tendons on each wheel) even when
/// no single bound applies to it.
fn every_actuator_bounded(robot: &Robot, j: usize) -> bool {
    let acts = robot.actuators_on_joint(j);
    !acts.is_empty() && acts.iter().all(|a| !actuator_bounds(a, a.gear).is_empty())
}

impl Rule for EffortLimitMismatch {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let tol = cx.opt("tolerance");
        let robot = cx.robot;
        let mut missing = Vec::new();
        let mut used_families: BTreeMap<String, usize> = BTreeMap::new();
        for j in robot.joints.iter().filter(|j| j.is_scalar()) {
            let acts = robot.actuators_on_joint(j.id);
            let facts = cx.facts(&j.name);
            let spec_actuated = facts.as_ref().is_some_and(|f| f.motor.is_some() && !f.passive);
            if acts.is_empty() && !spec_actuated {
                continue;
            }
            if let Some(fam) = facts.as_ref().and_then(|f| f.motor.clone()) {
                used_families.entry(fam).or_insert(j.id);
            }
            if acts.is_empty() {
                continue; // actuator-mapping reports the missing actuator
            }
            let unit = if j.jtype == crate::model::JointType::Slide { "N" } else { "N·m" };
            if let Some(f) = ctrl_contradicts_joint_limit(cx, j, &acts, tol, unit) {
                out.push(f);
            }
            if let Some(f) = force_contradicts_joint_limit(cx, j, &acts, tol, unit) {
                out.push(f);
            }
            if let Some(f) = actuators_disagree(cx, j, &acts, tol, unit) {
                out.push(f);
            }
            let Some((lim, src)) = joint_torque_limit(robot, j.id) else {
                if !every_actuator_bounded(robot, j.id) {
                    missing.push(j.id);
                }
                continue;
            };
            let Some(fam) = facts.as_ref().and_then(|f| f.motor.clone()) else { continue };
            let Some(m) = cx.spec.and_then(|s| s.motor(&fam)) else { continue };
            if let Some(vmax) = v(&m.velocity_limit)
                && j.damping * vmax > lim
            {
                out.push(damping_caps_speed(cx, j, lim, vmax, &fam, m));
            }
            let Some(peak) = v(&m.peak_torque) else { continue };
            let rel = (lim - peak) / peak;
            if rel.abs() <= tol {
                continue;
            }
            let msg = format!(
                "joint `{}` force limit {} {unit} {} the `{fam}` motor's peak torque {} {unit} by {}%",
                j.name,
                fmt_num(lim, 4),
                if rel > 0.0 { "exceeds" } else { "is below" },
                fmt_num(peak, 4),
                fmt_num(rel.abs() * 100.0, 3)
            );
            let mut f = match src {
                LimitSource::Joint => {
                    cx.at_attr(ElemKind::Joint, j.id, &j.name, "actuatorfrcrange", msg)
                }
                LimitSource::ActuatorForce(a) => {
                    cx.at_attr(ElemKind::Actuator, a, &robot.actuators[a].name, "forcerange", msg)
                }
                LimitSource::MotorCtrl(a) => {
                    cx.at_attr(ElemKind::Actuator, a, &robot.actuators[a].name, "ctrlrange", msg)
                }
            };
            if let Some(s) = cx.spec
                && let Some(p) = &m.peak_torque
            {
                f = f.secondary(s.loc(p.span()), format!("spec peak_torque of `{fam}`"));
            }
            f = f
                .label(format!("±{} {unit}", fmt_num(lim, 4)))
                .note(if rel > 0.0 {
                    "the policy can learn motions that need more torque than the motor can give; on hardware they saturate and the motion fails"
                } else {
                    "the model withholds torque the motor has; the policy learns an artificially weak robot"
                })
                .help(format!("set actuatorfrcrange=\"-{p} {p}\" on the joint (or forcerange on the actuator)", p = fmt_num(peak, 4)))
                .subject(Subject::Joint(j.id))
                .measured(lim, unit)
                .expected(peak, unit)
                .with("force_limit", lim)
                .with("peak_torque", peak);
            out.push(f);
        }
        crate::rules::limits::urdf_damping_speed::urdf_damping_caps_speed(cx, out);
        // Missing limits: one finding when no actuated joint has one, else one per joint.
        let n_act = robot
            .joints
            .iter()
            .filter(|j| j.is_scalar() && !robot.actuators_on_joint(j.id).is_empty())
            .count();
        let err = |mut f: Finding| {
            if cx.level == cx.meta.default_level {
                f.severity = Severity::Error;
            }
            f
        };
        let note = "without a force limit the simulated actuator delivers any torque the controller asks for; the policy learns motions the real motors cannot produce";
        if missing.len() >= 2 && missing.len() == n_act {
            let j = &robot.joints[missing[0]];
            let names: Vec<&str> = missing.iter().map(|&i| robot.joints[i].name.as_str()).collect();
            let f = cx
                .at_elem(ElemKind::Joint, j.id, &j.name, format!("none of the {} actuated joints has a force limit: {}", missing.len(), names.join(", ")))
                .label("no actuatorfrcrange / forcerange")
                .note(note)
                .help("give each joint actuatorfrcrange=\"-peak peak\" with its motor's peak torque (or forcerange on the actuators)")
                .subject(Subject::Joint(j.id));
            out.push(err(f));
        } else {
            for &ji in &missing {
                let j = &robot.joints[ji];
                let peak = cx
                    .facts(&j.name)
                    .and_then(|f| f.motor)
                    .and_then(|fam| cx.spec?.motor(&fam))
                    .and_then(|m| v(&m.peak_torque));
                let f = cx
                    .at_elem(
                        ElemKind::Joint,
                        j.id,
                        &j.name,
                        format!("actuated joint `{}` has no force limit", j.name),
                    )
                    .label("no actuatorfrcrange / forcerange")
                    .note(note)
                    .help(match peak {
                        Some(p) => format!(
                            "set actuatorfrcrange=\"-{p} {p}\" (spec peak torque)",
                            p = fmt_num(p, 4)
                        ),
                        None => "set actuatorfrcrange=\"-peak peak\" with the motor's peak torque"
                            .into(),
                    })
                    .subject(Subject::Joint(j.id));
                out.push(err(f));
            }
        }
        // Speed–torque saturation: one info per motor family that states it.
        let Some(spec) = cx.spec else { return };
        for (fam, &jid) in &used_families {
            let Some(m) = spec.motor(fam) else { continue };
            let (vl, st) = (v(&m.velocity_limit), v(&m.saturation_torque));
            let Some(span) = m
                .velocity_limit
                .as_ref()
                .map(|s| s.span())
                .or(m.saturation_torque.as_ref().map(|s| s.span()))
            else {
                continue;
            };
            let mut parts = Vec::new();
            if let Some(x) = vl {
                parts.push(format!("velocity limit {} rad/s", fmt_num(x, 4)));
            }
            if let Some(x) = st {
                parts.push(format!("saturation torque {} N·m", fmt_num(x, 4)));
            }
            let joints: Vec<&str> = robot
                .joints
                .iter()
                .filter(|j| {
                    cx.facts(&j.name).and_then(|f| f.motor).as_deref() == Some(fam.as_str())
                })
                .map(|j| j.name.as_str())
                .collect();
            let mut f = cx
                .finding(
                    format!(
                        "motor family `{fam}` has a speed–torque limit ({}) that MuJoCo actuators cannot express; it must be applied in the training stack ({} joints: {})",
                        parts.join(", "),
                        joints.len(),
                        joints.join(", ")
                    ),
                    spec.loc(span),
                )
                .label("not representable in MJCF")
                .note("a real motor's available torque falls with speed (Asimov system identification §4: speed–torque saturation); MuJoCo applies only a constant force range, so fast motions in simulation get more torque than the hardware")
                .help(match (st, vl, v(&m.peak_torque)) {
                    (Some(s), Some(w), _) => format!("in the actuator model clamp |τ| ≤ min(peak, {s}·(1 − |q̇|/{w})) N·m", s = fmt_num(s, 4), w = fmt_num(w, 4)),
                    (None, Some(w), Some(p)) => format!("in the actuator model clamp |τ| ≤ {p}·(1 − |q̇|/{w}) N·m, or at least limit joint speed to {w} rad/s", p = fmt_num(p, 4), w = fmt_num(w, 4)),
                    _ => "apply the speed–torque saturation in the training environment's actuator model".into(),
                })
                .subject(Subject::Joint(jid));
            if cx.level == cx.meta.default_level {
                f.severity = Severity::Info;
            }
            out.push(f);
        }
    }
}

/// Joint `j`'s linear damping takes its whole force limit `lim` below the motor family's
/// `velocity_limit`: at full torque the simulated joint stops accelerating at `lim / damping`.
fn damping_caps_speed(
    cx: &Context,
    j: &crate::model::Joint,
    lim: f64,
    vmax: f64,
    fam: &str,
    m: &crate::spec::Motor,
) -> Finding {
    let slide = j.jtype == crate::model::JointType::Slide;
    let (unit, vel, dunit) =
        if slide { ("N", "m/s", "N·s/m") } else { ("N·m", "rad/s", "N·m·s/rad") };
    let d = j.damping;
    let terminal = lim / d;
    let msg = format!(
        "joint `{}` damping {} {dunit} takes its whole force limit {} {unit} at {} {vel}: it cannot reach the `{fam}` motor's velocity limit {} {vel}",
        j.name,
        fmt_num(d, 4),
        fmt_num(lim, 4),
        fmt_num(terminal, 3),
        fmt_num(vmax, 4)
    );
    let mut f = cx
        .at_attr(ElemKind::Joint, j.id, &j.name, "damping", msg)
        .label(format!(
            "{} × {} {vel} = {} {unit} of damping at the velocity limit",
            fmt_num(d, 4),
            fmt_num(vmax, 4),
            fmt_num(d * vmax, 4)
        ))
        .note("joint damping is passive: it opposes every motion with damping × speed, so with full torque the simulated joint stops accelerating at force limit / damping; the policy learns a robot slower than the hardware, and a servo that relies on this damping for its stability gets none of it from the real joint")
        .help(format!(
            "lower the joint's damping below {} {dunit} (force limit / velocity limit: the motor's viscous friction, if identified) and give the servo its damping through the actuator's kv",
            fmt_num(lim / vmax, 3)
        ))
        .subject(Subject::Joint(j.id))
        .measured(terminal, vel)
        .expected(vmax, vel)
        .with("damping", d)
        .with("force_limit", lim)
        .with("terminal_speed", terminal)
        .with("velocity_limit", vmax);
    if let Some(s) = cx.spec
        && let Some(vl) = &m.velocity_limit
    {
        f = f.secondary(s.loc(vl.span()), format!("spec velocity_limit of `{fam}`"));
    }
    f
}

/// The one actuator of a joint whose `actuatorfrcrange` is set, and that range's larger bound.
fn sole_actuator_and_joint_limit<'a>(
    cx: &Context,
    j: &crate::model::Joint,
    acts: &[&'a crate::model::Actuator],
) -> Option<(&'a crate::model::Actuator, f64)> {
    let robot = cx.robot;
    if !robot.mj.jnt_actfrclimited().get(j.id).copied().unwrap_or(false) || acts.len() != 1 {
        return None;
    }
    let rng = robot.mj.jnt_actfrcrange().as_flattened();
    Some((acts[0], rng[2 * j.id].abs().max(rng[2 * j.id + 1].abs())))
}

/// An actuator's own bound `act` under its joint's clamp `joint` by at most the `derating`
/// fraction: a command held below the motor's peak on purpose (both are the same motor, the
/// actuator's the tighter by a margin), not two statements of its peak that disagree.
fn derated(cx: &Context, act: f64, joint: f64) -> bool {
    act < joint && act >= (1.0 - cx.opt("derating")) * joint
}

/// A `<motor>`'s torque command range that disagrees with the joint's `actuatorfrcrange`.
fn ctrl_contradicts_joint_limit(
    cx: &Context,
    j: &crate::model::Joint,
    acts: &[&crate::model::Actuator],
    tol: f64,
    unit: &str,
) -> Option<Finding> {
    let robot = cx.robot;
    let (a, jl) = sole_actuator_and_joint_limit(cx, j, acts)?;
    if a.kind != ActuatorKind::Motor || !a.ctrllimited || a.forcelimited {
        return None;
    }
    let ml = (a.gear * a.gainprm[0]).abs() * a.ctrlrange[0].abs().max(a.ctrlrange[1].abs());
    if !(jl > 0.0 && ml > 0.0) || (ml - jl).abs() <= tol * jl.max(ml) || derated(cx, ml, jl) {
        return None;
    }
    let above = ml > jl;
    let msg = format!(
        "motor {} commands up to ±{} {unit} (ctrlrange × gear), but joint `{}` clamps actuator force at ±{} {unit} (actuatorfrcrange)",
        cx.actuator_label(a.id),
        fmt_num(ml, 4),
        j.name,
        fmt_num(jl, 4)
    );
    let (jloc, _) = robot.attr_loc(ElemKind::Joint, j.id, &j.name, "actuatorfrcrange");
    Some(
        cx.at_attr(ElemKind::Actuator, a.id, &a.name, "ctrlrange", msg)
            .label(format!("±{} {unit}", fmt_num(ml, 4)))
            .secondary(jloc, format!("actuatorfrcrange ±{} {unit}", fmt_num(jl, 4)))
            .note(if above {
                format!(
                    "MuJoCo clamps the joint's actuator force at ±{} {unit}, so the top {}% of the policy's action range does nothing; one of the two numbers is not the motor's peak torque",
                    fmt_num(jl, 4),
                    fmt_num((1.0 - jl / ml) * 100.0, 3)
                )
            } else {
                format!("the policy can never reach the joint's ±{} {unit} limit; one of the two numbers is not the motor's peak torque", fmt_num(jl, 4))
            })
            .help("make ctrlrange × gear and actuatorfrcrange the same motor peak torque (a spec with peak_torque says which one is right)")
            .subject(Subject::Joint(j.id))
            .measured(ml, unit)
            .expected(jl, unit)
            .with("ctrl_limit", ml)
            .with("joint_limit", jl),
    )
}

/// Two or more actuators of one joint, each with a force bound, that state different motors:
/// the largest bound at the joint exceeds the smallest by more than `tol` (relative), and no
/// `actuatorfrcrange` on the joint says which the motor is.
fn actuators_disagree(
    cx: &Context,
    j: &crate::model::Joint,
    acts: &[&crate::model::Actuator],
    tol: f64,
    unit: &str,
) -> Option<Finding> {
    let robot = cx.robot;
    // Only actuators on the joint itself: tendon actuators (a differential drive's) are
    // virtual motors whose bounds combine, not statements of the joint's one motor.
    let direct = |a: &&&crate::model::Actuator| {
        matches!(
            a.trn,
            crate::model::Transmission::Joint | crate::model::Transmission::JointInParent
        )
    };
    if acts.iter().filter(direct).count() < 2
        || acts.len() != acts.iter().filter(direct).count()
        || robot.mj.jnt_actfrclimited().get(j.id).copied().unwrap_or(false)
    {
        return None;
    }
    let mut bounds = Vec::new();
    for a in acts {
        let b = actuator_bounds(a, a.gear);
        let (x, src) = b.into_iter().min_by(|p, q| p.0.total_cmp(&q.0))?;
        if !(x > 0.0) {
            return None;
        }
        bounds.push((x, src, a.id));
    }
    let lo = bounds.iter().min_by(|p, q| p.0.total_cmp(&q.0))?;
    let hi = bounds.iter().max_by(|p, q| p.0.total_cmp(&q.0))?;
    if hi.0 - lo.0 <= tol * hi.0 {
        return None;
    }
    let attr = |s: LimitSource| match s {
        LimitSource::MotorCtrl(_) => "ctrlrange",
        _ => "forcerange",
    };
    let list: Vec<String> = bounds
        .iter()
        .map(|(x, _, a)| format!("{} ±{} {unit}", cx.actuator_label(*a), fmt_num(*x, 4)))
        .collect();
    let msg = format!(
        "joint `{}`'s {} actuators bound its force differently ({}): they cannot all be its motor's peak",
        j.name,
        bounds.len(),
        list.join(", ")
    );
    let (lo_loc, _) =
        robot.attr_loc(ElemKind::Actuator, lo.2, &robot.actuators[lo.2].name, attr(lo.1));
    let ha = &robot.actuators[hi.2];
    Some(
        cx.at_attr(ElemKind::Actuator, ha.id, &ha.name, attr(hi.1), msg)
            .label(format!("±{} {unit}", fmt_num(hi.0, 4)))
            .secondary(lo_loc, format!("±{} {unit}", fmt_num(lo.0, 4)))
            .note(format!(
                "each actuator is clamped to its own bound, so the joint gets up to ±{} {unit} in one control mode and ±{} {unit} in another: the policy trained through the stronger one asks the motor for {}× what the weaker one says it has",
                fmt_num(hi.0, 4),
                fmt_num(lo.0, 4),
                fmt_num(hi.0 / lo.0, 3)
            ))
            .help("give every actuator of the joint the motor's peak torque, or bound the sum once with actuatorfrcrange on the joint")
            .subject(Subject::Joint(j.id))
            .measured(hi.0, unit)
            .expected(lo.0, unit)
            .with("largest_bound", hi.0)
            .with("smallest_bound", lo.0),
    )
}

/// An actuator's `forcerange` (× gear) that disagrees with its joint's `actuatorfrcrange`: MuJoCo
/// applies both, so the tighter one is the limit that acts and the other is not the motor's.
fn force_contradicts_joint_limit(
    cx: &Context,
    j: &crate::model::Joint,
    acts: &[&crate::model::Actuator],
    tol: f64,
    unit: &str,
) -> Option<Finding> {
    let robot = cx.robot;
    let (a, jl) = sole_actuator_and_joint_limit(cx, j, acts)?;
    if !a.forcelimited {
        return None;
    }
    let arm = robot.moment_at_joint(a, j.id).unwrap_or(a.gear).abs();
    let fl = arm * a.forcerange[0].abs().max(a.forcerange[1].abs());
    if !(jl > 0.0 && fl > 0.0 && jl.is_finite() && fl.is_finite()) {
        return None;
    }
    if (fl - jl).abs() <= tol * jl.max(fl) || derated(cx, fl, jl) {
        return None;
    }
    let (act, joint) = (fl.min(jl), fl.max(jl));
    let msg = format!(
        "actuator {} forcerange gives joint `{}` up to ±{} {unit} (× gear), but the joint's actuatorfrcrange clamps it at ±{} {unit}: {}× apart",
        cx.actuator_label(a.id),
        j.name,
        fmt_num(fl, 4),
        fmt_num(jl, 4),
        fmt_num(joint / act, 3)
    );
    let (jloc, _) = robot.attr_loc(ElemKind::Joint, j.id, &j.name, "actuatorfrcrange");
    Some(
        cx.at_attr(ElemKind::Actuator, a.id, &a.name, "forcerange", msg)
            .label(format!("±{} {unit}", fmt_num(fl, 4)))
            .secondary(jloc, format!("actuatorfrcrange ±{} {unit}", fmt_num(jl, 4)))
            .note(format!(
                "MuJoCo applies both limits, so ±{} {unit} ({}) is the one that acts and the other never does; one of the two numbers is not the motor's peak torque",
                fmt_num(act, 4),
                if jl < fl { "the joint's actuatorfrcrange" } else { "the actuator's forcerange" }
            ))
            .help("make forcerange × gear and actuatorfrcrange the same motor peak torque, or keep only one of them (a spec with peak_torque says which one is right)")
            .subject(Subject::Joint(j.id))
            .measured(fl, unit)
            .expected(jl, unit)
            .with("actuator_limit", fl)
            .with("joint_limit", jl),
    )
}
