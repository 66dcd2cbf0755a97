use std::collections::BTreeMap;

use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::lint::Loaded;
use crate::model::mjcf::ElemKind;
use crate::model::{ActuatorKind, Transmission};
use crate::probe::direction::Direction;
use crate::probe::{ActuatorDirection, Claim, Preconditions, Verdict};
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Checks the joint ↔ actuator mapping against the spec: every joint with a motor family has
    /// an actuator (joint or tendon transmission; up to `count` for parallel drives); no actuator
    /// drives a joint the spec marks passive; no second, force-unlimited actuator reaches a joint
    /// that already has a limited one; the numbers of actuated and passive joints match
    /// `robot.actuated` / `robot.passive`; the gear sign agrees with the spec `direction`.
    /// Without a spec it still checks that actuator targets exist and that a position
    /// actuator's ctrlrange does not reach outside its joint's range, or, on a fixed tendon, the
    /// lengths its joints' ranges allow it (Σ coef × range; a ctrlrange covering a joint's whole
    /// range is `soft-limits`' finding, a tendon's whole reach and past it this rule's: soft-limits
    /// does not judge tendons), and that no actuator drives a joint that moves nothing of the
    /// robot: a body hung on the world body with no geometry and no child bodies (a placeholder
    /// degree of freedom padded into the model). Missing force limits are
    /// `effort-limit-mismatch`'s.
    ///
    /// ## Why is this bad?
    /// Hardware mapping comes first (Asimov system identification §1): a joint driven in simulation but passive on
    /// the robot, a missing or doubled actuator, or a flipped sign produce unstable or seemingly
    /// random policy behaviour that no reward tuning fixes.
    ///
    /// ## How it is confirmed
    /// Probe `actuator-direction` for sign findings: the actuator is driven and the direction of
    /// the joint's motion compared with the spec; for an actuator with no target, that a command
    /// moves nothing. The other checks (ctrlrange outside the joint range, an actuator on a
    /// passive joint, extra or force-unlimited actuators, joint counts) are static: no motion
    /// measures them, so they carry no probe result.
    ///
    /// ## How to fix
    /// Add, remove or retarget actuators so each motor of the real robot has exactly one, flip
    /// `gear` where the direction disagrees, and keep position targets inside the joint range.
    pub ActuatorMapping {
        id: "actuator-mapping",
        group: "mapping",
        level: Severity::Error,
        probe: ActuatorDirection,
        options: [opt("tolerance", 0.02, "fraction of joint range", Domain::FRACTION_BELOW_ONE, "a ctrlrange end this close to the joint's end is that end (the same number written to other precision, as in soft-limits): only ends further past the range reach outside it")],
    }
}

/// What the `actuator-direction` probe checks about an actuator: that a positive command moves
/// nothing (an actuator with no transmission target), or that it moves its target joint against
/// the spec's `direction`. These are the only findings of the rule a direction run measures: a
/// ctrlrange outside the joint's range, an actuator on a joint the spec marks passive, an extra or
/// force-unlimited actuator are facts of the file no motion shows, and carry no probe result.
#[derive(Debug)]
pub struct MisdirectedActuator {
    pub actuator: usize,
    pub claim: ActuatorMotion,
}

/// The motion a finding of `actuator-mapping` predicts for a positive command.
#[derive(Debug, Clone, Copy)]
pub enum ActuatorMotion {
    /// The actuator has no target: nothing moves.
    Nothing,
    /// The target joint moves against the spec's `direction` (+1 / -1).
    AgainstDirection(i32),
}

