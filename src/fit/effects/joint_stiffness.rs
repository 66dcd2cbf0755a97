//! Joint stiffness: a spring towards the keyframe pose (`jnt_stiffness`, `qpos_spring` set to
//! the keyframe position) — cable drag, parallel springs, compliant covers.
use super::*;

pub struct JointStiffness;

const P: &[ParamDef] =
    &[ParamDef { name: "stiffness", unit: "N·m/rad", lo: 0.0, hi: 20.0, default: 0.0 }];

impl Effect for JointStiffness {
    fn id(&self) -> &'static str {
        "joint_stiffness"
    }
    fn params(&self) -> &'static [ParamDef] {
        P
    }
    fn entry(&self) -> Entry {
        Entry::Model
    }
    fn describe(&self) -> &'static str {
        "spring torque towards the keyframe pose: jnt_stiffness with springref at the keyframe"
    }
    fn initial(&self, m: &MjModel, t: &JointTarget) -> Vec<f64> {
        vec![get(m.jnt_stiffness(), t.jnt)]
    }
    fn bounds(&self, m: &MjModel, t: &JointTarget) -> (Vec<f64>, Vec<f64>) {
        (vec![0.0], vec![P[0].hi.max(10.0 * self.initial(m, t)[0])])
    }
    fn apply_model(&self, m: &mut MjModel, t: &JointTarget, p: &[f64]) {
        set(m.jnt_stiffness_mut(), t.jnt, p[0].max(0.0));
        set(m.qpos_spring_mut(), t.qposadr, t.key_q);
    }
    fn smooth(&self) -> bool {
        true
    }
    fn write_back(&self, p: &[f64]) -> WriteBack {
        WriteBack::Joint(vec![("stiffness", p[0])])
    }
}
