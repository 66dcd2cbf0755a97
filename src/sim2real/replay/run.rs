//! The physics loop of one replay episode (see the parent module's docs for the protocol).

use mujoco_rs::prelude::*;
use mujoco_rs::wrappers::mj_model::traits::ModelType;

use super::{
    ActuatorHook, BLOWUP, BaseMode, Episode, ReplayError, ReplayOptions, Replayer, StepIo,
    StepPeaks,
};
use crate::model::ActuatorKind;
use crate::sim2real::commands::Schedule;
use crate::sim2real::metrics::zoh_at;
use crate::sim2real::recording::Recording;

/// Writes actuator `a`'s kp-related gains (`gainprm[0]`, `biasprm[1]`, `biasprm[2]`) on the model
/// a data simulates: only for an episode that runs on its own copy of the model.
pub(super) type GainSetter<M> = fn(&mut MjData<M>, usize, f64, f64, f64);

/// What one episode's loop reads, prepared by [`Replayer::replay`].
#[derive(Clone, Copy)]
pub(super) struct Run<'a> {
    pub rec: &'a Recording,
    pub opts: &'a ReplayOptions,
    /// Recorded joint → model joint index.
    pub jm: &'a [usize],
    /// Initial velocity of each recorded joint.
    pub qd0: &'a [f64],
    /// (actuator, gainprm[0], biasprm[1], biasprm[2]) of each recorded joint's actuators.
    pub nominal: &'a [Vec<(usize, f64, f64, f64)>],
    /// (kp, kd) factor of each recorded joint's position servo in the simulated model over the
    /// robot's own gains (1 unless a fit scales them): applied to recorded kp/kd columns.
    pub gain_scale: &'a [(f64, f64)],
    /// Recorded joints whose actuators an [`ActuatorHook`] replaces.
    pub replaced: &'a [bool],
    /// Recorded joints driven by torque, replayed as the policy's PD ([`super::pd`]).
    pub pd: &'a [Option<super::pd::PdJoint>],
    pub rate: Option<f64>,
    pub tick0: f64,
    pub schedule: &'a Schedule,
    pub dt: f64,
}

