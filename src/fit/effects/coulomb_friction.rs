use super::*;
use crate::declare_effect;

declare_effect! {
    /// Velocity-independent dry friction (gearbox, seals).
    ///
    /// MuJoCo-native: `frictionloss` on the joint's DoF, a constraint with exact sticking.
    ///
    /// ## Simulation
    /// `dof_frictionloss` (MuJoCo constraint)
    ///
    /// ## Signature
    /// `tanh(q̇/ε)`, ε = 0.02·rms q̇ (residual ∝ sign of velocity)
    ///
    /// ## Evidence
    /// `implied_frictionloss` = −c·kp
    ///
    /// ## Write-back
    /// joint `frictionloss`
    ///
    /// ## Isaac Lab / mjlab
    /// `friction` field (check the simulator's friction model)
    pub CoulombFriction {
        id: "coulomb_friction",
        entry: Model,
        params: [ParamDef { name: "frictionloss", unit: "N·m", lo: 0.0, hi: 5.0, default: 0.0 }],
    }
}

const IMPLIED: &str = "implied_frictionloss";

impl Effect for CoulombFriction {
    fn friction(&self) -> bool {
        true
    }
    fn initial(&self, m: &MjModel, t: &JointTarget) -> Vec<f64> {
        vec![get(m.dof_frictionloss(), t.dof)]
    }
    /// Up to the fixed bound widened for a strong drive ([`super::JointTarget::strength`]), or
    /// 10 × the model's own value.
    fn bounds(&self, m: &MjModel, t: &JointTarget) -> (Vec<f64>, Vec<f64>) {
        (vec![0.0], vec![(Self::META.params[0].hi * t.strength()).max(10.0 * self.initial(m, t)[0])])
    }
    fn apply_model(&self, m: &mut MjModel, t: &JointTarget, p: &[f64]) {
        set(m.dof_frictionloss_mut(), t.dof, p[0].max(0.0));
    }
    fn smooth(&self) -> bool {
        true
    }
    /// At its start the model's own frictionloss, written back.
    fn neutral_start(&self) -> bool {
        true
    }
    fn signature(&self, s: &Samples) -> Signature {
        let f = s.qd.iter().map(|v| (v / (0.02 * s.qd_rms)).tanh()).collect();
        Signature { implied: Some(IMPLIED), ..Signature::centred(f) }
    }
    fn shown_evidence(&self) -> &'static [&'static str] {
        &[IMPLIED]
    }
    fn write_back(&self, p: &[f64]) -> WriteBack {
        WriteBack::Joint(vec![("frictionloss", p[0])])
    }
    fn isaaclab(&self, params: &BTreeMap<String, f64>, _timestep: f64) -> IsaacLab {
        IsaacLab::Field(format!(
            "friction={},  # N·m (MuJoCo frictionloss; check your simulator's friction model)",
            num(named(params, Self::META.params[0].name))
        ))
    }
}
