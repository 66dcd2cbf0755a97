//! `modellint synth`: recordings of a simulated "real robot" — the model plus hidden effects —
//! made by a simulated logging setup, with the answer key. Independent of `gap`/`fit`: its own
//! MuJoCo loop ([`sim`]), its own command clocks ([`clock`]), its own way the effects enter the
//! physics ([`truth`]) and its own writer ([`write`]). It shares only model loading and the
//! effect table (names, parameter order, defaults) with the rest of the tool.
//!
//! The logging setup (defaults = the `independent_arm2` development set):
//! a controller sends position commands at `control_hz` (ticks at control_t0_s + k/rate,
//! zero-order hold); a recorder samples asynchronously at `sample_hz` with ±`jitter` of the
//! period (or exactly at the ticks), and logs the measured q, qd and the command in force at the
//! sample time; q carries Gaussian noise then encoder quantisation, qd noise; rows are dropped
//! with probability `drop` (never the first or last); recording starts after an unrecorded
//! settle at the first command. See docs/synth.md.

pub mod clock;
pub mod cmd;
pub mod excitation;
#[cfg(test)]
pub mod recorded;
pub mod sim;
pub mod truth;
pub mod write;

use rayon::prelude::*;

use crate::model::{JointType, Robot};
use clock::{Commands, ControlClock, Rng, sample_times, to_us};
use excitation::{Band, Excitation, Plan, Segment};
use truth::Hidden;

/// Every knob of the simulated logging setup.
#[derive(Debug, Clone)]
pub struct Settings {
    pub episodes: usize,
    /// Recorded seconds per episode.
    pub duration_s: f64,
    pub control_hz: f64,
    /// Time of control tick 0 in recording time [s], in [0, 1/control_hz).
    pub control_phase_s: f64,
    /// Mean recorder rate [Hz].
    pub sample_hz: f64,
    /// Recorder period jitter, fraction of the period (uniform ±).
    pub jitter: f64,
    /// Rows exactly at the control ticks (state read, then the tick's command sent).
    pub log_at_ticks: bool,
    /// Unrecorded settle at the first command [s].
    pub settle_s: f64,
    /// Position noise σ [rad].
    pub noise: f64,
    /// Encoder resolution [bits] (quantum 2π / 2^bits); 0 = not quantised.
    pub quant_bits: u32,
    /// Velocity noise σ [rad/s].
    pub qd_noise: f64,
    /// Probability that a row is dropped.
    pub drop: f64,
    pub excitation: Excitation,
    /// Command amplitude about the centre pose [rad].
    pub amplitude: f64,
    /// The last `heldout` episodes carry `split: heldout`.
    pub heldout: usize,
    pub seed: u64,
    /// Floating base held this far above the keyframe pose [m] (0: no stand; base not written).
    pub suspend_m: f64,
}

impl Default for Settings {
    /// The arm2 logging setup: 100 Hz control, 88 Hz ±15 % recorder, 0.5 mrad + 12 bits,
    /// 0.01 rad/s, 0.5 % drops, 2 s settle, 4 × 10 s episodes, the last held out.
    fn default() -> Self {
        Settings {
            episodes: 4,
            duration_s: 10.0,
            control_hz: 100.0,
            control_phase_s: 0.0,
            sample_hz: 88.0,
            jitter: 0.15,
            log_at_ticks: false,
            settle_s: 2.0,
            noise: 5e-4,
            quant_bits: 12,
            qd_noise: 0.01,
            drop: 0.005,
            excitation: Excitation::Mix,
            amplitude: 0.35,
            heldout: 1,
            seed: 1,
            suspend_m: 0.0,
        }
    }
}

impl Settings {
    /// Encoder quantum [rad] (0: none).
    pub fn quantum(&self) -> f64 {
        if self.quant_bits == 0 {
            0.0
        } else {
            std::f64::consts::TAU / 2f64.powi(self.quant_bits as i32)
        }
    }

