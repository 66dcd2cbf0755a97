use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::{Joint, JointType, Robot};
use crate::rules::geometry::oversized_weight::effort_limit;
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds torque-driven hinges and slides whose joint spring pulls harder than their
    /// actuators can push before the joint reaches an end of its range. A joint with
    /// `stiffness` k > 0 and a range [lo, hi] is pulled towards its `springref` (MuJoCo's
    /// `qpos_spring`) with k·|q − springref|; its actuators can apply at most their compiled
    /// force bound F (each actuator's `forcerange`, or a `<motor>`'s ctrlrange × gain, × its
    /// gear, summed, no more than the joint's `actuatorfrcrange`). When k·d at the range end
    /// farther from `springref` (distance d) exceeds `spring_share` × F, the actuators can hold
    /// the joint only within springref ± F/k: the rest of its range is out of their reach.
    /// Isaac Gym reads an MJCF joint's `stiffness` and `damping` as the gains of its PD drive,
    /// MuJoCo as a passive spring and damper: a character file written for Isaac Gym (the AMP
    /// humanoid's hips at 300 N·m/rad under 125 N·m motors) becomes, in MuJoCo, a body held
    /// to its rest pose by springs its motors cannot overcome.
    ///
    /// Judged: limited hinges and slides driven only by actuators with no position servo (a
    /// `<motor>`, a `<general>` with no affine bias) whose force is bounded. Not judged: joints
    /// a position servo drives (`servo-sag` weighs their springs against the servo's
    /// stiffness), joints no actuator drives (`passive-joint-spring`), unlimited joints, and
    /// joints whose actuators have no force bound. Gravity is not counted: it moves the pose
    /// the actuators can hold, not the spring's pull.
    ///
    /// ## Why is this bad?
    /// A policy trained on the model spends its torque fighting springs the hardware does not
    /// have, cannot reach poses the real robot reaches, and learns the springs' return to the
    /// rest pose as free motion: the gains it learns transfer to no real actuator. MuJoCo XML
    /// reference, `joint/stiffness` and `joint/springref`; Isaac Gym's MJCF importer, which
    /// maps `stiffness`/`damping` to the DOF drive's gains.
    ///
    /// ## How it is confirmed
    /// Static: the compiled `jnt_stiffness`, `qpos_spring`, `jnt_range` and the actuators'
    /// force bounds, numbers of the file; no simulation is needed to compare them.
    ///
    /// ## How to fix
    /// If the stiffness is a PD gain, drive the joint with a `<position kp=…>` servo (and its
    /// damping with `kv`) and set the joint's `stiffness` to 0; if the joint has a real spring,
    /// give it the real spring's stiffness and `springref`, or the actuator its real force
    /// bound.
    pub SpringOverpowersActuator {
        id: "spring-overpowers-actuator",
        group: "control",
        level: Severity::Warning,
        probe: None,
        options: [opt(
            "spring_share",
            1.0,
            "",
            Domain::POSITIVE,
            "a joint is reported when its spring's pull at the range end farther from springref exceeds this share of its actuators' force bound (1: the actuators' whole force)"
        )],
    }
}

/// One joint whose spring outpulls its actuators at a range end.
struct Overpowered {
    joint: usize,
    /// The spring's pull at the farther range end (N·m or N).
    pull: f64,
    /// The actuators' force bound (N·m or N).
    bound: f64,
    /// The part of the range the actuators can hold against the spring.
    hold: [f64; 2],
}

/// Whether every actuator on joint `j` is a torque source (no position servo).
fn torque_driven(robot: &Robot, j: usize) -> bool {
    let acts = robot.actuators_on_joint(j);
    !acts.is_empty() && acts.iter().all(|a| a.servo.is_none())
}

