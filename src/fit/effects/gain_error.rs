//! Gain error: the servo's real PD gains differ from the model's (firmware units, supply
//! voltage, current limits). A hook adds (kp_scale − 1)·kp·(ctrl − q) − (kd_scale − 1)·kd·q̇, so
//! it also scales gains that come from the recording's kp/kd columns.
use super::*;

pub struct GainError;

const P: &[ParamDef] = &[
    ParamDef { name: "kp_scale", unit: "", lo: 0.3, hi: 3.0, default: 1.0 },
    ParamDef { name: "kd_scale", unit: "", lo: 0.2, hi: 5.0, default: 1.0 },
];

impl Effect for GainError {
    fn id(&self) -> &'static str {
        "gain_error"
    }
    fn params(&self) -> &'static [ParamDef] {
        P
    }
    fn entry(&self) -> Entry {
        Entry::Torque
    }
    fn describe(&self) -> &'static str {
        "real PD gains = model gains × (kp_scale, kd_scale)"
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
        if io.enabled {
            io.tau += (p[0] - 1.0) * io.kp * (io.ctrl - q) - (p[1] - 1.0) * io.kd * qd;
        }
    }
    fn smooth(&self) -> bool {
        true
    }
    fn write_back(&self, p: &[f64]) -> WriteBack {
        WriteBack::Actuator(vec![("kp_scale", p[0]), ("kv_scale", p[1])])
    }
}
