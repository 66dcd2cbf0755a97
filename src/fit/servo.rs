//! Dynamixel XL330 servo model as an [`ActuatorHook`]: the documented firmware position law with
//! its real PWM saturation, plus switchable candidate physics (armature, Coulomb, viscous,
//! Stribeck, load-dependent friction, action delay, back-EMF braking when torque is off).
//!
//! Firmware law (public facts of the BAM project, see `../shared/data/README.md`):
//! ```text
//! duty = clip(kp · error_gain · (goal − q), −1, 1)     error_gain = (4096/2π)/(256·885)
//! V    = vin · duty
//! τ_m  = (kt / R) · (V − kt · q̇)
//! ```
//! With `torque_enable` false the H-bridge is off: `τ_m = −β · (kt²/R) · q̇`, where β = 0 is a
//! coasting (open) bridge and β = 1 a shorted one (full back-EMF braking); β is an effect the
//! data may select ([`Effect::OffBrake`]).
//!
//! Friction: the friction budget of a step is
//! ```text
//! F = Fc + Fs_extra · exp(−(q̇/v_s)²) + μ_m · |τ_m| + μ_e · |τ_ext|
//! ```
//! (Coulomb, Stribeck, load-dependent on the motor torque and on the external — gravity —
//! torque). It is applied implicitly so that stiction is robust: the torque `τ_stop` that would
//! bring q̇ to exactly zero at the end of the (semi-implicit Euler) step is computed from the
//! joint inertia and the other torques, and the friction torque is `clamp(τ_stop, −F, F)`. A
//! moving joint thus gets `−F · sign(q̇)`; a joint whose other torques are below `F` is held,
//! and friction never reverses the motion within a step. Viscous friction `−Fv · q̇` is separate.
//!
//! Armature (the motor's reflected inertia) is MuJoCo-native: [`model_with_armature`] returns a
//! copy of the rig model with `dof_armature` set; the hook only needs its value for `τ_stop`.

use std::collections::VecDeque;

use mujoco_rs::prelude::*;

use crate::model::{Robot, mj};
use crate::sim2real::bam::{XL330_ERROR_GAIN, XL330_KT, XL330_R};
use crate::sim2real::recording::Recording;
use crate::sim2real::replay::{
    ActuatorHook, Episode, ReplayError, ReplayOptions, Replayer, StepIo,
};

/// Standard gravity used for the external (gravity) torque of the pendulum rig.
pub const G: f64 = 9.81;

/// All parameters of the servo model. Effects that are off have their neutral value (0, or the
/// nominal motor constants).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ServoParams {
    /// Firmware P gain (firmware units, 100…800 in the BAM logs).
    pub kp_firmware: f64,
    /// Supply voltage [V].
    pub vin: f64,
    /// Motor torque constant [N·m/A] (also the back-EMF constant).
    pub kt: f64,
    /// Motor resistance [Ω].
    pub r: f64,
    /// Reflected rotor inertia [kg·m²] (set in the model copy, see [`model_with_armature`]).
    pub armature: f64,
    /// Coulomb friction [N·m].
    pub coulomb: f64,
    /// Viscous friction [N·m·s/rad].
    pub viscous: f64,
    /// Stribeck: static friction in excess of Coulomb [N·m] …
    pub stribeck_extra: f64,
    /// … and its velocity scale v_s [rad/s].
    pub stribeck_vs: f64,
    /// Load-dependent friction: fraction of |τ_motor| added to the friction budget.
    pub load_motor: f64,
    /// Load-dependent friction: fraction of |τ_external| (gravity) added to the budget.
    pub load_ext: f64,
    /// Action delay [s]: the firmware acts on the goal of `t − delay`.
    pub delay: f64,
    /// Back-EMF braking fraction β when torque is off (0 coast … 1 shorted bridge).
    pub off_brake: f64,
    /// Rigid inertia of the link about the joint [kg·m²] (pendulum: m·l²).
    pub link_inertia: f64,
    /// Amplitude of the external torque, τ_ext = −mgl · sin q [N·m] (pendulum: m·g·l).
    pub mgl: f64,
}

impl ServoParams {
    /// Nominal XL330 (BAM's kt, R), no friction, no armature, no delay, coasting when off.
    pub fn nominal(kp_firmware: f64, vin: f64, mass: f64, length: f64) -> Self {
        ServoParams {
            kp_firmware,
            vin,
            kt: XL330_KT,
            r: XL330_R,
            armature: 0.0,
            coulomb: 0.0,
            viscous: 0.0,
            stribeck_extra: 0.0,
            stribeck_vs: 0.1,
            load_motor: 0.0,
            load_ext: 0.0,
            delay: 0.0,
            off_brake: 0.0,
            link_inertia: mass * length * length,
            mgl: mass * G * length,
        }
    }

