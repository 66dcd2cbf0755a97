//! Position-controlled trajectory replay (seed study §4.4): drive a MuJoCo model with a
//! recording's commands and sample the simulated joints at the recording's own timestamps.
//!
//! Protocol, per episode:
//! 1. Initialise: model joints take the keyframe `qpos` (or `qpos0`), recorded joints the first
//!    recorded `q`, their velocity the first recorded `qd` (or the derivative of `q`).
//! 2. Commands: [`crate::sim2real::commands`] reconstructs the command in force at every moment
//!    from `q_cmd` (or `q` when the recording has no command): with a control rate (`control_hz`
//!    option, else the recording's `control_rate_hz`) one command per control tick at
//!    `control_t0_s + k/rate` (`t[0]` when absent), held over the tick; without one, each goal
//!    held from its own timestamp. Every physics step applies the command in force at the step's
//!    start to every recorded joint's position actuators. The recorded `kp`/`kd`
//!    columns (N·m/rad, N·m·s/rad) set the actuator's `gainprm[0] = kp`, `biasprm[1] = −kp`,
//!    `biasprm[2] = −kd` at the same ticks; `enabled = false` zeroes the actuator's gain and bias
//!    (torque off, e.g. free fall). Model joints without recording hold their keyframe `ctrl`.
//! 3. Physics steps at the model's timestep; an [`ActuatorHook`] may rewrite each recorded
//!    joint's `ctrl` and add a joint torque (`qfrc_applied`) before every step.
//! 4. Samples: the simulated `q`, `q̇` at each recording timestamp are linearly interpolated
//!    between the two physics states around it (exact at `t[0]`).
//!
//! The model is never mutated: an episode that changes gains (kp/kd/enabled columns, or a hook
//! that replaces actuators) runs on its own copy of the model.

use std::path::PathBuf;

use mujoco_rs::prelude::*;
use rayon::prelude::*;

use crate::model::{ActuatorKind, JointType, Robot, mj};
use crate::sim2real::commands::{CommandTiming, reconstruct};
use crate::sim2real::metrics::zoh_at;
use crate::sim2real::recording::{Recording, RecordingError, derivative};

/// What the floating base does during replay.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BaseMode {
    /// Pinned at the first recorded base pose (else the keyframe pose) every physics step.
    #[default]
    Fixed,
    /// Driven kinematically from the recording's `base.*` columns (error when absent).
    Recorded,
    /// Free: initialised like `Fixed`, then left to the physics.
    Free,
}

#[derive(Debug, Clone)]
pub struct ReplayOptions {
    /// Control rate override [Hz]; else the recording's `control_rate_hz`; else none (each goal
    /// held from its own timestamp).
    pub control_hz: Option<f64>,
    /// What a row's `q_cmd` means; else the recording's `command_timing` key; else in force.
    pub command_timing: Option<CommandTiming>,
    pub base: BaseMode,
    /// Model joints absent from the recording: `true` → their actuators get the keyframe ctrl
    /// (hold the key pose); `false` → ctrl 0.
    pub hold_unlisted_at_key: bool,
    /// Control ticks without a row are interpolated across ramps (and, without a control rate,
    /// dropped rows' commands are interpolated, [`crate::sim2real::metrics::fill_dropped_rows`]);
    /// `false` holds the command before the gap.
    pub fill_dropped_commands: bool,
}

impl Default for ReplayOptions {
    fn default() -> Self {
        ReplayOptions {
            control_hz: None,
            command_timing: None,
            base: BaseMode::Fixed,
            hold_unlisted_at_key: true,
            fill_dropped_commands: true,
        }
    }
}

/// One replayed episode, sampled at the recording's timestamps.
#[derive(Debug, Clone)]
pub struct Episode {
    pub t: Vec<f64>,
    /// Recorded joints, in the recording's order.
    pub joints: Vec<String>,
    pub q_sim: Vec<Vec<f64>>,
    pub qd_sim: Vec<Vec<f64>>,
    /// Why the simulation stopped early (samples after it are NaN); `None` when it completed.
    pub diverged: Option<String>,
}

