use super::*;
use crate::declare_effect;

declare_effect! {
    /// Dry friction growing with the motor torque: base + load_coeff·|τ_motor|.
    ///
    /// A dry-friction budget that grows with the transmitted torque (gear-mesh normal force),
    /// applied as −tanh(q̇/ε)·budget with ε = 0.02 rad/s.
    ///
    /// ## Simulation
    /// hook: `−tanh(q̇/0.02)·(F0 + k·|τ_motor|)`
    ///
    /// ## Signature
    /// `tanh(q̇/ε)·|τ|`, ε = 0.02·rms q̇
    ///
    /// ## Write-back
    /// TOML
    ///
    /// ## Isaac Lab / mjlab
    /// comment with the parameters
    pub LoadDependentFriction {
        id: "load_dependent_friction",
        entry: Torque,
        params: [
            ParamDef { name: "frictionloss", unit: "N·m", lo: 0.0, hi: 2.0, default: 0.0 },
            ParamDef { name: "load_coeff", unit: "", lo: 0.0, hi: 0.5, default: 0.0 },
        ],
    }
}

/// Smoothing velocity of the sign [rad/s] (the synth's `FRICTION_EPS`).
pub const EPS: f64 = 0.02;

impl Effect for LoadDependentFriction {
    fn friction(&self) -> bool {
        true
    }
    fn plain_variant(&self) -> Option<&'static dyn Effect> {
        Some(&super::coulomb_friction::CoulombFriction)
    }
    fn initial(&self, _m: &MjModel, _t: &JointTarget) -> Vec<f64> {
        vec![0.02, 0.02]
    }
    /// The parameter box, the frictionloss widened for a strong drive ([`super::JointTarget::strength`]).
    fn bounds(&self, _m: &MjModel, t: &JointTarget) -> (Vec<f64>, Vec<f64>) {
        super::bounds_for_drive(self, t, &[0])
    }
    fn torque(&self, cx: HookCtx<'_>) {
        let HookCtx { q, qd, io, p, .. } = cx;
        let budget = p[0].max(0.0) + p[1].max(0.0) * servo_torque(q, qd, io).abs();
        io.tau -= smooth_sign(qd, EPS) * budget;
    }
    /// Coulomb friction adds its extra frictionloss to the base.
    fn absorb(&self, other: &dyn Effect, mine: &[f64], delta: &[f64]) -> Option<Vec<f64>> {
        match (other.id(), mine, delta) {
            ("coulomb_friction", [f0, k], [c]) => Some(vec![f0 + c, *k]),
            _ => None,
        }
    }
    fn signature(&self, s: &Samples) -> Signature {
        Signature::centred(
            s.qd.iter()
                .zip(&s.tau)
                .map(|(v, t)| (v / (0.02 * s.qd_rms)).tanh() * t.abs())
                .collect(),
        )
    }
    fn write_back(&self, _p: &[f64]) -> WriteBack {
        WriteBack::TomlOnly
    }
}
