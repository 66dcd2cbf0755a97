use super::*;
use crate::declare_effect;

declare_effect! {
    /// Dry friction growing with the external (gravity) load, exact stiction.
    ///
    /// External-load friction: dry friction whose level grows with the load the joint carries from
    /// outside the motor — gravity and the other bias forces, taken from the simulator itself
    /// (MuJoCo's `qfrc_bias` on the DoF, so any rig or robot gets its own load, not a hand-written
    /// pendulum formula). Budget `F = mu_ext·|τ_ext|`, `τ_ext = −qfrc_bias`.
    ///
    /// Applied implicitly, so that stiction is exact: the torque that would stop the joint at the
    /// end of this (semi-implicit Euler) step is computed from the DoF's inertia and every other
    /// torque of the step (actuator, hook torques, passive, bias), and the friction is that torque
    /// clamped to ±F. A moving joint gets −F·sign(q̇); a joint whose driving torques are below F is
    /// held; friction never reverses the motion within a step. It runs after every other hook
    /// effect ([`Effect::stage`] 2) so that it sees their torques.
    ///
    /// ## Simulation
    /// hook torque: budget `mu_ext·|qfrc_bias|`, applied implicitly (stage 2, after every other torque)
    ///
    /// ## Signature
    /// `tanh(q̇/ε)` (as Coulomb friction; ranked by the simulated sensitivity)
    ///
    /// ## Write-back
    /// actuator TOML only
    ///
    /// ## Isaac Lab / mjlab
    /// comment with `mu_ext` (no Isaac Lab field)
    pub ExternalLoadFriction {
        id: "external_load_friction",
        entry: Torque,
        params: [ParamDef { name: "mu_ext", unit: "", lo: 0.0, hi: 1.0, default: 0.0 }],
    }
}

/// Friction torque with budget `budget` ≥ 0, applied implicitly (see the module docs).
pub(super) fn implicit_friction(q: f64, qd: f64, io: &StepIo, dt: f64, budget: f64) -> f64 {
    if budget <= 0.0 {
        return 0.0;
    }
    let other = servo_torque(q, qd, io) + io.tau + io.passive - io.bias;
    let stop = -io.inertia * qd / dt.max(1e-9) - other;
    stop.clamp(-budget, budget)
}

impl Effect for ExternalLoadFriction {
    fn friction(&self) -> bool {
        true
    }
    fn plain_variant(&self) -> Option<&'static dyn Effect> {
        Some(&super::coulomb_friction::CoulombFriction)
    }
    fn signature(&self, s: &Samples) -> Signature {
        // No feature of its own: the sign of the velocity (as Coulomb friction); the greedy
        // round re-ranks every candidate by its simulated sensitivity.
        Signature::centred(s.qd.iter().map(|v| (v / (0.02 * s.qd_rms)).tanh()).collect())
    }
    fn stage(&self) -> u8 {
        2
    }
    fn torque(&self, cx: HookCtx<'_>) {
        let HookCtx { q, qd, io, dt, p, .. } = cx;
        let budget = p[0].max(0.0) * io.bias.abs();
        io.tau += implicit_friction(q, qd, io, dt, budget);
    }
    fn write_back(&self, _p: &[f64]) -> WriteBack {
        WriteBack::TomlOnly
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn io(bias: f64) -> StepIo {
        StepIo { enabled: false, bias, inertia: 0.0049, ..Default::default() }
    }

    /// One 1 ms step at `q`, `qd` with friction coefficient `mu`.
    fn step(st: &mut EffectState, q: f64, qd: f64, io: &mut StepIo, mu: f64) {
        ExternalLoadFriction.torque(HookCtx { st, q, qd, q_target: 0.0, io, dt: 0.001, p: &[mu] });
    }

    #[test]
    fn holds_at_rest_and_never_reverses() {
        let mut st = EffectState::default();
        // At rest under a gravity load of 0.2 N·m with mu 1.5 ≥ 1: held exactly.
        let mut x = io(0.2);
        step(&mut st, 0.5, 0.0, &mut x, 1.0);
        assert!((x.tau - 0.2).abs() < 1e-12, "{}", x.tau);
        // Slowly moving: stopped within the step, not pushed backwards.
        let mut x = io(0.2);
        let qd = 1e-4;
        step(&mut st, 0.5, qd, &mut x, 1.0);
        let acc = (x.tau - x.bias) / x.inertia;
        assert!((qd + acc * 0.001).abs() < 1e-12);
        // Fast: the full budget against the motion.
        let mut x = io(0.2);
        step(&mut st, 0.5, 5.0, &mut x, 0.5);
        assert!((x.tau + 0.1).abs() < 1e-12, "{}", x.tau);
        // No load, no friction.
        let mut x = io(0.0);
        step(&mut st, 0.0, 5.0, &mut x, 0.5);
        assert_eq!(x.tau, 0.0);
    }
}
