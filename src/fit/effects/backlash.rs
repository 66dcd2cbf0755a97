//! Backlash: gear play. The servo's position error has a dead band of total width
//! `backlash_rad` (±half of it produces no torque).
use super::*;

pub struct Backlash;

const P: &[ParamDef] =
    &[ParamDef { name: "backlash_rad", unit: "rad", lo: 0.0, hi: 0.2, default: 0.0 }];

impl Effect for Backlash {
    fn id(&self) -> &'static str {
        "backlash"
    }
    fn params(&self) -> &'static [ParamDef] {
        P
    }
    fn entry(&self) -> Entry {
        Entry::Command
    }
    fn describe(&self) -> &'static str {
        "gear play: dead band on the position error the servo sees"
    }
    fn torque(
        &self,
        _st: &mut EffectState,
        q: f64,
        _qd: f64,
        _q_target: f64,
        io: &mut StepIo,
        _dt: f64,
        p: &[f64],
    ) {
        let h = 0.5 * p[0].max(0.0);
        let e = io.ctrl - q;
        let e2 = if e.abs() <= h { 0.0 } else { e - h * e.signum() };
        io.ctrl = q + e2;
    }
    fn write_back(&self, _p: &[f64]) -> WriteBack {
        WriteBack::TomlOnly
    }
}
