//! Position-controlled trajectory replay (seed study §4.4): drive a MuJoCo model with a
//! recording's commands and sample the simulated joints at the recording's own timestamps.
//!
//! Protocol, per episode:
//! 1. Initialise: model joints take the keyframe `qpos` (or `qpos0`), recorded joints the first
//!    recorded `q`, their velocity the first recorded `qd` (or the derivative of `q`).
//! 2. Commands: [`crate::sim2real::commands`] reconstructs the command in force at every moment
//!    from `q_cmd` (or `q` when the joint has no command: `gap` and `fit` accept that only for
//!    a joint no actuator drives, or one left out of the scores with `--no-command`,
//!    [`crate::sim2real::input::read_for_replay`]): with a control rate (`control_hz`
//!    option, else the recording's `control_rate_hz`) one command per control tick at
//!    `control_t0_s + k/rate` (`t[0]` when absent), held over the tick; without one, each goal
//!    held from its own timestamp. Every physics step applies the command in force at the step's
//!    start to every recorded joint's position actuators. The recorded `kp`/`kd`
//!    columns (N·m/rad, N·m·s/rad) set the actuator's `gainprm[0] = kp`, `biasprm[1] = −kp`,
//!    `biasprm[2] = −kd` at the same ticks; `enabled = false` zeroes the actuator's gain and bias
//!    (torque off, e.g. free fall). Model joints without recording hold their keyframe `ctrl`.
//!    A joint driven by torque actuators only (`<motor>`, `<general>` without bias) runs the
//!    policy's PD at every physics step from the kp/kd columns or the spec (`pd` module).
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
use crate::sim2real::commands::{CommandTiming, Fill, reconstruct};
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

/// Armature given to each of a held floating base's six DoFs [kg on the translations, kg·m² on
/// the rotations], per kilogram of the robot. A test stand is a body of unbounded inertia: with
/// a million times the robot's mass on the base's DoFs, the forces of the robot's own joints and
/// gravity (which acts on mass, not on armature) move the base by at most a millionth of what
/// they would move it free, so the limbs swing under gravity as on a stand (a robot within a few
/// metres has composite rotational inertia well under its mass × 10 m²).
pub const HELD_BASE_ARMATURE_PER_KG: f64 = 1e6;

/// Gives the first floating base of `robot` the inertia of a test stand when the replay holds
/// (`Fixed`) or drives (`Recorded`) it: resetting the base's pose and velocity around each
/// physics step alone leaves the base free *during* the step, where the whole robot then falls
/// and its joints carry no gravity load (a robot on a stand replayed as if in orbit). The
/// replay applies a driven base's recorded acceleration as a force on that armature. Nothing is
/// changed for `Free` or a fixed-base model.
pub fn hold_base(robot: &mut Robot, base: BaseMode) {
    let Some((dof, a)) = base_hold(robot, base) else { return };
    for k in 0..6 {
        mj::set_armature(&mut robot.mj, dof + k, a);
    }
}

/// A copy of `robot` with its base held ([`hold_base`]) when the replay holds or drives a
/// floating base that is not held yet; `None` when nothing is to change.
pub fn held(robot: &Robot, base: BaseMode) -> Option<Robot> {
    base_hold(robot, base)?;
    let mut r = robot.clone();
    hold_base(&mut r, base);
    Some(r)
}

/// (first DoF of the floating base, the stand's armature) when `base` holds or drives it and its
/// DoFs do not have that armature yet.
fn base_hold(robot: &Robot, base: BaseMode) -> Option<(usize, f64)> {
    if base == BaseMode::Free {
        return None;
    }
    let dof = robot.joints.iter().find(|j| j.jtype == JointType::Free)?.dofadr;
    let mass: f64 = robot.mj.body_mass().iter().sum();
    let a = HELD_BASE_ARMATURE_PER_KG * mass.max(1e-9);
    let arm = robot.mj.dof_armature();
    (0..6).any(|k| arm.get(dof + k).is_some_and(|&x| x < a)).then_some((dof, a))
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
    /// What control ticks without a row get ([`Fill`]; default: filled along the command's shape,
    /// held across steps; without a control rate, dropped rows' commands are interpolated,
    /// [`crate::sim2real::metrics::fill_dropped_rows`]).
    pub command_fill: Fill,
    /// PD gains (kp N·m/rad, kd N·m·s/rad) per joint name for joints driven by torque whose
    /// recording has no `kp`/`kd` column ([`spec_pd_gains`]: the spec's motor families).
    pub pd_gains: std::collections::BTreeMap<String, (f64, f64)>,
}

