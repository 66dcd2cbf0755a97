use super::*;
use crate::declare_effect;

declare_effect! {
    /// Spring torque towards the keyframe pose (cable drag, parallel springs, compliant covers).
    ///
    /// MuJoCo-native: `jnt_stiffness`, with `qpos_spring` set to the keyframe position.
    ///
    /// ## Simulation
    /// `jnt_stiffness`, `qpos_spring` = keyframe
    ///
    /// ## Signature
    /// `q − q_key` (error ∝ deflection / load)
    ///
    /// ## Evidence
    /// `implied_stiffness` = −c·kp
    ///
    /// ## Write-back
    /// joint `stiffness`, and `springref` at the keyframe position
    ///
    /// ## Isaac Lab / mjlab
    /// comment with the parameters
    pub JointStiffness {
        id: "joint_stiffness",
        entry: Model,
        params: [ParamDef { name: "stiffness", unit: "N·m/rad", lo: 0.0, hi: 20.0, default: 0.0 }],
    }
}

impl Effect for JointStiffness {
    fn initial(&self, m: &MjModel, t: &JointTarget) -> Vec<f64> {
        vec![get(m.jnt_stiffness(), t.jnt)]
    }
    /// Up to the fixed bound widened for a strong drive ([`super::JointTarget::strength`]), or
    /// 10 × the model's own value.
    fn bounds(&self, m: &MjModel, t: &JointTarget) -> (Vec<f64>, Vec<f64>) {
        (vec![0.0], vec![(Self::META.params[0].hi * t.strength()).max(10.0 * self.initial(m, t)[0])])
    }
    fn apply_model(&self, m: &mut MjModel, t: &JointTarget, p: &[f64]) {
        set(m.jnt_stiffness_mut(), t.jnt, p[0].max(0.0));
        set(m.qpos_spring_mut(), t.qposadr, t.key_q);
    }
    fn smooth(&self) -> bool {
        true
    }
    /// At its start the model's own stiffness, written back — with the spring's reference moved
    /// to the keyframe, which changes nothing only where that stiffness is zero.
    fn neutral_at(&self, m: &MjModel, t: &JointTarget) -> bool {
        self.initial(m, t)[0] == 0.0
    }
    fn signature(&self, s: &Samples) -> Signature {
        Signature { implied: Some("implied_stiffness"), ..Signature::centred(s.qrel.clone()) }
    }
    fn write_back(&self, p: &[f64]) -> WriteBack {
        WriteBack::Joint(vec![("stiffness", p[0])])
    }
}