#[derive(Debug, Clone, thiserror::Error)]
pub enum ReplayError {
    #[error("{0}")]
    Recording(#[from] RecordingError),
    #[error("{file}: {message}")]
    Setup { file: PathBuf, message: String },
}

/// Per-step input/output of an [`ActuatorHook`] for one recorded joint. On entry the fields hold
/// what the plain replay would do; the hook may change `ctrl` and `tau`.
#[derive(Debug, Clone, Copy, Default)]
pub struct StepIo {
    /// Value written to the ctrl of every position actuator of the joint (rad).
    pub ctrl: f64,
    /// Generalised force added on the joint's DoF (written to `qfrc_applied`) [N·m or N].
    pub tau: f64,
    /// Recorded (or model) gains in force at this step.
    pub kp: f64,
    pub kd: f64,
    /// Recorded torque-enable state in force at this step.
    pub enabled: bool,
}

/// Per-physics-step actuator override, for effects MuJoCo cannot express (Stribeck friction,
/// backlash, speed–torque saturation, fractional delays, custom servo laws).
pub trait ActuatorHook {
    /// Called once per episode before the first step: the recorded joints (indices used by
    /// `before_step`) and the physics timestep.
    fn reset(&mut self, joints: &[String], dt: f64);
    /// `true` when the hook computes the whole joint torque itself: the joint's MuJoCo
    /// actuators are then switched off (gain and bias 0) for the episode and only `tau` acts.
    fn replaces_actuator(&self, _joint_idx: usize) -> bool {
        false
    }
    /// Called every physics step before `mj_step` for every recorded joint. `t` is the
    /// simulation time (recording clock), `q_target` the held command.
    fn before_step(
        &mut self,
        t: f64,
        joint_idx: usize,
        q: f64,
        qd: f64,
        q_target: f64,
        out: &mut StepIo,
    );
}

#[derive(Debug, Clone)]
struct JointInfo {
    scalar: bool,
    qposadr: usize,
    dofadr: usize,
    /// (actuator id, kind) of the actuators that reach this joint.
    acts: Vec<(usize, ActuatorKind)>,
}

/// Joint/actuator mapping of a model, built once and reused for any number of replays.
#[derive(Clone)]
pub struct Replayer<'m> {
    model: &'m MjModel,
    joints: Vec<JointInfo>,
    names: Vec<String>,
    key_qpos: Vec<f64>,
    key_ctrl: Vec<f64>,
    /// (qposadr, dofadr) of the first free joint.
    free: Option<(usize, usize)>,
}

const NGAIN: usize = 10;
const NBIAS: usize = 10;
/// |q| beyond this [rad or m] counts as a blow-up.
const BLOWUP: f64 = 1e3;

impl<'m> Replayer<'m> {
    /// Mapping for `robot.mj`.
    pub fn new(robot: &'m Robot) -> Self {
        Self::with_model(robot, &robot.mj)
    }

    /// Mapping from `robot`, simulating `model` instead: a copy of `robot.mj` with changed
    /// numeric parameters (what a fit engine varies). Its sizes must equal `robot.mj`'s.
    pub fn with_model(robot: &Robot, model: &'m MjModel) -> Self {
        let joints = robot
            .joints
            .iter()
            .map(|j| JointInfo {
                scalar: j.is_scalar(),
                qposadr: j.qposadr,
                dofadr: j.dofadr,
                acts: robot.actuators_on_joint(j.id).iter().map(|a| (a.id, a.kind)).collect(),
            })
            .collect();
        let free =
            robot.joints.iter().find(|j| j.jtype == JointType::Free).map(|j| (j.qposadr, j.dofadr));
        Replayer {
            model,
            joints,
            names: robot.joints.iter().map(|j| j.name.clone()).collect(),
            key_qpos: robot.key.qpos.clone(),
            key_ctrl: robot.key.ctrl.clone(),
            free,
        }
    }

    pub fn joint_names(&self) -> &[String] {
        &self.names
    }

