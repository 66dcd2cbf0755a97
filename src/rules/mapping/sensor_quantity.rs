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
    /// A name that ends in a one-letter abbreviation (`knee_p`, `knee_v`, `knee_f`) is judged
    /// by the file's own use of the letter: `p` and `q` may say position, `v` velocity, `f`
    /// and `t` force, and the letter says it only when more than half of the model's joint,
    /// actuator and tendon sensors ending in it measure that quantity. A sensor ending in the
    /// letter that measures another quantity is then reported (`leg_r4_joint_v` an
    /// `<actuatorpos>` among eleven `*_v` `<actuatorvel>`s). Other letters (`x`, `y`, `z`,
    /// sides) and letters the file uses otherwise are not judged.
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

/// The quantity a one-letter abbreviation may stand for at the end of a sensor name.
fn letter_quantity(w: &str) -> Option<Quantity> {
    match w {
        "p" | "q" => Some(Quantity::Position),
        "v" => Some(Quantity::Velocity),
        "f" | "t" => Some(Quantity::Force),
        _ => None,
    }
}

/// The quantity each sensor's name states: by its words, else by a final one-letter
/// abbreviation that more than half of the sensors ending in that letter use for the
/// quantity the letter may stand for (the file's own convention). `sensors`: (name, measured).
fn stated_all(sensors: &[(Option<&str>, Option<Quantity>)]) -> Vec<Option<Quantity>> {
    let last = |n: &str| words(n).pop().filter(|w| w.len() == 1);
    let mut out = Vec::with_capacity(sensors.len());
    for &(name, _) in sensors {
        let Some(name) = name else {
            out.push(None);
            continue;
        };
        if let Some(q) = stated(name) {
            out.push(Some(q));
            continue;
        }
        let by_letter = last(name).and_then(|letter| {
            let q = letter_quantity(&letter)?;
            let same: Vec<Option<Quantity>> = sensors
                .iter()
                .filter(|(n, m)| {
                    m.is_some() && n.and_then(last).as_deref() == Some(letter.as_str())
                })
                .map(|&(_, m)| m)
                .collect();
            let agree = same.iter().filter(|&&m| m == Some(q)).count();
            (2 * agree > same.len()).then_some(q)
        });
        out.push(by_letter);
    }
    out
}

impl Rule for SensorQuantity {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let list = cx.robot.src.list(ElemKind::Sensor);
        let sensors: Vec<(Option<&str>, Option<Quantity>)> =
            list.iter().map(|e| (e.name.as_deref(), measured(&e.tag))).collect();
        let says_all = stated_all(&sensors);
        for (i, e) in list.iter().enumerate() {
            let Some(name) = e.name.as_deref() else { continue };
            let (Some(is), Some(says)) = (measured(&e.tag), says_all[i]) else { continue };
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

    #[test]
    fn a_final_letter_says_what_most_sensors_ending_in_it_measure() {
        let p = Some(Quantity::Position);
        let v = Some(Quantity::Velocity);
        let s = [
            (Some("a_p"), p),
            (Some("b_p"), p),
            (Some("a_v"), v),
            (Some("b_v"), v),
            (Some("c_v"), p),
            (Some("a_x"), p),
            (Some("b_x"), v),
            (Some("c_x"), v),
            (Some("gyro_v"), None),
        ];
        let got = stated_all(&s);
        assert_eq!(got[4], v, "c_v: 2 of the 3 `_v` sensors are velocities");
        assert_eq!(got[0], p);
        assert_eq!(got[5], None, "x is no quantity letter");
        // A letter most of whose sensors measure another quantity says nothing.
        let t = [(Some("a_v"), p), (Some("b_v"), p), (Some("c_v"), v)];
        assert!(stated_all(&t).iter().all(Option::is_none));
        // Half is not more than half.
        let h = [(Some("a_f"), Some(Quantity::Force)), (Some("b_f"), p)];
        assert!(stated_all(&h).iter().all(Option::is_none));
    }
}
