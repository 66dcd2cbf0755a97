use crate::declare_rule;
use std::collections::BTreeMap;

use crate::finding::{Finding, Severity, Subject};
use crate::lint::Loaded;
use crate::model::mjcf::ElemKind;
use crate::probe::ringdown::{MIN_STEPS_PER_PERIOD, Ring};
use crate::probe::settle::Settle;
use crate::probe::{Measure, Measurement, Preconditions, RingDown, StanceSettle};
use crate::rules::{Context, Rule, RuleMeta};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// For every joint the spec marks `passive = true` (e.g. spring toes), checks that the model
    /// gives it a spring (`stiffness` > 0), `damping` > 0, a `range`, and collision geometry on
    /// the body it moves (a geom that takes part in contacts: masks that allow them, or an
    /// explicit `<pair>`; none when `<flag contact="disable"/>`).
    ///
    /// Without a spec (and for joints the spec does not mention) it reports what the file alone
    /// shows: an unactuated spring joint (`stiffness` > 0) with no damping of any kind (joint,
    /// actuator or tendon damping, and no `frictionloss`) and no `range` — nothing dissipates its
    /// energy and nothing stops it.
    ///
    /// ## Why is this bad?
    /// A passive toe still shapes whole-body stability through contact and push-off (Asimov system identification
    /// §6). Without stiffness it flops freely and gives no support, so the policy learns to
    /// ignore it; without damping it rings; without limits it folds past the real stops; without
    /// collision geometry it never touches the ground.
    ///
    /// ## How it is confirmed
    /// Every finding of this rule is a fact of the file (a value that is zero or absent), so no
    /// simulation refutes it; probes measure the consequence. Missing damping: probe
    /// `ring-down` releases the joint from its spring's rest position on a fixed stand and
    /// measures how long it rings (inconclusive when an equality acts on the joint on the
    /// stand — a closed loop, which with the other joints frozen is held rigid, so the
    /// constraint's softness and not the spring would decide the motion — or when the joint
    /// cannot move). Missing spring, range or collision geometry: probe `stance-settle`
    /// measures the joint's deflection under the standing load (inconclusive without a floor,
    /// with the feet unloaded or the robot fallen).
    ///
    /// ## How to fix
    /// Give the joint the identified `stiffness`, `damping` and `range`, and add simple collision
    /// capsules to the toe body.
    pub PassiveJointSpring {
        id: "passive-joint-spring",
        group: "mapping",
        level: Severity::Error,
        probe: StanceSettle,
        also: [RingDown],
        options: [],
    }
}

/// What the `stance-settle` probe measures about a passive joint (a fact of the file: no
/// spring, no range, no collision geometry): its deflection under the standing load. Needs the
/// stance preconditions (a floor, the feet loaded, the robot upright); never a verdict.
#[derive(Debug)]
pub struct StanceDeflection {
    pub joint: usize,
}

impl Measure for StanceDeflection {
    type Probe = StanceSettle;
    fn key(&self, _: &Loaded) -> Result<(), &'static str> {
        Ok(())
    }
    fn measure(&self, l: &Loaded, s: &Settle) -> Measurement {
        let robot = &l.robot;
        let jt = &robot.joints[self.joint];
        let mut m = s.stance_measured();
        m.extend(s.foot(robot, jt.body).measured);
        let defl = s.joint_deflection.get(&self.joint).copied().unwrap_or(0.0);
        m.insert("deflection_rad".into(), defl);
        let q = robot.key.qpos.get(jt.qposadr).copied().unwrap_or(0.0) + defl;
        let at_limit = jt.limited && (q <= jt.range[0] + 1e-3 || q >= jt.range[1] - 1e-3);
        let note = format!(
            "passive joint deflected {} rad under the standing load{}",
            fmt_num(defl, 3),
            if at_limit { ", onto its limit" } else { "" }
        );
        let note = match crate::probe::stance::copy_note(&s.stance) {
            Some(c) => format!("{note} ({c})"),
            None => note,
        };
        Measurement::new(&s.preconditions(), m, note)
    }
}

