use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::{Format, JointType};
use crate::rules::inertia::drive_family::{Family, GROUP_MIN, motor_families};
use crate::rules::{Context, Rule, RuleMeta};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Finds a motor family whose joints state the drive's dry friction (`frictionloss`; a
    /// URDF's `<dynamics friction>`) or its viscous damping (`damping`, the effective value:
    /// joint + actuator·gear²; a URDF's `<dynamics damping>`) on some joints and leave it at zero
    /// on others. A family is the joints one motor drives: with a spec, the joints its `motor`
    /// names (the families `armature-mismatch` checks); without one, the motor-driven joints of
    /// one type whose torque limits are equal to six significant digits (an actuator on the
    /// joint in MJCF, a positive `effort` in a URDF). The joint's and its actuator's
    /// `<default class>` split a family further (a joint given a class of its own is a design of
    /// its own). Reported once per family and quantity when the family holds at least three
    /// joints. Not judged: passive joints, joints a joint
    /// equality couples (a linkage), wheels, joints with no motor known and no torque limit.
    /// Values that differ but are all above zero (identified per joint) are not judged.
    ///
    /// ## Why is this bad?
    /// Friction and damping belong to the gearbox and motor, not to the joint's place in the
    /// robot: one drive has them on every joint it turns. A zero on some joints of a drive the
    /// file gives friction elsewhere is a value left out (or one copied onto the wrong joints);
    /// the policy then trains on joints that coast where the hardware brakes, or the reverse
    /// (SpotMicroAI: 0.5 N·m on the shoulder and foot joints, 0 on the leg joints of the same
    /// servo). MuJoCo XML reference, `joint/frictionloss` and `joint/damping`.
    ///
    /// ## How it is confirmed
    /// Static: compiled `dof_frictionloss` and effective damping, grouped by motor family.
    ///
    /// ## How to fix
    /// Give every joint of the drive its identified friction and damping — one `<default class>`
    /// per motor family; in a URDF, the same `<dynamics>` on each of its joints. A joint that is
    /// damped on purpose (an added damper) belongs in its own class.
    pub DriveFrictionMismatch {
        id: "drive-friction-mismatch",
        group: "control",
        level: Severity::Warning,
        probe: None,
        options: [],
    }
}

impl Rule for DriveFrictionMismatch {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        for fam in motor_families(cx).iter().filter(|f| f.joints.len() >= GROUP_MIN) {
            for q in &QUANTITIES {
                if let Some(f) = stated_on_some(cx, fam, q) {
                    out.push(f);
                }
            }
        }
    }
}

/// A quantity of a drive that every joint of it shares.
struct Quantity {
    /// The MJCF attribute, the URDF one (on `<dynamics>`).
    attr: &'static str,
    urdf: &'static str,
    /// Units of a hinge's and a slide's value.
    units: [&'static str; 2],
    value: fn(&crate::model::Joint) -> f64,
    what: &'static str,
}

const QUANTITIES: [Quantity; 2] = [
    Quantity {
        attr: "frictionloss",
        urdf: "dynamics.friction",
        units: ["N·m", "N"],
        value: |j| j.frictionloss,
        what: "dry friction",
    },
    Quantity {
        attr: "damping",
        urdf: "dynamics.damping",
        units: ["N·m·s/rad", "N·s/m"],
        value: |j| j.damping,
        what: "damping",
    },
];

fn names(cx: &Context, js: &[usize]) -> String {
    let n: Vec<&str> = js.iter().map(|j| cx.robot.joints[*j].name.as_str()).collect();
    if n.len() > 6 {
        format!("`{}`, …", n[..6].join("`, `"))
    } else {
        format!("`{}`", n.join("`, `"))
    }
}

/// The finding when `q` is above zero on some of `fam`'s joints and zero on the others.
fn stated_on_some(cx: &Context, fam: &Family, q: &Quantity) -> Option<Finding> {
    let robot = cx.robot;
    let (on, off): (Vec<usize>, Vec<usize>) =
        fam.joints.iter().partition(|j| (q.value)(&robot.joints[**j]) > 0.0);
    if on.is_empty() || off.is_empty() {
        return None;
    }
    let first = &robot.joints[on[0]];
    let unit = q.units[(first.jtype == JointType::Slide) as usize];
    let mut vals: Vec<f64> = on.iter().map(|j| (q.value)(&robot.joints[*j])).collect();
    vals.sort_by(f64::total_cmp);
    vals.dedup();
    let shown = if vals.len() == 1 {
        format!("{} {unit}", fmt_num(vals[0], 4))
    } else {
        format!("{}–{} {unit}", fmt_num(vals[0], 4), fmt_num(vals[vals.len() - 1], 4))
    };
    let attr = if robot.format == Format::Urdf { q.urdf } else { q.attr };
    let zero = &robot.joints[off[0]];
    let msg = format!(
        "the {} joints of one motor family ({}) state `{}` {shown} on {} ({}) and none on {} ({})",
        fam.joints.len(),
        fam.label,
        q.attr,
        on.len(),
        names(cx, &on),
        off.len(),
        names(cx, &off)
    );
    Some(
        cx.at_attr(ElemKind::Joint, first.id, &first.name, attr, msg)
            .label(format!("{} {shown}", q.attr))
            .secondary(
                robot.elem_loc(ElemKind::Joint, zero.id, &zero.name),
                format!("joint `{}`: no {}", zero.name, q.what),
            )
            .note(format!(
                "{} belongs to the motor and gearbox, so one drive has it on every joint it turns; zero on some of them is a value left out (or one copied onto the wrong joints), and the policy trains on joints that coast where the hardware brakes",
                q.what
            ))
            .help(format!(
                "give every joint of the drive its identified `{}` (one <default class> per motor family; in a URDF the same <dynamics> on each joint); a joint damped on purpose belongs in a class of its own",
                q.attr
            ))
            .subject(Subject::Joint(zero.id))
            .measured(0.0, unit)
            .expected(vals[0], unit)
            .with("joints_with", on.len() as f64)
            .with("joints_without", off.len() as f64),
    )
}