    /// Replays one recording; see the module docs.
    pub fn replay(
        &self,
        rec: &Recording,
        opts: &ReplayOptions,
        mut hook: Option<&mut dyn ActuatorHook>,
    ) -> Result<Episode, ReplayError> {
        let setup = |message: String| ReplayError::Setup { file: rec.source.clone(), message };
        let n = rec.t.len();
        if n < 2 {
            return Err(setup(format!("need at least 2 samples, found {n}")));
        }
        rec.validate_joint_names(&self.names)?;
        let rate = opts.control_hz.or(rec.control_rate_hz);
        let timing = opts.command_timing.or_else(|| rec.command_timing()).unwrap_or_default();
        if opts.base == BaseMode::Recorded && rec.base.is_none() && self.free.is_some() {
            return Err(setup(
                "--base recorded needs base.x … base.qz columns; the recording has none".into(),
            ));
        }

        // Recorded joint → model joint, command and velocity traces.
        let nj = rec.joints.len();
        let mut jm = Vec::with_capacity(nj);
        let mut qd0 = Vec::with_capacity(nj);
        for jt in &rec.joints {
            let ji = self.names.iter().position(|s| *s == jt.name).expect("validated");
            let info = &self.joints[ji];
            if !info.scalar {
                return Err(setup(format!(
                    "joint '{}' is not a hinge or slide joint; only scalar joints can be replayed",
                    jt.name
                )));
            }
            jm.push(ji);
            qd0.push(match &jt.qd {
                Some(v) => v[0],
                None => derivative(&rec.t[..n.min(3)], &jt.q[..n.min(3)])[0],
            });
        }

        let cmds: Vec<&[f64]> =
            rec.joints.iter().map(|jt| jt.q_cmd.as_deref().unwrap_or(&jt.q)).collect();
        let tick0 = rec.control_t0_s.unwrap_or(rec.t[0]);
        let schedule = reconstruct(&rec.t, &cmds, rate, tick0, timing, opts.fill_dropped_commands)
            .map_err(|e| setup(e.to_string()))?;
        if let Some(h) = hook.as_deref_mut() {
            let names: Vec<String> = rec.joints.iter().map(|j| j.name.clone()).collect();
            h.reset(&names, mj::raw(self.model).opt.timestep);
        }
        let replaced: Vec<bool> =
            (0..nj).map(|i| hook.as_deref().is_some_and(|h| h.replaces_actuator(i))).collect();
        for (i, &ji) in jm.iter().enumerate() {
            for &(aid, kind) in &self.joints[ji].acts {
                if !replaced[i]
                    && !matches!(
                        kind,
                        ActuatorKind::Position { .. } | ActuatorKind::Velocity { .. }
                    )
                {
                    return Err(setup(format!(
                        "actuator {aid} on joint '{}' is not a position (or velocity) actuator; replaying torque \
                         actuators needs an ActuatorHook that replaces it with a servo law",
                        rec.joints[i].name
                    )));
                }
            }
        }
        let gain_cols =
            rec.joints.iter().any(|j| j.kp.is_some() || j.kd.is_some() || j.enabled.is_some());
        let owned: Option<MjModel> =
            (gain_cols || replaced.iter().any(|&r| r)).then(|| self.model.clone());
        let m: &MjModel = owned.as_ref().unwrap_or(self.model);
        let r = mj::raw(m);
        let (nq, nv, nu) = (r.nq as usize, r.nv as usize, r.nu as usize);
        let dt = r.opt.timestep;
        if !(dt > 0.0) {
            return Err(setup(format!("model timestep {dt} is not positive")));
        }
        // Nominal gains of every position actuator of the recorded joints.
        let gp = r.actuator_gainprm;
        let bp = r.actuator_biasprm;
        let nominal: Vec<Vec<(usize, f64, f64, f64)>> = jm
            .iter()
            .map(|&ji| {
                self.joints[ji]
                    .acts
                    .iter()
                    .map(|&(a, _)| {
                        let g = mj::slice(gp, NGAIN * nu);
                        let b = mj::slice(bp, NBIAS * nu);
                        (a, g[NGAIN * a], b[NBIAS * a + 1], b[NBIAS * a + 2])
                    })
                    .collect()
            })
            .collect();
        // Writes gain/bias of actuator `a` on the owned copy (never on the shared model).
        let set_gains = |a: usize, g0: f64, b1: f64, b2: f64| {
            debug_assert!(owned.is_some());
            // SAFETY: `owned` is this episode's private copy; gainprm/biasprm have 10·nu entries
            // and no slice into them is alive across this write.
            unsafe {
                *gp.add(NGAIN * a) = g0;
                *bp.add(NBIAS * a + 1) = b1;
                *bp.add(NBIAS * a + 2) = b2;
            }
        };
        for (i, acts) in nominal.iter().enumerate() {
            if replaced[i] {
                for &(a, ..) in acts {
                    set_gains(a, 0.0, 0.0, 0.0);
                }
            }
        }

        let mut d = MjData::new(m);
        let t0 = rec.t[0];
        {
            let dr = mj::data_raw_mut(&mut d);
            let qpos = mj::slice_mut(dr.qpos, nq);
            if self.key_qpos.len() == nq {
                qpos.copy_from_slice(&self.key_qpos);
            }
            for (i, &ji) in jm.iter().enumerate() {
                qpos[self.joints[ji].qposadr] = rec.joints[i].q[0];
            }
            let qvel = mj::slice_mut(dr.qvel, nv);
            for (i, &ji) in jm.iter().enumerate() {
                qvel[self.joints[ji].dofadr] = qd0[i];
            }
            let ctrl = mj::slice_mut(dr.ctrl, nu);
            if opts.hold_unlisted_at_key && self.key_ctrl.len() == nu {
                ctrl.copy_from_slice(&self.key_ctrl);
            }
            dr.time = t0;
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
                let q = mj::slice(mj::data_raw(&d).qpos, nq);
                std::array::from_fn(|k| q[qa + k])
            }
        });
        let base_mode = if rec.base.is_none() && opts.base == BaseMode::Recorded {
            BaseMode::Fixed
        } else {
            opts.base
        };
        let set_base = |d: &mut MjData<&MjModel>, t: f64| {
            let (Some((qa, va)), Some(pin)) = (self.free, base_pin) else { return };
            let dr = mj::data_raw_mut(d);
            let qpos = mj::slice_mut(dr.qpos, nq);
            let qvel = mj::slice_mut(dr.qvel, nv);
            match base_mode {
                BaseMode::Fixed => {
                    qpos[qa..qa + 7].copy_from_slice(&pin);
                    qvel[va..va + 6].fill(0.0);
                }
                BaseMode::Recorded => {
                    let b = rec.base.as_ref().expect("checked");
                    let p0 = base_pose(&rec.t, b, t);
                    let p1 = base_pose(&rec.t, b, t + dt);
                    qpos[qa..qa + 7].copy_from_slice(&p0);
                    for k in 0..3 {
                        qvel[va + k] = (p1[k] - p0[k]) / dt;
                    }
                    let w = quat_ang_vel(&p0[3..7], &p1[3..7], dt);
                    qvel[va + 3..va + 6].copy_from_slice(&w);
                }
                BaseMode::Free => {}
            }
        };
        if base_mode == BaseMode::Free {
            if let (Some((qa, _)), Some(pin)) = (self.free, base_pin) {
                let dr = mj::data_raw_mut(&mut d);
                mj::slice_mut(dr.qpos, nq)[qa..qa + 7].copy_from_slice(&pin);
            }
        }
        set_base(&mut d, t0);
        d.forward();

        let mut q_sim = vec![vec![f64::NAN; n]; nj];
        let mut qd_sim = vec![vec![f64::NAN; n]; nj];
        let mut prev_q = vec![0.0; nj];
        let mut prev_qd = vec![0.0; nj];
        let read = |d: &MjData<&MjModel>, q: &mut [f64], qd: &mut [f64]| {
            let dr = mj::data_raw(d);
            let qpos = mj::slice(dr.qpos, nq);
            let qvel = mj::slice(dr.qvel, nv);
            for (i, &ji) in jm.iter().enumerate() {
                q[i] = qpos[self.joints[ji].qposadr];
                qd[i] = qvel[self.joints[ji].dofadr];
            }
        };
        read(&d, &mut prev_q, &mut prev_qd);
        for i in 0..nj {
            q_sim[i][0] = prev_q[i];
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
        let t_end = rec.t[n - 1];
        let nsteps = ((t_end - t0) / dt - 1e-9).ceil().max(0.0) as usize;
        let mut diverged = None;

        for k in 0..nsteps {
            let tk = t0 + k as f64 * dt;
            for (i, x) in target.iter_mut().enumerate() {
                *x = schedule.at(i, tk);
            }
            let (ti, tt) = match rate {
                Some(r) => {
                    let ti = ((tk - tick0) * r + 1e-6).floor() as i64;
                    (ti, tick0 + ti as f64 / r)
                }
                None => (k as i64, tk),
            };
            if tick != Some(ti) {
                tick = Some(ti);
                for (i, jt) in rec.joints.iter().enumerate() {
                    let nom = nominal[i].first().map(|&(_, g, b1, b2)| (g, -b1, -b2));
                    kp[i] =
                        jt.kp.as_ref().map_or(nom.map_or(0.0, |x| x.0), |v| zoh_at(&rec.t, v, tt));
                    kd[i] =
                        jt.kd.as_ref().map_or(nom.map_or(0.0, |x| x.2), |v| zoh_at(&rec.t, v, tt));
                    enabled[i] = jt.enabled.as_ref().is_none_or(|v| {
                        let j = rec.t.partition_point(|&x| x <= tt);
                        v[j.saturating_sub(1)]
                    });
                    if replaced[i] || owned.is_none() {
                        continue;
                    }
                    let want_gain = (jt.kp.is_some() || jt.kd.is_some()).then_some((kp[i], kd[i]));
                    if enabled[i] != applied_enabled[i] || want_gain != applied_gain[i] {
                        for &(a, g, b1, b2) in &nominal[i] {
                            let is_pos = self.joints[jm[i]].acts.iter().any(|&(x, kd)| {
                                x == a && matches!(kd, ActuatorKind::Position { .. })
                            });
                            if !enabled[i] {
                                set_gains(a, 0.0, 0.0, 0.0);
                            } else if let (Some((p, v)), true) = (want_gain, is_pos) {
                                set_gains(a, p, -p, -v);
                            } else {
                                set_gains(a, g, b1, b2);
                            }
                        }
                        applied_enabled[i] = enabled[i];
                        applied_gain[i] = want_gain;
                    }
                }
            }
            for i in 0..nj {
                io[i] =
                    StepIo { ctrl: target[i], tau: 0.0, kp: kp[i], kd: kd[i], enabled: enabled[i] };
                if let Some(h) = hook.as_deref_mut() {
                    h.before_step(tk, i, cur_q[i], cur_qd[i], target[i], &mut io[i]);
                }
            }
            {
                let dr = mj::data_raw_mut(&mut d);
                let ctrl = mj::slice_mut(dr.ctrl, nu);
                let qfrc = mj::slice_mut(dr.qfrc_applied, nv);
                for (i, &ji) in jm.iter().enumerate() {
                    let info = &self.joints[ji];
                    for &(a, kind) in &info.acts {
                        if replaced[i] {
                            continue;
                        }
                        ctrl[a] = match kind {
                            ActuatorKind::Velocity { .. } => 0.0,
                            _ => io[i].ctrl,
                        };
                    }
                    qfrc[info.dofadr] = io[i].tau;
                }
            }
            if k == 0 {
                hold_delay_history(&mut d, t0, dt);
            }
            set_base(&mut d, tk);
            d.step();
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
            let t1 = t0 + (k + 1) as f64 * dt;
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
        })
    }
}