    /// Checks every knob; the message names the flag.
    pub fn validate(&self) -> Result<(), String> {
        let pos = |flag: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(format!("{flag} must be a positive number, got {v}"))
            }
        };
        let nonneg = |flag: &str, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(format!("{flag} must be a finite number ≥ 0, got {v}"))
            }
        };
        if self.episodes == 0 || self.episodes > 10_000 {
            return Err(format!("--episodes must be 1…10000, got {}", self.episodes));
        }
        pos("--duration", self.duration_s)?;
        if !(0.01..=3600.0).contains(&self.duration_s) {
            return Err(format!("--duration must be 0.01…3600 s, got {}", self.duration_s));
        }
        pos("--control-hz", self.control_hz)?;
        if self.control_hz > 100_000.0 {
            return Err(format!("--control-hz must be at most 100000, got {}", self.control_hz));
        }
        nonneg("--control-phase", self.control_phase_s)?;
        if to_us(self.control_phase_s) as f64 >= 1e6 / self.control_hz {
            return Err(format!(
                "--control-phase must be less than one control period ({} s), got {}",
                1.0 / self.control_hz,
                self.control_phase_s
            ));
        }
        pos("--sample-hz", self.sample_hz)?;
        if self.sample_hz > 100_000.0 {
            return Err(format!("--sample-hz must be at most 100000, got {}", self.sample_hz));
        }
        nonneg("--jitter", self.jitter)?;
        if self.jitter >= 1.0 {
            return Err(format!(
                "--jitter is a fraction of the period and must be < 1, got {}",
                self.jitter
            ));
        }
        nonneg("--settle", self.settle_s)?;
        if self.settle_s > 600.0 {
            return Err(format!("--settle must be at most 600 s, got {}", self.settle_s));
        }
        nonneg("--noise", self.noise)?;
        nonneg("--qd-noise", self.qd_noise)?;
        if self.quant_bits > 32 {
            return Err(format!("--quant-bits must be 0 (none) … 32, got {}", self.quant_bits));
        }
        nonneg("--drop", self.drop)?;
        if self.drop > 0.5 {
            return Err(format!("--drop is a probability and must be ≤ 0.5, got {}", self.drop));
        }
        pos("--amplitude", self.amplitude)?;
        if self.heldout >= self.episodes {
            return Err(format!(
                "--heldout must be less than --episodes ({}), got {}",
                self.episodes, self.heldout
            ));
        }
        nonneg("--suspend", self.suspend_m)?;
        Ok(())
    }
}

/// RNG purposes (independent streams).
const RNG_EXCITATION: u64 = 1;
const RNG_RECORDER: u64 = 2;
const RNG_NOISE: u64 = 3;
const RNG_DROP: u64 = 4;

/// Noise + quantisation floor of one joint: recorded q against the true reading (true position
/// + sensor offset) over the kept rows.
#[derive(Debug, Clone, Copy, Default)]
pub struct Floor {
    pub mae: f64,
    pub rmse: f64,
    pub n: usize,
}

impl Floor {
    fn of<'a>(pairs: impl Iterator<Item = (&'a f64, &'a f64)>) -> Floor {
        let (mut sa, mut s2, mut n) = (0.0, 0.0, 0usize);
        for (a, b) in pairs {
            let e = a - b;
            sa += e.abs();
            s2 += e * e;
            n += 1;
        }
        if n == 0 {
            Floor::default()
        } else {
            Floor { mae: sa / n as f64, rmse: (s2 / n as f64).sqrt(), n }
        }
    }
}

/// One recorded episode (kept rows only) with its truth.
#[derive(Debug, Clone)]
pub struct Episode {
    pub index: usize,
    pub heldout: bool,
    /// Row times [µs].
    pub t_us: Vec<i64>,
    /// `q[j][i]` recorded position, `qd` recorded velocity, `q_cmd` command in force.
    pub q: Vec<Vec<f64>>,
    pub qd: Vec<Vec<f64>>,
    pub q_cmd: Vec<Vec<f64>>,
    /// True reading (true position + sensor offset) and true velocity, noise-free.
    pub q_true: Vec<Vec<f64>>,
    pub qd_true: Vec<Vec<f64>>,
    pub commands: Commands,
    pub segments: Vec<Segment>,
    /// Rows before the drops, and rows dropped.
    pub samples: usize,
    pub dropped: usize,
    pub floor: Vec<Floor>,
}

/// A generated dataset.
#[derive(Debug, Clone)]
pub struct Dataset {
    pub robot: String,
    pub model_path: std::path::PathBuf,
    pub joints: Vec<String>,
    pub hidden: Vec<Hidden>,
    pub settings: Settings,
    pub control_t0_s: f64,
    /// Base pose on the stand (x y z qw qx qy qz), written as base.* columns.
    pub base: Option<[f64; 7]>,
    pub episodes: Vec<Episode>,
    /// Over all episodes, per joint.
    pub floor: Vec<Floor>,
}

/// The joints `synth` drives by default: actuated hinge/slide joints with a position servo,
/// filtered by an optional glob.
pub fn driven_joints(robot: &Robot, glob: Option<&str>) -> Result<Vec<String>, String> {
    let m = match glob {
        Some(g) => {
            Some(globset::Glob::new(g).map_err(|e| format!("--joints: {e}"))?.compile_matcher())
        }
        None => None,
    };
    let v: Vec<String> = robot
        .joints
        .iter()
        .filter(|j| {
            j.is_scalar()
                && robot
                    .actuators_on_joint(j.id)
                    .iter()
                    .any(|a| matches!(a.kind, crate::model::ActuatorKind::Position { .. }))
        })
        .filter(|j| m.as_ref().is_none_or(|m| m.is_match(&j.name)))
        .map(|j| j.name.clone())
        .collect();
    if v.is_empty() {
        let why = no_servo_reason(robot, m.as_ref());
        return Err(match glob {
            Some(g) => {
                format!(
                    "--joints `{g}`: no hinge/slide joint with a position actuator matches{why}"
                )
            }
            None => {
                format!("the model has no hinge/slide joint with a position actuator to drive{why}")
            }
        });
    }
    Ok(v)
}