    /// Nominal parameters for a BAM recording (meta `kp`, `vin`, `mass`, `length`).
    pub fn for_recording(rec: &Recording) -> Option<Self> {
        let get = |k: &str| rec.meta.get(k).and_then(|v| v.parse::<f64>().ok());
        Some(Self::nominal(get("kp")?, get("vin")?, get("mass")?, get("length")?))
    }

    /// Motor torque for a goal error, joint velocity and torque-enable state.
    pub fn motor_torque(&self, error: f64, qd: f64, enabled: bool) -> f64 {
        if enabled {
            let duty = (self.kp_firmware * XL330_ERROR_GAIN * error).clamp(-1.0, 1.0);
            (self.kt / self.r) * (self.vin * duty - self.kt * qd)
        } else {
            -self.off_brake * (self.kt * self.kt / self.r) * qd
        }
    }

    /// Friction budget F ≥ 0 (Coulomb + Stribeck + load-dependent terms).
    pub fn friction_budget(&self, qd: f64, tau_motor: f64, tau_ext: f64) -> f64 {
        let mut f =
            self.coulomb + self.load_motor * tau_motor.abs() + self.load_ext * tau_ext.abs();
        if self.stribeck_extra > 0.0 && self.stribeck_vs > 0.0 {
            let x = qd / self.stribeck_vs;
            f += self.stribeck_extra * (-x * x).exp();
        }
        f.max(0.0)
    }
}

/// The servo model as a replay hook for one recorded joint (index 0). Replaces the joint's
/// MuJoCo actuator: the hook's `tau` is the whole motor + friction torque (gravity and armature
/// stay with MuJoCo).
#[derive(Debug, Clone)]
pub struct ServoHook {
    pub p: ServoParams,
    dt: f64,
    /// (time, goal) history for the action delay.
    hist: VecDeque<(f64, f64)>,
}

impl ServoHook {
    pub fn new(p: ServoParams) -> Self {
        ServoHook { p, dt: 0.001, hist: VecDeque::new() }
    }

    /// Goal at `t − delay`, linearly interpolated in the per-step goal history (so the model is
    /// smooth in the delay); the first goal before the history starts.
    fn delayed_goal(&mut self, t: f64, goal: f64) -> f64 {
        if self.p.delay <= 0.0 {
            return goal;
        }
        self.hist.push_back((t, goal));
        let tq = t - self.p.delay;
        // Keep the newest entry at or before tq and everything after it.
        while self.hist.len() >= 2 && self.hist[1].0 <= tq {
            self.hist.pop_front();
        }
        let (t0, g0) = self.hist[0];
        if tq <= t0 || self.hist.len() < 2 {
            return g0;
        }
        let (t1, g1) = self.hist[1];
        g0 + (g1 - g0) * (tq - t0) / (t1 - t0)
    }

    /// Joint torque (motor + viscous + friction) for one step; gravity is not included.
    pub fn torque(&mut self, t: f64, q: f64, qd: f64, goal: f64, enabled: bool) -> f64 {
        let p = self.p;
        let g = self.delayed_goal(t, goal);
        let tau_m = p.motor_torque(g - q, qd, enabled);
        let tau_ext = -p.mgl * q.sin();
        let tau_v = -p.viscous * qd;
        let budget = p.friction_budget(qd, tau_m, tau_ext);
        let tau_f = if budget > 0.0 {
            let inertia = p.link_inertia + p.armature;
            // Torque that stops the joint exactly at the end of this semi-implicit Euler step.
            let tau_stop = -inertia * qd / self.dt - (tau_m + tau_ext + tau_v);
            tau_stop.clamp(-budget, budget)
        } else {
            0.0
        };
        tau_m + tau_v + tau_f
    }
}

impl ActuatorHook for ServoHook {
    fn reset(&mut self, _joints: &[String], dt: f64) {
        self.dt = dt;
        self.hist.clear();
    }
    fn replaces_actuator(&self, _joint_idx: usize) -> bool {
        true
    }
    fn before_step(
        &mut self,
        t: f64,
        _joint_idx: usize,
        q: f64,
        qd: f64,
        q_target: f64,
        out: &mut StepIo,
    ) {
        out.tau = self.torque(t, q, qd, q_target, out.enabled);
    }
}

