//! Armature: reflected rotor inertia added to the joint's DoF (`dof_armature`).
use super::*;

pub struct Armature;

const P: &[ParamDef] =
    &[ParamDef { name: "armature", unit: "kg·m²", lo: 0.0, hi: 0.5, default: 0.0 }];

impl Effect for Armature {
    fn id(&self) -> &'static str {
        "armature"
    }
    fn params(&self) -> &'static [ParamDef] {
        P
    }
    fn entry(&self) -> Entry {
        Entry::Model
    }
    fn describe(&self) -> &'static str {
        "reflected rotor inertia (gear ratio² × rotor inertia): dof_armature"
    }
    fn initial(&self, m: &MjModel, t: &JointTarget) -> Vec<f64> {
        vec![get(m.dof_armature(), t.dof)]
    }
    fn bounds(&self, m: &MjModel, t: &JointTarget) -> (Vec<f64>, Vec<f64>) {
        (vec![0.0], vec![P[0].hi.max(10.0 * self.initial(m, t)[0])])
    }
    fn apply_model(&self, m: &mut MjModel, t: &JointTarget, p: &[f64]) {
        mj::set_armature(m, t.dof, p[0].max(0.0));
    }
    fn smooth(&self) -> bool {
        true
    }
    fn write_back(&self, p: &[f64]) -> WriteBack {
        WriteBack::Joint(vec![("armature", p[0])])
    }
}
