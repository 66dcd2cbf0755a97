use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::ActuatorKind;
use crate::model::mjcf::ElemKind;
use crate::rules::control::keyframe_scan::{key_actuators, keyframes};
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds keyframes whose `ctrl` gives torque (`<motor>`) actuators the joint angles of the
    /// keyframe's own `qpos`: for every motor on a hinge or slide joint, the keyframe's control
    /// equals the joint's position in that keyframe (within `tolerance`), and at least one of
    /// them is not zero. Position servos are not judged (their control *is* a joint target), nor
    /// motors whose controls differ from the pose (a gravity-compensation feed-forward, say).
    ///
    /// ## Why is this bad?
    /// A motor's control is a force: `ctrl` 0.9 on a knee motor is 0.9 N·m (× gear), not
    /// 0.9 rad. A keyframe written for position servos (or copied from a variant that has them)
    /// starts every episode or reset with arbitrary torques that push the robot out of the
    /// pose the keyframe means to hold, and a training stack that reads the keyframe's `ctrl`
    /// as its default action offsets every joint by a torque of the angle's size. MuJoCo XML
    /// reference, `keyframe/key/ctrl` and `actuator/motor`: force = gear·ctrl.
    ///
    /// ## How it is confirmed
    /// Static: compares the compiled `key_ctrl` with `key_qpos` at each motor's joint. A fact of
    /// the file, not a prediction a simulation could refute.
    ///
    /// ## How to fix
    /// Set the motors' keyframe controls to the torques that hold the pose (zero, or a
    /// gravity-compensation feed-forward), or use position actuators if the controls are meant
    /// as joint targets.
    pub KeyframeMotorCtrl {
        id: "keyframe-motor-ctrl",
        group: "control",
        level: Severity::Warning,
        probe: None,
        options: [opt("tolerance", 1e-6, "joint units", Domain::NON_NEGATIVE, "how close a motor's keyframe control must be to its joint's keyframe position to count as the angle")],
    }
}

impl Rule for KeyframeMotorCtrl {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let tol = cx.opt("tolerance");
        let motors = key_actuators(robot, |a| a.kind == ActuatorKind::Motor);
        if motors.is_empty() {
            return;
        }
        for key in keyframes(robot) {
            let pairs: Vec<(usize, usize, f64, f64)> = motors
                .iter()
                .map(|m| (m.actuator, m.joint, key.ctrl[m.ctrl], key.joint_pos(robot, m.joint)))
                .collect();
            let nonzero: Vec<&(usize, usize, f64, f64)> =
                pairs.iter().filter(|p| p.2.abs() > tol).collect();
            let all_equal = pairs.iter().all(|p| (p.2 - p.3).abs() <= tol);
            if nonzero.is_empty() || !all_equal {
                continue;
            }
            let (k, key_name) = (key.index, key.label());
            let shown: Vec<String> = nonzero
                .iter()
                .take(4)
                .map(|p| format!("{} {}", cx.actuator_label(p.0), fmt_num(p.2, 4)))
                .collect();
            let more = if nonzero.len() > 4 {
                format!(", … ({} in all)", nonzero.len())
            } else {
                String::new()
            };
            let msg = format!(
                "keyframe {key_name} sets the controls of all {} motor (torque) actuators to their joints' angles in the same keyframe: {}{more}",
                motors.len(),
                shown.join(", ")
            );
            let first = nonzero[0];
            let f = cx
                .at_attr(ElemKind::Key, k, &key.name, "ctrl", msg)
                .label("ctrl = qpos of the motors' joints")
                .note("a motor's control is a force (force = gear·ctrl): these controls are torques the size of the joint angles, applied at every reset to this keyframe")
                .help("set the motors' keyframe controls to zero or to the torques that hold the pose (gravity compensation); use position actuators if the controls are meant as joint targets")
                .subject(Subject::Actuator(first.0))
                .measured(first.2, if robot.joints[first.1].jtype == crate::model::JointType::Slide { "N" } else { "N·m" })
                .with("motors", nonzero.len() as f64);
            out.push(f);
        }
    }
}
