use super::*;
use crate::declare_effect;

declare_effect! {
    /// Gear play: a dead band on the position error the servo sees.
    ///
    /// The servo's position error has a dead band of total width `backlash_rad` (±half of it
    /// produces no torque): a command effect, rewriting the set-point to q + deadzone(ctrl − q).
    ///
    /// ## Simulation
    /// hook: dead band of total width b on the servo's position error
    ///
    /// ## Signature
    /// sign of the servo error, `tanh(u/(0.1·rms u))`
    ///
    /// ## Write-back
    /// TOML
    ///
    /// ## Isaac Lab / mjlab
    /// comment with the parameters
    pub Backlash {
        id: "backlash",
        entry: Command,
        params: [ParamDef { name: "backlash_rad", unit: "rad", lo: 0.0, hi: 0.2, default: 0.0 }],
    }
}

impl Effect for Backlash {
    fn holds_start(&self) -> bool {
        true
    }
    fn torque(&self, cx: HookCtx<'_>) {
        let HookCtx { q, io, p, .. } = cx;
        let h = 0.5 * p[0].max(0.0);
        let e = io.ctrl - q;
        let e2 = if e.abs() <= h { 0.0 } else { e - h * e.signum() };
        io.ctrl = q + e2;
    }
    fn signature(&self, s: &Samples) -> Signature {
        Signature::centred(s.u.iter().map(|u| (u / (0.1 * s.u_rms)).tanh()).collect())
    }
    fn write_back(&self, _p: &[f64]) -> WriteBack {
        WriteBack::TomlOnly
    }
}
