//! Probe `ring-down`: one joint displaced from its spring's rest position and released, on a
//! fixed test stand, to measure how long its spring rings.
//!
//! * Drives: nothing. Every other DoF frozen (the joint sees its own row of MuJoCo's mass
//!   matrix), contacts and gravity off, so the joint swings about its spring reference
//!   (`springref`, MuJoCo's `qpos_spring`). Released from the rest position + 0.1 rad (or a
//!   quarter of its range, towards the side with more room).
//! * Measures: the oscillation's period, the amplitude after up to 20 periods relative to the
//!   release amplitude, the damping ratio that decay implies (logarithmic decrement), and the
//!   time until the amplitude falls below 10 % of the release (or that it never did).
//! * Preconditions it records: no active equality constraint acts on the joint on the stand
//!   ([`equality_on`]: with the other DoFs frozen a closed loop is rigid, and the constraint's
//!   softness, not the spring, decides the motion); the released joint moved (a closed loop or
//!   an equality can hold it still); the spring's period spans at least [`MIN_STEPS_PER_PERIOD`] timesteps (else
//!   the integrator, not the model's damping, decides the decay).
//! * Used by `passive-joint-spring` to *measure* a spring joint with no damping (a fact of the
//!   file): how long it rings. It never refutes that fact.
//! * Budget: 20 undamped periods, at least 2 s and at most 10 s, at the model's timestep.

use super::bench::{self, Bench, Setup};
use crate::lint::Loaded;
use crate::model::Robot;

/// The probe: a released spring joint (key: the joint's id).
pub struct RingDown;

impl super::Probe for RingDown {
    const NAME: &'static str = "ring-down";
    const UNAVAILABLE: &'static str = "joint is not a scalar joint with a spring";
    type Key = usize;
    fn steps(out: &Ring) -> usize {
        out.steps
    }
    type Output = Ring;
    fn run(l: &Loaded, joint: usize) -> Option<Ring> {
        run(&l.robot, joint)
    }
}

/// Fewest timesteps per oscillation period for a ring-down to be resolved.
pub const MIN_STEPS_PER_PERIOD: f64 = 10.0;

#[derive(Debug, Clone, Default)]
pub struct Ring {
    /// The model's timestep, s.
    pub dt: f64,
    /// 2π·√(I/k) from the stiffness and the joint's row of the mass matrix, s.
    pub undamped_period: f64,
    pub steps: usize,
    pub stiffness: f64,
    /// Release displacement from the spring's rest position, rad or m.
    pub release: f64,
    /// Largest |q − rest| over the run, rad or m.
    pub max_motion: f64,
    /// Largest |q − release position| over the run, rad or m (0: the joint did not move).
    pub moved: f64,
    /// Mean interval between successive maxima, s (NaN without two maxima).
    pub period: f64,
    /// Number of periods simulated.
    pub periods: f64,
    /// Amplitude of the last period over the release amplitude.
    pub amplitude_ratio: f64,
    /// Damping ratio implied by the decay (logarithmic decrement over the run).
    pub zeta: f64,
    /// Time until the amplitude stays below 10 % of the release, s; None: it never did.
    pub ring_time: Option<f64>,
    /// Simulated time, s.
    pub duration: f64,
    /// An active equality constraint that acts on the joint on the stand (name, or `#id`):
    /// with every other DoF frozen it holds a closed loop rigid, so the constraint's own
    /// softness and damping, not the spring's, decide the motion.
    pub held_by: Option<String>,
}

/// The first active equality constraint that acts on `joint` when every other DoF is frozen: a
/// connect or weld between a body the joint moves (its body and that body's descendants) and
/// one it does not, a joint equality naming it, or a tendon equality whose tendon passes the
/// joint or joins sites on a moved and an unmoved body.
pub fn equality_on(robot: &Robot, joint: usize) -> Option<String> {
    let j = robot.joints.get(joint)?;
    let m = &robot.mj;
    let moved = |mut b: usize| {
        for _ in 0..=robot.bodies.len() {
            if b == j.body {
                return true;
            }
            let p = robot.bodies.get(b).map_or(0, |x| x.parent);
            if p == b || b == 0 {
                return false;
            }
            b = p;
        }
        false
    };
    let site_body = |s: i32| usize::try_from(s).ok().and_then(|s| m.site_bodyid().get(s).copied());
    // mjtObj: body 1, site 6.
    let obj_body = |ty: i32, id: i32| match ty {
        6 => site_body(id).and_then(|b| usize::try_from(b).ok()),
        _ => usize::try_from(id).ok(),
    };
    let (types, active) = (m.eq_objtype(), m.eq_active0());
    let (tadr, tnum, wtype, wobj) = (m.tendon_adr(), m.tendon_num(), m.wrap_type(), m.wrap_objid());
    robot.equalities.iter().find_map(|e| {
        if !active.get(e.id).is_some_and(|&a| a) {
            return None;
        }
        let acts = match e.etype {
            // connect, weld
            0 | 1 => {
                let ty = types.get(e.id).map_or(1, |&t| t as i32);
                let b1 = obj_body(ty, e.obj1).map(moved);
                // obj2 -1: the world.
                let b2 = if e.obj2 < 0 { Some(false) } else { obj_body(ty, e.obj2).map(moved) };
                matches!((b1, b2), (Some(x), Some(y)) if x != y)
            }
            // joint
            2 => e.obj1 == joint as i32 || e.obj2 == joint as i32,
            // tendon: its path passes the joint (mjWRAP_JOINT 1) or sites on both sides
            3 => [e.obj1, e.obj2].iter().any(|&t| {
                let Ok(t) = usize::try_from(t) else { return false };
                let (Some(&a), Some(&n)) = (tadr.get(t), tnum.get(t)) else { return false };
                let (a, n) = (a.max(0) as usize, n.max(0) as usize);
                let mut sides = [false, false];
                for w in a..a + n {
                    let (Some(&ty), Some(&id)) = (wtype.get(w), wobj.get(w)) else { continue };
                    match ty as i32 {
                        1 if id == joint as i32 => return true,
                        // mjWRAP_SITE 3
                        3 => {
                            if let Some(b) = site_body(id).and_then(|b| usize::try_from(b).ok()) {
                                sides[usize::from(moved(b))] = true;
                            }
                        }
                        _ => {}
                    }
                }
                sides[0] && sides[1]
            }),
            _ => false,
        };
        acts.then(|| {
            if !e.name.is_empty() {
                return format!("`{}`", e.name);
            }
            let ty = types.get(e.id).map_or(1, |&t| t as i32);
            let body = |o: i32| {
                if o < 0 {
                    "world".to_string()
                } else {
                    obj_body(ty, o).map_or_else(String::new, |b| robot.body_name(b).to_string())
                }
            };
            match e.etype {
                0 | 1 => format!(
                    "{} `{}`–`{}`",
                    if e.etype == 0 { "connect" } else { "weld" },
                    body(e.obj1),
                    body(e.obj2)
                ),
                _ => format!("#{}", e.id),
            }
        })
    })
}

