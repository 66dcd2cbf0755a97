//! The hidden "real robot": which effects it has and how each one enters the physics. This is
//! the synth's own implementation; only the effect names, parameter lists and defaults are read
//! from the fit's effect table (`crate::fit::effects::by_id(..).params()`), so that a spec means
//! the same to both. Meanings (matching each effect's documentation in src/fit/effects/):
//!
//! | effect | parameters | how it enters here |
//! |---|---|---|
//! | armature | armature [kg·m²] (absolute value) | `dof_armature` of the model copy |
//! | viscous_damping | damping [N·m·s/rad] (absolute) | `dof_damping` |
//! | coulomb_friction | frictionloss [N·m] (absolute) | `dof_frictionloss` |
//! | joint_stiffness | stiffness [N·m/rad] | `jnt_stiffness`, spring reference = keyframe position |
//! | gain_error | kp_scale, kd_scale | the joint's position actuators: `gainprm[0]`, `biasprm[1]` × kp_scale, `biasprm[2]` × kd_scale |
//! | torque_limit | effort_limit, saturation_effort, velocity_limit | effort only: `forcerange` ±effort; with a torque–speed line: per-step clip of the servo torque via `qfrc_applied` |
//! | action_delay | delay_s [s] | the servo sees the command signal delayed by delay_s (exact, sub-step: mean over each physics step) |
//! | backlash | backlash_rad (total play) | a rotor (the joint's armature) behind the play, driven by the servo: on a flank the servo acts on the link with its set-point moved by play/2; inside the play no servo force on the link; an inelastic impact at the flank ([`Play`]) |
//! | position_offset | offset_rad | sensor only: recorded q = true q + offset (the servo acts on the true angle) |
//! | stribeck_friction | static, dynamic [N·m], v_stribeck [rad/s] | `qfrc_applied`: dry friction with exact stiction, budget Fd + (Fs − Fd)·exp(−(q̇/vs)²): the torque that stops the joint within the step ([`StepLoad`]) clamped to ± the budget |
//! | load_dependent_friction | frictionloss [N·m], load_coeff | `qfrc_applied` −tanh(q̇/0.02)·(f0 + k·|τ_servo|) |
//!
//! τ_servo is the torque the servo applies in the step (with a MuJoCo actuator `delay`, from the
//! control the actuator reads from its ctrl history: [`servo_torque`]).

use mujoco_rs::prelude::*;

use crate::model::{ActuatorKind, Robot, mj};

/// Smoothing velocity of the load-dependent friction's sign [rad/s] (the same ε the fit's
/// effect documents).
pub const FRICTION_EPS: f64 = 0.02;

/// One hidden effect on one joint.
#[derive(Debug, Clone, PartialEq)]
pub struct Hidden {
    pub effect: &'static str,
    pub joint: String,
    /// Full parameter vector (the effect's order; missing values at their defaults).
    pub params: Vec<f64>,
}

/// Parameter names of an effect (from the fit's effect table).
pub fn param_names(effect: &str) -> Vec<&'static str> {
    crate::fit::effects::by_id(effect)
        .map(|e| e.params().iter().map(|p| p.name).collect())
        .unwrap_or_default()
}

/// Parses `effect[@joint_glob]=v1,v2;…` (no glob: every joint in `joints`). One [`Hidden`] per
/// (effect, joint). An empty spec or `none` means nothing hidden.
pub fn parse(spec: &str, joints: &[String]) -> Result<Vec<Hidden>, String> {
    let mut out: Vec<Hidden> = Vec::new();
    if spec.trim() == "none" {
        return Ok(out);
    }
    for item in spec.split(';').map(str::trim).filter(|s| !s.is_empty()) {
        let (lhs, rhs) = item
            .split_once('=')
            .ok_or_else(|| format!("`{item}`: expected effect[@joint_glob]=v1,v2,…"))?;
        let (id, glob) = match lhs.split_once('@') {
            Some((a, b)) => (a.trim(), Some(b.trim())),
            None => (lhs.trim(), None),
        };
        let e = crate::fit::effects::by_id(id).ok_or_else(|| {
            let all: Vec<&str> = crate::fit::effects::all().iter().map(|e| e.id()).collect();
            format!("unknown effect `{id}` (known: {})", all.join(", "))
        })?;
        let defs = e.params();
        let mut params: Vec<f64> = defs.iter().map(|p| p.default).collect();
        for (k, v) in rhs.split(',').enumerate() {
            if k >= params.len() {
                let names: Vec<&str> = defs.iter().map(|d| d.name).collect();
                return Err(format!(
                    "`{item}`: {id} has {} parameter(s): {}",
                    params.len(),
                    names.join(", ")
                ));
            }
            let x: f64 = v
                .trim()
                .parse()
                .map_err(|_| format!("`{item}`: `{}` is not a number", v.trim()))?;
            if !x.is_finite() {
                return Err(format!("`{item}`: `{}` is not finite", v.trim()));
            }
            params[k] = x;
        }
        check_values(id, &params).map_err(|m| format!("`{item}`: {m}"))?;
        let sel: Vec<&String> = match glob {
            Some(g) => {
                let m =
                    globset::Glob::new(g).map_err(|x| format!("`{item}`: {x}"))?.compile_matcher();
                joints.iter().filter(|j| m.is_match(j.as_str())).collect()
            }
            None => joints.iter().collect(),
        };
        if sel.is_empty() {
            return Err(format!(
                "`{item}`: no recorded joint matches (recorded: {})",
                joints.join(", ")
            ));
        }
        for j in sel {
            if out.iter().any(|h| h.effect == id && &h.joint == j) {
                return Err(format!("`{item}`: {id} is given twice for joint {j}"));
            }
            out.push(Hidden { effect: e.id(), joint: j.clone(), params: params.clone() });
        }
    }
    Ok(out)
}