/// Copy of `robot.mj` with every DoF's armature set to `armature` (the rig has one DoF).
pub fn model_with_armature(robot: &Robot, armature: f64) -> MjModel {
    let mut m = robot.mj.clone();
    let nv = mj::raw(&m).nv as usize;
    for d in 0..nv {
        mj::set_armature(&mut m, d, armature);
    }
    m
}

/// Replays `rec` on the rig with the servo model `p` (armature in a model copy, the rest in
/// the hook).
pub fn simulate(robot: &Robot, rec: &Recording, p: &ServoParams) -> Result<Episode, ReplayError> {
    let model = model_with_armature(robot, p.armature);
    let rp = Replayer::with_model(robot, &model);
    let mut hook = ServoHook::new(*p);
    rp.replay(rec, &ReplayOptions::default(), Some(&mut hook))
}

// ------------------------------------------------------------------ effects

/// One switchable piece of candidate physics, with its parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
pub enum Effect {
    /// Reflected rotor inertia (MuJoCo `dof_armature`).
    Armature,
    /// Coulomb friction Fc.
    Coulomb,
    /// Viscous friction Fv.
    Viscous,
    /// Stribeck static excess and velocity scale.
    Stribeck,
    /// Friction growing with |τ_motor|.
    LoadMotor,
    /// Friction growing with |τ_external| (gravity).
    LoadExternal,
    /// Action delay on the goal.
    Delay,
    /// Back-EMF braking when torque is off.
    OffBrake,
    /// Refit of the motor constants kt, R.
    Motor,
}

/// A parameter of an effect: name, unit, bounds and starting value.
#[derive(Debug, Clone, Copy)]
pub struct ParamSpec {
    pub name: &'static str,
    pub unit: &'static str,
    pub lo: f64,
    pub hi: f64,
    pub init: f64,
    /// Value at which the effect is absent (adding the effect at this value changes nothing).
    pub neutral: f64,
}

const fn ps(name: &'static str, unit: &'static str, lo: f64, hi: f64, init: f64) -> ParamSpec {
    ParamSpec { name, unit, lo, hi, init, neutral: lo }
}

const fn psn(
    name: &'static str,
    unit: &'static str,
    lo: f64,
    hi: f64,
    init: f64,
    neutral: f64,
) -> ParamSpec {
    ParamSpec { name, unit, lo, hi, init, neutral }
}

impl Effect {
    pub const ALL: [Effect; 9] = [
        Effect::Armature,
        Effect::Coulomb,
        Effect::Viscous,
        Effect::Stribeck,
        Effect::LoadMotor,
        Effect::LoadExternal,
        Effect::Delay,
        Effect::OffBrake,
        Effect::Motor,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Effect::Armature => "armature",
            Effect::Coulomb => "coulomb",
            Effect::Viscous => "viscous",
            Effect::Stribeck => "stribeck",
            Effect::LoadMotor => "load_motor",
            Effect::LoadExternal => "load_ext",
            Effect::Delay => "delay",
            Effect::OffBrake => "off_brake",
            Effect::Motor => "motor_kt_r",
        }
    }

    pub fn is_friction(self) -> bool {
        matches!(
            self,
            Effect::Coulomb
                | Effect::Viscous
                | Effect::Stribeck
                | Effect::LoadMotor
                | Effect::LoadExternal
        )
    }

    pub fn params(self) -> &'static [ParamSpec] {
        match self {
            Effect::Armature => {
                const P: &[ParamSpec] = &[ps("armature", "kg·m²", 0.0, 0.03, 0.003)];
                P
            }
            Effect::Coulomb => {
                const P: &[ParamSpec] = &[ps("Fc", "N·m", 0.0, 0.3, 0.03)];
                P
            }
            Effect::Viscous => {
                const P: &[ParamSpec] = &[ps("Fv", "N·m·s/rad", 0.0, 0.5, 0.02)];
                P
            }
            Effect::Stribeck => {
                const P: &[ParamSpec] = &[
                    ps("Fs-Fc", "N·m", 0.0, 0.3, 0.03),
                    psn("v_s", "rad/s", 0.005, 1.0, 0.1, 0.1),
                ];
                P
            }
            Effect::LoadMotor => {
                const P: &[ParamSpec] = &[ps("mu_motor", "", 0.0, 1.0, 0.05)];
                P
            }
            Effect::LoadExternal => {
                const P: &[ParamSpec] = &[ps("mu_ext", "", 0.0, 1.0, 0.05)];
                P
            }
            Effect::Delay => {
                const P: &[ParamSpec] = &[ps("delay", "s", 0.0, 0.05, 0.005)];
                P
            }
            Effect::OffBrake => {
                const P: &[ParamSpec] = &[ps("beta_off", "", 0.0, 1.0, 0.5)];
                P
            }
            Effect::Motor => {
                const P: &[ParamSpec] = &[
                    psn("kt", "N·m/A", 0.2, 0.8, XL330_KT, XL330_KT),
                    psn("R", "Ω", 2.0, 10.0, XL330_R, XL330_R),
                ];
                P
            }
        }
    }

    /// Writes this effect's parameter values (`v.len() == self.params().len()`) into `p`.
    pub fn apply(self, p: &mut ServoParams, v: &[f64]) {
        match self {
            Effect::Armature => p.armature = v[0],
            Effect::Coulomb => p.coulomb = v[0],
            Effect::Viscous => p.viscous = v[0],
            Effect::Stribeck => {
                p.stribeck_extra = v[0];
                p.stribeck_vs = v[1];
            }
            Effect::LoadMotor => p.load_motor = v[0],
            Effect::LoadExternal => p.load_ext = v[0],
            Effect::Delay => p.delay = v[0],
            Effect::OffBrake => p.off_brake = v[0],
            Effect::Motor => {
                p.kt = v[0];
                p.r = v[1];
            }
        }
    }
}

