use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::model::mjcf::ElemKind;
use crate::model::urdf_transmissions::{drives, transmissions};
use crate::rules::contact::welded_legged_base::urdf_legs;
use crate::rules::{Context, Rule, RuleMeta};

declare_rule! {
    /// ## What it does
    /// In a URDF robot with legs (two or more chains leaving the root link, each ending two or
    /// more hinge/slide joints further out in its lowest contact: a foot, or a wheel at the end
    /// of a hip and a knee, leaving the root link below the top quarter of its colliding height,
    /// where arms leave a torso; or, when qpos0 hides them — Qmini's zero folds each leg up behind
    /// its hip, the feet above the hips — two or more chains of two or more hinge/slide joints,
    /// no wheel, that leave the root link through the lower half of its colliding height, end
    /// in a colliding link and, stretched straight, reach below the root link's lowest point:
    /// a humanoid upper body's arms leave the torso at its top and are no legs), finds the hinge and slide joints whose compiled armature is zero
    /// while nothing says what drives them: no `<transmission>` names the joint and the spec
    /// gives it no motor family (nor marks it passive). They are reported in one finding. Not
    /// judged: an MJCF (`zero-armature` judges its actuated joints), a URDF arm or gripper (one
    /// chain, or chains that end above the base), joints a transmission names
    /// (`transmission-without-armature` judges a reduction N > 1; a reduction of 1 says direct
    /// drive), joints with a spec motor family (`zero-armature` and `armature-mismatch` judge
    /// them; a family with `gear_ratio = 1` is a direct drive declared), and a spec that says
    /// nothing is actuated (`robot.actuated = 0`).
    ///
    /// ## Why is this bad?
    /// A legged robot's joints are driven by motors, nearly always through a reduction (a
    /// 6:1 planetary, a 9:1 belt): the rotor's inertia reaches the joint × N², often more
    /// than a light leg link's own. A URDF has no field for it, MuJoCo's URDF importer sets
    /// armature 0 on every joint (it ignores `<transmission>`s, and a URDF's `<mujoco>` block
    /// takes only `<compiler>`, `<option>` and `<size>`, none of which sets armature), so a
    /// policy trained on the URDF as it is gets legs with no rotor inertia: they accelerate and
    /// overshoot more under the same gains than the hardware, and light shanks become stiff to
    /// integrate.
    ///
    /// ## How it is confirmed
    /// Static: the compiled joints' armature, the file's `<transmission>`s and the spec. A
    /// fact of the file; neither the rotor inertia nor the reduction is in it, so the finding
    /// names no value.
    ///
    /// ## How to fix
    /// Say what the motors are. In a spec beside the model (`modellint init-spec`): a motor
    /// family per actuator type with `rotor_inertia` and `gear_ratio` (`gear_ratio = 1` for a
    /// direct drive) and `[joints."…"] motor = "…"`; `armature-mismatch` then names the expected
    /// armature J_rotor·N². For the simulation, the armature goes where MuJoCo reads it: an MJCF
    /// wrapper that attaches the URDF and adds the actuators with it
    /// (`<actuator><position joint="…" armature="J_rotor·N²" …/>`, gear 1), or
    /// `spec.joint("…").armature` set in an mjSpec before compiling.
    pub LeggedUrdfArmature {
        id: "legged-urdf-armature",
        group: "inertia",
        level: Severity::Warning,
        probe: None,
        options: [],
    }
}

impl Rule for LeggedUrdfArmature {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let robot = cx.robot;
        let Some(legs) = urdf_legs(robot) else { return };
        if cx.spec.and_then(|s| s.robot.actuated.as_ref()).is_some_and(|a| *a.get_ref() == 0) {
            return;
        }
        let drv = transmissions(cx.sources, &robot.tree);
        let zero: Vec<usize> = robot
            .joints
            .iter()
            .filter(|j| j.is_scalar() && j.armature == 0.0)
            .filter(|j| !drives(&drv, &j.name) && cx.facts(&j.name).is_none())
            .map(|j| j.id)
            .collect();
        let Some(&first) = zero.first() else { return };
        let names: Vec<String> =
            zero.iter().map(|&i| format!("`{}`", robot.joints[i].name)).collect();
        let shown = if names.len() > 8 {
            format!("{}, and {} more", names[..8].join(", "), names.len() - 8)
        } else {
            names.join(", ")
        };
        let n_scalar = robot.joints.iter().filter(|j| j.is_scalar()).count();
        let j0 = &robot.joints[first];
        let at = robot.elem_loc(ElemKind::Joint, j0.id, &j0.name);
        let msg = format!(
            "{} of the {n_scalar} joints of this {}-legged URDF {} armature 0 in MuJoCo, and nothing says what drives {}: no <transmission> names {} and no spec gives {} a motor family: {shown}",
            zero.len(),
            legs.len(),
            if zero.len() == 1 { "gets" } else { "get" },
            if zero.len() == 1 { "it" } else { "them" },
            if zero.len() == 1 { "it" } else { "them" },
            if zero.len() == 1 { "it" } else { "them" },
        );
        let f = cx
            .finding(msg, at)
            .element(format!("joint `{}`", j0.name), at)
            .label("no armature, no transmission, no motor in a spec")
            .note("a legged robot's joints are driven by motors, nearly always through a reduction N: the rotor's inertia reaches the joint × N². A URDF has no field for it, and MuJoCo's importer sets armature 0 on every joint (it ignores <transmission>s; a URDF's <mujoco> block takes only <compiler>, <option> and <size>), so a policy trained on this file gets legs with no rotor inertia, which accelerate and overshoot more under the same gains than the hardware")
            .help("say what the motors are: a spec beside the model (`modellint init-spec`) with a motor family per actuator type (rotor_inertia, gear_ratio; gear_ratio = 1 for a direct drive) and [joints.\"…\"] motor = \"…\", so armature-mismatch names the expected armature J_rotor·N²; and give MuJoCo that armature in an MJCF wrapper that attaches the URDF (<actuator><position joint=\"…\" armature=\"J_rotor·N²\" …/>, gear 1) or through spec.joint(\"…\").armature in an mjSpec")
            .subject(Subject::Joint(j0.id))
            .measured(0.0, "kg·m²")
            .with("joints", zero.len() as f64)
            .with("legs", legs.len() as f64);
        out.push(f);
    }
}
