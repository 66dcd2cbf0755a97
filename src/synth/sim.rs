//! The physics loop of the simulated real robot: its own MuJoCo stepping (no replay code).
//!
//! 1. Start at the keyframe (or qpos0) with every recorded joint at its first command, at rest;
//!    a floating base is pinned at the keyframe pose raised by `suspend_m` (a test stand).
//! 2. Settle for `settle_s` at the first command (not recorded).
//! 3. Run the control ticks; before every physics step each recorded joint's servo gets the mean
//!    over that step of the (delayed) zero-order-hold command, through the backlash play (a
//!    rotor behind it, `truth::Play`), and
//!    the per-step torques of the hidden effects go to `qfrc_applied`.
//! 4. The state at every sample time is the linear interpolation of the two physics steps that
//!    bracket it.

use mujoco_rs::prelude::*;

use super::clock::{Commands, US};
use super::truth::{JointPhysics, Play, RealRobot, StepLoad, step_torque};
use crate::model::{Robot, mj};

/// The floating base on a test stand: qpos address, dof address and the pinned pose.
#[derive(Debug, Clone, Copy)]
pub struct Stand {
    pub qposadr: usize,
    pub dofadr: usize,
    pub pose: [f64; 7],
}

/// True state at every sample time.
#[derive(Debug, Clone, Default)]
pub struct Trace {
    /// `q[j][i]`, `qd[j][i]`: joint j at sample i.
    pub q: Vec<Vec<f64>>,
    pub qd: Vec<Vec<f64>>,
}

/// Simulates one episode. `samples_us` must be sorted and ≥ 0.
pub fn run(
    robot: &Robot,
    real: &RealRobot,
    cmds: &Commands,
    samples_us: &[i64],
    settle_s: f64,
    stand: Option<Stand>,
) -> Result<Trace, String> {
    let m = &real.model;
    let r = mj::raw(m);
    let nu = r.nu as usize;
    let dt = r.opt.timestep;
    if !(dt > 0.0 && dt.is_finite()) {
        return Err(format!("model timestep {dt} is not a positive number"));
    }
    let nj = real.joints.len();
    let mut d = MjData::new(m);
    if let Some(k) = robot.key.key {
        d.reset_keyframe(k).map_err(|e| format!("keyframe {k}: {e:?}"))?;
    }
    {
        let qpos = d.qpos_mut();
        for (j, jp) in real.joints.iter().enumerate() {
            qpos[jp.qposadr] = cmds.of_tick(cmds.first, j);
        }
        d.qvel_mut().iter_mut().for_each(|v| *v = 0.0);
        if robot.key.key.is_none() && robot.key.ctrl.len() == nu {
            d.ctrl_mut().copy_from_slice(&robot.key.ctrl);
        }
    }
    let pin = |d: &mut MjData<&MjModel>| {
        if let Some(s) = stand {
            d.qpos_mut()[s.qposadr..s.qposadr + 7].copy_from_slice(&s.pose);
            d.qvel_mut()[s.dofadr..s.dofadr + 6].iter_mut().for_each(|v| *v = 0.0);
        }
    };
    pin(&mut d);
    d.forward();
    let read = |d: &MjData<&MjModel>, q: &mut Vec<f64>, qd: &mut Vec<f64>| {
        let (qpos, qvel) = (d.qpos(), d.qvel());
        q.clear();
        qd.clear();
        for jp in &real.joints {
            q.push(qpos[jp.qposadr]);
            qd.push(qvel[jp.dof]);
        }
    };
    let mut out = Trace {
        q: vec![Vec::with_capacity(samples_us.len()); nj],
        qd: vec![Vec::with_capacity(samples_us.len()); nj],
    };
    let n_settle = (settle_s / dt).round() as i64;
    let (mut q0, mut qd0, mut q1, mut qd1) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    read(&d, &mut q0, &mut qd0);
    let mut n = -n_settle;
    let mut next = 0usize;
    let emit = |out: &mut Trace, a: (&[f64], &[f64]), b: (&[f64], &[f64]), w: f64| {
        for j in 0..nj {
            out.q[j].push(a.0[j] + w * (b.0[j] - a.0[j]));
            out.qd[j].push(a.1[j] + w * (b.1[j] - a.1[j]));
        }
    };
    // A sample at the very start (no settle).
    while next < samples_us.len() && (samples_us[next] as f64) <= n as f64 * dt * US + 1e-6 {
        emit(&mut out, (&q0, &qd0), (&q0, &qd0), 0.0);
        next += 1;
    }
    let mut tau = vec![0.0; nj];
    let mut impact = vec![0.0; nj];
    let mut play = vec![Play::default(); nj];
    let mut acting = Vec::new();
    while next < samples_us.len() {
        let t = n as f64 * dt;
        {
            for (j, jp) in real.joints.iter().enumerate() {
                let mut u = cmds.mean(t - jp.delay_s, t + dt - jp.delay_s, j);
                if jp.half_play > 0.0 {
                    let dinv = d.q_ldiag_inv().get(jp.dof).copied().unwrap_or(0.0);
                    let inertia = if dinv > 0.0 { 1.0 / dinv } else { 0.0 };
                    (u, impact[j]) = play[j].step(m, jp, (u, q0[j], qd0[j]), inertia);
                }
                let ctrl = d.ctrl_mut();
                for s in &jp.servos {
                    ctrl[s.id] = u;
                }
            }
            for (j, jp) in real.joints.iter().enumerate() {
                if jp.has_torque_hook() {
                    acting_ctrl(m, &d, jp, &mut acting);
                    let dinv = d.q_ldiag_inv().get(jp.dof).copied().unwrap_or(0.0);
                    let load = StepLoad {
                        bias: d.qfrc_bias().get(jp.dof).copied().unwrap_or(0.0),
                        passive: d.qfrc_passive().get(jp.dof).copied().unwrap_or(0.0),
                        inertia: if dinv > 0.0 { 1.0 / dinv } else { 0.0 },
                        dt,
                    };
                    tau[j] = step_torque(m, jp, &acting, (q0[j], qd0[j]), &load);
                }
            }
            let qfrc = d.qfrc_applied_mut();
            for (j, jp) in real.joints.iter().enumerate() {
                qfrc[jp.dof] = tau[j] + impact[j];
            }
        }
        pin(&mut d);
        d.step();
        pin(&mut d);
        read(&d, &mut q1, &mut qd1);
        if !q1.iter().chain(&qd1).all(|x| x.is_finite()) {
            return Err(format!("the simulation diverged at t = {:.4} s (recording time)", t + dt));
        }
        n += 1;
        let t1 = n as f64 * dt;
        while next < samples_us.len() {
            let s = samples_us[next] as f64 / US;
            if s > t1 + 1e-12 {
                break;
            }
            let w = ((s - t) / dt).clamp(0.0, 1.0);
            emit(&mut out, (&q0, &qd0), (&q1, &qd1), w);
            next += 1;
        }
        std::mem::swap(&mut q0, &mut q1);
        std::mem::swap(&mut qd0, &mut qd1);
    }
    Ok(out)
}