/// What the `ring-down` probe measures about a spring joint with no damping (a fact of the
/// file): released from its rest position, how long it rings. Never a verdict.
#[derive(Debug)]
pub struct SpringRings {
    pub joint: usize,
}

impl Measure for SpringRings {
    type Probe = RingDown;
    fn key(&self, l: &Loaded) -> Result<usize, &'static str> {
        match l.robot.joints.get(self.joint) {
            Some(j) if j.stiffness > 0.0 => Ok(self.joint),
            _ => Err("the joint has no spring to ring"),
        }
    }
    fn measure(&self, _: &Loaded, r: &Ring) -> Measurement {
        let mut m = BTreeMap::from([
            ("release".to_string(), r.release),
            ("max_motion".to_string(), r.max_motion),
            ("amplitude_ratio".to_string(), r.amplitude_ratio),
            ("periods".to_string(), r.periods),
            ("duration_s".to_string(), r.duration),
        ]);
        if r.period.is_finite() {
            m.insert("period_s".into(), r.period);
        }
        if r.zeta.is_finite() {
            m.insert("zeta".into(), r.zeta);
        }
        if let Some(t) = r.ring_time {
            m.insert("ring_time_s".into(), t);
        }
        let steps_per_period = r.undamped_period / r.dt;
        let pre = Preconditions::new().check(
            "loop_free",
            r.held_by.is_none(),
            format!(
                "equality {} acts on the joint: on the stand, with the other joints frozen, it holds the closed loop rigid, so the constraint's softness, not the spring, decides how the joint moves",
                r.held_by.as_deref().unwrap_or("none")
            ),
        ).check(
            "joint_moved",
            r.moved >= 0.5 * r.release,
            format!(
                "released {} from its spring's rest position, the joint moved at most {} from there (at least half the release is needed; a closed loop or an equality can hold it)",
                fmt_num(r.release, 3),
                fmt_num(r.moved, 3)
            ),
        ).check(
            "period_resolved",
            steps_per_period >= MIN_STEPS_PER_PERIOD,
            format!(
                "the spring's period 2π√(I/k) ({} s) spans {} timesteps (need ≥ {}): the integrator, not the model's damping, decides the decay",
                fmt_num(r.undamped_period, 3),
                fmt_num(steps_per_period, 3),
                fmt_num(MIN_STEPS_PER_PERIOD, 3)
            ),
        );
        let note = match r.ring_time {
            None => format!(
                "released {} from rest, the spring still rings at {} % of the release after {} s ({} periods, ζ = {})",
                fmt_num(r.release, 3),
                fmt_num(100.0 * r.amplitude_ratio, 3),
                fmt_num(r.duration, 3),
                fmt_num(r.periods, 3),
                if r.zeta.is_finite() { fmt_num(r.zeta, 3) } else { "n/a".into() }
            ),
            Some(t) => format!(
                "released {} from rest, the spring rings for {} s before staying under 10 % of the release (ζ = {})",
                fmt_num(r.release, 3),
                fmt_num(t, 3),
                if r.zeta.is_finite() { fmt_num(r.zeta, 3) } else { "n/a".into() }
            ),
        };
        Measurement::new(&pre, m, note)
    }
}

impl Rule for PassiveJointSpring {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let first = out.len();
        self.check_joints(cx, out);
        // Every finding of this rule is a fact of the file; probes only measure consequences.
        for f in &mut out[first..] {
            match f.subject {
                Subject::Joint(joint) if f.data.contains_key("undamped") => {
                    f.set_measure(SpringRings { joint })
                }
                Subject::Joint(joint) => f.set_measure(StanceDeflection { joint }),
                _ => f.fact = true,
            }
        }
    }
}

