use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::rules::{Context, Rule, RuleMeta};

declare_rule! {
    /// ## What it does
    /// Reports actuated hinge and slide joints whose *effective* armature is zero: nothing on the
    /// joint (`armature`), nothing on its actuators (`armature` × gear², MuJoCo ≥ 3.17) and
    /// nothing on a fixed tendon that reaches it. Needs no spec. Joints the spec marks passive
    /// are skipped, and so are a mobile base's coordinates over the floor (a body fixed to the
    /// world but for two or more joints of its own, at least one a slide: x, y and yaw written
    /// in place of a free joint — no rotor turns with them). Joints whose spec motor family
    /// gives a rotor inertia and gear ratio are left to `armature-mismatch`, which can name the
    /// expected value. All such joints are reported in one finding.
    ///
    /// ## Why is this bad?
    /// A geared motor's rotor spins gear-ratio times faster than the joint, so its inertia appears
    /// at the joint multiplied by gear²: the reflected inertia that MuJoCo's `armature` stands
    /// for (MuJoCo XML reference, `joint/armature`: inertia of the joint's motion not due to
    /// body mass, e.g. a rotor; MuJoCo 3.17 adds `actuator/armature`, applied × gear²). The
    /// Asimov system identification (§2, "Armature as reflected rotor inertia") sets it
    /// per actuator family from the motor datasheet and transmission and notes that it strongly
    /// affects closed-loop behaviour and stability. With none, a simulated joint under the same
    /// PD gains accelerates and overshoots more than the hardware, and light distal links become
    /// stiff to integrate.
    ///
    /// ## How it is confirmed
    /// Static: compiled `dof_armature` plus every actuator's and tendon's `armature` referred to
    /// the joint.
    ///
    /// ## How to fix
    /// Set `armature` = rotor_inertia × gear_ratio² (× number of motors driving the joint) on the
    /// joint, or `armature` = rotor_inertia on the actuator with its `gear` (MuJoCo multiplies by
    /// gear²). Give the motor facts in a spec so `armature-mismatch` can check the values.
    pub ZeroArmature {
        id: "zero-armature",
        group: "inertia",
        level: Severity::Warning,
        probe: None,
        options: [],
    }
}

impl Rule for ZeroArmature {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let mut zero = Vec::new();
        let mut n_act = 0usize;
        for j in robot.joints.iter().filter(|j| j.is_scalar()) {
            let facts = cx.facts(&j.name);
            if facts.as_ref().is_some_and(|f| f.passive) {
                continue;
            }
            let spec_motor = facts.as_ref().is_some_and(|f| f.motor.is_some());
            if robot.actuators_on_joint(j.id).is_empty() && !spec_motor {
                continue;
            }
            n_act += 1;
            // A mobile base's x, y and yaw over the floor are no motor joints: no rotor turns
            // with them (the wheels' motors, if modelled, are joints of their own).
            if j.armature > 0.0 || (robot.is_base_coordinate(j.id) && !spec_motor) {
                continue;
            }
            // A spec family with a known reflected inertia: armature-mismatch reports it with
            // the expected value.
            let expected =
                facts.as_ref().and_then(|f| cx.spec?.expected_armature(f)).filter(|e| *e > 0.0);
            if expected.is_some() {
                continue;
            }
            zero.push(j.id);
        }
        if zero.is_empty() {
            return;
        }
        let first = &robot.joints[zero[0]];
        let names: Vec<&str> = zero.iter().map(|&i| robot.joints[i].name.as_str()).collect();
        let msg = if zero.len() == 1 {
            format!(
                "actuated joint `{}` has no armature: none on the joint, its actuator or a tendon",
                first.name
            )
        } else if zero.len() == n_act {
            format!(
                "none of the {} actuated joints has any armature (joint, actuator or tendon): {}",
                zero.len(),
                names.join(", ")
            )
        } else {
            format!(
                "{} of the {n_act} actuated joints have no armature (joint, actuator or tendon): {}",
                zero.len(),
                names.join(", ")
            )
        };
        let f = cx
            .at_attr(ElemKind::Joint, first.id, &first.name, "armature", msg)
            .label("armature 0")
            .note("a geared motor's rotor inertia appears at the joint × gear² (MuJoCo's `armature`); the Asimov system identification sets it per actuator family because it strongly affects closed-loop behaviour; without it the simulated joint accelerates and overshoots more under the same PD gains than the hardware")
            .help("set armature = rotor_inertia × gear_ratio² on each joint (or armature = rotor_inertia on its actuator, which MuJoCo multiplies by gear²); a spec with the motor families lets armature-mismatch check the values")
            .subject(Subject::Joint(first.id))
            .measured(0.0, "kg·m²")
            .with("joints", zero.len() as f64);
        out.push(f);
    }
}