/// Physically meaningless values are refused (negative inertia, friction, delay…).
fn check_values(id: &str, p: &[f64]) -> Result<(), String> {
    let names = param_names(id);
    let nonneg = |i: usize| {
        if p[i] < 0.0 { Err(format!("{} must be ≥ 0, got {}", names[i], p[i])) } else { Ok(()) }
    };
    match id {
        "armature" | "viscous_damping" | "coulomb_friction" | "joint_stiffness" | "backlash" => {
            nonneg(0)
        }
        "action_delay" => {
            nonneg(0)?;
            if p[0] > 1.0 { Err(format!("delay_s {} s is longer than 1 s", p[0])) } else { Ok(()) }
        }
        "gain_error" | "torque_limit" => {
            for (i, v) in p.iter().enumerate() {
                if *v <= 0.0 {
                    return Err(format!("{} must be > 0, got {v}", names[i]));
                }
            }
            Ok(())
        }
        "stribeck_friction" => {
            nonneg(0)?;
            nonneg(1)?;
            if p[2] <= 0.0 { Err(format!("v_stribeck must be > 0, got {}", p[2])) } else { Ok(()) }
        }
        "load_dependent_friction" => {
            nonneg(0)?;
            nonneg(1)
        }
        _ => Ok(()),
    }
}

/// A position actuator driving a recorded joint: id, gear, and (after gain edits) its PD law.
#[derive(Debug, Clone, Copy)]
pub struct Servo {
    pub id: usize,
    pub gear: f64,
}

/// Per recorded joint: indices and the effects that act every physics step.
#[derive(Debug, Clone, Default)]
pub struct JointPhysics {
    pub dof: usize,
    pub qposadr: usize,
    pub servos: Vec<Servo>,
    pub delay_s: f64,
    /// Half the total play [rad].
    pub half_play: f64,
    /// (effort, saturation, velocity limit) when clipped per step.
    pub torque_line: Option<[f64; 3]>,
    pub stribeck: Option<[f64; 3]>,
    pub load_friction: Option<[f64; 2]>,
    /// Sensor offset [rad].
    pub offset: f64,
}

impl JointPhysics {
    pub fn has_torque_hook(&self) -> bool {
        self.torque_line.is_some() || self.stribeck.is_some() || self.load_friction.is_some()
    }
}

/// The real robot: a model copy with the MuJoCo-native effects written in, and the per-step
/// physics of every recorded joint.
pub struct RealRobot {
    pub model: MjModel,
    pub joints: Vec<JointPhysics>,
}