fn judge(robot: &Robot, j: &Joint, share: f64) -> Option<Overpowered> {
    if !matches!(j.jtype, JointType::Hinge | JointType::Slide)
        || !j.limited
        || !(j.stiffness > 0.0)
        || !torque_driven(robot, j.id)
    {
        return None;
    }
    let bound = effort_limit(robot, j.id).filter(|&f| f > 0.0)?;
    let reff = j.springref;
    let d = (j.range[0] - reff).abs().max((j.range[1] - reff).abs());
    let pull = j.stiffness * d;
    if !(pull > share * bound) {
        return None;
    }
    let reach = bound / j.stiffness;
    let hold = [(reff - reach).max(j.range[0]), (reff + reach).min(j.range[1])];
    Some(Overpowered { joint: j.id, pull, bound, hold })
}

impl Rule for SpringOverpowersActuator {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let share = cx.opt("spring_share");
        let mut found: Vec<Overpowered> =
            robot.joints.iter().filter_map(|j| judge(robot, j, share)).collect();
        if found.is_empty() {
            return;
        }
        found.sort_by(|a, b| (b.pull / b.bound).total_cmp(&(a.pull / a.bound)));
        let unit = |j: usize| match robot.joints[j].jtype {
            JointType::Slide => ("N/m", "N", "m"),
            _ => ("N·m/rad", "N·m", "rad"),
        };
        let item = |o: &Overpowered| {
            let j = &robot.joints[o.joint];
            let (ku, fu, qu) = unit(o.joint);
            let span = j.range[1] - j.range[0];
            let held = if span > 0.0 { (o.hold[1] - o.hold[0]).max(0.0) / span } else { 0.0 };
            format!(
                "`{}` {} {ku} pulls {} {fu} at its range end, {}× its actuators' {} {fu}: they hold it within {}..{} {qu} of {}..{} {qu} ({} % of its range)",
                j.name,
                fmt_num(j.stiffness, 4),
                fmt_num(o.pull, 4),
                fmt_num(o.pull / o.bound, 3),
                fmt_num(o.bound, 4),
                fmt_num(o.hold[0], 3),
                fmt_num(o.hold[1], 3),
                fmt_num(j.range[0], 3),
                fmt_num(j.range[1], 3),
                fmt_num(100.0 * held, 3)
            )
        };
        let n = found.len();
        let shown: Vec<String> = found.iter().take(4).map(item).collect();
        let more = if n > 4 { format!("; … ({n} joints)") } else { String::new() };
        let first = &robot.joints[found[0].joint];
        let mut f = cx
            .at_attr(
                ElemKind::Joint,
                first.id,
                &first.name,
                "stiffness",
                format!(
                    "{n} torque-driven joint{} {} a spring stronger than {} actuators at {} range end{}: {}{more}",
                    if n == 1 { "" } else { "s" },
                    if n == 1 { "has" } else { "have" },
                    if n == 1 { "its" } else { "their" },
                    if n == 1 { "its" } else { "their" },
                    if n == 1 { "" } else { "s" },
                    shown.join("; ")
                ),
            )
            .label(format!("stiffness {}", fmt_num(first.stiffness, 4)))
            .note("MuJoCo applies stiffness × (springref − q) as a passive force: the actuators fight the spring everywhere and cannot reach the rest of the range; Isaac Gym reads the same attribute as its PD drive's gain, which MuJoCo expresses with a position servo's kp")
            .help("if the stiffness is a PD gain, drive the joint with <position kp=\"…\" kv=\"…\"> and set stiffness=\"0\"; if the spring is real, give it the real spring's stiffness and springref, or the actuator its real force bound")
            .subject(Subject::Joint(first.id))
            .measured(found[0].pull, unit(first.id).1)
            .expected(found[0].bound, unit(first.id).1);
        for o in found.iter().skip(1).take(3) {
            let j = &robot.joints[o.joint];
            f = f.secondary(
                robot.attr_loc(ElemKind::Joint, j.id, &j.name, "stiffness").0,
                format!("stiffness {}", fmt_num(j.stiffness, 4)),
            );
        }
        out.push(f);
    }
}
