//! Load-dependent friction: a dry-friction budget that grows with the transmitted torque
//! (gear-mesh normal force), base + k·|τ_motor|, applied as −tanh(q̇/ε)·budget.
use super::*;

pub struct LoadDependentFriction;

const P: &[ParamDef] = &[
    ParamDef { name: "frictionloss", unit: "N·m", lo: 0.0, hi: 2.0, default: 0.0 },
    ParamDef { name: "load_coeff", unit: "", lo: 0.0, hi: 0.5, default: 0.0 },
];

impl Effect for LoadDependentFriction {
    fn friction(&self) -> bool {
        true
    }
    fn id(&self) -> &'static str {
        "load_dependent_friction"
    }
    fn params(&self) -> &'static [ParamDef] {
        P
    }
    fn entry(&self) -> Entry {
        Entry::Torque
    }
    fn describe(&self) -> &'static str {
        "dry friction growing with the motor torque: base + load_coeff·|τ_motor|"
    }
    fn initial(&self, _m: &MjModel, _t: &JointTarget) -> Vec<f64> {
        vec![0.02, 0.02]
    }
    fn torque(
        &self,
        _st: &mut EffectState,
        q: f64,
        qd: f64,
        _q_target: f64,
        io: &mut StepIo,
        _dt: f64,
        p: &[f64],
    ) {
        let budget = p[0].max(0.0) + p[1].max(0.0) * servo_torque(q, qd, io).abs();
        io.tau -= smooth_sign(qd, super::stribeck_friction::EPS) * budget;
    }
    fn write_back(&self, _p: &[f64]) -> WriteBack {
        WriteBack::TomlOnly
    }
}