/// Builds the real robot for the recorded `joints` (names) with `hidden` effects.
pub fn real_robot(
    robot: &Robot,
    joints: &[String],
    hidden: &[Hidden],
) -> Result<RealRobot, String> {
    let mut model = robot.mj.clone();
    let mut out = Vec::new();
    for name in joints {
        let j = robot.joint(name).ok_or_else(|| format!("joint `{name}` is not in the model"))?;
        let servos: Vec<Servo> = robot
            .actuators_on_joint(j.id)
            .into_iter()
            .filter(|a| matches!(a.kind, ActuatorKind::Position { .. }))
            .map(|a| Servo { id: a.id, gear: if a.gear != 0.0 { a.gear } else { 1.0 } })
            .collect();
        let key_q = robot.key.qpos.get(j.qposadr).copied().unwrap_or(0.0);
        let mut jp =
            JointPhysics { dof: j.dofadr, qposadr: j.qposadr, servos, ..Default::default() };
        for h in hidden.iter().filter(|h| &h.joint == name) {
            let p = &h.params;
            let need_servo = || {
                if jp.servos.is_empty() {
                    Err(format!("{} on {name}: the joint has no position actuator", h.effect))
                } else {
                    Ok(())
                }
            };
            match h.effect {
                "armature" => {
                    // dof_M0 (the inertia MuJoCo uses directly for "simple" dofs, compiled with
                    // the armature in it) moves with the armature.
                    let a = model.dof_armature_mut().get_mut(j.dofadr).ok_or("dof")?;
                    let delta = p[0] - *a;
                    *a = p[0];
                    *model.dof_m0_mut().get_mut(j.dofadr).ok_or("dof")? += delta;
                }
                "viscous_damping" => {
                    *model.dof_damping_mut().get_mut(j.dofadr).ok_or("dof")? = p[0]
                }
                "coulomb_friction" => {
                    *model.dof_frictionloss_mut().get_mut(j.dofadr).ok_or("dof")? = p[0]
                }
                "joint_stiffness" => {
                    *model.jnt_stiffness_mut().get_mut(j.id).ok_or("jnt")? = p[0];
                    *model.qpos_spring_mut().get_mut(j.qposadr).ok_or("qpos")? = key_q;
                }
                "gain_error" => {
                    need_servo()?;
                    for s in &jp.servos {
                        *mj::actuator_gainprm_mut(&mut model).get_mut(10 * s.id).ok_or("act")? *=
                            p[0];
                        let b = model.actuator_biasprm_mut().get_mut(s.id).ok_or("act")?;
                        b[1] *= p[0];
                        b[2] *= p[1];
                    }
                }
                "torque_limit" => {
                    need_servo()?;
                    if p[1] >= 1e4 && p[2] >= 1e4 {
                        // Effort only: MuJoCo's own actuator force clamp (force = torque / gear).
                        for s in &jp.servos {
                            let e = p[0] / s.gear.abs();
                            *model.actuator_forcelimited_mut().get_mut(s.id).ok_or("act")? = true;
                            *model.actuator_forcerange_mut().get_mut(s.id).ok_or("act")? = [-e, e];
                        }
                    } else {
                        jp.torque_line = Some([p[0], p[1], p[2]]);
                    }
                }
                "action_delay" => {
                    need_servo()?;
                    jp.delay_s = p[0];
                }
                "backlash" => {
                    need_servo()?;
                    jp.half_play = 0.5 * p[0];
                }
                "position_offset" => jp.offset = p[0],
                "stribeck_friction" => jp.stribeck = Some([p[0], p[1], p[2]]),
                "load_dependent_friction" => {
                    need_servo()?;
                    jp.load_friction = Some([p[0], p[1]]);
                }
                other => return Err(format!("effect `{other}` is not simulated by synth")),
            }
        }
        out.push(jp);
    }
    Ok(RealRobot { model, joints: out })
}

/// The torque the joint's servos produce at (q, qd) when servo k acts on control `ctrl[k]`
/// (the set-point, or for an actuator with a MuJoCo `delay` the value it reads from its ctrl
/// history), from the model copy's actuator parameters (force = gain·ctrl + b0 + b1·gear·q +
/// b2·gear·qd, ctrl clamped to ctrlrange, force to forcerange; joint torque = gear · force).
pub fn servo_torque(m: &MjModel, jp: &JointPhysics, ctrl: &[f64], q: f64, qd: f64) -> f64 {
    let (g, b) = (m.actuator_gainprm().as_flattened(), m.actuator_biasprm().as_flattened());
    let (fl, fr) = (m.actuator_forcelimited(), m.actuator_forcerange().as_flattened());
    let (cl, cr) = (m.actuator_ctrllimited(), m.actuator_ctrlrange().as_flattened());
    let mut tau = 0.0;
    for (s, &u) in jp.servos.iter().zip(ctrl) {
        let i = s.id;
        let ctrl = if cl[i] { u.clamp(cr[2 * i], cr[2 * i + 1]) } else { u };
        let mut f =
            g[10 * i] * ctrl + b[10 * i] + b[10 * i + 1] * s.gear * q + b[10 * i + 2] * s.gear * qd;
        if fl[i] {
            f = f.clamp(fr[2 * i], fr[2 * i + 1]);
        }
        tau += s.gear * f;
    }
    tau
}