impl Replayer<'_> {
    /// Initialises `d` and steps it through the recording. `set_gains` is `Some` exactly when
    /// the episode runs on its own model copy (recorded gains, torque-enable, replaced actuators).
    pub(super) fn run<M: ModelType>(
        &self,
        mut d: MjData<M>,
        c: &Run<'_>,
        mut hook: Option<&mut dyn ActuatorHook>,
        set_gains: Option<GainSetter<M>>,
    ) -> Result<Episode, ReplayError> {
        let Run {
            rec,
            opts,
            jm,
            qd0,
            nominal,
            gain_scale,
            replaced,
            pd,
            rate,
            tick0,
            schedule,
            dt,
        } = *c;
        let (n, nj) = (rec.t.len(), rec.joints.len());
        let t0 = rec.t[0];
        // With a control rate the physics steps sit on the ticks' grid (tick0 + j·dt), so a
        // command switches at its tick, not up to a step later by an amount that depends on
        // where the first row happens to fall. The simulation starts at the grid point
        // `lead` ≤ one step before the first row, from the first row's state moved back along
        // its velocity (`lead` × q̇: sub-mrad; the first row itself is reproduced at t0).
        let lead = match rate {
            Some(_) if dt > 0.0 => {
                let x = (t0 - tick0) / dt;
                let l = (x - (x + 1e-6).floor()) * dt;
                if l > 1e-9 * dt.max(1.0) { l } else { 0.0 }
            }
            _ => 0.0,
        };
        let ts = t0 - lead;
        {
            let qpos = d.qpos_mut();
            if self.key_qpos.len() == qpos.len() {
                qpos.copy_from_slice(&self.key_qpos);
            }
            for (i, &ji) in jm.iter().enumerate() {
                qpos[self.joints[ji].qposadr] = rec.joints[i].q[0] - lead * qd0[i];
            }
            let qvel = d.qvel_mut();
            for (i, &ji) in jm.iter().enumerate() {
                qvel[self.joints[ji].dofadr] = qd0[i];
            }
            let ctrl = d.ctrl_mut();
            if opts.hold_unlisted_at_key && self.key_ctrl.len() == ctrl.len() {
                ctrl.copy_from_slice(&self.key_ctrl);
            }
            d.set_time(ts);
        }
        // Base pose to pin (Fixed/Free start).
        let base_pin: Option<[f64; 7]> = self.free.map(|(qa, _)| match &rec.base {
            Some(b) => [
                b.pos[0][0],
                b.pos[0][1],
                b.pos[0][2],
                b.quat[0][0],
                b.quat[0][1],
                b.quat[0][2],
                b.quat[0][3],
            ],
            None => {
                let q = d.qpos();
                std::array::from_fn(|k| q[qa + k])
            }
        });
        let base_mode = if rec.base.is_none() && opts.base == BaseMode::Recorded {
            BaseMode::Fixed
        } else {
            opts.base
        };
        let set_base = |d: &mut MjData<M>, t: f64| {
            let (Some((qa, va)), Some(pin)) = (self.free, base_pin) else { return };
            match base_mode {
                BaseMode::Fixed => {
                    d.qpos_mut()[qa..qa + 7].copy_from_slice(&pin);
                    d.qvel_mut()[va..va + 6].fill(0.0);
                }
                BaseMode::Recorded => {
                    let b = rec.base.as_ref().expect("checked");
                    let p0 = base_pose(&rec.t, b, t);
                    let p1 = base_pose(&rec.t, b, t + dt);
                    let p2 = base_pose(&rec.t, b, t + 2.0 * dt);
                    let vel = |a: &[f64; 7], b: &[f64; 7]| -> [f64; 6] {
                        let w = quat_ang_vel(&a[3..7], &b[3..7], dt);
                        [
                            (b[0] - a[0]) / dt,
                            (b[1] - a[1]) / dt,
                            (b[2] - a[2]) / dt,
                            w[0],
                            w[1],
                            w[2],
                        ]
                    };
                    let (v0, v1) = (vel(&p0, &p1), vel(&p1, &p2));
                    d.qpos_mut()[qa..qa + 7].copy_from_slice(&p0);
                    d.qvel_mut()[va..va + 6].copy_from_slice(&v0);
                    // The recorded acceleration as a force on the base's armature (a held base,
                    // `hold_base`): the base then moves as recorded within the step too, and the
                    // limbs feel its acceleration and gravity. Without armature this adds nothing.
                    let arm: [f64; 6] = std::array::from_fn(|k| d.model().dof_armature()[va + k]);
                    let qfrc = d.qfrc_applied_mut();
                    for k in 0..6 {
                        qfrc[va + k] = arm[k] * (v1[k] - v0[k]) / dt;
                    }
                }
                BaseMode::Free => {}
            }
        };
        if base_mode == BaseMode::Free
            && let (Some((qa, _)), Some(pin)) = (self.free, base_pin)
        {
            d.qpos_mut()[qa..qa + 7].copy_from_slice(&pin);
        }
        set_base(&mut d, ts);
        d.forward();

        let mut q_sim = vec![vec![f64::NAN; n]; nj];
        let mut qd_sim = vec![vec![f64::NAN; n]; nj];
        let mut prev_q = vec![0.0; nj];
        let mut prev_qd = vec![0.0; nj];
        let read = |d: &MjData<M>, q: &mut [f64], qd: &mut [f64]| {
            let (qpos, qvel) = (d.qpos(), d.qvel());
            for (i, &ji) in jm.iter().enumerate() {
                q[i] = qpos[self.joints[ji].qposadr];
                qd[i] = qvel[self.joints[ji].dofadr];
            }
        };
        read(&d, &mut prev_q, &mut prev_qd);
        for i in 0..nj {
            q_sim[i][0] = prev_q[i] + lead * prev_qd[i];
            qd_sim[i][0] = prev_qd[i];
        }
        let mut cur_q = prev_q.clone();
        let mut cur_qd = prev_qd.clone();
        let mut next_sample = 1usize;

        // Gains and torque-enable are re-read at the control ticks (every physics step without a
        // control rate); commands at every step from the schedule.
        let mut tick: Option<i64> = None;
        let mut target = vec![0.0; nj];
        let mut kp = vec![0.0; nj];
        let mut kd = vec![0.0; nj];
        let mut enabled = vec![true; nj];
        let mut applied_enabled = vec![true; nj];
        let mut applied_gain: Vec<Option<(f64, f64)>> = vec![None; nj];
        let mut io = vec![StepIo::default(); nj];
        // Per recorded joint: its position actuator with a MuJoCo `delay`, and the history's
        // interpolation order.
        let delayed_pos: Vec<Option<(usize, i32)>> = {
            let m = d.model();
            let (hist, delay) = (m.actuator_history(), m.actuator_delay());
            jm.iter()
                .map(|&ji| {
                    self.joints[ji].acts.iter().find_map(|&(a, kind)| {
                        (matches!(kind, ActuatorKind::Position { .. })
                            && hist[a][0] > 0
                            && delay[a] > 0.0)
                            .then_some((a, hist[a][1]))
                    })
                })
                .collect()
        };
        // Per recorded joint: the joint-torque range MuJoCo clamps its position servo's force to
        // (`forcerange` × gear), when force-limited.
        let servo_range: Vec<Option<(f64, f64)>> = {
            let m = d.model();
            let (fl, fr, gear) =
                (m.actuator_forcelimited(), m.actuator_forcerange(), m.actuator_gear());
            jm.iter()
                .zip(pd)
                .map(|(&ji, pd)| {
                    if let Some(p) = pd {
                        return p.torque_range(m);
                    }
                    self.joints[ji].acts.iter().find_map(|&(a, kind)| {
                        if !matches!(kind, ActuatorKind::Position { .. }) {
                            return None;
                        }
                        let g = if gear[a][0] != 0.0 { gear[a][0] } else { 1.0 };
                        let (x, y) = (g * fr[a][0], g * fr[a][1]);
                        Some(fl[a].then_some((x.min(y), x.max(y))))
                    })?
                })
                .collect()
        };
        let t_end = rec.t[n - 1];
        let nsteps = ((t_end - ts) / dt - 1e-9).ceil().max(0.0) as usize;
        let mut diverged = None;

        // With a control rate, a step takes the command in force at its middle: a tick that
        // falls inside a step (a tick period that is no multiple of the timestep: 40 Hz with
        // 2 ms steps, 30 Hz, a rate fitted from the rows) switches at the nearest step edge, not
        // at the next one — no lag on average, at most half a step either way. A tick on a
        // step edge (the usual case, the steps sitting on the ticks' grid) is unaffected.
        // Without a rate each goal still takes effect at the first step at or after its time.
        let probe = if rate.is_some() { 0.5 * dt } else { 0.0 };
        // The peaks of every physics step ([`StepPeaks`]); no servo peak under RK4, whose inner
        // stages' forces are not left in `actuator_force`.
        let rk4 =
            d.model().opt().integrator == mujoco_rs::mujoco_c::mjtIntegrator::mjINT_RK4 as i32;
        let mut peaks =
            StepPeaks { servo: if rk4 { vec![] } else { vec![0.0; nj] }, speed: vec![0.0; nj] };
        for k in 0..nsteps {
            for (p, qd) in peaks.speed.iter_mut().zip(&cur_qd) {
                *p = p.max(qd.abs());
            }
            let tk = ts + k as f64 * dt;
            for (i, x) in target.iter_mut().enumerate() {
                *x = schedule.at(i, tk + probe);
            }
            let (ti, tt) = match rate {
                Some(r) => {
                    let ti = ((tk + probe - tick0) * r + 1e-6).floor() as i64;
                    (ti, tick0 + ti as f64 / r)
                }
                None => (k as i64, tk),
            };
            if tick != Some(ti) {
                tick = Some(ti);
                for (i, jt) in rec.joints.iter().enumerate() {
                    let nom = match &pd[i] {
                        Some(p) => Some((p.kp, 0.0, p.kd)),
                        None => nominal[i].first().map(|&(_, g, b1, b2)| (g, -b1, -b2)),
                    };
                    let (sp, sd) = gain_scale.get(i).copied().unwrap_or((1.0, 1.0));
                    kp[i] = jt
                        .kp
                        .as_ref()
                        .map_or(nom.map_or(0.0, |x| x.0), |v| sp * zoh_at(&rec.t, v, tt));
                    kd[i] = jt
                        .kd
                        .as_ref()
                        .map_or(nom.map_or(0.0, |x| x.2), |v| sd * zoh_at(&rec.t, v, tt));
                    enabled[i] = jt.enabled.as_ref().is_none_or(|v| {
                        let j = rec.t.partition_point(|&x| x <= tt);
                        v[j.saturating_sub(1)]
                    });
                    let Some(set_gains) = set_gains.filter(|_| !replaced[i]) else { continue };
                    let want_gain = (jt.kp.is_some() || jt.kd.is_some()).then_some((kp[i], kd[i]));
                    if enabled[i] != applied_enabled[i] || want_gain != applied_gain[i] {
                        for &(a, g, b1, b2) in &nominal[i] {
                            let is_pos = self.joints[jm[i]].acts.iter().any(|&(x, kd)| {
                                x == a && matches!(kd, ActuatorKind::Position { .. })
                            });
                            if !enabled[i] {
                                set_gains(&mut d, a, 0.0, 0.0, 0.0);
                            } else if let (Some((p, v)), true) = (want_gain, is_pos) {
                                set_gains(&mut d, a, p, -p, -v);
                            } else {
                                set_gains(&mut d, a, g, b1, b2);
                            }
                        }
                        applied_enabled[i] = enabled[i];
                        applied_gain[i] = want_gain;
                    }
                }
            }
            let (bias, passive, dinv) = (d.qfrc_bias(), d.qfrc_passive(), d.q_ldiag_inv());
            let armature = d.model().dof_armature();
            for i in 0..nj {
                let dof = self.joints[jm[i]].dofadr;
                // A delayed position actuator acts on its history (filled with the first command
                // before the first step, so at step 0 that is the command itself).
                let delayed = delayed_pos[i].map(|(a, interp)| {
                    let mut v = [target[i]];
                    if k > 0 {
                        let _ = d.read_ctrl_into(a, d.time(), interp, &mut v);
                    }
                    v[0]
                });
                io[i] = StepIo {
                    ctrl: target[i],
                    delayed_ctrl: delayed,
                    servo_range: servo_range[i],
                    tau: 0.0,
                    kp: kp[i],
                    kd: kd[i],
                    enabled: enabled[i],
                    bias: bias[dof],
                    passive: passive[dof],
                    inertia: if dinv[dof] > 0.0 { 1.0 / dinv[dof] } else { 0.0 },
                    armature: armature.get(dof).copied().unwrap_or(0.0),
                };
            }
            for i in 0..nj {
                if let Some(h) = hook.as_deref_mut() {
                    h.before_step(tk, i, cur_q[i], cur_qd[i], target[i], &mut io[i]);
                }
            }
            let ctrl = d.ctrl_mut();
            for (i, &ji) in jm.iter().enumerate() {
                if let (Some(p), false) = (&pd[i], replaced[i]) {
                    // The policy's PD on this step's state; MuJoCo clamps the motors' ctrl and force.
                    let tau = io[i].kp * (io[i].ctrl - cur_q[i]) - io[i].kd * cur_qd[i];
                    for (a, u) in p.ctrl(tau) {
                        ctrl[a] = u;
                    }
                    continue;
                }
                for &(a, kind) in &self.joints[ji].acts {
                    if replaced[i] {
                        continue;
                    }
                    // A velocity actuator beside a position servo is its damper (ctrl 0); on a
                    // joint driven by velocity actuators only (a wheel) the command is the
                    // velocity target.
                    ctrl[a] = match kind {
                        ActuatorKind::Velocity { .. } if !self.joints[ji].velocity_driven() => 0.0,
                        _ => io[i].ctrl,
                    };
                }
            }
            let qfrc = d.qfrc_applied_mut();
            for (i, &ji) in jm.iter().enumerate() {
                qfrc[self.joints[ji].dofadr] = io[i].tau;
            }
            if k == 0 {
                hold_delay_history(&mut d, ts, dt);
            }
            set_base(&mut d, tk);
            d.step();
            if !peaks.servo.is_empty() {
                let (force, gear) = (d.actuator_force(), d.model().actuator_gear());
                for (i, &ji) in jm.iter().enumerate() {
                    for &(a, _) in &self.joints[ji].acts {
                        let g =
                            gear.get(a).map_or(1.0, |g| if g[0] != 0.0 { g[0].abs() } else { 1.0 });
                        let f = force.get(a).map_or(f64::INFINITY, |f| (f * g).abs());
                        peaks.servo[i] =
                            peaks.servo[i].max(if f.is_nan() { f64::INFINITY } else { f });
                    }
                }
            }
            if base_mode == BaseMode::Fixed {
                set_base(&mut d, tk + dt);
            }
            prev_q.copy_from_slice(&cur_q);
            prev_qd.copy_from_slice(&cur_qd);
            read(&d, &mut cur_q, &mut cur_qd);
            if let Some(msg) = divergence(&d, &cur_q, &cur_qd, tk + dt) {
                diverged = Some(msg);
                break;
            }
            // Samples in (tk, tk + dt].
            let t1 = ts + (k + 1) as f64 * dt;
            while next_sample < n && (rec.t[next_sample] <= t1 || k + 1 == nsteps) {
                let a = ((rec.t[next_sample] - tk) / dt).clamp(0.0, 1.0);
                for i in 0..nj {
                    q_sim[i][next_sample] = prev_q[i] + a * (cur_q[i] - prev_q[i]);
                    qd_sim[i][next_sample] = prev_qd[i] + a * (cur_qd[i] - prev_qd[i]);
                }
                next_sample += 1;
            }
        }
        Ok(Episode {
            t: rec.t.clone(),
            joints: rec.joints.iter().map(|j| j.name.clone()).collect(),
            q_sim,
            qd_sim,
            diverged,
            peaks,
        })
    }
}

