use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::source::XNode;
use crate::model::{Actuator, JointType, Robot, Transmission};
use crate::probe::LimitApproach;
use crate::rules::limits::soft_limits::HardStopExposure;
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds position servos on hinge joints (a `<position>`, or a `<general biastype="affine">`
    /// servo, judged by the setpoints its ctrlrange commands) whose `ctrlrange` was written in
    /// degrees. MuJoCo
    /// converts joint `range` (and other angles) from degrees when `<compiler angle="degree">` is
    /// in force — the MJCF default — but never converts `ctrlrange`. A ctrlrange that equals the
    /// joint range × 180/π, or whose ends lie beyond ±2π while the joint range does not, is
    /// reported.
    ///
    /// ## Why is this bad?
    /// The policy's action space is scaled to the ctrlrange: a servo target range of ±60 "rad"
    /// on a ±60° joint means almost every action drives the joint into its hard stops, and
    /// action normalisation in the training stack is off by a factor of 57.3.
    ///
    /// ## How it is confirmed
    /// A fact of the file (the numbers of `ctrlrange`, `range` and `<compiler angle>`), never
    /// refuted by simulation. Probe `limit-approach` measures the consequence: the actuator is
    /// commanded to the ends of its ctrlrange and the probe records whether the joint slams into
    /// its hard stop, and how fast.
    ///
    /// ## How to fix
    /// Write `ctrlrange` in radians (the help gives the converted values), or use
    /// `inheritrange="0.9"` on the position actuator so MuJoCo derives it from the joint range.
    pub CtrlrangeInDegrees {
        id: "ctrlrange-in-degrees",
        group: "limits",
        level: Severity::Error,
        probe: LimitApproach,
        options: [opt("ratio_tolerance", 0.05, "fraction", Domain::FRACTION_BELOW_ONE, "how close ctrlrange/range must be to 180/π to count as degrees")],
    }
}

/// Whether the model's `<compiler>` leaves angles in degrees (MJCF's default).
pub fn degree_mode(robot: &Robot) -> bool {
    if robot.format != crate::model::Format::Mjcf {
        return false;
    }
    let mut deg = true;
    let mut visit = |n: &XNode| {
        if n.tag == "compiler"
            && let Some(a) = n.get("angle")
        {
            deg = a != "radian";
        }
    };
    for c in &robot.tree.children {
        visit(c);
    }
    deg
}

/// Largest hinge range magnitude, as written in the file, below which a range in degrees is
/// implausible for a robot joint (±π° is ±0.055 rad) and plausible in radians: π.
const RADIAN_LIKE_DEG: f64 = std::f64::consts::PI;

/// MJCF's default `<compiler angle="degree">` reads every hinge range, yet each limited
/// hinge's range as written is within ±π: the file's numbers were most likely meant as
/// radians (a ±2 "hardware range" compiled to ±0.0349 rad).
pub fn ranges_look_like_radians(robot: &Robot) -> bool {
    let mut hinges =
        robot.joints.iter().filter(|j| j.jtype == JointType::Hinge && j.limited).peekable();
    degree_mode(robot)
        && hinges.peek().is_some()
        && hinges.all(|j| j.range.iter().all(|r| r.to_degrees().abs() <= RADIAN_LIKE_DEG))
}

/// The ctrlrange (in joint units) of a position actuator on a limited hinge looks like degrees.
pub fn looks_like_degrees(robot: &Robot, a: &Actuator, ratio_tol: f64) -> bool {
    if a.servo.is_none()
        || !matches!(a.trn, Transmission::Joint | Transmission::JointInParent)
        || !a.ctrllimited
    {
        return false;
    }
    let Some(j) = usize::try_from(a.target).ok().and_then(|t| robot.joints.get(t)) else {
        return false;
    };
    if j.jtype != JointType::Hinge || !j.limited || !degree_mode(robot) {
        return false;
    }
    // The joint positions the servo commands (a scaled `<general biastype="affine">` servo's
    // setpoints, not its ctrl).
    let Some([c0, c1]) = a.setpoint_range() else { return false };
    let k = 180.0 / std::f64::consts::PI;
    let span_ratio = (c1 - c0) / (j.range[1] - j.range[0]).max(1e-12);
    let beyond = c0.abs().max(c1.abs()) > 2.0 * std::f64::consts::PI
        && j.range[0].abs().max(j.range[1].abs()) <= 2.0 * std::f64::consts::PI;
    ((span_ratio / k) - 1.0).abs() <= ratio_tol || (beyond && span_ratio > 10.0)
}

impl Rule for CtrlrangeInDegrees {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let tol = cx.opt("ratio_tolerance");
        for a in &cx.robot.actuators {
            if !looks_like_degrees(cx.robot, a, tol) {
                continue;
            }
            let j = &cx.robot.joints[a.target as usize];
            let rad = [a.ctrlrange[0].to_radians(), a.ctrlrange[1].to_radians()];
            let f: Finding = cx
                .at_attr(
                    ElemKind::Actuator,
                    a.id,
                    &a.name,
                    "ctrlrange",
                    format!(
                        "ctrlrange [{}, {}] of actuator {} is in degrees, but MuJoCo reads it as radians (joint `{}` range is [{}, {}] rad)",
                        fmt_num(a.ctrlrange[0], 4),
                        fmt_num(a.ctrlrange[1], 4),
                        cx.actuator_label(a.id),
                        j.name,
                        fmt_num(j.range[0], 4),
                        fmt_num(j.range[1], 4)
                    ),
                )
                .label("degrees, read as radians")
                .note("`<compiler angle=\"degree\">` converts joint ranges but never ctrlrange: the servo target range is 57.3× too wide and the policy's action scaling is wrong")
                .help(format!("ctrlrange=\"{} {}\" (radians), or inheritrange=\"0.9\"", fmt_num(rad[0], 4), fmt_num(rad[1], 4)))
                .subject(Subject::Actuator(a.id))
                .measure(HardStopExposure { actuator: a.id })
                .measured(a.ctrlrange[1] - a.ctrlrange[0], "rad")
                .expected(j.range[1] - j.range[0], "rad");
            out.push(f);
        }
    }
}
