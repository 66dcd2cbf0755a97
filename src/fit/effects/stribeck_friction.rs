use super::external_load_friction::implicit_friction;
use super::*;
use crate::declare_effect;

declare_effect! {
    /// Breakaway (static) friction above the sliding level at low speed.
    ///
    /// Static friction above the sliding (Coulomb) level at low speed: a dry-friction budget
    /// F(q̇) = Fd + (Fs − Fd)·exp(−(q̇/vs)²) against the motion, applied implicitly with exact
    /// stiction as external-load friction applies its own: the torque that would stop the joint
    /// within the (semi-implicit Euler) step, from the DoF's inertia and every other torque of
    /// the step, clamped to ±F(q̇). A sliding joint gets −F(q̇)·sign(q̇), a joint whose driving
    /// torques stay below Fs is held, and friction never reverses the motion within a step —
    /// stable at any step, inertia and friction level, with no smoothing velocity to choose.
    ///
    /// ## Simulation
    /// hook: budget `Fd + (Fs−Fd)·exp(−(q̇/vs)²)`, applied implicitly (stage 2, after every other torque)
    ///
    /// ## Signature
    /// `sign(q̇)·exp(−(q̇/v_s)²)`, v_s = 0.2·rms q̇ (sticking at reversals)
    ///
    /// ## Write-back
    /// TOML
    ///
    /// ## Isaac Lab / mjlab
    /// comment with the parameters
    pub StribeckFriction {
        id: "stribeck_friction",
        entry: Torque,
        params: [
            ParamDef { name: "static", unit: "N·m", lo: 0.0, hi: 5.0, default: 0.0 },
            ParamDef { name: "dynamic", unit: "N·m", lo: 0.0, hi: 5.0, default: 0.0 },
            ParamDef { name: "v_stribeck", unit: "rad/s", lo: 0.01, hi: 2.0, default: 0.1 },
        ],
    }
}

