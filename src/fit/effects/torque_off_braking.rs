use super::*;
use crate::declare_effect;

declare_effect! {
    /// Back-EMF braking while torque is off (0 coasting … 1 shorted bridge).
    ///
    /// Torque-off braking: with torque disabled (recorded `enabled` false) the model's actuator is
    /// off and the joint coasts; a real servo's H-bridge may instead short the motor, whose back-EMF
    /// then brakes the joint. Adds `−beta·kd·q̇` while disabled, `kd` the actuator's velocity gain
    /// (for a DC-motor servo the back-EMF damping kt²/R): beta 0 = open bridge (coasting), 1 =
    /// shorted bridge (full back-EMF braking).
    ///
    /// ## Simulation
    /// hook torque `−beta_off·kd·q̇` while the recording's `enabled` is false
    ///
    /// ## Signature
    /// `tanh(q̇/ε)` (ranked by the simulated sensitivity)
    ///
    /// ## Write-back
    /// actuator TOML only
    ///
    /// ## Isaac Lab / mjlab
    /// comment with `beta_off` (no Isaac Lab field)
    pub TorqueOffBraking {
        id: "torque_off_braking",
        entry: Torque,
        params: [ParamDef { name: "beta_off", unit: "", lo: 0.0, hi: 1.0, default: 0.0 }],
    }
}

impl Effect for TorqueOffBraking {
    /// Brakes with the servo's `kd`: nothing on a joint no position servo drives.
    fn acts_on(&self, t: &JointTarget) -> bool {
        t.servoed()
    }
    fn signature(&self, s: &Samples) -> Signature {
        // No feature of its own: the sign of the velocity (a velocity-opposing torque); the greedy
        // round re-ranks every candidate by its simulated sensitivity.
        Signature::centred(s.qd.iter().map(|v| (v / (0.02 * s.qd_rms)).tanh()).collect())
    }
    fn applies(&self, recs: &[Recording]) -> bool {
        recs.iter().any(|r| {
            r.joints.iter().any(|j| j.enabled.as_ref().is_some_and(|e| e.iter().any(|x| !x)))
        })
    }
    fn torque(&self, cx: HookCtx<'_>) {
        let HookCtx { qd, io, p, .. } = cx;
        if !io.enabled {
            io.tau -= p[0].max(0.0) * io.kd * qd;
        }
    }
    fn smooth(&self) -> bool {
        true
    }
    fn write_back(&self, _p: &[f64]) -> WriteBack {
        WriteBack::TomlOnly
    }
}