/// Why no joint has a position servo: what drives the (matching) joints instead, and what
/// `synth` needs. Empty when there is no hinge/slide joint at all.
fn no_servo_reason(robot: &Robot, m: Option<&globset::GlobMatcher>) -> String {
    use crate::model::ActuatorKind;
    let mut by_kind: Vec<(&str, Vec<&str>)> = Vec::new();
    for j in robot.joints.iter().filter(|j| j.is_scalar()) {
        if m.is_some_and(|m| !m.is_match(&j.name)) {
            continue;
        }
        let acts = robot.actuators_on_joint(j.id);
        let kind = match acts.first().map(|a| &a.kind) {
            None => "no actuator (passive)",
            Some(ActuatorKind::Motor) => "torque actuators (<motor>)",
            Some(ActuatorKind::Velocity { .. }) => "velocity actuators",
            Some(ActuatorKind::DcMotor { .. }) => "DC motors (<dcmotor>)",
            Some(_) => "general actuators without a position servo",
        };
        match by_kind.iter_mut().find(|(k, _)| *k == kind) {
            Some((_, v)) => v.push(&j.name),
            None => by_kind.push((kind, vec![&j.name])),
        }
    }
    if by_kind.is_empty() {
        return String::new();
    }
    let parts: Vec<String> = by_kind
        .iter()
        .map(|(k, v)| {
            let shown: Vec<&str> = v.iter().take(4).copied().collect();
            let more =
                if v.len() > 4 { format!(", … ({} joints)", v.len()) } else { String::new() };
            format!("{k}: {}{more}", shown.join(", "))
        })
        .collect();
    format!(
        ". Its joints have {}. synth simulates a robot tracking position commands through its \
         servos (the controller, the servo's PD law and what the recorder logs: q, qd, q_cmd); \
         with torque actuators the servo law is in your controller, not in the model. Add the \
         servo to the model: a <position kp=\"…\" kv=\"…\"> actuator per joint with your \
         controller's PD gains (and forcerange = the motor's torque limit); `gap` and `fit` \
         replay q_cmd through such actuators too",
        parts.join("; ")
    )
}

