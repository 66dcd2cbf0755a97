use super::*;
use crate::declare_effect;

declare_effect! {
    /// Real PD gains = model gains × (kp_scale, kd_scale).
    ///
    /// The servo's real gains differ from the model's (firmware units, supply voltage, current
    /// limits). A hook adds (kp_scale − 1)·kp·(ctrl − q) − (kd_scale − 1)·kd·q̇, so it also scales
    /// gains that come from the recording's kp/kd columns.
    ///
    /// ## Simulation
    /// hook: adds `(s_p−1)·kp·(ctrl−q) − (s_d−1)·kd·q̇` (also scales recorded kp/kd columns)
    ///
    /// ## Signature
    /// servo error `ctrl − q`
    ///
    /// ## Write-back
    /// `<position>` `kp`, `kv` scaled
    ///
    /// ## Isaac Lab / mjlab
    /// comment with the parameters
    pub GainError {
        id: "gain_error",
        entry: Torque,
        params: [
            ParamDef { name: "kp_scale", unit: "", lo: 0.3, hi: 3.0, default: 1.0 },
            ParamDef { name: "kd_scale", unit: "", lo: 0.2, hi: 5.0, default: 1.0 },
        ],
    }
}

impl Effect for GainError {
    fn torque(&self, cx: HookCtx<'_>) {
        let HookCtx { q, qd, io, p, .. } = cx;
        if io.enabled {
            io.tau += (p[0] - 1.0) * io.kp * (io.ctrl - q) - (p[1] - 1.0) * io.kd * qd;
        }
    }
    fn smooth(&self) -> bool {
        true
    }
    fn signature(&self, s: &Samples) -> Signature {
        Signature::centred(s.u.clone())
    }
    fn write_back(&self, p: &[f64]) -> WriteBack {
        WriteBack::Actuator(vec![("kp_scale", p[0]), ("kv_scale", p[1])])
    }
    /// The scaled gain of a compiled position servo written as `<position>`'s `kp` / `kv`.
    fn actuator_attr(
        &self,
        attr: &'static str,
        v: f64,
        act: &ActuatorSite,
    ) -> Result<Vec<(&'static str, String)>, String> {
        let Some(ActuatorKind::Position { kp, kv }) = act.kind else {
            return Err("actuator is not a position servo".into());
        };
        if act.tag != "position" {
            return Err(format!("<{}> is not <position>", act.tag));
        }
        Ok(vec![if attr == "kp_scale" { ("kp", num(kp * v)) } else { ("kv", num(kv * v)) }])
    }
}