/// Backlash: a rotor (inertia: the joint's armature) that the servo drives and that pushes the
/// link through a play of ±`half_play`. On a flank rotor and link move as one and the servo
/// acts on the link with its set-point moved by the half play; inside the play the servo acts
/// on the rotor alone (no force on the link) and the rotor's momentum passes to the link
/// inelastically when it reaches a flank. Without an armature the rotor sits at the command.
#[derive(Debug, Clone, Copy, Default)]
pub struct Play {
    /// Rotor angle and velocity while it is inside the play.
    qm: f64,
    qmd: f64,
    /// The flank the rotor rests on: −1, +1, or 0 inside the play.
    side: f64,
    /// The joint velocity of the previous step (its acceleration, for the flank's force).
    qd_prev: f64,
    started: bool,
}

impl Play {
    /// One physics step of joint `jp` at (q, qd) for command `u`, with `inertia` the inertia the
    /// joint presents to its own torque (armature included): the control its servos get and the
    /// joint torque the rotor's impact adds.
    pub fn step(
        &mut self,
        m: &MjModel,
        jp: &JointPhysics,
        (u, q, qd): (f64, f64, f64),
        inertia: f64,
    ) -> (f64, f64) {
        let h = jp.half_play;
        let dt = m.opt().timestep;
        let j = m.dof_armature().get(jp.dof).copied().unwrap_or(0.0);
        let (g, b) = (m.actuator_gainprm().as_flattened(), m.actuator_biasprm().as_flattened());
        // The control that makes the servos apply no force at (q, qd).
        let (mut num, mut den) = (0.0, 0.0);
        for s in &jp.servos {
            let i = s.id;
            num -= s.gear * (b[10 * i] + b[10 * i + 1] * s.gear * q + b[10 * i + 2] * s.gear * qd);
            den += s.gear * g[10 * i];
        }
        let free = if den != 0.0 { num / den } else { q };
        if j <= 0.0 || dt <= 0.0 {
            let e = u - q;
            return (if e.abs() <= h { free } else { u - h * e.signum() }, 0.0);
        }
        let on_rotor = |qm: f64, qmd: f64| {
            let c = vec![u; jp.servos.len()];
            servo_torque(m, jp, &c, qm, qmd)
        };
        if !self.started {
            let e = u - q;
            *self = Play { qm: q + e.clamp(-h, h), qmd: qd, side: 0.0, qd_prev: qd, started: true };
            if e.abs() > h {
                self.side = e.signum();
            }
        }
        let acc = (qd - self.qd_prev) / dt;
        self.qd_prev = qd;
        if self.side != 0.0 {
            let c = vec![u - self.side * h; jp.servos.len()];
            if self.side * (servo_torque(m, jp, &c, q, qd) - j * acc) < 0.0 {
                (self.qm, self.qmd, self.side) = (q + self.side * h, qd, 0.0);
            }
        }
        let mut tau = 0.0;
        if self.side == 0.0 {
            let qmd = self.qmd + dt * on_rotor(self.qm, self.qmd) / j;
            let qm = self.qm + dt * qmd;
            let vl = qd + dt * acc;
            let d = qm - (q + dt * vl);
            if d.abs() >= h && (qmd - vl) * d > 0.0 {
                self.side = d.signum();
                tau = j * (qmd - vl) / dt;
                // The next step's acceleration estimate leaves the impact's jump out.
                self.qd_prev = qd + tau * dt / inertia.max(j);
            } else {
                (self.qm, self.qmd) = (qm, qmd);
            }
        }
        if self.side != 0.0 { (u - self.side * h, tau) } else { (free, tau) }
    }
}

/// What the joint's dry friction needs of the step, from MuJoCo's last forward pass: the DoF's
/// `qfrc_bias` and `qfrc_passive` [N·m], the inertia it presents to its own torque (1 / diag(D)
/// of the factorised mass matrix) [kg·m²] and the time step [s].
#[derive(Debug, Clone, Copy, Default)]
pub struct StepLoad {
    pub bias: f64,
    pub passive: f64,
    pub inertia: f64,
    pub dt: f64,
}