impl Default for ReplayOptions {
    fn default() -> Self {
        ReplayOptions {
            control_hz: None,
            command_timing: None,
            base: BaseMode::Fixed,
            hold_unlisted_at_key: true,
            command_fill: Fill::Ramps,
            pd_gains: Default::default(),
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
    /// What the physics steps reached on each recorded joint ([`StepPeaks`]).
    pub peaks: StepPeaks,
}

/// What the physics steps of a replay reached, per recorded joint (the recording's order):
/// facts a model change can be tested against without replaying it (a torque limit above
/// every force the servo applied clamps nothing). Empty when not measured.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StepPeaks {
    /// The largest |force| any of the joint's actuators applied at a physics step, in joint
    /// units (MuJoCo's `actuator_force` after the model's own `forcerange` clamp, × |gear|, a
    /// gear of 0 counted as 1) [N·m or N]. Empty with the RK4 integrator: its inner stages
    /// evaluate forces the replay does not see.
    pub servo: Vec<f64>,
    /// The largest |q̇| at the start of a physics step (the velocity an actuator hook sees)
    /// [rad/s or m/s].
    pub speed: Vec<f64>,
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
    /// The command the joint's position actuator acts on at this step when the actuator has a
    /// MuJoCo `delay` (read from its control history, i.e. `ctrl` as written `delay` seconds
    /// ago); `None` without one, when it acts on `ctrl` itself. See [`StepIo::acting_ctrl`].
    pub delayed_ctrl: Option<f64>,
    /// The joint-torque range MuJoCo clamps the joint's position servo to (`forcerange` × gear,
    /// a torque limit's fitted effort included), `None` when its force is not limited.
    pub servo_range: Option<(f64, f64)>,
    /// Generalised force added on the joint's DoF (written to `qfrc_applied`) [N·m or N].
    pub tau: f64,
    /// Recorded (or model) gains in force at this step.
    pub kp: f64,
    pub kd: f64,
    /// Recorded torque-enable state in force at this step.
    pub enabled: bool,
    /// The simulator's own forces on the joint's DoF at the step's start state, from MuJoCo's
    /// last forward pass (one physics step old at most): `qfrc_bias` (gravity, Coriolis and
    /// centrifugal, the force the motion *needs*: the external load torque is `−bias`) and
    /// `qfrc_passive` (springs, dampers) [N·m or N].
    pub bias: f64,
    pub passive: f64,
    /// Inertia the DoF presents to its own torque, 1 / diag(D) of MuJoCo's L'DL factorisation
    /// of the mass matrix (armature included; exact for a single DoF) [kg·m² or kg].
    pub inertia: f64,
    /// The DoF's armature in the model copy (`dof_armature`, a rotor's reflected inertia)
    /// [kg·m² or kg].
    pub armature: f64,
}

impl StepIo {
    /// The command the servo acts on at this step: the delayed one when the actuator has a MuJoCo
    /// `delay` (the Asimov legs: 20 ms), else `ctrl`. An effect that models the servo's own
    /// torque (a gain error, a torque limit) must use this, not `ctrl`: on a delayed actuator,
    /// `kp·(ctrl − q)` is a torque the servo does not apply for another `delay` seconds.
    pub fn acting_ctrl(&self) -> f64 {
        self.delayed_ctrl.unwrap_or(self.ctrl)
    }
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
    /// Every actuator of the joint is a torque actuator on the joint itself (`pd` module).
    torque: bool,
}

impl JointInfo {
    /// Driven by velocity actuators only (a wheel): its recorded command is a velocity target
    /// [rad/s or m/s], applied as the actuators' ctrl.
    fn velocity_driven(&self) -> bool {
        !self.acts.is_empty()
            && self.acts.iter().all(|(_, k)| matches!(k, ActuatorKind::Velocity { .. }))
    }
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
    /// Actuator names by id (for errors).
    act_names: Vec<String>,
}

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
                torque: pd::torque_actuators(robot, j.id).is_some(),
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
            act_names: {
                let mut v = vec![String::new(); robot.actuators.len()];
                for a in &robot.actuators {
                    if let Some(x) = v.get_mut(a.id) {
                        *x = if a.name.is_empty() { format!("#{}", a.id) } else { a.name.clone() };
                    }
                }
                v
            },
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
        let (rate, _, tick0) = timing_of(rec, opts);
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

