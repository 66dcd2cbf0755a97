//! Viscous damping: MuJoCo's joint `damping` (integrated implicitly by MuJoCo).
use super::*;

pub struct ViscousDamping;

const P: &[ParamDef] =
    &[ParamDef { name: "damping", unit: "N·m·s/rad", lo: 0.0, hi: 5.0, default: 0.0 }];

impl Effect for ViscousDamping {
    fn id(&self) -> &'static str {
        "viscous_damping"
    }
    fn params(&self) -> &'static [ParamDef] {
        P
    }
    fn entry(&self) -> Entry {
        Entry::Model
    }
    fn describe(&self) -> &'static str {
        "torque proportional to joint velocity (lubricant, back-EMF): dof_damping"
    }
    fn initial(&self, m: &MjModel, t: &JointTarget) -> Vec<f64> {
        vec![get(m.dof_damping(), t.dof)]
    }
    fn bounds(&self, m: &MjModel, t: &JointTarget) -> (Vec<f64>, Vec<f64>) {
        (vec![0.0], vec![P[0].hi.max(10.0 * self.initial(m, t)[0])])
    }
    fn apply_model(&self, m: &mut MjModel, t: &JointTarget, p: &[f64]) {
        set(m.dof_damping_mut(), t.dof, p[0].max(0.0));
    }
    fn smooth(&self) -> bool {
        true
    }
    fn write_back(&self, p: &[f64]) -> WriteBack {
        WriteBack::Joint(vec![("damping", p[0])])
    }
}
