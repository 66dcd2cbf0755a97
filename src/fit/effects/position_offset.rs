//! Position offset: encoder calibration bias. A measurement effect: the sensor reads the true
//! position plus `offset_rad` (the simulation starts at reading − offset and is compared after
//! adding the offset back).
use super::*;

pub struct PositionOffset;

const P: &[ParamDef] =
    &[ParamDef { name: "offset_rad", unit: "rad", lo: -0.3, hi: 0.3, default: 0.0 }];

impl Effect for PositionOffset {
    fn id(&self) -> &'static str {
        "position_offset"
    }
    fn params(&self) -> &'static [ParamDef] {
        P
    }
    fn entry(&self) -> Entry {
        Entry::Measurement
    }
    fn describe(&self) -> &'static str {
        "encoder zero offset (calibration): reading = true position + offset"
    }
    fn measurement_bias(&self, p: &[f64]) -> f64 {
        p[0]
    }
    fn smooth(&self) -> bool {
        true
    }
    fn write_back(&self, _p: &[f64]) -> WriteBack {
        WriteBack::TomlOnly
    }
}