        let schedule =
            schedule_of(rec, opts, opts.command_fill).map_err(|e| setup(e.to_string()))?;
        if let Some(h) = hook.as_deref_mut() {
            let names: Vec<String> = rec.joints.iter().map(|j| j.name.clone()).collect();
            h.reset(&names, mj::raw(self.model).opt.timestep);
        }
        let replaced: Vec<bool> =
            (0..nj).map(|i| hook.as_deref().is_some_and(|h| h.replaces_actuator(i))).collect();
        let mut pd_joints: Vec<Option<pd::PdJoint>> = vec![None; nj];
        for (i, &ji) in jm.iter().enumerate() {
            let (info, jt) = (&self.joints[ji], &rec.joints[i]);
            if replaced[i] {
                continue;
            }
            let act_names = || -> String {
                let n: Vec<String> = info
                    .acts
                    .iter()
                    .map(|&(a, _)| format!("actuator '{}'", self.act_names[a]))
                    .collect();
                n.join(", ")
            };
            if info.torque {
                let spec = opts.pd_gains.get(&jt.name);
                let (has_kp, has_kd) =
                    (jt.kp.is_some() || spec.is_some(), jt.kd.is_some() || spec.is_some());
                if !(has_kp && has_kd) {
                    return Err(setup(pd::missing_gains(&jt.name, &act_names(), has_kp, has_kd)));
                }
                let (gear, gp) = (self.model.actuator_gear(), self.model.actuator_gainprm());
                pd_joints[i] = Some(pd::PdJoint {
                    acts: info.acts.iter().map(|&(a, _)| (a, gp[a][0] * gear[a][0])).collect(),
                    kp: spec.map_or(0.0, |g| g.0),
                    kd: spec.map_or(0.0, |g| g.1),
                });
                continue;
            }
            let beside_servo = info.acts.iter().any(|(_, k)| {
                matches!(k, ActuatorKind::Position { .. } | ActuatorKind::Velocity { .. })
            });
            for &(aid, kind) in &info.acts {
                if !matches!(kind, ActuatorKind::Position { .. } | ActuatorKind::Velocity { .. }) {
                    return Err(setup(format!(
                        "actuator '{}' on joint '{}' is {}: {}",
                        self.act_names[aid],
                        jt.name,
                        pd::unsupported(kind, beside_servo),
                        pd::SUPPORTED
                    )));
                }
            }
        }
        let gain_cols =
            rec.joints.iter().any(|j| j.kp.is_some() || j.kd.is_some() || j.enabled.is_some());
        let mut owned: Option<MjModel> =
            (gain_cols || replaced.iter().any(|&r| r)).then(|| self.model.clone());
        let m: &MjModel = owned.as_ref().unwrap_or(self.model);
        let dt = mj::raw(m).opt.timestep;
        if dt.is_nan() || dt <= 0.0 {
            return Err(setup(format!("model timestep {dt} is not positive")));
        }
        // Nominal gains of every position actuator of the recorded joints.
        let (gp, bp) = (m.actuator_gainprm(), m.actuator_biasprm());
        let nominal: Vec<Vec<(usize, f64, f64, f64)>> = jm
            .iter()
            .map(|&ji| {
                self.joints[ji]
                    .acts
                    .iter()
                    .map(|&(a, _)| {
                        let (g, b) = (gp.get(a), bp.get(a));
                        (
                            a,
                            g.map_or(0.0, |g| g[0]),
                            b.map_or(0.0, |b| b[1]),
                            b.map_or(0.0, |b| b[2]),
                        )
                    })
                    .collect()
            })
            .collect();
        // The model's position-servo gains relative to the robot's own (a fit's servo gain
        // error scales them in the model copy): recorded kp/kd columns are scaled alike.
        let gain_scale: Vec<(f64, f64)> = jm
            .iter()
            .zip(&nominal)
            .map(|(&ji, nom)| {
                self.joints[ji]
                    .acts
                    .iter()
                    .zip(nom)
                    .find_map(|(&(_, kind), &(_, g, _, b2))| match kind {
                        ActuatorKind::Position { kp, kv } => Some((
                            if kp > 0.0 { g / kp } else { 1.0 },
                            if kv > 0.0 { -b2 / kv } else { 1.0 },
                        )),
                        _ => None,
                    })
                    .unwrap_or((1.0, 1.0))
            })
            .collect();
        let c = run::Run {
            rec,
            opts,
            jm: &jm,
            qd0: &qd0,
            nominal: &nominal,
            gain_scale: &gain_scale,
            replaced: &replaced,
            pd: &pd_joints,
            rate,
            tick0,
            schedule: &schedule,
            dt,
        };
        // Gains are written on the episode's own copy only, never on the shared model.
        match owned.as_mut() {
            Some(copy) => {
                for (i, acts) in nominal.iter().enumerate() {
                    if replaced[i] {
                        for &(a, ..) in acts {
                            mj::set_model_gains(copy, a, 0.0, 0.0, 0.0);
                        }
                    }
                }
                self.run(MjData::new(copy), &c, hook, Some(mj::set_actuator_gains))
            }
            None => self.run(MjData::new(self.model), &c, hook, None),
        }
    }
}

