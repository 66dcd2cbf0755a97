use super::*;
use crate::declare_effect;

declare_effect! {
    /// Reflected rotor inertia (gear ratio² × rotor inertia) added to the joint's DoF.
    ///
    /// MuJoCo-native: `dof_armature` of the model copy, fitted as an absolute value from the
    /// model's own.
    ///
    /// ## Simulation
    /// `dof_armature`
    ///
    /// ## Signature
    /// `q̈`
    ///
    /// ## Evidence
    /// `implied_armature` = −c·kp
    ///
    /// ## Write-back
    /// joint `armature`
    ///
    /// ## Isaac Lab / mjlab
    /// `armature` field
    pub Armature {
        id: "armature",
        entry: Model,
        params: [ParamDef { name: "armature", unit: "kg·m²", lo: 0.0, hi: 0.5, default: 0.0 }],
    }
}

const IMPLIED: &str = "implied_armature";

impl Effect for Armature {
    fn initial(&self, m: &MjModel, t: &JointTarget) -> Vec<f64> {
        vec![get(m.dof_armature(), t.dof)]
    }
    fn bounds(&self, m: &MjModel, t: &JointTarget) -> (Vec<f64>, Vec<f64>) {
        (vec![0.0], vec![Self::META.params[0].hi.max(10.0 * self.initial(m, t)[0])])
    }
    fn apply_model(&self, m: &mut MjModel, t: &JointTarget, p: &[f64]) {
        mj::set_armature(m, t.dof, p[0].max(0.0));
    }
    fn smooth(&self) -> bool {
        true
    }
    /// At its start the model's own armature, written back.
    fn neutral_start(&self) -> bool {
        true
    }
    fn signature(&self, s: &Samples) -> Signature {
        Signature { implied: Some(IMPLIED), ..Signature::centred(s.qdd.clone()) }
    }
    fn shown_evidence(&self) -> &'static [&'static str] {
        &[IMPLIED]
    }
    fn write_back(&self, p: &[f64]) -> WriteBack {
        WriteBack::Joint(vec![("armature", p[0])])
    }
    fn isaaclab(&self, params: &BTreeMap<String, f64>, _timestep: f64) -> IsaacLab {
        IsaacLab::Field(format!(
            "armature={},  # kg·m² (reflected rotor inertia)",
            num(named(params, Self::META.params[0].name))
        ))
    }
}