impl Effect for StribeckFriction {
    fn friction(&self) -> bool {
        true
    }
    fn plain_variant(&self) -> Option<&'static dyn Effect> {
        Some(&super::coulomb_friction::CoulombFriction)
    }
    fn initial(&self, _m: &MjModel, _t: &JointTarget) -> Vec<f64> {
        vec![0.1, 0.05, 0.1]
    }
    /// The parameter box, static and dynamic friction widened for a strong drive ([`super::JointTarget::strength`]).
    fn bounds(&self, _m: &MjModel, t: &JointTarget) -> (Vec<f64>, Vec<f64>) {
        super::bounds_for_drive(self, t, &[0, 1])
    }
    /// After every other torque of the step: the friction is applied implicitly
    /// ([`super::external_load_friction`]), so it needs them all.
    fn stage(&self) -> u8 {
        2
    }
    fn torque(&self, cx: HookCtx<'_>) {
        let HookCtx { q, qd, io, dt, p, .. } = cx;
        let (fs, fd, vs) = (p[0].max(0.0), p[1].max(0.0), p[2].max(1e-4));
        let budget = fd + (fs - fd) * (-(qd / vs).powi(2)).exp();
        io.tau += implicit_friction(q, qd, io, dt, budget);
    }
    /// Coulomb friction adds its extra frictionloss to both levels.
    fn absorb(&self, other: &dyn Effect, mine: &[f64], delta: &[f64]) -> Option<Vec<f64>> {
        match (other.id(), mine, delta) {
            ("coulomb_friction", [fs, fd, vs], [c]) => Some(vec![fs + c, fd + c, *vs]),
            _ => None,
        }
    }
    fn nests(&self) -> Option<&'static str> {
        Some("coulomb_friction")
    }
    /// A sharper breakaway at the Coulomb fit's sliding level: static friction 2, 3 and 4 ×
    /// it at v_s 0.05, 0.05 and 0.03 rad/s. From (c, c, 0.1) alone a high, narrow breakaway
    /// (static 0.8, dynamic 0.2, v_s 0.05 N·m on arm3's elbow) ended at (0.357, 0.198, 0.150):
    /// a wider, lower bump fits the same data almost as well (training RMSE 0.80 mrad against
    /// 0.67 at the truth) and the simplex stays on that side of the ridge. (3c, c, 0.05) scores
    /// 0.82 there against 1.12 for (c, c, 0.1).
    fn nested_alternatives(&self, start: &[f64]) -> Vec<Vec<f64>> {
        let [_, c, ..] = start else { return vec![] };
        [(2.0, 0.05), (3.0, 0.05), (4.0, 0.03)].iter().map(|&(r, vs)| vec![r * c, *c, vs]).collect()
    }
    /// The velocity scale where static and sliding levels are equal (as the hook reads them,
    /// clamped at zero): the budget `Fd + (Fs − Fd)·exp(−(q̇/v_s)²)` is `Fd + 0·e`, with `e` in
    /// [0, 1] for every finite q̇ (NaN alike at every v_s), and `Fd` to the last bit.
    fn idle(&self, p: &[f64], i: usize) -> bool {
        matches!(p, [fs, fd, _, ..] if i == 2 && fs.max(0.0) == fd.max(0.0))
    }
    fn signature(&self, s: &Samples) -> Signature {
        let vs = 0.2 * s.qd_rms;
        Signature::centred(s.qd.iter().map(|v| v.signum() * (-(v / vs).powi(2)).exp()).collect())
    }
    fn write_back(&self, _p: &[f64]) -> WriteBack {
        WriteBack::TomlOnly
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One 1 ms step of the Stribeck hook (static 0.06, sliding 0.03 N·m, v_s 0.2 rad/s) on a
    /// DoF of inertia 0.005 kg·m² (the pendulum servo) with `drive` N·m of other torque.
    fn step(qd: f64, drive: f64) -> f64 {
        let mut st = EffectState::default();
        let mut io = StepIo { enabled: false, tau: drive, inertia: 0.005, ..Default::default() };
        let p = [0.06, 0.03, 0.2];
        let cx = HookCtx { st: &mut st, q: 0.0, qd, q_target: 0.0, io: &mut io, dt: 0.001, p: &p };
        StribeckFriction.torque(cx);
        io.tau - drive
    }

    /// The velocity scale is idle exactly where static and sliding levels are equal (as the
    /// hook clamps them): one step's torque is then the same to the last bit at every scale,
    /// moving or at rest; anywhere else, or for another parameter, it is not idle.
    #[test]
    fn the_velocity_scale_is_idle_where_the_breakaway_has_no_height() {
        let tau = |p: [f64; 3], qd: f64| {
            let mut st = EffectState::default();
            let mut io = StepIo { enabled: false, tau: 0.01, inertia: 0.005, ..Default::default() };
            let cx = HookCtx { st: &mut st, q: 0.0, qd, q_target: 0.0, io: &mut io, dt: 0.001, p: &p };
            StribeckFriction.torque(cx);
            io.tau
        };
        for (fs, fd) in [(0.03, 0.03), (0.0, 0.0), (-0.2, 0.0)] {
            assert!(StribeckFriction.idle(&[fs, fd, 0.1], 2), "{fs} {fd}");
            assert!(!StribeckFriction.idle(&[fs, fd, 0.1], 0) && !StribeckFriction.idle(&[fs, fd, 0.1], 1));
            for qd in [0.0, 1e-3, -0.05, 0.3, 40.0] {
                let at = |vs: f64| tau([fs, fd, vs], qd).to_bits();
                assert!([0.01, 0.05, 2.0, 1e-9].iter().all(|&vs| at(vs) == at(0.1)), "{fs} {fd} {qd}");
            }
        }
        // A breakaway of some height: the scale shapes it.
        assert!(!StribeckFriction.idle(&[0.06, 0.03, 0.1], 2));
        assert_ne!(tau([0.06, 0.03, 0.2], 0.1), tau([0.06, 0.03, 0.05], 0.1));
    }

    #[test]
    fn sticks_below_the_static_level_and_slides_at_the_curve() {
        // At rest under 0.05 N·m (below static 0.06): held exactly, no creep.
        assert!((step(0.0, 0.05) + 0.05).abs() < 1e-12);
        // At rest under 0.07 N·m: breaks away against the static level.
        assert!((step(0.0, 0.07) + 0.06).abs() < 1e-12);
        // Sliding at 0.2 rad/s (= v_s): the curve's value, against the motion.
        let want = 0.03 + 0.03 * (-1.0f64).exp();
        assert!((step(0.2, 0.0) + want).abs() < 1e-12, "{}", step(0.2, 0.0));
        // Slowly moving with no drive: stopped within the step, never pushed backwards.
        let f = step(1e-3, 0.0);
        assert!((1e-3 + f * 0.001 / 0.005).abs() < 1e-12, "{f}");
    }
}
