use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::rules::{Context, Rule, RuleMeta};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds wheels that carry a joint spring (`stiffness` > 0). A wheel is an unlimited hinge
    /// with no joint beyond it whose collision geometry is round about its axis
    /// (`Robot::is_wheel`: drive wheels, caster wheels); actuated or not.
    ///
    /// ## Why is this bad?
    /// A wheel has no rest angle: it turns without bound as the robot drives. A spring on its
    /// joint pulls it back towards `springref` with a torque that grows with every turn rolled,
    /// k·2π per turn: the simulated robot brakes harder the further it has driven, and a pushed,
    /// unpowered base rolls back. MuJoCo applies `stiffness` to any hinge, wheels included
    /// (XML reference, joint/stiffness).
    ///
    /// ## How it is confirmed
    /// Static: a fact of the file (the compiled `jnt_stiffness` of a wheel joint); the torque
    /// per turn is k·2π, which no run needs to measure.
    ///
    /// ## How to fix
    /// Remove `stiffness` from the wheel joints (often inherited from a class meant for other
    /// joints); model the drive's resistance with `damping` and `frictionloss`.
    pub WheelSpring {
        id: "wheel-spring",
        group: "limits",
        level: Severity::Warning,
        probe: None,
        options: [],
    }
}

impl Rule for WheelSpring {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        for j in &robot.joints {
            if !(j.stiffness > 0.0) || !robot.is_wheel(j.id) {
                continue;
            }
            let per_turn = j.stiffness * std::f64::consts::TAU;
            let msg = format!(
                "wheel joint `{}` has a spring (stiffness {} N·m/rad): a wheel turns without bound, so the spring pulls it back by {} N·m more with every turn rolled ({} N·m after 100 turns)",
                j.name,
                fmt_num(j.stiffness, 4),
                fmt_num(per_turn, 3),
                fmt_num(100.0 * per_turn, 3)
            );
            out.push(
                cx.at_attr(ElemKind::Joint, j.id, &j.name, "stiffness", msg)
                    .label("spring on a wheel")
                    .note("the joint is an unlimited hinge with no joint beyond it and round collision geometry about its axis (a wheel); a spring needs a rest angle, which a rolling wheel does not have")
                    .help("remove stiffness from the wheel joint (a class default meant for other joints?); model the drive's resistance with damping and frictionloss")
                    .subject(Subject::Joint(j.id))
                    .measured(j.stiffness, "N·m/rad")
                    .expected(0.0, "N·m/rad"),
            );
        }
    }
}
