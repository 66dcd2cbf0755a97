use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::{Joint, Robot, Transmission};
use crate::rules::{Context, Rule, RuleMeta, opt};
use crate::spec::{JointFacts, Spec, v};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// A joint driven by N motors together (spec `count = N > 1`, e.g. ankle pitch and roll
    /// through a parallel RSU linkage, or detected: N tendon actuators reaching the joint) sees
    /// the reflected inertia of all N rotors, so its armature must be N × rotor_inertia × gear².
    /// Reports such joints that carry a different value (typically one motor's), and single-motor
    /// joints that carry a doubled value: twice their own family's, or the parallel family's
    /// N-motor value copied onto them.
    ///
    /// ## Why is this bad?
    /// Armature strongly affects closed-loop behaviour (seed 001 §2). Halving a parallel ankle's
    /// reflected inertia makes it twice as lively in simulation as on hardware; copying the
    /// doubled ankle value onto a single-motor joint makes that joint artificially sluggish.
    ///
    /// ## How it is confirmed
    /// Static: compiled `dof_armature` against the spec's motor families and counts.
    ///
    /// ## How to fix
    /// Set armature = count × rotor_inertia × gear_ratio² for the joint's own family.
    pub ParallelAnkleArmature {
        id: "parallel-ankle-armature",
        group: "inertia",
        level: Severity::Error,
        probe: None,
        options: [opt("tolerance", 0.05, "fraction", "relative tolerance when comparing armature values")],
    }
}

#[derive(Debug, Clone, PartialEq)]
pub enum Issue {
    /// An N-motor joint whose armature is not N × single.
    Parallel { n: u32, detected: bool, single: f64, expected: f64, carries_single: bool },
    /// A single-motor joint carrying twice its own family's value.
    DoubledOwn { single: f64 },
    /// A single-motor joint carrying another (parallel) family's N-motor value.
    Reused { family: String, n: u32, value: f64, single: f64 },
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * b.abs().max(1e-12)
}

fn single_value(spec: &Spec, family: &str) -> Option<f64> {
    let m = spec.motor(family)?;
    let (ri, g) = (v(&m.rotor_inertia)?, v(&m.gear_ratio)?);
    Some(ri * g * g)
}

/// Number of tendon-transmission actuators reaching joint `j` (a parallel linkage drives each
/// of its joints through several).
pub fn tendon_motor_count(robot: &Robot, j: usize) -> u32 {
    robot.actuators_on_joint(j).iter().filter(|a| a.trn == Transmission::Tendon).count() as u32
}

/// The parallel-drive armature problem of a joint, if any (shared with `armature-mismatch`,
/// which leaves these joints to this rule).
pub fn parallel_issue(cx: &Context, spec: &Spec, j: &Joint, facts: &JointFacts, tol: f64) -> Option<Issue> {
    let fam = facts.motor.as_deref()?;
    if facts.passive {
        return None;
    }
    let single = single_value(spec, fam)?;
    let detected = tendon_motor_count(cx.robot, j.id);
    let n = facts.count.max(if facts.count == 1 && detected >= 2 { detected } else { 1 });
    let a = j.armature;
    if n > 1 {
        let expected = single * n as f64;
        if close(a, expected, tol) {
            return None;
        }
        return Some(Issue::Parallel { n, detected: facts.count == 1, single, expected, carries_single: close(a, single, tol) });
    }
    if !(a > 0.0) || close(a, single, tol) {
        return None;
    }
    // One value copy-pasted onto every actuated joint is `armature-mismatch`'s uniform finding,
    // not a doubling, even when it happens to be twice some family's value.
    let uniform = cx.robot.joints.iter().filter(|o| o.is_scalar() && spec.joint(&o.name).is_some_and(|f| f.motor.is_some() && !f.passive)).all(|o| o.armature == a);
    if !uniform && close(a, 2.0 * single, tol) {
        return Some(Issue::DoubledOwn { single });
    }
    for other in &cx.robot.joints {
        let Some(of) = spec.joint(&other.name) else { continue };
        let (Some(ofam), true) = (of.motor.as_deref(), of.count > 1) else { continue };
        let Some(os) = single_value(spec, ofam) else { continue };
        let value = os * of.count as f64;
        if close(a, value, tol) {
            return Some(Issue::Reused { family: ofam.to_string(), n: of.count, value, single });
        }
    }
    None
}

impl Rule for ParallelAnkleArmature {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let Some(spec) = cx.spec else { return };
        let tol = cx.opt("tolerance");
        for j in cx.robot.joints.iter().filter(|j| j.is_scalar()) {
            let Some(facts) = spec.joint(&j.name) else { continue };
            let Some(issue) = parallel_issue(cx, spec, j, &facts, tol) else { continue };
            let fam = facts.motor.clone().unwrap_or_default();
            let a = j.armature;
            let (msg, expected, note) = match &issue {
                Issue::Parallel { n, detected, single, expected, carries_single } => (
                    format!(
                        "joint `{}` is driven by {n} `{fam}` motors{} but its armature {} kg·m² {}; expected {n} × {} = {} kg·m²",
                        j.name,
                        if *detected { format!(" (the model reaches it through {n} tendon actuators; the spec says count = 1)") } else { String::new() },
                        fmt_num(a, 4),
                        if *carries_single { "is one motor's reflected inertia" } else { "is not their combined reflected inertia" },
                        fmt_num(*single, 4),
                        fmt_num(*expected, 4)
                    ),
                    *expected,
                    "every motor of a parallel linkage reflects its rotor inertia onto the joint; with one motor's value the simulated joint is far livelier than the hardware (seed 001 §2: the ankle value is doubled for the two RSU motors)",
                ),
                Issue::DoubledOwn { single } => (
                    format!(
                        "single-motor joint `{}` carries armature {} kg·m², twice its `{fam}` family's reflected inertia {} kg·m²",
                        j.name,
                        fmt_num(a, 4),
                        fmt_num(*single, 4)
                    ),
                    *single,
                    "doubling belongs to joints driven by two motors through a parallel linkage; on a single-motor joint it makes the simulated joint twice as sluggish as the hardware",
                ),
                Issue::Reused { family, n, value, single } => (
                    format!(
                        "single-motor joint `{}` carries armature {} kg·m², the {n}-motor value of the parallel `{family}` family ({} kg·m²), not its own `{fam}` value {} kg·m²",
                        j.name,
                        fmt_num(a, 4),
                        fmt_num(*value, 4),
                        fmt_num(*single, 4)
                    ),
                    *single,
                    "a value copied from the parallel ankle carries that linkage's doubled inertia onto a joint that has one motor",
                ),
            };
            let mut f = cx
                .at_attr(ElemKind::Joint, j.id, &j.name, "armature", msg)
                .label(format!("armature {} kg·m²", fmt_num(a, 4)))
                .note(note)
                .help(format!("set armature=\"{}\" (count × rotor_inertia × gear_ratio²)", fmt_num(expected, 6)))
                .subject(Subject::Joint(j.id))
                .measured(a, "kg·m²")
                .expected(expected, "kg·m²")
                .with("armature", a)
                .with("expected_armature", expected);
            if let Some(l) = facts.motor_loc {
                f = f.secondary(l, format!("spec motor family `{fam}` (count = {})", facts.count));
            }
            out.push(f);
        }
    }
}
