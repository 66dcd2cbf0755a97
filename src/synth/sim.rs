//! The physics loop of the simulated real robot: its own MuJoCo stepping (no replay code).
//!
//! 1. Start at the keyframe (or qpos0) with every recorded joint at its first command, at rest;
//!    a floating base is pinned at the keyframe pose raised by `suspend_m` (a test stand).
//! 2. Settle for `settle_s` at the first command (not recorded).
//! 3. Run the control ticks; before every physics step each recorded joint's servo gets the mean
//!    over that step of the (delayed) zero-order-hold command, through the backlash play, and
//!    the per-step torques of the hidden effects go to `qfrc_applied`.
//! 4. The state at every sample time is the linear interpolation of the two physics steps that
//!    bracket it.

use mujoco_rs::prelude::*;

use super::clock::{Commands, US};
use super::truth::{RealRobot, step_torque, through_play};
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
    while next < samples_us.len() {
        let t = n as f64 * dt;
        {
            let ctrl = d.ctrl_mut();
            for (j, jp) in real.joints.iter().enumerate() {
                let mut u = cmds.mean(t - jp.delay_s, t + dt - jp.delay_s, j);
                if jp.half_play > 0.0 {
                    u = through_play(u, q0[j], jp.half_play);
                }
                for s in &jp.servos {
                    ctrl[s.id] = u;
                }
                tau[j] = step_torque(m, jp, u, q0[j], qd0[j]);
            }
            let qfrc = d.qfrc_applied_mut();
            for (jp, &t) in real.joints.iter().zip(&tau) {
                qfrc[jp.dof] = t;
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
