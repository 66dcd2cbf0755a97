use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::rules::{Context, Rule, RuleMeta};

declare_rule! {
    /// ## What it does
    /// Reports a model that has hinge or slide joints but not a single actuator — an `<actuator>`
    /// block that was never written (or a URDF whose `<transmission>`s MuJoCo ignores). Needs no
    /// spec. With a spec, the finding is an error when the spec says joints are driven
    /// (`robot.actuated` > 0 or a joint with a motor family), and it is dropped when the spec
    /// says every joint is passive (`robot.actuated = 0`).
    ///
    /// ## Why is this bad?
    /// Without actuators MuJoCo has no controls (`nu = 0`; MuJoCo XML reference, `actuator`): the policy's action vector maps onto
    /// nothing, the robot collapses under gravity, and none of the actuator checks (gains, force
    /// limits, training ranges) can run — so a linter that stays silent here gives false
    /// comfort. Hardware mapping comes first (Asimov system identification §1): every motor of
    /// the real robot needs an actuator on its joint.
    ///
    /// ## How it is confirmed
    /// Static: the compiled model's actuator count.
    ///
    /// ## How to fix
    /// MJCF: add an `<actuator>` block with one `<position>` (or `<motor>`) per driven joint, with
    /// the motor's gains, `forcerange`/`actuatorfrcrange` and a soft `ctrlrange`. URDF (which has
    /// no MuJoCo actuators: its `<transmission>`s are ignored, and its `<mujoco>` extension element
    /// takes compiler options only): write a small MJCF wrapper that loads the URDF as a model
    /// asset and attaches it (`<asset><model name="robot" file="robot.urdf"/></asset>`,
    /// `<worldbody><attach model="robot" prefix=""/></worldbody>`; `<include>` takes MJCF only)
    /// and adds the `<actuator>` block, then lint and simulate the wrapper.
    pub MissingActuators {
        id: "missing-actuators",
        group: "mapping",
        level: Severity::Warning,
        probe: None,
        options: [],
    }
}

impl Rule for MissingActuators {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        if !robot.actuators.is_empty() {
            return;
        }
        let joints: Vec<&str> =
            robot.joints.iter().filter(|j| j.is_scalar()).map(|j| j.name.as_str()).collect();
        if joints.is_empty() {
            return;
        }
        let spec_actuated = cx.spec.and_then(|s| s.robot.actuated.as_ref().map(|a| *a.get_ref()));
        if spec_actuated == Some(0) {
            return;
        }
        let spec_driven = robot
            .joints
            .iter()
            .filter(|j| cx.facts(&j.name).is_some_and(|f| f.motor.is_some() && !f.passive))
            .count();
        let mut shown: Vec<String> = joints.iter().take(8).map(|n| format!("`{n}`")).collect();
        if joints.len() > 8 {
            shown.push(format!("and {} more", joints.len() - 8));
        }
        let mut f = cx
            .finding(
                format!("the model has {} hinge/slide joints ({}) but no actuator at all", joints.len(), shown.join(", ")),
                robot.root_loc(),
            )
            .label("no <actuator> block")
            .element("model", robot.root_loc())
            .note("with no actuator MuJoCo has no controls: a policy's actions drive nothing, the robot collapses under gravity, and no actuator check (gains, force limits, training ranges) can run")
            .help(if robot.format == crate::model::Format::Urdf {
                "a URDF has no MuJoCo actuators (MuJoCo ignores its <transmission>s, and its <mujoco> extension takes compiler options only): write an MJCF wrapper that attaches the URDF and adds the actuators — <mujoco><asset><model name=\"robot\" file=\"robot.urdf\"/></asset><worldbody><attach model=\"robot\" prefix=\"\"/></worldbody><actuator>…</actuator></mujoco> (<include> takes MJCF only), one <position> or <motor> per driven joint with the motor's gains, force limit and a soft ctrlrange — and lint and simulate the wrapper"
            } else {
                "add an <actuator> block with one <position> or <motor> per driven joint, with the motor's gains, force limit and a soft ctrlrange"
            })
            .subject(Subject::Model)
            .with("joints", joints.len() as f64);
        if let Some(s) = cx.spec {
            if let Some(a) = &s.robot.actuated {
                f = f.secondary(
                    s.loc(a.span()),
                    format!("the spec says {} joints are actuated", a.get_ref()),
                );
            }
            if (spec_actuated.unwrap_or(0) > 0 || spec_driven > 0)
                && cx.level == cx.meta.default_level
            {
                f.severity = Severity::Error;
            }
        }
        out.push(f);
    }
}
