use super::*;
use crate::declare_effect;
use crate::fit::diagnose::mean;

declare_effect! {
    /// Encoder zero offset (calibration): reading = true position + offset.
    ///
    /// A measurement effect: the sensor reads the true position plus `offset_rad`; the
    /// simulation starts at reading − offset and is compared after adding the offset back.
    ///
    /// ## Simulation
    /// measurement: sensor = true + offset (the replay starts at reading − offset)
    ///
    /// ## Signature
    /// constant
    ///
    /// ## Evidence
    /// `bias_rad` (mean residual)
    ///
    /// ## Write-back
    /// TOML (calibration)
    ///
    /// ## Isaac Lab / mjlab
    /// comment with the parameters
    pub PositionOffset {
        id: "position_offset",
        entry: Measurement,
        params: [ParamDef { name: "offset_rad", unit: "rad", lo: -0.3, hi: 0.3, default: 0.0 }],
    }
}

/// Evidence: the mean residual [rad].
const BIAS: &str = "bias_rad";

impl Effect for PositionOffset {
    fn measurement_bias(&self, p: &[f64]) -> f64 {
        p[0]
    }
    fn smooth(&self) -> bool {
        true
    }
    /// At its start no offset.
    fn neutral_start(&self) -> bool {
        true
    }
    fn signature(&self, s: &Samples) -> Signature {
        Signature {
            feature: vec![1.0; s.r.len()],
            raw: true,
            evidence: vec![(BIAS, mean(&s.r))],
            implied: None,
        }
    }
    fn shown_evidence(&self) -> &'static [&'static str] {
        &[BIAS]
    }
    fn write_back(&self, _p: &[f64]) -> WriteBack {
        WriteBack::TomlOnly
    }
}