impl PassiveJointSpring {
    fn check_joints(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        for j in robot.joints.iter().filter(|j| j.is_scalar()) {
            let Some(facts) = cx.facts(&j.name) else {
                if j.stiffness > 0.0
                    && !(j.damping > 0.0)
                    && !(j.frictionloss > 0.0)
                    && !j.limited
                    && robot.actuators_on_joint(j.id).is_empty()
                {
                    let mut f = cx
                        .at_attr(ElemKind::Joint, j.id, &j.name, "stiffness", format!("spring joint `{}` (stiffness {} N·m/rad) has no damping and no range", j.name, fmt_num(j.stiffness, 4)))
                        .label(format!("stiffness {}, damping 0, no range", fmt_num(j.stiffness, 4)))
                        .note("an undamped spring with no stops oscillates for ever after every touchdown and can wind past any real stop; a passive spring joint on hardware has both damping and hard stops (Asimov system identification §1, §6: passive spring toes)")
                        .help("set the joint's identified damping (N·m·s/rad) and its hardware range=\"lo hi\"; a spec with `passive = true` checks the rest")
                        .subject(Subject::Joint(j.id))
                        .measured(0.0, "N·m·s/rad")
                        .with("stiffness", j.stiffness)
                        .with("undamped", 1.0);
                    if cx.level == cx.meta.default_level {
                        f.severity = Severity::Warning;
                    }
                    out.push(f);
                }
                continue;
            };
            if !facts.passive {
                continue;
            }
            let warn = |mut f: Finding| {
                if cx.level == cx.meta.default_level {
                    f.severity = Severity::Warning;
                }
                f
            };
            let spec_label = |f: Finding| match facts.locs.first() {
                Some(&l) => f.secondary(l, "the spec marks this joint passive"),
                None => f,
            };
            if !(j.stiffness > 0.0) {
                let f = cx
                    .at_attr(ElemKind::Joint, j.id, &j.name, "stiffness", format!("passive joint `{}` has no spring: stiffness = {}", j.name, fmt_num(j.stiffness, 4)))
                    .label("stiffness 0")
                    .note("the real passive joint is spring-loaded; without stiffness it flops freely, gives no support in stance and the policy learns to ignore it (Asimov system identification §6)")
                    .help("set the identified stiffness (N·m/rad) on the joint, and springref to its rest angle");
                out.push(
                    spec_label(f)
                        .subject(Subject::Joint(j.id))
                        .measured(j.stiffness, "N·m/rad")
                        .with("stiffness", j.stiffness),
                );
            }
            if !(j.damping > 0.0) {
                let f = cx
                    .at_attr(ElemKind::Joint, j.id, &j.name, "damping", format!("passive joint `{}` has no damping", j.name))
                    .label("damping 0")
                    .note("an undamped spring joint rings after every touchdown, feeding oscillation into the contact the policy learns from")
                    .help("set the identified damping (N·m·s/rad) on the joint");
                out.push(
                    warn(spec_label(f))
                        .subject(Subject::Joint(j.id))
                        .with("damping", j.damping)
                        .with("undamped", 1.0),
                );
            }
            if !j.limited {
                let f = cx
                    .at_elem(ElemKind::Joint, j.id, &j.name, format!("passive joint `{}` has no range", j.name))
                    .label("no range")
                    .note("the real joint has hard stops; without them the simulated toe folds through positions the hardware cannot reach")
                    .help("set the joint's hardware range=\"lo hi\"");
                out.push(warn(spec_label(f)).subject(Subject::Joint(j.id)));
            }
            if !robot
                .geoms
                .iter()
                .any(|g| g.body == j.body && crate::model::contact::takes_part(robot, g.id))
            {
                let b = &robot.bodies[j.body];
                let f = cx
                    .at_elem(ElemKind::Body, b.id, &b.name, format!("passive joint `{}` moves body `{}`, which has no collision geometry", j.name, b.name))
                    .label("no colliding geom")
                    .note("a toe without collision geometry never touches the ground, so its spring never acts in stance or push-off (Asimov system identification §6–7)")
                    .help("add simple collision capsules (e.g. radius ≈ 12 mm, condim 3) to the body");
                out.push(warn(spec_label(f)).subject(Subject::Body(b.id)));
            }
        }
    }
}
