use super::*;
use crate::declare_effect;

declare_effect! {
    /// Gear play: the servo drives a rotor that pushes the link through a dead band.
    ///
    /// The servo's encoder sits on the rotor (inertia: the joint's armature), which reaches the
    /// link through a play of total width `backlash_rad`. While the rotor rests on a flank the
    /// two move as one: the servo acts on the link with its set-point moved by half the play
    /// (its `kp` and `kd` terms both act) and the armature is felt. Inside the play the link
    /// feels no servo force at all (neither `kp` nor `kd`): the rotor travels across the gap on
    /// its own, driven by the servo (`armature · q̈ₘ = kp (u − qₘ) − kd q̇ₘ`, clamped to the force
    /// range), and takes the link along inelastically when it reaches the other flank. It leaves
    /// a flank when the torque the rotor passes on would pull. The rotor starts on the flank the
    /// load presses it to. Without an armature the rotor is taken to sit at the command (a dead
    /// band on the position error, no force inside it). Known limit: inside the play the
    /// armature stays on the joint's inertia (MuJoCo's mass matrix is not changed per step).
    ///
    /// ## Simulation
    /// hook: rotor state behind a play of total width b; no servo force inside it
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

/// The servo's torque on a rotor at (qm, qmd) for set-point `u`, clamped to its force range.
fn servo_on(u: f64, qm: f64, qmd: f64, io: &StepIo) -> f64 {
    if !io.enabled {
        return 0.0;
    }
    let t = io.kp * (u - qm) - io.kd * qmd;
    match io.servo_range {
        Some((lo, hi)) if lo <= hi => t.clamp(lo, hi),
        _ => t,
    }
}

impl Effect for Backlash {
    /// The play between the servo and its link: none on a joint no position servo drives.
    fn acts_on(&self, t: &JointTarget) -> bool {
        t.servoed()
    }
    fn holds_start(&self) -> bool {
        true
    }
    fn torque(&self, cx: HookCtx<'_>) {
        let HookCtx { st, q, qd, io, dt, p, .. } = cx;
        let h = 0.5 * p[0].max(0.0);
        if h <= 0.0 {
            return; // no play: no effect, to the last bit
        }
        let u = io.ctrl;
        // The set-point that makes the joint's servo apply no force: kp(ctrl − q) − kd·q̇ = 0.
        let free = if io.kp > 0.0 { q + io.kd * qd / io.kp } else { q };
        let j = io.armature;
        if j <= 0.0 || dt <= 0.0 {
            let e = u - q;
            io.ctrl = if e.abs() > h { u - h * e.signum() } else { free };
            return;
        }
        // s = [rotor angle, rotor velocity, flank (−1, 0 free, +1), joint velocity last step]
        if !st.started {
            st.started = true;
            let side = if io.bias != 0.0 {
                io.bias.signum()
            } else if (u - q).abs() > h {
                (u - q).signum()
            } else {
                0.0
            };
            st.s = [q + side * h, qd, side, qd];
        }
        let acc = (qd - st.s[3]) / dt;
        st.s[3] = qd;
        let mut side = st.s[2];
        if side != 0.0 {
            // On a flank: the rotor moves with the link; it leaves when it would pull.
            let ts = servo_on(u - side * h, q, qd, io);
            if side * (ts - j * acc) < 0.0 {
                side = 0.0;
                st.s[0] = q + st.s[2] * h;
                st.s[1] = qd;
            }
        }
        if side == 0.0 {
            let (qm, qmd) = (st.s[0], st.s[1]);
            let tm = servo_on(u, qm, qmd, io);
            let qmd = qmd + dt * tm / j;
            let qm = qm + dt * qmd;
            // Against where the link will be, moving on at its last acceleration: a rotor just
            // left on a flank by a link that runs ahead of it does not hit it again.
            let vl = qd + dt * acc;
            let d = qm - (q + dt * vl);
            if d.abs() >= h && (qmd - vl) * d > 0.0 {
                // Reaches a flank: an inelastic impact passes the rotor's momentum on.
                side = d.signum();
                io.tau += j * (qmd - vl) / dt;
                // The next step's acceleration estimate leaves the impact's jump out.
                if io.inertia > 0.0 {
                    st.s[3] = qd + j * (qmd - vl) / io.inertia;
                }
            } else {
                st.s[0] = qm;
                st.s[1] = qmd;
            }
        }
        st.s[2] = side;
        if side != 0.0 {
            st.s[0] = q + side * h;
            st.s[1] = qd;
            io.ctrl = u - side * h;
        } else {
            io.ctrl = free;
        }
    }
    fn signature(&self, s: &Samples) -> Signature {
        Signature::centred(s.u.iter().map(|u| (u / (0.1 * s.u_rms)).tanh()).collect())
    }
    fn write_back(&self, _p: &[f64]) -> WriteBack {
        WriteBack::TomlOnly
    }
}