pub fn run(robot: &Robot, joint: usize) -> Option<Ring> {
    let j = robot.joints.get(joint)?;
    if !j.is_scalar() || !(j.stiffness > 0.0) {
        return None;
    }
    let b = Bench::new(
        robot,
        Setup {
            isolate_dof: Some(j.dofadr),
            no_contact: true,
            no_gravity: true,
            ..Default::default()
        },
    )?;
    let mut d = b.data(robot);
    let dt = b.dt();
    let rest = b.m.qpos_spring().get(j.qposadr).copied().unwrap_or(0.0);
    let inertia = robot.key.m_diag.get(j.dofadr).copied().unwrap_or(f64::NAN);
    let omega = (j.stiffness / inertia).sqrt();
    let t_period =
        if omega.is_finite() && omega > 0.0 { 2.0 * std::f64::consts::PI / omega } else { 1.0 };
    let duration = (20.0 * t_period).clamp(2.0, 10.0);
    let n = ((duration / dt).ceil() as usize).max(10);
    let mut delta: f64 = 0.1;
    if j.limited {
        let room_hi = j.range[1] - rest;
        let room_lo = rest - j.range[0];
        delta = delta.min(0.25 * room_hi.max(room_lo).max(0.0));
        if room_lo > room_hi {
            delta = -delta;
        }
    }
    {
        let q = d.qpos_mut();
        q[j.qposadr] = rest + delta;
        let v = d.qvel_mut();
        v[j.dofadr] = 0.0;
    }
    d.forward();
    let mut out = Ring {
        dt,
        stiffness: j.stiffness,
        release: delta.abs(),
        held_by: equality_on(robot, joint),
        ..Default::default()
    };
    out.undamped_period = if omega.is_finite() && omega > 0.0 { t_period } else { f64::NAN };
    let mut x = Vec::with_capacity(n);
    for _ in 0..n {
        b.step(&mut d);
        out.steps += 1;
        let q = bench::qpos(&d, j.qposadr);
        if !q.is_finite() {
            break;
        }
        x.push(q - rest);
    }
    out.duration = x.len() as f64 * dt;
    out.max_motion = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    out.moved = x.iter().fold(0.0f64, |m, v| m.max((v - delta).abs()));
    let peaks: Vec<(usize, f64)> = (1..x.len().saturating_sub(1))
        .filter(|&i| x[i].abs() >= x[i - 1].abs() && x[i].abs() > x[i + 1].abs())
        .filter(|&i| x[i].signum() == delta.signum())
        .map(|i| (i, x[i].abs()))
        .collect();
    let a0 = delta.abs().max(1e-12);
    out.period = if peaks.len() >= 2 {
        (peaks[peaks.len() - 1].0 - peaks[0].0) as f64 * dt / (peaks.len() - 1) as f64
    } else {
        f64::NAN
    };
    out.periods = if out.period.is_finite() { out.duration / out.period } else { 0.0 };
    let last = peaks.last().map(|p| p.1).unwrap_or(out.max_motion);
    out.amplitude_ratio = last / a0;
    out.zeta = match peaks.len() {
        k if k >= 2 && last > 0.0 => {
            let dl = (a0 / last).ln() / (k as f64);
            dl / (4.0 * std::f64::consts::PI.powi(2) + dl * dl).sqrt()
        }
        _ => f64::NAN,
    };
    // Ring time: after the last sample whose |x| is at least 10 % of the release.
    out.ring_time = match x.iter().rposition(|v| v.abs() >= 0.1 * a0) {
        Some(i) if i + 1 >= x.len() => None,
        Some(i) => Some((i + 1) as f64 * dt),
        None => Some(0.0),
    };
    Some(out)
}
