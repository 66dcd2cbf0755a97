//! Torque limit: DC-motor torque–speed line. The servo torque is clipped to
//! [sat·(−1 − q̇/v_lim), sat·(1 − q̇/v_lim)] ∩ [−effort, effort] (Isaac Lab's DCMotor law).
//! Only `effort_limit` is fitted by default; the line parameters start unlimited.
use super::*;

pub struct TorqueLimit;

const P: &[ParamDef] = &[
    ParamDef { name: "effort_limit", unit: "N·m", lo: 0.05, hi: 50.0, default: 50.0 },
    ParamDef { name: "saturation_effort", unit: "N·m", lo: 0.05, hi: 1e4, default: 1e4 },
    ParamDef { name: "velocity_limit", unit: "rad/s", lo: 0.5, hi: 1e4, default: 1e4 },
];

impl Effect for TorqueLimit {
    fn id(&self) -> &'static str {
        "torque_limit"
    }
    fn params(&self) -> &'static [ParamDef] {
        P
    }
    fn entry(&self) -> Entry {
        Entry::Torque
    }
    fn describe(&self) -> &'static str {
        "motor torque saturation (peak torque, torque–speed line)"
    }
    fn fitted(&self) -> usize {
        1
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
        let raw = servo_torque(q, qd, io);
        let (e, sat, vl) = (p[0].max(0.0), p[1].max(0.0), p[2].max(1e-6));
        let hi = (sat * (1.0 - qd / vl)).clamp(0.0, e);
        let lo = (sat * (-1.0 - qd / vl)).clamp(-e, 0.0);
        io.tau += raw.clamp(lo, hi) - raw;
    }
    fn write_back(&self, p: &[f64]) -> WriteBack {
        WriteBack::Actuator(vec![("forcerange", p[0])])
    }
}