impl Claim for MisdirectedActuator {
    type Probe = ActuatorDirection;
    fn key(&self, _: &Loaded) -> Result<usize, &'static str> {
        Ok(self.actuator)
    }
    fn judge(&self, l: &Loaded, d: &Direction) -> Verdict {
        let robot = &l.robot;
        let mut m = BTreeMap::new();
        for (j, dq) in &d.moved {
            m.insert(format!("dq.{}", robot.joints[*j].name), *dq);
        }
        let none = Preconditions::new();
        let act = &robot.actuators[self.actuator];
        let target = (act.target >= 0).then_some(act.target as usize);
        m.insert("actuator_force".into(), d.actuator_force);
        let moved = || {
            let names: Vec<String> = d
                .moved
                .iter()
                .map(|(j, dq)| format!("{} {:+.4}", robot.joints[*j].name, dq))
                .collect();
            format!("a positive command moved: {}", names.join(", "))
        };
        let (t, expected) = match (self.claim, target) {
            (ActuatorMotion::Nothing, _) => {
                // That nothing moves is the claim itself; motion it cannot attribute to an
                // actuator with no target says nothing about the claim.
                return if d.moved.is_empty() {
                    Verdict::confirmed(&none, m, "a positive command moved no joint")
                } else {
                    Verdict::inconclusive(&none, m, moved())
                };
            }
            (ActuatorMotion::AgainstDirection(e), Some(t)) => (t, e),
            (ActuatorMotion::AgainstDirection(_), None) => {
                return Verdict::inconclusive(&none, m, "the actuator has no target joint");
            }
        };
        // The sign claim needs the target to have moved: a held joint shows no direction.
        let on_target = d.moved.iter().find(|(j, _)| *j == t).map(|(_, dq)| *dq);
        let target_name = &robot.joints[t].name;
        let unit =
            if robot.joints[t].jtype == crate::model::JointType::Slide { "m" } else { "rad" };
        let moved_detail = match on_target {
            Some(dq) => format!(
                "a positive command moved the targeted joint `{target_name}` by {} {unit}",
                fmt_num(dq, 3)
            ),
            None => format!(
                "a positive command did not move the targeted joint `{target_name}` (less than {} {unit} in 0.3 s): {}",
                fmt_num(crate::probe::direction::MOVED, 3),
                why_held(d)
            ),
        };
        let pre =
            Preconditions::new().check("target_moved", on_target.is_some(), moved_detail.clone());
        match on_target {
            Some(dq) if dq.signum() != f64::from(expected).signum() => Verdict::confirmed(
                &pre,
                m,
                format!(
                    "a positive command moved the joint by {} rad: opposite to the spec's direction {expected:+}",
                    fmt_num(dq, 3)
                ),
            ),
            Some(dq) => Verdict::refuted_or_inconclusive(
                &pre,
                m,
                format!(
                    "a positive command moved the joint by {} rad, as the spec says",
                    fmt_num(dq, 3)
                ),
            ),
            None => Verdict::inconclusive(&pre, m, moved_detail),
        }
    }
}

/// Why a commanded target did not move, from what the probe saw at the end of its run.
fn why_held(d: &Direction) -> String {
    if !d.actuator_force.is_finite() || d.actuator_force.abs() <= 1e-9 {
        "the actuator applied no force (zero gain, or its command clamped to where it was)"
            .to_string()
    } else if d.holding.is_empty() {
        format!(
            "the actuator's force {} did not overcome the joint's load",
            fmt_num(d.actuator_force, 3)
        )
    } else {
        format!(
            "the actuator's force {} is held by {}",
            fmt_num(d.actuator_force, 3),
            d.holding.join(", ")
        )
    }
}

impl Rule for ActuatorMapping {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        self.check_mapping(cx, out);
    }
}

