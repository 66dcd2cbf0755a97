use super::*;
use crate::declare_effect;

declare_effect! {
    /// DC-motor servo law with the supply clip, kt and R refitted.
    ///
    /// Motor constants: a servo whose position law drives a DC motor through a PWM H-bridge
    /// (Dynamixel-style firmware), with the motor's torque constant and winding resistance refitted.
    ///
    /// The model's linear position actuator `τ = kp·(ctrl − q) − kd·q̇` is read as that law at the
    /// nominal constants kt₀, R₀: `V = kp·(R₀/kt₀)·(ctrl − q)` is the commanded voltage, `kd` the
    /// back-EMF damping kt₀²/R₀. The effect replaces it by
    /// ```text
    /// τ = (kt/R)·clip(V, −vin, vin) − (kt²/R)·q̇,   kt = kt_scale·kt₀,  R = r_scale·R₀
    /// ```
    /// i.e. `(kt_scale/r_scale)·clip(kp·(ctrl − q), ±τ_stall) − (kt_scale²/r_scale)·kd·q̇` with the
    /// stall torque `τ_stall = vin·kt₀/R₀`. The supply clip needs the recording's metadata `vin`
    /// [V], `motor_kt` [N·m/A] and `motor_r` [Ω] (the BAM importer writes them); without them the
    /// effect is not a candidate (its scales would only be a `gain_error` in disguise). At scales 1
    /// the effect is the model's actuator plus the supply clip.
    ///
    /// ## Simulation
    /// hook torque replacing the linear actuator by the clipped DC-motor law (needs `vin`, `motor_kt`, `motor_r` in the recording)
    ///
    /// ## Signature
    /// servo error `ctrl − q` (as a gain error; ranked by the simulated sensitivity)
    ///
    /// ## Write-back
    /// actuator TOML only
    ///
    /// ## Isaac Lab / mjlab
    /// comment with `kt_scale`, `r_scale` (no Isaac Lab field)
    pub MotorConstants {
        id: "motor_constants",
        entry: Torque,
        params: [ParamDef { name: "kt_scale", unit: "", lo: 0.4, hi: 2.5, default: 1.0 },
            ParamDef { name: "r_scale", unit: "", lo: 0.4, hi: 3.0, default: 1.0 },],
    }
}

/// Stall torque vin·kt₀/R₀ from a recording's metadata (∞ when it does not say).
pub fn stall_torque(meta: &BTreeMap<String, String>) -> f64 {
    let get = |k: &str| meta.get(k).and_then(|v| v.parse::<f64>().ok()).filter(|v| *v > 0.0);
    match (get("vin"), get("motor_kt"), get("motor_r")) {
        (Some(v), Some(kt), Some(r)) => v * kt / r,
        _ => f64::INFINITY,
    }
}

impl Effect for MotorConstants {
    /// The servo law of the joint's position servo: none without one.
    fn acts_on(&self, t: &JointTarget) -> bool {
        t.servoed()
    }
    fn signature(&self, s: &Samples) -> Signature {
        Signature::centred(s.u.clone())
    }
    /// Only with the motor declared (else kt/R scales are a gain error in disguise).
    fn applies(&self, recs: &[Recording]) -> bool {
        !recs.is_empty() && recs.iter().all(|r| stall_torque(&r.meta).is_finite())
    }
    fn start(&self, st: &mut EffectState, meta: &BTreeMap<String, String>, _p: &[f64]) {
        st.s[0] = stall_torque(meta);
    }
    fn torque(&self, cx: HookCtx<'_>) {
        let HookCtx { st, q, qd, io, p, .. } = cx;
        if !io.enabled {
            return;
        }
        let (a, b) = (p[0].max(1e-6), p[1].max(1e-6));
        let pd = io.kp * (io.acting_ctrl() - q);
        let stall = if st.s[0] > 0.0 { st.s[0] } else { f64::INFINITY };
        let law = (a / b) * pd.clamp(-stall, stall) - (a * a / b) * io.kd * qd;
        io.tau += law - (pd - io.kd * qd);
    }
    fn smooth(&self) -> bool {
        true
    }
    fn write_back(&self, _p: &[f64]) -> WriteBack {
        WriteBack::TomlOnly
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn firmware_law_with_supply_clip() {
        let mut meta = BTreeMap::new();
        for (k, v) in [("vin", "7.4"), ("motor_kt", "0.387"), ("motor_r", "4.02")] {
            meta.insert(k.to_string(), v.to_string());
        }
        let e = MotorConstants;
        let mut st = EffectState::default();
        e.start(&mut st, &meta, &[1.0, 1.0]);
        let stall = 7.4 * 0.387 / 4.02;
        assert!((st.s[0] - stall).abs() < 1e-12);
        let (kp, kd) = (0.82, 0.387 * 0.387 / 4.02);
        let run = |err: f64, qd: f64, p: &[f64], st: &mut EffectState| {
            let mut io = StepIo { ctrl: err, kp, kd, enabled: true, ..Default::default() };
            e.torque(HookCtx { st, q: 0.0, qd, q_target: err, io: &mut io, dt: 0.001, p });
            servo_torque(0.0, qd, &io) + io.tau
        };
        // Small error, nominal constants: the linear actuator unchanged.
        assert!((run(0.1, 1.0, &[1.0, 1.0], &mut st) - (kp * 0.1 - kd)).abs() < 1e-12);
        // Large error: clipped at the stall torque, back-EMF still acting.
        assert!((run(3.0, 1.0, &[1.0, 1.0], &mut st) - (stall - kd)).abs() < 1e-12);
        // kt ×2, R ×2: gain unchanged, back-EMF damping doubled.
        assert!((run(0.1, 1.0, &[2.0, 2.0], &mut st) - (kp * 0.1 - 2.0 * kd)).abs() < 1e-12);
    }
}
