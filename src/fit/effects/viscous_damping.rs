use super::*;
use crate::declare_effect;

declare_effect! {
    /// Torque proportional to joint velocity (lubricant, back-EMF).
    ///
    /// MuJoCo-native: the joint's `damping` (`dof_damping`, integrated implicitly by MuJoCo).
    ///
    /// ## Simulation
    /// `dof_damping`
    ///
    /// ## Signature
    /// `q̇`
    ///
    /// ## Evidence
    /// `implied_damping` = −c·kp
    ///
    /// ## Write-back
    /// joint `damping`
    ///
    /// ## Isaac Lab / mjlab
    /// comment: passive joint damping is not an actuator field (add it to the joint's damping or
    /// to the PD damping `kd`)
    pub ViscousDamping {
        id: "viscous_damping",
        entry: Model,
        params: [ParamDef { name: "damping", unit: "N·m·s/rad", lo: 0.0, hi: 5.0, default: 0.0 }],
    }
}

const IMPLIED: &str = "implied_damping";

impl Effect for ViscousDamping {
    fn initial(&self, m: &MjModel, t: &JointTarget) -> Vec<f64> {
        vec![get(m.dof_damping(), t.dof)]
    }
    /// Up to the fixed bound widened for a strong drive ([`super::JointTarget::strength`]), or
    /// 10 × the model's own value.
    fn bounds(&self, m: &MjModel, t: &JointTarget) -> (Vec<f64>, Vec<f64>) {
        (vec![0.0], vec![(Self::META.params[0].hi * t.strength()).max(10.0 * self.initial(m, t)[0])])
    }
    fn apply_model(&self, m: &mut MjModel, t: &JointTarget, p: &[f64]) {
        set(m.dof_damping_mut(), t.dof, p[0].max(0.0));
    }
    fn smooth(&self) -> bool {
        true
    }
    /// At its start the model's own damping, written back.
    fn neutral_start(&self) -> bool {
        true
    }
    fn signature(&self, s: &Samples) -> Signature {
        Signature { implied: Some(IMPLIED), ..Signature::centred(s.qd.clone()) }
    }
    fn shown_evidence(&self) -> &'static [&'static str] {
        &[IMPLIED]
    }
    fn write_back(&self, p: &[f64]) -> WriteBack {
        WriteBack::Joint(vec![("damping", p[0])])
    }
    fn isaaclab(&self, params: &BTreeMap<String, f64>, _timestep: f64) -> IsaacLab {
        IsaacLab::Comment(format!(
            "# passive joint damping {} N·m·s/rad: not an actuator field; add it to the joint's damping, or to the PD damping (kd)",
            num(named(params, Self::META.params[0].name))
        ))
    }
}