/// Generates the dataset. `progress(done, total)` is called after each episode.
pub fn generate(
    robot: &Robot,
    joints: &[String],
    hidden: &[Hidden],
    s: &Settings,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Dataset, String> {
    s.validate()?;
    crate::model::mj::silence_warnings();
    let mut real = truth::real_robot(robot, joints, hidden)?;
    let bands: Vec<Band> = joints
        .iter()
        .map(|n| {
            let j = robot.joint(n).ok_or_else(|| format!("joint `{n}` is not in the model"))?;
            let key = robot.key.qpos.get(j.qposadr).copied().unwrap_or(0.0);
            Ok(Band::new(key, s.amplitude, j.limited.then_some(j.range)))
        })
        .collect::<Result<_, String>>()?;
    let stand = if s.suspend_m > 0.0 {
        let f = robot
            .joints
            .iter()
            .find(|j| j.jtype == JointType::Free)
            .ok_or("--suspend needs a floating-base model (a free joint)")?;
        let k = robot.key.qpos.get(f.qposadr..f.qposadr + 7).ok_or("free joint outside qpos")?;
        Some(sim::Stand {
            qposadr: f.qposadr,
            dofadr: f.dofadr,
            pose: [k[0], k[1], k[2] + s.suspend_m, k[3], k[4], k[5], k[6]],
        })
    } else if let Some(f) = robot.joints.iter().find(|j| j.jtype == JointType::Free) {
        // A free base would fall (or stand on whatever is below it) while the file says
        // `base: fixed`, and every replay pinned to the keyframe would disagree with it by
        // degrees: the exact model of a clean recording 5° RMSE off on the Asimov legs.
        return Err(format!(
            "the model has a floating base ({}): the synth records a robot on a test stand; \
             give --suspend M to pin the base M m above its keyframe pose (e.g. --suspend 0.5, \
             written as base.* columns)",
            if f.name.is_empty() {
                "an unnamed free joint".into()
            } else {
                format!("free joint `{}`", f.name)
            }
        ));
    } else {
        None
    };
    if let Some(st) = &stand {
        // The stand holds the base with unbounded inertia: pinning its pose between physics
        // steps alone would let the robot fall freely within each step, its legs unloaded.
        let m = &mut real.model;
        let a = 1e6 * m.body_mass().iter().sum::<f64>().max(1e-9);
        for k in st.dofadr..st.dofadr + 6 {
            let old = m.dof_armature()[k];
            m.dof_armature_mut()[k] = a;
            m.dof_m0_mut()[k] += a - old;
        }
    }
    let clock = ControlClock { rate_hz: s.control_hz, t0_us: to_us(s.control_phase_s) };
    let dur_us = to_us(s.duration_s);
    let offsets: Vec<f64> = real.joints.iter().map(|j| j.offset).collect();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let episodes: Vec<Episode> = (0..s.episodes)
        .into_par_iter()
        .map(|e| {
            let mut rng = Rng::stream(s.seed, RNG_EXCITATION, e as u64);
            let plan = Plan::new(s.excitation, s.duration_s, &bands, &mut rng);
            let ticks = clock.ticks(dur_us);
            let first = *ticks.start();
            let cmd: Vec<Vec<f64>> = ticks
                .map(|k| {
                    (0..joints.len())
                        .map(|j| plan.command(j, clock.tick_us(k) as f64 / clock::US))
                        .collect()
                })
                .collect();
            let commands = Commands { clock, first, cmd };
            let mut rr = Rng::stream(s.seed, RNG_RECORDER, e as u64);
            let t_all = sample_times(
                dur_us,
                s.sample_hz,
                s.jitter,
                s.log_at_ticks.then_some(&clock),
                &mut rr,
            );
            let tr = sim::run(robot, &real, &commands, &t_all, s.settle_s, stand)
                .map_err(|m| format!("episode {e}: {m}"))?;
            let ep = measure(e, s, &commands, &t_all, tr, &offsets, plan.segments.clone());
            let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress(n, s.episodes);
            Ok(ep)
        })
        .collect::<Result<_, String>>()?;
    let floor = (0..joints.len())
        .map(|j| Floor::of(episodes.iter().flat_map(|ep| ep.q[j].iter().zip(&ep.q_true[j]))))
        .collect();
    Ok(Dataset {
        robot: robot.path.file_stem().map(|x| x.to_string_lossy().into_owned()).unwrap_or_default(),
        model_path: robot.path.clone(),
        joints: joints.to_vec(),
        hidden: hidden.to_vec(),
        settings: s.clone(),
        control_t0_s: clock.t0_us as f64 / clock::US,
        base: stand.map(|st| st.pose),
        episodes,
        floor,
    })
}

/// Measurement: noise, quantisation, velocity noise, the logged command, dropped rows.
fn measure(
    e: usize,
    s: &Settings,
    cmds: &Commands,
    t_all: &[i64],
    tr: sim::Trace,
    offsets: &[f64],
    segments: Vec<Segment>,
) -> Episode {
    let mut noise = Rng::stream(s.seed, RNG_NOISE, e as u64);
    let mut drops = Rng::stream(s.seed, RNG_DROP, e as u64);
    let n = t_all.len();
    let keep: Vec<bool> =
        (0..n).map(|i| i == 0 || i + 1 == n || drops.uniform() >= s.drop).collect();
    let quantum = s.quantum();
    let nj = offsets.len();
    let (mut q, mut qd, mut q_cmd, mut q_true, mut qd_true) =
        (vec![vec![]; nj], vec![vec![]; nj], vec![vec![]; nj], vec![vec![]; nj], vec![vec![]; nj]);
    let mut t_us = Vec::new();
    for i in 0..n {
        // Noise is drawn for every row (kept or not), so a different drop rate leaves the
        // other rows' noise unchanged.
        let draws: Vec<(f64, f64)> = (0..nj).map(|_| (noise.normal(), noise.normal())).collect();
        if !keep[i] {
            continue;
        }
        t_us.push(t_all[i]);
        for j in 0..nj {
            let reading = tr.q[j][i] + offsets[j];
            let v = reading + s.noise * draws[j].0;
            q[j].push(if quantum > 0.0 { (v / quantum).round() * quantum } else { v });
            qd[j].push(tr.qd[j][i] + s.qd_noise * draws[j].1);
            q_true[j].push(reading);
            qd_true[j].push(tr.qd[j][i]);
            // The command in force at the row's time: tick floor((t − t0)·rate). Rows exactly
            // at a tick carry that tick's command (read, then send).
            q_cmd[j].push(cmds.in_force(t_all[i], j));
        }
    }
    let floor = (0..nj).map(|j| Floor::of(q[j].iter().zip(&q_true[j]))).collect();
    Episode {
        index: e,
        heldout: e + s.heldout >= s.episodes,
        dropped: n - t_us.len(),
        samples: n,
        t_us,
        q,
        qd,
        q_cmd,
        q_true,
        qd_true,
        commands: cmds.clone(),
        segments,
        floor,
    }
}
