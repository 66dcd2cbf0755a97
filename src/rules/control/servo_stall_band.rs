use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::{ActuatorKind, JointType, Transmission};
use crate::rules::{Context, Domain, Rule, RuleMeta, opt};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds position servos too weak for their joint's dry friction. MuJoCo's `frictionloss`
    /// holds a joint still while the generalized force on it stays below `frictionloss`; a
    /// position actuator of gain `kp` and `gear` g pushes with kp·g²·e at a command error e (in
    /// joint units), so no command error smaller than the servo's *stall band*
    /// frictionloss / (kp·g²) ever moves the joint. A band wider than `max_band_rad` (hinges),
    /// `max_band_m` (slides) or `max_band_fraction` of the joint's range is reported, and so is a
    /// servo whose `forcerange` (× gear) cannot reach `frictionloss` at all. Joints driven by
    /// more than one actuator are left out (their stiffnesses add).
    ///
    /// ## Why is this bad?
    /// Inside the band the simulated joint sticks wherever it stopped: a policy's small
    /// corrections do nothing, the joint ends up to a band width away from every target, and
    /// the policy learns to command exaggerated targets that the real servo (usually stiffer,
    /// or with less friction) overshoots. MuJoCo XML reference, `joint/frictionloss`: dry friction
    /// as a constraint on the DoF; `position`: force = kp·(ctrl − length) with length = gear·q.
    ///
    /// ## How it is confirmed
    /// Static: the band is computed from the compiled `dof_frictionloss`, `actuator_gainprm`,
    /// `actuator_gear` and `actuator_forcerange` — a fact of MuJoCo's friction model for these
    /// numbers, not a prediction a simulation could refute (other loads such as gravity shift
    /// where the joint sticks, not how wide the band is).
    ///
    /// ## How to fix
    /// Raise `kp` to the servo's real stiffness, or lower `frictionloss` to the identified dry
    /// friction (Asimov system identification, §3: friction per actuator family). The help gives
    /// the kp at which the band shrinks to the threshold.
    pub ServoStallBand {
        id: "servo-stall-band",
        group: "control",
        level: Severity::Warning,
        probe: None,
        options: [
            opt("max_band_rad", 0.05, "rad", Domain::POSITIVE, "widest acceptable stall band of a hinge servo"),
            opt("max_band_m", 0.005, "m", Domain::POSITIVE, "widest acceptable stall band of a slide servo"),
            opt("max_band_fraction", 0.05, "fraction", Domain::POSITIVE_FRACTION, "widest acceptable stall band as a fraction of the joint's range"),
        ],
    }
}

impl Rule for ServoStallBand {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        for a in &robot.actuators {
            let ActuatorKind::Position { kp, .. } = a.kind else { continue };
            if !matches!(a.trn, Transmission::Joint | Transmission::JointInParent) {
                continue;
            }
            let Some(j) = usize::try_from(a.target).ok().and_then(|t| robot.joints.get(t)) else {
                continue;
            };
            if !j.is_scalar()
                || !(j.frictionloss > 0.0)
                || robot.actuators_on_joint(j.id).len() != 1
            {
                continue;
            }
            let g = if a.gear != 0.0 { a.gear.abs() } else { 1.0 };
            let stiffness = kp * g * g;
            let (unit, abs_max) = match j.jtype {
                JointType::Slide => ("m", cx.opt("max_band_m")),
                _ => ("rad", cx.opt("max_band_rad")),
            };
            let span = if j.limited { j.range[1] - j.range[0] } else { f64::INFINITY };
            let limit = abs_max.min(cx.opt("max_band_fraction") * span);
            let max_push = if a.forcelimited {
                g * a.forcerange[0].abs().max(a.forcerange[1].abs())
            } else {
                f64::INFINITY
            };
            let stuck = max_push <= j.frictionloss;
            let band = if stiffness > 0.0 { j.frictionloss / stiffness } else { f64::INFINITY };
            if !stuck && !(band > limit) {
                continue;
            }
            let msg = if stuck {
                format!(
                    "position actuator {} can push at most {} on joint `{}`, not more than its frictionloss {}: no command ever moves the joint",
                    cx.actuator_label(a.id),
                    fmt_num(max_push, 3),
                    j.name,
                    fmt_num(j.frictionloss, 3)
                )
            } else {
                let of_range = if span.is_finite() {
                    format!(", {} % of the joint's range", fmt_num(100.0 * band / span, 2))
                } else {
                    String::new()
                };
                format!(
                    "position actuator {} (kp {}) cannot overcome joint `{}`'s frictionloss {} within {} {unit} of its target (stall band frictionloss / kp{of_range})",
                    cx.actuator_label(a.id),
                    fmt_num(stiffness, 3),
                    j.name,
                    fmt_num(j.frictionloss, 3),
                    fmt_num(band, 3)
                )
            };
            let jloc = robot.attr_loc(ElemKind::Joint, j.id, &j.name, "frictionloss").0;
            let kp_needed = j.frictionloss / (limit * g * g);
            let help = if stuck {
                format!(
                    "raise forcerange above the frictionloss {} (÷ gear {}), or lower frictionloss to the identified dry friction",
                    fmt_num(j.frictionloss, 3),
                    fmt_num(g, 3)
                )
            } else {
                format!(
                    "kp ≥ {} keeps the band within {} {unit}; or lower frictionloss to the identified dry friction",
                    fmt_num(kp_needed, 3),
                    fmt_num(limit, 3)
                )
            };
            let f = cx
                .at_attr(ElemKind::Actuator, a.id, &a.name, "kp", msg)
                .label(format!("kp {}", fmt_num(kp, 3)))
                .secondary(jloc, format!("frictionloss {}", fmt_num(j.frictionloss, 3)))
                .note("MuJoCo's dry friction holds the joint while the force on it is below frictionloss; the servo's force kp·g²·error reaches it only beyond the stall band, so smaller corrections never move the joint")
                .help(help)
                .subject(Subject::Actuator(a.id))
                .measured(band, unit)
                .expected(limit, unit);
            out.push(f);
        }
    }
}
