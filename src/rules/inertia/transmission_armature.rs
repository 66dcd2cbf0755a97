use std::collections::BTreeMap;

use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::Format;
use crate::model::source::Loc;
use crate::model::urdf_transmissions::transmissions;
use crate::rules::{Context, Rule, RuleMeta};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// In a URDF, finds joints a ROS `<transmission>` drives through a mechanical reduction
    /// N > 1 (`<mechanicalReduction>` of the old and the ros_control syntax,
    /// `<mechanical_reduction>` of ros2_control) whose compiled joint has no armature. Joints
    /// with one reduction are reported together. Not judged: a reduction of 1 or none written
    /// (a direct drive; ROS takes 1), joints no transmission names (a hydraulic or passive
    /// joint), and a joint the compiled model gives armature.
    ///
    /// ## Why is this bad?
    /// A motor behind an N:1 reduction turns N times per joint turn, so its rotor's inertia
    /// J_rotor appears at the joint as N²·J_rotor (81 × J_rotor at 9:1, 2,500 × at 50:1): on
    /// light links often more than the links themselves. MuJoCo's `armature` stands for it, and
    /// MuJoCo's URDF importer sets none: it ignores `<transmission>`s, and a URDF's `<mujoco>`
    /// block takes only `<compiler>`, `<option>` and `<size>`. Without it the simulated joint
    /// accelerates and overshoots more under the same gains than the hardware, and light distal
    /// links become stiff to integrate.
    ///
    /// ## How it is confirmed
    /// Static: the transmissions' reductions as written, against the compiled joint's effective
    /// armature (joint, actuators and tendons). A fact of the file. The rotor inertia is not in
    /// the file, so the finding says the factor N², not a value.
    ///
    /// ## How to fix
    /// Take the rotor inertia J_rotor from the motor's datasheet; the joint's armature is
    /// N²·J_rotor. A URDF cannot hold it: write an MJCF wrapper that attaches the URDF and adds
    /// the actuators (`<actuator><position joint="…" armature="N²·J_rotor" …/>`: MuJoCo applies
    /// an actuator's `armature` × gear², so with gear 1 write the product), or set
    /// `spec.joint("…").armature` in an mjSpec before compiling.
    pub TransmissionWithoutArmature {
        id: "transmission-without-armature",
        group: "inertia",
        level: Severity::Warning,
        probe: None,
        options: [],
    }
}

/// One geared joint with no armature: its compiled id, and where its reduction is written.
struct Geared {
    joint: usize,
    reduction_at: Loc,
    transmission: String,
}

impl Rule for TransmissionWithoutArmature {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        if robot.format != Format::Urdf {
            return;
        }
        // Reduction (by its bits: one finding per distinct value) → its joints.
        let mut groups: BTreeMap<u64, (f64, Vec<Geared>)> = BTreeMap::new();
        for d in transmissions(cx.sources, &robot.tree) {
            let Some((n, at)) = d.reduction else { continue };
            if !(n > 1.0) {
                continue;
            }
            for (name, _) in &d.joints {
                let Some(j) = robot.joint(name) else { continue };
                if !j.is_scalar() || j.armature > 0.0 {
                    continue;
                }
                let g = groups.entry(n.to_bits()).or_insert((n, Vec::new()));
                if g.1.iter().all(|x| x.joint != j.id) {
                    g.1.push(Geared {
                        joint: j.id,
                        reduction_at: at,
                        transmission: d.name.clone(),
                    });
                }
            }
        }
        for (n, joints) in groups.into_values() {
            let names: Vec<String> =
                joints.iter().map(|g| format!("`{}`", robot.joints[g.joint].name)).collect();
            let k = joints.len();
            let shown = if k > 8 {
                format!("{}, and {} more", names[..8].join(", "), k - 8)
            } else {
                names.join(", ")
            };
            let factor = n * n;
            let first = &joints[0];
            let j0 = &robot.joints[first.joint];
            let msg = format!(
                "{k} joint{} driven through a {}:1 reduction (<transmission>) {} no armature: the rotor's inertia reaches the joint × {} (N²), and neither the URDF nor MuJoCo's importer gives any: {shown}",
                if k == 1 { "" } else { "s" },
                fmt_num(n, 4),
                if k == 1 { "has" } else { "have" },
                fmt_num(factor, 5)
            );
            let mut f = cx
                .finding(msg, first.reduction_at)
                .element(format!("joint `{}`", j0.name), first.reduction_at)
                .label(format!(
                    "reduction {} of transmission `{}`: armature N²·J_rotor = {}·J_rotor",
                    fmt_num(n, 4),
                    first.transmission,
                    fmt_num(factor, 5)
                ));
            let mut seen = vec![first.reduction_at];
            for g in joints.iter().skip(1) {
                if seen.len() >= 4 || seen.contains(&g.reduction_at) {
                    continue;
                }
                seen.push(g.reduction_at);
                f = f.secondary(
                    g.reduction_at,
                    format!("also {}:1, `{}`", fmt_num(n, 4), robot.joints[g.joint].name),
                );
            }
            let f = f
                .note("MuJoCo's URDF importer makes no actuator and no armature: it ignores <transmission>s, and a URDF's <mujoco> block takes only <compiler>, <option> and <size>; without the rotor's reflected inertia the simulated joint accelerates and overshoots more than the hardware under the same gains")
                .help(format!(
                    "take the rotor inertia J_rotor from the motor's datasheet: armature = {}·J_rotor; a URDF cannot hold it, so add it in an MJCF wrapper that attaches the URDF (<actuator><position joint=\"{}\" armature=\"{}·J_rotor\" …/>: an actuator's armature is applied × gear², so with gear 1 write the product) or set spec.joint(\"{}\").armature in an mjSpec",
                    fmt_num(factor, 5),
                    j0.name,
                    fmt_num(factor, 5),
                    j0.name
                ))
                .subject(Subject::Joint(j0.id))
                .measured(0.0, "kg·m²")
                .with("reduction", n)
                .with("reflection_factor", factor)
                .with("joints", k as f64);
            out.push(f);
        }
    }
}