impl ActuatorMapping {
    fn check_mapping(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let warn = |mut f: Finding| {
            if cx.level == cx.meta.default_level {
                f.severity = Severity::Warning;
            }
            f
        };
        // Targets exist.
        for a in &robot.actuators {
            if a.target < 0 {
                let f = cx
                    .at_elem(ElemKind::Actuator, a.id, &a.name, format!("actuator {} has no transmission target", cx.actuator_label(a.id)))
                    .label("no target")
                    .note("an actuator that drives nothing is a mapping error: the policy's action for it has no effect")
                    .help("point the actuator at the joint (or tendon) of its motor, or remove it")
                    .subject(Subject::Actuator(a.id))
                    .claim(MisdirectedActuator { actuator: a.id, claim: ActuatorMotion::Nothing });
                out.push(f);
            }
        }
        // An actuated joint that moves nothing of the robot: its body hangs on the world body
        // and has no geometry and no child bodies (a placeholder degree of freedom written in
        // for a joint the robot does not have, e.g. to pad the action space).
        for a in &robot.actuators {
            if !matches!(a.trn, Transmission::Joint | Transmission::JointInParent) {
                continue;
            }
            let Some(j) = usize::try_from(a.target).ok().and_then(|t| robot.joints.get(t)) else {
                continue;
            };
            let b = j.body;
            let hangs_on_world = robot.bodies.get(b).is_some_and(|x| x.parent == 0) && b != 0;
            let has_geom = robot.geoms.iter().any(|g| g.body == b);
            let has_child = robot.bodies.iter().any(|x| x.id != b && x.parent == b);
            if !j.is_scalar() || !hangs_on_world || has_geom || has_child {
                continue;
            }
            let f = cx
                .at_elem(ElemKind::Actuator, a.id, &a.name, format!(
                    "actuator `{}` drives joint `{}` of body `{}`, which hangs on the world body with no geometry and no child bodies ({} kg): the joint moves nothing of the robot",
                    a.name, j.name, robot.body_name(b), fmt_num(robot.bodies[b].mass, 3)
                ))
                .label("drives a placeholder body")
                .secondary(robot.elem_loc(ElemKind::Joint, j.id, &j.name), "joint of a body outside the robot")
                .note("a degree of freedom the robot does not have, padded into the model: the policy gets an action and an observation with no physical counterpart, and the body's made-up mass and inertia are integrated every step")
                .help("remove the body, its joint and the actuator, and pad the action or observation vector in the training code if its size must match")
                .subject(Subject::Actuator(a.id))
                .with("body_mass", robot.bodies[b].mass);
            out.push(warn(f));
        }
        // Actuators whose gear sign contradicts the spec: their shifted ctrlrange is a consequence.
        // Only a joint transmission's target is a joint id (a tendon's is a tendon id).
        let flipped = |a: &crate::model::Actuator| {
            matches!(a.trn, Transmission::Joint | Transmission::JointInParent)
                && usize::try_from(a.target)
                    .ok()
                    .and_then(|t| robot.joints.get(t))
                    .and_then(|j| cx.facts(&j.name))
                    .and_then(|f| f.direction)
                    .is_some_and(|d| a.gear * f64::from(d) < 0.0)
        };
        // Position targets outside the joint range (partial overlap; full coverage is soft-limits').
        let tol = cx.opt("tolerance");
        for a in &robot.actuators {
            if flipped(a) {
                continue;
            }
            if a.servo.is_none() || !a.ctrllimited || a.target < 0 {
                continue;
            }
            // The target's range: a limited scalar joint's, or what a fixed tendon's joints
            // allow it (its own length limits too, when it has them).
            let (r, u, what) = match a.trn {
                Transmission::Joint | Transmission::JointInParent => {
                    let Some(j) = robot.joints.get(a.target as usize) else { continue };
                    if !j.is_scalar() || !j.limited {
                        continue;
                    }
                    let u = if j.jtype == crate::model::JointType::Slide { "m" } else { "rad" };
                    (j.range, u, format!("joint `{}`'s range", j.name))
                }
                Transmission::Tendon => {
                    let Some((r, u)) = fixed_tendon_range(robot, a.target as usize) else {
                        continue;
                    };
                    let name = robot.tendons.get(a.target as usize).cloned().unwrap_or_default();
                    (r, u, format!("fixed tendon `{name}`'s reachable length (its joints' ranges)"))
                }
                _ => continue,
            };
            let Some(c) = a.setpoint_range() else { continue };
            // Ends within `tolerance` of the joint's ends are those ends: a ctrlrange written to
            // full precision (-0.22689280275926285) for a range rounded to six digits (-0.226893)
            // reaches nowhere past the stop.
            let near = tol * (r[1] - r[0]).abs();
            let below = c[0] < r[0] - near;
            let above = c[1] > r[1] + near;
            let covers = c[0] <= r[0] + near && c[1] >= r[1] - near;
            // A ctrlrange past both ends of a joint's range is soft-limits' finding; soft-limits
            // does not judge a tendon's length, so a tendon servo's is this rule's either way.
            let tendon = a.trn == Transmission::Tendon;
            if (below || above) && (!covers || tendon) {
                let f = cx
                    .at_attr(
                        ElemKind::Actuator,
                        a.id,
                        &a.name,
                        "ctrlrange",
                        format!(
                            "position actuator {} {} [{}, {}] {u} reaches outside {what} [{}, {}] {u}",
                            cx.actuator_label(a.id),
                            match a.servo {
                                Some(s) if !s.is_unit() => format!(
                                    "ctrlrange [{}, {}] commands setpoints (gain/kp {})",
                                    fmt_num(a.ctrlrange[0], 4),
                                    fmt_num(a.ctrlrange[1], 4),
                                    fmt_num(s.scale, 4)
                                ),
                                _ => "ctrlrange".into(),
                            },
                            fmt_num(c[0], 4),
                            fmt_num(c[1], 4),
                            fmt_num(r[0], 4),
                            fmt_num(r[1], 4)
                        ),
                    )
                    .label("outside the joint range")
                    .note("targets beyond the hard stop can never be reached: the controller pushes the joint into its limit, and a ctrlrange shifted off the joint's range usually means the actuator drives the wrong joint or uses the wrong zero")
                    .help("make ctrlrange a centred sub-range of the joint range (see soft-limits), or check the actuator's joint and the joint's zero")
                    .subject(Subject::Actuator(a.id));
                out.push(warn(f));
            }
        }
        let Some(spec) = cx.spec else { return };
        let (mut n_act, mut n_passive) = (0usize, 0usize);
        for j in robot.joints.iter().filter(|j| j.is_scalar()) {
            let acts = robot.actuators_on_joint(j.id);
            if acts.is_empty() {
                n_passive += 1;
            } else {
                n_act += 1;
            }
            let Some(facts) = spec.joint(&j.name) else { continue };
            let spec_label = |f: Finding| match facts.locs.first() {
                Some(&l) => f.secondary(l, "spec entry for this joint"),
                None => f,
            };
            if facts.passive {
                if let Some(a) = acts.first() {
                    let f = cx
                        .at_elem(ElemKind::Actuator, a.id, &a.name, format!("actuator `{}` drives joint `{}`, which the spec marks passive", a.name, j.name))
                        .label("drives a passive joint")
                        .note("the real joint has no motor (e.g. a spring toe); a simulated actuator lets the policy use torque that does not exist")
                        .help("remove the actuator and model the joint's spring and damping instead")
                        .subject(Subject::Actuator(a.id));
                    out.push(spec_label(f));
                }
                continue;
            }
            let Some(fam) = facts.motor.clone() else { continue };
            // A model with no actuator at all is one `missing-actuators` finding, not one per joint.
            if acts.is_empty() && robot.actuators.is_empty() {
                continue;
            }
            if acts.is_empty() {
                let f = cx
                    .at_elem(ElemKind::Joint, j.id, &j.name, format!("joint `{}` has a `{fam}` motor on the robot but no actuator in the model", j.name))
                    .label("no actuator")
                    .note("the simulated joint is passive while the real one is driven; the policy cannot learn to use it")
                    .help("add an actuator (joint or tendon transmission) for this joint with the motor's force limit")
                    .subject(Subject::Joint(j.id));
                out.push(spec_label(f));
                continue;
            }
            // A force-unlimited extra actuator on a joint that already has a limited one.
            let limited = |a: &&crate::model::Actuator| {
                a.forcelimited || (a.kind == ActuatorKind::Motor && a.ctrllimited)
            };
            if acts.len() > 1
                && acts.iter().any(limited)
                && let Some(a) = acts.iter().find(|a| !limited(a))
            {
                let f = cx
                        .at_elem(ElemKind::Actuator, a.id, &a.name, format!("actuator `{}` reaches joint `{}` without a force limit, beside a limited actuator", a.name, j.name))
                        .label("unlimited second actuator")
                        .note("the extra actuator adds torque past the motor's limit, so the joint's effort limit is no longer enforced")
                        .help("remove the extra actuator or give it a forcerange")
                        .subject(Subject::Actuator(a.id));
                out.push(spec_label(f));
                continue;
            }
            if acts.len() > facts.count as usize {
                let names: Vec<&str> = acts.iter().map(|a| a.name.as_str()).collect();
                let a = acts[1];
                let f = cx
                    .at_elem(ElemKind::Actuator, a.id, &a.name, format!("joint `{}` is driven by {} actuators ({}), but the spec gives it {} motor(s)", j.name, acts.len(), names.join(", "), facts.count))
                    .label("extra actuator")
                    .note("duplicate actuators add their torques, doubling the joint's strength and gains relative to the hardware")
                    .help("keep one actuator per real motor")
                    .subject(Subject::Actuator(a.id));
                out.push(warn(spec_label(f)));
            }
            if let Some(d) = facts.direction {
                for a in acts
                    .iter()
                    .filter(|a| matches!(a.trn, Transmission::Joint | Transmission::JointInParent))
                {
                    if a.gear * d as f64 >= 0.0 {
                        continue;
                    }
                    let f = cx
                        .at_attr(ElemKind::Actuator, a.id, &a.name, "gear", format!("actuator `{}` gear {} drives joint `{}` opposite to the spec direction {}", a.name, fmt_num(a.gear, 4), j.name, d))
                        .label(format!("gear {}", fmt_num(a.gear, 4)))
                        .note("a flipped actuator sign makes every command move the joint the wrong way relative to the hardware's convention; the deployed policy drives the real joint backwards")
                        .help(format!("set gear=\"{}\" (or fix the spec's direction)", fmt_num(-a.gear, 4)))
                        .subject(Subject::Actuator(a.id))
                        .claim(MisdirectedActuator {
                            actuator: a.id,
                            claim: ActuatorMotion::AgainstDirection(d),
                        })
                        .with("gear", a.gear)
                        .with("direction", d as f64);
                    out.push(spec_label(f));
                }
            }
        }
        for (what, count, want) in
            [("actuated", n_act, &spec.robot.actuated), ("passive", n_passive, &spec.robot.passive)]
        {
            let Some(w) = want else { continue };
            if count == *w.get_ref() {
                continue;
            }
            let f = cx
                .finding(format!("the model has {count} {what} joints, the spec says robot.{what} = {}", w.get_ref()), spec.loc(w.span()))
                .label(format!("model: {count}"))
                .element("model", robot.root_loc())
                .note("a different number of driven joints than the hardware means a joint is mapped wrongly; the policy's action and observation spaces will not match the robot")
                .help(format!("check which joints have actuators (hinge/slide joints with no actuator count as passive){}", if what == "passive" { "" } else { ", or correct the spec" }))
                .subject(Subject::Model)
                .with(what, count as f64);
            out.push(f);
        }
    }
}