fn divergence(d: &MjData<&MjModel>, q: &[f64], qd: &[f64], t: f64) -> Option<String> {
    let dr = mj::data_raw(d);
    let names =
        ["", "", "", "bad qpos", "bad qvel", "bad qacc (NaN/Inf/huge acceleration)", "bad ctrl"];
    for w in 3..=6 {
        if dr.warning[w].number > 0 {
            return Some(format!(
                "MuJoCo warning at t = {t:.4} s: {} (index {})",
                names[w], dr.warning[w].lastinfo
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
fn base_pose(t: &[f64], b: &crate::sim2real::recording::BaseTrace, tq: f64) -> [f64; 7] {
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
fn quat_ang_vel(q0: &[f64], q1: &[f64], dt: f64) -> [f64; 3] {
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

/// [`Replayer::replay`] on `robot.mj`.
pub fn replay(
    robot: &Robot,
    rec: &Recording,
    opts: &ReplayOptions,
    hook: Option<&mut dyn ActuatorHook>,
) -> Result<Episode, ReplayError> {
    Replayer::new(robot).replay(rec, opts, hook)
}

/// Replays many recordings in parallel (rayon); results in input order, each deterministic.
/// `progress` is called with the number of finished episodes.
pub fn replay_all(
    replayer: &Replayer<'_>,
    recs: &[Recording],
    opts: &ReplayOptions,
    progress: Option<&(dyn Fn(usize) + Sync)>,
) -> Vec<Result<Episode, ReplayError>> {
    let done = std::sync::atomic::AtomicUsize::new(0);
    recs.par_iter()
        .map(|r| {
            let e = replayer.replay(r, opts, None);
            let k = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if let Some(p) = progress {
                p(k);
            }
            e
        })
        .collect()
}

/// Fills the control history of every actuator with a `delay` (MuJoCo's `nsample` buffer) with
/// its first command, as if that command had been in force before the replay starts. A fresh
/// `MjData` holds zeros there: a recording that starts mid-motion would otherwise drive the
/// delayed actuators towards 0 for the first `delay` seconds (on the Asimov legs, 20 ms of
/// target 0 kicked the bent knee, hip and ankle pitch joints into a 4–6 mrad transient against a
/// 1 mrad noise floor on a clean recording). Must run after the first commands are written to
/// `ctrl` and before the first step.
fn hold_delay_history(d: &mut MjData<&MjModel>, t0: f64, dt: f64) {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angular_velocity_of_a_yaw_rotation() {
        let a: f64 = 0.01; // rad turned about z in dt
        let q0 = [1.0, 0.0, 0.0, 0.0];
        let q1 = [(a / 2.0).cos(), 0.0, 0.0, (a / 2.0).sin()];
        let w = quat_ang_vel(&q0, &q1, 0.002);
        assert!((w[2] - 5.0).abs() < 1e-9 && w[0].abs() < 1e-12 && w[1].abs() < 1e-12, "{w:?}");
    }

    #[test]
    fn base_pose_interpolates_and_normalises() {
        let b = crate::sim2real::recording::BaseTrace {
            pos: vec![[0.0, 0.0, 1.0], [1.0, 0.0, 1.0]],
            quat: vec![[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]],
        };
        let p = base_pose(&[0.0, 1.0], &b, 0.5);
        assert!((p[0] - 0.5).abs() < 1e-12);
        let n: f64 = p[3..].iter().map(|x| x * x).sum();
        assert!((n - 1.0).abs() < 1e-12);
    }

    #[test]
    fn replay_samples_first_state_exactly_and_holds_commands() {
        let mut map = crate::model::source::SourceMap::default();
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/bam_xl330/rig.xml");
        let robot = crate::model::load(&mut map, &path, None).unwrap();
        let n = 200;
        let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.005).collect();
        let mut j = crate::sim2real::recording::JointTrace::new("servo", vec![0.3; n]);
        j.q_cmd = Some(vec![0.3; n]);
        j.qd = Some(vec![0.0; n]);
        let rec = Recording {
            source: "r.csv".into(),
            meta: Default::default(),
            control_rate_hz: None,
            control_t0_s: None,
            t,
            joints: vec![j],
            base: None,
        };
        let ep = replay(&robot, &rec, &ReplayOptions::default(), None).unwrap();
        assert_eq!(ep.q_sim[0][0], 0.3);
        assert!(ep.diverged.is_none());
        // Gravity pulls the arm below the held target: K (0.3 − q) = m g l sin q.
        let q = *ep.q_sim[0].last().unwrap();
        assert!(q < 0.3 && q > -0.5, "{q}");
        assert!(ep.q_sim[0].iter().all(|x| x.is_finite()));
    }

    #[test]
    fn delayed_actuator_starts_from_the_first_command_not_zero() {
        // No gravity, no friction: a joint held at its command is at equilibrium, so the
        // replay of a recording that holds q = q_cmd = 0.5 must stay at 0.5 exactly. A delay
        // history left at zero would drive the servo towards 0 for the first 20 ms
        // (kp 50 × 0.5 rad = 25 N·m on 0.01 kg·m²).
        let xml = r#"<mujoco><option gravity="0 0 0" timestep="0.002"/>
  <worldbody><body><joint name="j" type="hinge" axis="0 1 0"/>
    <geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.02" mass="0.5"/></body></worldbody>
  <actuator><position joint="j" kp="50" kv="2" delay="0.02" nsample="10"/></actuator>
</mujoco>"#;
        let dir = std::env::temp_dir().join(format!("modellint-delay-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("delayed.xml");
        std::fs::write(&path, xml).unwrap();
        let mut map = crate::model::source::SourceMap::default();
        let robot = crate::model::load(&mut map, &path, None).unwrap();
        let n = 100;
        let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.005).collect();
        let mut j = crate::sim2real::recording::JointTrace::new("j", vec![0.5; n]);
        j.q_cmd = Some(vec![0.5; n]);
        j.qd = Some(vec![0.0; n]);
        let rec = Recording {
            source: "r.csv".into(),
            meta: Default::default(),
            control_rate_hz: Some(100.0),
            control_t0_s: None,
            t,
            joints: vec![j],
            base: None,
        };
        let ep = replay(&robot, &rec, &ReplayOptions::default(), None).unwrap();
        let worst = ep.q_sim[0].iter().map(|q| (q - 0.5).abs()).fold(0.0, f64::max);
        assert!(worst < 1e-9, "the held joint moved by {worst} rad");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn dropped_command_rows_are_filled_before_the_hold() {
        let mut map = crate::model::source::SourceMap::default();
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/bam_xl330/rig.xml");
        let robot = crate::model::load(&mut map, &path, None).unwrap();
        // A 2 rad/s ramp logged at the 100 Hz control rate; then the same log with rows 50–52 lost.
        let n = 120;
        let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.01).collect();
        let c: Vec<f64> = t.iter().map(|&x| 2.0 * x).collect();
        let rec_of = |keep: &dyn Fn(usize) -> bool| {
            let idx: Vec<usize> = (0..n).filter(|&i| keep(i)).collect();
            let mut j = crate::sim2real::recording::JointTrace::new(
                "servo",
                idx.iter().map(|&i| c[i]).collect(),
            );
            j.q_cmd = Some(idx.iter().map(|&i| c[i]).collect());
            let t = idx.iter().map(|&i| t[i]).collect();
            Recording {
                source: "r.csv".into(),
                meta: Default::default(),
                control_rate_hz: Some(100.0),
                control_t0_s: None,
                t,
                joints: vec![j],
                base: None,
            }
        };
        let full = replay(&robot, &rec_of(&|_| true), &ReplayOptions::default(), None).unwrap();
        let lossy = rec_of(&|i| !(50..53).contains(&i));
        let err = |fill: bool| {
            let o = ReplayOptions { fill_dropped_commands: fill, ..Default::default() };
            let ep = replay(&robot, &lossy, &o, None).unwrap();
            // Same timestamps after the gap: compare there.
            (0..lossy.t.len())
                .filter(|&k| lossy.t[k] > 0.5)
                .map(|k| (ep.q_sim[0][k] - full.q_sim[0][k + 3]).abs())
                .fold(0.0, f64::max)
        };
        let (held, filled) = (err(false), err(true));
        assert!(held > 1e-3, "holding the row before the gap should lag the ramp: {held}");
        assert!(filled < 0.2 * held, "filled {filled} vs held {held}");
    }

    #[test]
    fn blow_up_is_reported_not_panicked() {
        let mut map = crate::model::source::SourceMap::default();
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/bam_xl330/rig.xml");
        let robot = crate::model::load(&mut map, &path, None).unwrap();
        let n = 100;
        let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.01).collect();
        let mut j = crate::sim2real::recording::JointTrace::new("servo", vec![0.0; n]);
        // An absurd gain makes explicit Euler unstable.
        j.kp = Some(vec![1e9; n]);
        j.q_cmd = Some(vec![1.0; n]);
        let rec = Recording {
            source: "r.csv".into(),
            meta: Default::default(),
            control_rate_hz: None,
            control_t0_s: None,
            t,
            joints: vec![j],
            base: None,
        };
        let ep = replay(&robot, &rec, &ReplayOptions::default(), None).unwrap();
        assert!(ep.diverged.is_some());
        assert!(ep.q_sim[0].last().unwrap().is_nan());
    }
}
