use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::JointType;
use crate::model::mjcf::ElemKind;
use crate::rules::control::keyframe_scan::{key_actuators, keyframes};
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds keyframes that give position servos no targets: every position servo on a
    /// hinge or slide joint (a `<position>`, or a `<general biastype="affine">` servo whatever
    /// its gain scale and offset) has control 0 in the keyframe (its `ctrl` is omitted or all
    /// zero) while the keyframe places at least one of their joints away from the setpoint
    /// control 0 commands (0 for a `<position>`, the offset biasprm[0]/kp ÷ gear for an affine
    /// servo; by more than `tolerance`). Keyframes whose servo controls are not all zero are not judged (a target
    /// other than the pose may be meant, e.g. a gripper commanded shut), nor keyframes whose
    /// servo joints all sit at 0.
    ///
    /// ## Why is this bad?
    /// A position servo's control is its target: force = kp·(ctrl − gear·q) − kv·q̇. Reset to
    /// such a keyframe (`mj_resetDataKeyframe` copies its `ctrl`, zeros when omitted), every
    /// servo pulls its joint from the keyframe's pose towards 0 with kp × the joint's offset,
    /// so the pose the keyframe means to hold is left at the first step, and a training stack
    /// that reads the keyframe's `ctrl` as its default action offsets every joint by its angle.
    /// MuJoCo XML reference, `keyframe/key/ctrl` and `actuator/position`.
    ///
    /// ## How it is confirmed
    /// Static: compares the compiled `key_ctrl` of the position servos with `key_qpos` at their
    /// joints. A fact of the file, not a prediction a simulation could refute.
    ///
    /// ## How to fix
    /// Give the keyframe `ctrl` the servo targets that hold its pose (for a position actuator
    /// of gear g, g × the joint's keyframe position), in actuator order.
    pub KeyframeServoCtrl {
        id: "keyframe-servo-ctrl",
        group: "control",
        level: Severity::Warning,
        probe: None,
        options: [opt("tolerance", 1e-6, "joint units", Domain::NON_NEGATIVE, "how far from 0 a servo joint's keyframe position must be for a zero target to count as not holding it")],
    }
}

impl Rule for KeyframeServoCtrl {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let tol = cx.opt("tolerance");
        let servos = key_actuators(robot, |a| a.servo.is_some());
        if servos.is_empty() {
            return;
        }
        for key in keyframes(robot) {
            if servos.iter().any(|s| key.ctrl[s.ctrl] != 0.0) {
                continue;
            }
            // (actuator, joint, keyframe position) of the servos whose joints sit away from the
            // setpoint ctrl 0 commands (0 for a `<position>`; offset / gear for a scaled
            // `<general biastype="affine">` servo).
            let zero_setpoint = |a: usize| {
                let a = &robot.actuators[a];
                let g = if a.gear != 0.0 { a.gear } else { 1.0 };
                a.servo.map_or(0.0, |s| s.setpoint(0.0) / g)
            };
            let mut off: Vec<(usize, usize, f64)> = servos
                .iter()
                .map(|s| (s.actuator, s.joint, key.joint_pos(robot, s.joint)))
                .filter(|p| (p.2 - zero_setpoint(p.0)).abs() > tol)
                .collect();
            if off.is_empty() {
                continue;
            }
            off.sort_by(|a, b| b.2.abs().total_cmp(&a.2.abs()).then(a.0.cmp(&b.0)));
            let (k, key_name) = (key.index, key.label());
            let unit =
                |j: usize| if robot.joints[j].jtype == JointType::Slide { "m" } else { "rad" };
            let shown: Vec<String> = off
                .iter()
                .take(4)
                .map(|p| format!("`{}` {} {}", robot.joints[p.1].name, fmt_num(p.2, 4), unit(p.1)))
                .collect();
            let more =
                if off.len() > 4 { format!(", … ({} in all)", off.len()) } else { String::new() };
            let first = off[0];
            let msg = format!(
                "keyframe {key_name} gives its {} position servos target 0 while it places {} of their joints away from 0: {}{more}",
                servos.len(),
                off.len(),
                shown.join(", ")
            );
            let f = cx
                .at_attr(ElemKind::Key, k, &key.name, "ctrl", msg)
                .label("servo targets 0, pose elsewhere")
                .note("a position servo's control is its target: reset to this keyframe, every servo pulls its joint from the keyframe's pose towards 0 (force kp × the offset) from the first step")
                .help("set the keyframe's ctrl to the servo targets that hold its pose (gear × the joint's keyframe position for a <position>; for a scaled servo the ctrl whose setpoint it is), in actuator order")
                .subject(Subject::Actuator(first.0))
                .measured(first.2, unit(first.1))
                .with("servos_off_target", off.len() as f64);
            out.push(f);
        }
    }
}
