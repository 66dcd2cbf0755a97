use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::rules::{Context, Rule, RuleMeta};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// For every joint the spec marks `passive = true` (e.g. spring toes), checks that the model
    /// gives it a spring (`stiffness` > 0), `damping` > 0, a `range`, and collision geometry on
    /// the body it moves.
    ///
    /// ## Why is this bad?
    /// A passive toe still shapes whole-body stability through contact and push-off (seed 001
    /// §6). Without stiffness it flops freely and gives no support, so the policy learns to
    /// ignore it; without damping it rings; without limits it folds past the real stops; without
    /// collision geometry it never touches the ground.
    ///
    /// ## How it is confirmed
    /// Probe `stance-settle`: the robot is settled at the standing keyframe and the toe's
    /// deflection and contact are measured.
    ///
    /// ## How to fix
    /// Give the joint the identified `stiffness`, `damping` and `range`, and add simple collision
    /// capsules to the toe body.
    pub PassiveJointSpring {
        id: "passive-joint-spring",
        group: "mapping",
        level: Severity::Error,
        probe: Some("stance-settle"),
        options: [],
    }
}

impl Rule for PassiveJointSpring {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        for j in robot.joints.iter().filter(|j| j.is_scalar()) {
            let Some(facts) = cx.facts(&j.name) else { continue };
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
                    .note("the real passive joint is spring-loaded; without stiffness it flops freely, gives no support in stance and the policy learns to ignore it (seed 001 §6)")
                    .help("set the identified stiffness (N·m/rad) on the joint, and springref to its rest angle");
                out.push(spec_label(f).subject(Subject::Joint(j.id)).measured(j.stiffness, "N·m/rad").with("stiffness", j.stiffness));
            }
            if !(j.damping > 0.0) {
                let f = cx
                    .at_attr(ElemKind::Joint, j.id, &j.name, "damping", format!("passive joint `{}` has no damping", j.name))
                    .label("damping 0")
                    .note("an undamped spring joint rings after every touchdown, feeding oscillation into the contact the policy learns from")
                    .help("set the identified damping (N·m·s/rad) on the joint");
                out.push(warn(spec_label(f)).subject(Subject::Joint(j.id)).with("damping", j.damping));
            }
            if !j.limited {
                let f = cx
                    .at_elem(ElemKind::Joint, j.id, &j.name, format!("passive joint `{}` has no range", j.name))
                    .label("no range")
                    .note("the real joint has hard stops; without them the simulated toe folds through positions the hardware cannot reach")
                    .help("set the joint's hardware range=\"lo hi\"");
                out.push(warn(spec_label(f)).subject(Subject::Joint(j.id)));
            }
            if !robot.geoms.iter().any(|g| g.body == j.body && g.collides()) {
                let b = &robot.bodies[j.body];
                let f = cx
                    .at_elem(ElemKind::Body, b.id, &b.name, format!("passive joint `{}` moves body `{}`, which has no collision geometry", j.name, b.name))
                    .label("no colliding geom")
                    .note("a toe without collision geometry never touches the ground, so its spring never acts in stance or push-off (seed 001 §6–7)")
                    .help("add simple collision capsules (e.g. radius ≈ 12 mm, condim 3) to the body");
                out.push(warn(spec_label(f)).subject(Subject::Body(b.id)));
            }
        }
    }
}