/// Fills the control history of every actuator with a `delay` (MuJoCo's `nsample` buffer) with
/// its first command, as if that command had been in force before the replay starts. A fresh
/// `MjData` holds zeros there: a recording that starts mid-motion would otherwise drive the
/// delayed actuators towards 0 for the first `delay` seconds (on the Asimov legs, 20 ms of
/// target 0 kicked the bent knee, hip and ankle pitch joints into a 4–6 mrad transient against a
/// 1 mrad noise floor on a clean recording). Must run after the first commands are written to
/// `ctrl` and before the first step.
fn hold_delay_history<M: ModelType>(d: &mut MjData<M>, t0: f64, dt: f64) {
    let m = d.model();
    let hist: Vec<[i32; 2]> = m.actuator_history().to_vec();
    let ctrlnum: Vec<i32> = m.actuator_ctrlnum().to_vec();
    let adr: Vec<i32> = m.actuator_ctrladr().to_vec();
    for (a, h) in hist.iter().enumerate() {
        let ns = h[0];
        if ns <= 0 {
            continue;
        }
        let (ns, nc) = (ns as usize, ctrlnum[a].max(0) as usize);
        let c0 = adr[a].max(0) as usize;
        let now: Vec<f64> = d.ctrl()[c0..c0 + nc].to_vec();
        // Strictly increasing times ending one step before t0 (the first step appends t0).
        let times: Vec<f64> = (0..ns).map(|i| t0 - (ns - i) as f64 * dt).collect();
        let values: Vec<f64> = (0..ns).flat_map(|_| now.iter().copied()).collect();
        // Errors only for a missing buffer or wrong lengths, both excluded above.
        let _ = d.init_ctrl_history(a, Some(&times), &values);
    }
}

