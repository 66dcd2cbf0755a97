use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::rules::{Context, Rule, RuleMeta};

declare_rule! {
    /// ## What it does
    /// Finds joint, actuator and tendon sensors whose name states one quantity while the sensor
    /// measures another: a `<jointpos>` named `knee_vel`, a `<jointvel>` named `hip_pos`, an
    /// `<actuatorfrc>` named `ankle_angle`. The name's quantity is read from its words (split
    /// at `_`, `-`, `.`, digits and case changes): `pos`, `position`, `angle`, `qpos` say
    /// position; `vel`, `velocity`, `qvel`, `dq`, `speed` say velocity; `frc`, `force`,
    /// `torque`, `tau`, `effort` say force. A name with none of these words, or with words of
    /// two quantities, is not judged.
    ///
    /// ## Why is this bad?
    /// Training stacks read observations by sensor name. A velocity observation that is
    /// really the joint angle (a `<jointpos>` block copied and renamed `*_vel`) trains the
    /// policy on a signal the real robot's velocity estimate never shows; the policy fails on
    /// hardware although everything runs in simulation.
    ///
    /// ## How it is confirmed
    /// Static: the sensor's type is its MJCF tag, which MuJoCo compiles as written. A fact of
    /// the file.
    ///
    /// ## How to fix
    /// Use the sensor type the name states (`<jointvel>` for a `*_vel` sensor), or rename it.
    pub SensorQuantity {
        id: "sensor-quantity",
        group: "mapping",
        level: Severity::Warning,
        probe: None,
        options: [],
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Quantity {
    Position,
    Velocity,
    Force,
}

impl Quantity {
    fn word(self) -> &'static str {
        match self {
            Quantity::Position => "position",
            Quantity::Velocity => "velocity",
            Quantity::Force => "force",
        }
    }
}

/// What a sensor of this MJCF tag measures (only scalar joint, actuator and tendon sensors).
fn measured(tag: &str) -> Option<Quantity> {
    match tag {
        "jointpos" | "actuatorpos" | "tendonpos" => Some(Quantity::Position),
        "jointvel" | "actuatorvel" | "tendonvel" => Some(Quantity::Velocity),
        "actuatorfrc" | "jointactuatorfrc" | "tendonactuatorfrc" => Some(Quantity::Force),
        _ => None,
    }
}

/// The words of a name: split at non-letters and at lower→upper case changes, lowercased.
fn words(name: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut prev_lower = false;
    for c in name.chars() {
        if !c.is_ascii_alphabetic() {
            if !cur.is_empty() {
                out.push(std::mem::take(&mut cur));
            }
            prev_lower = false;
            continue;
        }
        if c.is_ascii_uppercase() && prev_lower && !cur.is_empty() {
            out.push(std::mem::take(&mut cur));
        }
        prev_lower = c.is_ascii_lowercase();
        cur.push(c.to_ascii_lowercase());
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// The one quantity a name states, if exactly one.
fn stated(name: &str) -> Option<Quantity> {
    let mut found: Vec<Quantity> = Vec::new();
    for w in words(name) {
        let q = match w.as_str() {
            "pos" | "position" | "angle" | "qpos" => Quantity::Position,
            "vel" | "velocity" | "qvel" | "dq" | "speed" => Quantity::Velocity,
            "frc" | "force" | "torque" | "tau" | "effort" => Quantity::Force,
            _ => continue,
        };
        if !found.contains(&q) {
            found.push(q);
        }
    }
    if found.len() == 1 { found.first().copied() } else { None }
}

impl Rule for SensorQuantity {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        for (i, e) in cx.robot.src.list(ElemKind::Sensor).iter().enumerate() {
            let Some(name) = e.name.as_deref() else { continue };
            let (Some(is), Some(says)) = (measured(&e.tag), stated(name)) else { continue };
            if is == says {
                continue;
            }
            let f = cx
                .finding(
                    format!(
                        "sensor `{name}` is a <{}>, which measures {}, but its name says {}",
                        e.tag,
                        is.word(),
                        says.word()
                    ),
                    e.loc,
                )
                .label(format!("<{}>: {}", e.tag, is.word()))
                .note("training stacks read observations by sensor name: a signal named for one quantity that carries another trains the policy on an observation the real robot never gives")
                .help(format!(
                    "use the sensor type for {} (e.g. <{}>), or rename the sensor",
                    says.word(),
                    match says {
                        Quantity::Position => "jointpos",
                        Quantity::Velocity => "jointvel",
                        Quantity::Force => "jointactuatorfrc",
                    }
                ))
                .subject(Subject::Model)
                .with("sensor", i as f64);
            out.push(f);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_state_one_quantity() {
        assert_eq!(stated("waist_z_joint_vel"), Some(Quantity::Velocity));
        assert_eq!(stated("l_hip_z_joint_pos"), Some(Quantity::Position));
        assert_eq!(stated("kneeTorque"), Some(Quantity::Force));
        assert_eq!(stated("Body_Gyro"), None);
        assert_eq!(stated("pos_and_vel"), None);
        assert_eq!(stated("velocimeter"), None);
        assert_eq!(measured("jointpos"), Some(Quantity::Position));
        assert_eq!(measured("gyro"), None);
    }
}