/// The joint torque added this step (qfrc_applied) by the per-step effects, when servo k acts
/// on control `ctrl[k]` (see [`servo_torque`]). Stribeck friction is dry friction with exact
/// stiction: the torque that would bring the joint to rest at the end of this semi-implicit
/// Euler step (every other torque of the step counted), clamped to ± its budget.
pub fn step_torque(
    m: &MjModel,
    jp: &JointPhysics,
    ctrl: &[f64],
    (q, qd): (f64, f64),
    load: &StepLoad,
) -> f64 {
    if !jp.has_torque_hook() {
        return 0.0;
    }
    let servo = servo_torque(m, jp, ctrl, q, qd);
    let sign = (qd / FRICTION_EPS).tanh();
    let mut tau = 0.0;
    if let Some([e, sat, vl]) = jp.torque_line {
        let hi = (sat * (1.0 - qd / vl)).clamp(0.0, e);
        let lo = (sat * (-1.0 - qd / vl)).clamp(-e, 0.0);
        tau += servo.clamp(lo, hi) - servo;
    }
    if let Some([fs, fd, vs]) = jp.stribeck {
        let budget = fd + (fs - fd) * (-(qd / vs).powi(2)).exp();
        let driving = servo + tau + load.passive - load.bias;
        let stop = -load.inertia * qd / load.dt.max(1e-9) - driving;
        tau += stop.clamp(-budget, budget);
    }
    if let Some([f0, k]) = jp.load_friction {
        tau -= sign * (f0 + k * servo.abs());
    }
    tau
}

#[cfg(test)]
mod tests {
    use super::*;

    fn joints() -> Vec<String> {
        vec!["left_knee".into(), "right_knee".into(), "hip".into()]
    }

    #[test]
    fn spec_parsing() {
        let h = parse("armature@*knee=0.05;action_delay=0.012", &joints()).unwrap();
        assert_eq!(h.len(), 5);
        assert_eq!(
            h[0],
            Hidden { effect: "armature", joint: "left_knee".into(), params: vec![0.05] }
        );
        assert_eq!(h[4].joint, "hip");
        // Missing parameters take the effect's defaults (stribeck: v_stribeck 0.1).
        let s = parse("stribeck_friction@hip=0.3,0.1", &joints()).unwrap();
        assert_eq!(s[0].params, vec![0.3, 0.1, 0.1]);
        assert!(parse("none", &joints()).unwrap().is_empty());
        assert!(parse("", &joints()).unwrap().is_empty());
        for bad in [
            "armature@nothing=1",
            "bogus=1",
            "armature=1,2",
            "armature=x",
            "armature=-1",
            "gain_error=0,1",
            "armature",
            "action_delay=2",
            "armature=1;armature@hip=2",
        ] {
            assert!(parse(bad, &joints()).is_err(), "{bad}");
        }
    }

    /// Inside the play the servos get the control at which they apply no force (kp and kv terms
    /// both); beyond it the command moved by the half play, and the rotor, once it has crossed
    /// the play, hits the flank with an impulse.
    #[test]
    fn play_has_no_servo_force_inside_and_a_rotor_that_crosses_it() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut map = crate::model::source::SourceMap::default();
        let robot =
            crate::model::load(&mut map, &root.join("fixtures/gap/arm3.xml"), None).unwrap();
        let hidden =
            [Hidden { effect: "backlash", joint: "elbow_pitch".into(), params: vec![0.04] }];
        let real = real_robot(&robot, &["elbow_pitch".to_string()], &hidden).unwrap();
        let (m, jp) = (&real.model, &real.joints[0]);
        let servo = |c: f64, q: f64, qd: f64| servo_torque(m, jp, &vec![c; jp.servos.len()], q, qd);
        // Inside the play (error 0.01 < 0.02), the link moving: no servo force.
        let mut p = Play::default();
        let (c, imp) = p.step(m, jp, (0.31, 0.3, 0.5), 0.05);
        assert!(servo(c, 0.3, 0.5).abs() < 1e-9 && imp == 0.0, "{c} {imp}");
        // Far beyond the flank: the command moved by the half play.
        let mut p = Play::default();
        let (c, imp) = p.step(m, jp, (0.5, 0.3, 0.0), 0.05);
        assert!((c - 0.48).abs() < 1e-12 && imp == 0.0, "{c} {imp}");
        // A command step of 0.1 from inside the play: the rotor crosses the gap, then hits.
        let mut p = Play::default();
        p.step(m, jp, (0.0, 0.0, 0.0), 0.05);
        let mut hit = None;
        for k in 0..200 {
            let (_, imp) = p.step(m, jp, (0.1, 0.0, 0.0), 0.05);
            if imp != 0.0 {
                hit = Some((k, imp));
                break;
            }
        }
        let (k, imp) = hit.expect("the rotor reaches the flank");
        assert!(k > 0 && imp > 0.0, "step {k}, impulse {imp}");
    }
}