/// The lengths a fixed tendon can take: Σ coef × its joints' ranges (interval sums; every joint
/// scalar and limited), narrowed by the tendon's own length limits when it has them; with the
/// unit of its joints (m for slides, rad for hinges, "joint units" when mixed). `None` for a
/// spatial tendon or an unlimited joint.
fn fixed_tendon_range(robot: &crate::model::Robot, t: usize) -> Option<([f64; 2], &'static str)> {
    let m = &robot.mj;
    let adr = usize::try_from(*m.tendon_adr().get(t)?).ok()?;
    let num = usize::try_from(*m.tendon_num().get(t)?).ok()?;
    let (wt, wo, wp) = (m.wrap_type(), m.wrap_objid(), m.wrap_prm());
    let (mut lo, mut hi) = (0.0, 0.0);
    let (mut slides, mut hinges) = (0, 0);
    for w in adr..adr + num {
        if *wt.get(w)? as i32 != 1 {
            return None; // not a joint wrap: a spatial tendon
        }
        let j = robot.joints.get(usize::try_from(*wo.get(w)?).ok()?)?;
        if !j.is_scalar() || !j.limited {
            return None;
        }
        let c = *wp.get(w)?;
        let (a, b) = (c * j.range[0], c * j.range[1]);
        lo += a.min(b);
        hi += a.max(b);
        if j.jtype == crate::model::JointType::Slide { slides += 1 } else { hinges += 1 }
    }
    if num == 0 {
        return None;
    }
    if m.tendon_limited().get(t).is_some_and(|&l| l) {
        let r = m.tendon_range().get(t)?;
        lo = lo.max(r[0]);
        hi = hi.min(r[1]);
    }
    let u = match (slides, hinges) {
        (_, 0) => "m",
        (0, _) => "rad",
        _ => "joint units",
    };
    (lo <= hi).then_some(([lo, hi], u))
}