/// The control each of the joint's servos acts on this step (after `ctrl` is set, before the
/// step): its `ctrl`, or for an actuator with a MuJoCo `delay` (the Asimov legs: 20 ms) the
/// value MuJoCo reads from its ctrl history, which is what the actuator force uses. A
/// torque-dependent effect (friction growing with the servo torque, a torque–speed line) must
/// see the torque the servo applies, not the one it is commanded to apply `delay` later.
fn acting_ctrl(m: &MjModel, d: &MjData<&MjModel>, jp: &JointPhysics, out: &mut Vec<f64>) {
    let (hist, delay) = (m.actuator_history(), m.actuator_delay());
    out.clear();
    for s in &jp.servos {
        let mut v = [d.ctrl()[s.id]];
        if hist[s.id][0] > 0 && delay[s.id] > 0.0 {
            let _ = d.read_ctrl_into(s.id, d.time(), hist[s.id][1], &mut v);
        }
        out.push(v[0]);
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::model::source::SourceMap;
    use crate::synth::truth::{real_robot, servo_torque};

    /// Over `steps` physics steps of a command that changes every step, the largest difference
    /// between the servo torque computed before the step from [`acting_ctrl`] and the one MuJoCo
    /// applies in it (gear × `actuator_force`), and the largest difference between the latter
    /// and the torque of the current command.
    fn applied_vs_computed(model: &str, joint: &str, steps: usize) -> (f64, f64) {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let robot =
            crate::model::load(&mut SourceMap::default(), &root.join(model), None).expect("model");
        let real = real_robot(&robot, &[joint.to_string()], &[]).expect("real robot");
        let (m, jp) = (&real.model, &real.joints[0]);
        assert!(!jp.servos.is_empty(), "{joint} has a position servo");
        let mut d = MjData::new(m);
        if let Some(k) = robot.key.key {
            d.reset_keyframe(k).expect("keyframe");
        }
        d.forward();
        let q_key = d.qpos()[jp.qposadr];
        let (mut acting, mut err, mut lag) = (Vec::new(), 0.0f64, 0.0f64);
        for k in 0..steps {
            let t = d.time();
            let u = q_key + 0.2 * (2.0 * std::f64::consts::PI * 3.0 * t).sin() + 1e-3 * k as f64;
            for s in &jp.servos {
                d.ctrl_mut()[s.id] = u;
            }
            let (q, qd) = (d.qpos()[jp.qposadr], d.qvel()[jp.dof]);
            acting_ctrl(m, &d, jp, &mut acting);
            let computed = servo_torque(m, jp, &acting, q, qd);
            let now = servo_torque(m, jp, &vec![u; jp.servos.len()], q, qd);
            d.step();
            let applied: f64 = jp.servos.iter().map(|s| s.gear * d.actuator_force()[s.id]).sum();
            err = err.max((computed - applied).abs());
            lag = lag.max((now - applied).abs());
        }
        (err, lag)
    }

    /// A torque-dependent hidden effect must see the torque the servo applies. The Asimov knee
    /// servo has a MuJoCo `delay` of 20 ms: the torque of the current command is off by
    /// newtons-metres from the applied one, the torque from the ctrl history is the applied
    /// one (before this, the synth's load-dependent friction used the current command while the
    /// actuator applied the one of 20 ms before).
    #[test]
    fn servo_torque_is_the_applied_one_on_a_delayed_actuator() {
        let (err, lag) = applied_vs_computed("models/asimov.xml", "left_knee", 300);
        assert!(err < 1e-9, "computed vs applied: {err} N·m");
        assert!(lag > 1.0, "the current command's torque is {lag} N·m off: no delay seen?");
    }

    /// Without a MuJoCo delay the acting control is the command itself.
    #[test]
    fn servo_torque_is_the_applied_one_without_delay() {
        let (err, lag) = applied_vs_computed("fixtures/gap/arm3.xml", "elbow_pitch", 300);
        assert!(err < 1e-9, "computed vs applied: {err} N·m");
        assert!(lag < 1e-9, "no delay, yet {lag} N·m");
    }
}