/// The command traces the replay follows: each joint's `q_cmd` (its `q` when it has none; the
/// CLI's inputs allow that only where it drives nothing or is not scored, see the module docs).
pub fn command_traces(rec: &Recording) -> Vec<&[f64]> {
    rec.joints.iter().map(|jt| jt.q_cmd.as_deref().unwrap_or(&jt.q)).collect()
}

/// The control rate, command timing and tick origin the replay uses for `rec`: `--control-hz`
/// and `--command-timing` over the recording's keys; ticks at `control_t0_s + k / rate`
/// (`t[0]` when absent — [`resolve_tick_origin`] estimates it from the rows first).
pub fn timing_of(rec: &Recording, opts: &ReplayOptions) -> (Option<f64>, CommandTiming, f64) {
    let rate = opts.control_hz.or(rec.control_rate_hz);
    let timing = opts.command_timing.or_else(|| rec.command_timing()).unwrap_or_default();
    let tick0 = rec.control_t0_s.unwrap_or(rec.t.first().copied().unwrap_or(0.0));
    (rate, timing, tick0)
}

/// The reconstructed command schedule of `rec` as the replay sees it, with `fill`.
pub fn schedule_of(
    rec: &Recording,
    opts: &ReplayOptions,
    fill: Fill,
) -> Result<crate::sim2real::commands::Schedule, crate::sim2real::commands::ScheduleError> {
    let (rate, timing, tick0) = timing_of(rec, opts);
    reconstruct(&rec.t, &command_traces(rec), rate, tick0, timing, fill)
}

/// Whether the recording's timestamps map onto its control ticks as the replay will map them
/// ([`schedule_of`]): `fit` checks every file before simulating anything, so a unit mistake
/// (milliseconds, nanoseconds) is one clear error, not a failed search (`gap` gets the same
/// error from its replay).
pub fn check_schedule(rec: &Recording, opts: &ReplayOptions) -> Result<(), ReplayError> {
    if opts.control_hz.or(rec.control_rate_hz).is_none() {
        return Ok(());
    }
    schedule_of(rec, opts, opts.command_fill)
        .map(|_| ())
        .map_err(|e| ReplayError::Setup { file: rec.source.clone(), message: e.to_string() })
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

mod origin;
mod pd;
mod run;
mod timestep;
pub use origin::{
    KEY_TIME_SCALE, OffGrid, RateFix, TickOrigin, off_grid, origin_messages, rate_messages,
    resolve_rate, resolve_tick_origin,
};
pub use pd::spec_pd_gains;
pub use timestep::{JointTimestep, REFINE, TimestepCheck, timestep_check, timestep_note};
#[cfg(test)]
pub(crate) mod tests;