fn divergence<M: ModelType>(d: &MjData<M>, q: &[f64], qd: &[f64], t: f64) -> Option<String> {
    let dr = d.ffi();
    let names =
        ["", "", "", "bad qpos", "bad qvel", "bad qacc (NaN/Inf/huge acceleration)", "bad ctrl"];
    for (w, name) in names.iter().enumerate().skip(3) {
        if dr.warning[w].number > 0 {
            return Some(format!(
                "MuJoCo warning at t = {t:.4} s: {name} (index {})",
                dr.warning[w].lastinfo
            ));
        }
    }
    if q.iter().chain(qd.iter()).any(|x| !x.is_finite() || x.abs() > BLOWUP) {
        return Some(format!(
            "simulation blew up at t = {t:.4} s (|q| or |q\u{307}| > {BLOWUP} or not finite)"
        ));
    }
    None
}

/// Base pose at time `t`: linear position, normalised-lerp quaternion (sign-aligned).
pub(super) fn base_pose(t: &[f64], b: &crate::sim2real::recording::BaseTrace, tq: f64) -> [f64; 7] {
    let j = t.partition_point(|&x| x <= tq).clamp(1, t.len() - 1);
    let a = ((tq - t[j - 1]) / (t[j] - t[j - 1])).clamp(0.0, 1.0);
    let (p0, p1, q0, mut q1) = (b.pos[j - 1], b.pos[j], b.quat[j - 1], b.quat[j]);
    if q0.iter().zip(&q1).map(|(x, y)| x * y).sum::<f64>() < 0.0 {
        q1 = q1.map(|x| -x);
    }
    let mut q: [f64; 4] = std::array::from_fn(|k| q0[k] + a * (q1[k] - q0[k]));
    let nrm = q.iter().map(|x| x * x).sum::<f64>().sqrt().max(1e-12);
    q.iter_mut().for_each(|x| *x /= nrm);
    [
        p0[0] + a * (p1[0] - p0[0]),
        p0[1] + a * (p1[1] - p0[1]),
        p0[2] + a * (p1[2] - p0[2]),
        q[0],
        q[1],
        q[2],
        q[3],
    ]
}

/// Body-frame angular velocity taking unit quaternion `q0` to `q1` in `dt` (w-x-y-z).
pub(super) fn quat_ang_vel(q0: &[f64], q1: &[f64], dt: f64) -> [f64; 3] {
    // dq = conj(q0) ⊗ q1
    let (w0, x0, y0, z0) = (q0[0], -q0[1], -q0[2], -q0[3]);
    let (w1, x1, y1, z1) = (q1[0], q1[1], q1[2], q1[3]);
    let mut dw = w0 * w1 - x0 * x1 - y0 * y1 - z0 * z1;
    let mut v = [
        w0 * x1 + x0 * w1 + y0 * z1 - z0 * y1,
        w0 * y1 - x0 * z1 + y0 * w1 + z0 * x1,
        w0 * z1 + x0 * y1 - y0 * x1 + z0 * w1,
    ];
    if dw < 0.0 {
        dw = -dw;
        v = v.map(|x| -x);
    }
    let s = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    if s < 1e-15 {
        return [0.0; 3];
    }
    let angle = 2.0 * s.atan2(dw);
    v.map(|x| x / s * angle / dt)
}