/// A set of effects and the flat parameter vector they use (in effect order).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct EffectSet(pub Vec<Effect>);

impl EffectSet {
    pub fn specs(&self) -> Vec<ParamSpec> {
        self.0.iter().flat_map(|e| e.params().iter().copied()).collect()
    }
    pub fn n_params(&self) -> usize {
        self.0.iter().map(|e| e.params().len()).sum()
    }
    /// `base` with this set's parameter values `x` applied.
    pub fn apply(&self, base: &ServoParams, x: &[f64]) -> ServoParams {
        let mut p = *base;
        let mut k = 0;
        for e in &self.0 {
            let n = e.params().len();
            e.apply(&mut p, &x[k..k + n]);
            k += n;
        }
        p
    }
    pub fn names(&self) -> String {
        if self.0.is_empty() {
            return "(nominal)".into();
        }
        self.0.iter().map(|e| e.name()).collect::<Vec<_>>().join("+")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p0() -> ServoParams {
        ServoParams::nominal(400.0, 7.4, 0.49, 0.1)
    }

    #[test]
    fn duty_saturates() {
        let p = p0();
        let big = p.motor_torque(3.0, 0.0, true);
        assert!((big - 7.4 * XL330_KT / XL330_R).abs() < 1e-12);
        let small = p.motor_torque(0.01, 0.0, true);
        assert!((small - crate::sim2real::bam::xl330_kp_si(400.0, 7.4) * 0.01).abs() < 1e-12);
        assert_eq!(p.motor_torque(1.0, 0.0, false), 0.0);
    }

    #[test]
    fn stiction_holds_and_never_reverses() {
        let mut p = p0();
        p.coulomb = 0.6; // larger than the gravity torque at 0.5 rad (0.23 N·m)
        p.kp_firmware = 0.0;
        let mut h = ServoHook::new(p);
        h.reset(&[], 0.001);
        // At rest at 0.5 rad with the motor off: friction cancels gravity exactly.
        let tau = h.torque(0.0, 0.5, 0.0, 0.5, false);
        assert!((tau - p.mgl * 0.5f64.sin()).abs() < 1e-12, "{tau}");
        // Slowly moving: friction stops it but does not push it backwards.
        let qd = 1e-4;
        let tau = h.torque(0.0, 0.5, qd, 0.5, false);
        let acc = (tau - p.mgl * 0.5f64.sin()) / p.link_inertia;
        assert!((qd + acc * 0.001).abs() < 1e-12);
        // Fast: full Coulomb against the motion.
        let tau = h.torque(0.0, 0.0, 5.0, 0.0, false);
        assert!((tau + 0.6).abs() < 1e-12);
    }

    #[test]
    fn delay_holds_old_goal() {
        let mut p = p0();
        p.delay = 0.0105;
        let mut h = ServoHook::new(p);
        h.reset(&[], 0.001);
        let mut g = 0.0;
        for k in 0..30 {
            let t = k as f64 * 0.001;
            g = h.delayed_goal(t, t);
        }
        assert!((g - 0.0185).abs() < 1e-9, "{g}");
    }
}
