//! Coulomb (dry) friction: MuJoCo's `frictionloss` on the joint's DoF (a constraint, exact
//! sticking).
use super::*;

pub struct CoulombFriction;

const P: &[ParamDef] =
    &[ParamDef { name: "frictionloss", unit: "N·m", lo: 0.0, hi: 5.0, default: 0.0 }];

impl Effect for CoulombFriction {
    fn friction(&self) -> bool {
        true
    }
    fn id(&self) -> &'static str {
        "coulomb_friction"
    }
    fn params(&self) -> &'static [ParamDef] {
        P
    }
    fn entry(&self) -> Entry {
        Entry::Model
    }
    fn describe(&self) -> &'static str {
        "velocity-independent dry friction (gearbox, seals): dof_frictionloss"
    }
    fn initial(&self, m: &MjModel, t: &JointTarget) -> Vec<f64> {
        vec![get(m.dof_frictionloss(), t.dof)]
    }
    fn bounds(&self, m: &MjModel, t: &JointTarget) -> (Vec<f64>, Vec<f64>) {
        (vec![0.0], vec![P[0].hi.max(10.0 * self.initial(m, t)[0])])
    }
    fn apply_model(&self, m: &mut MjModel, t: &JointTarget, p: &[f64]) {
        set(m.dof_frictionloss_mut(), t.dof, p[0].max(0.0));
    }
    fn smooth(&self) -> bool {
        true
    }
    fn write_back(&self, p: &[f64]) -> WriteBack {
        WriteBack::Joint(vec![("frictionloss", p[0])])
    }
}
