//! Probe `limit-approach`: command one joint to the extreme of its actuator's control range and
//! record whether it reaches the hard stop.
//!
//! * Drives: the joint's position actuator to the end of its ctrlrange nearer the joint limit
//!   (both ends tried), other DoFs frozen, contacts off, gravity on.
//! * Measures: whether MuJoCo's joint-limit constraint becomes active with force, and the joint
//!   velocity at the first moment it does (the impact velocity).
//! * Confirms `soft-limits` when the commanded extreme drives the joint into the hard stop.
//! * Budget: 2 × 1 s at the model's timestep.

use super::bench::{self, Bench, Setup};
use crate::lint::Loaded;
use crate::model::{Robot, mj};

/// The probe: one actuator commanded to its ctrlrange extremes (key: the actuator's id).
pub struct LimitApproach;

impl super::Probe for LimitApproach {
    const NAME: &'static str = "limit-approach";
    const UNAVAILABLE: &'static str = "actuator does not drive a hinge or slide joint";
    type Key = usize;
    fn steps(out: &LimitHit) -> usize {
        out.steps
    }
    type Output = LimitHit;
    fn run(l: &Loaded, actuator: usize) -> Option<LimitHit> {
        run(&l.robot, actuator)
    }
}

#[derive(Debug, Clone)]
pub struct LimitHit {
    pub steps: usize,
    pub hit: bool,
    pub impact_velocity: f64,
    pub max_limit_force: f64,
}

pub fn run(robot: &Robot, act: usize) -> Option<LimitHit> {
    let a = robot.actuators.get(act)?;
    if a.target < 0 {
        return None;
    }
    let j = robot.joints.get(a.target as usize)?;
    if !j.is_scalar() {
        return None;
    }
    let b = Bench::new(
        robot,
        Setup { isolate_dof: Some(j.dofadr), no_contact: true, ..Default::default() },
    )?;
    let (lo, hi) = if a.ctrllimited {
        (a.ctrlrange[0], a.ctrlrange[1])
    } else {
        (j.range[0] * a.gear, j.range[1] * a.gear)
    };
    let mut out = LimitHit { steps: 0, hit: false, impact_velocity: 0.0, max_limit_force: 0.0 };
    for target in [lo, hi] {
        let mut d = b.data(robot);
        let n = (1.0 / b.dt()).ceil() as usize;
        let mut first = true;
        for _ in 0..n {
            bench::set_ctrl(&mut d, act, target);
            b.step(&mut d);
            out.steps += 1;
            for (ty, id, f) in mj::constraint_forces(&d) {
                if ty == 3 && id == j.id as i32 && f.abs() > 1e-9 {
                    if first {
                        out.impact_velocity =
                            out.impact_velocity.max(bench::qvel(&d, j.dofadr).abs());
                        first = false;
                    }
                    out.hit = true;
                    out.max_limit_force = out.max_limit_force.max(f.abs());
                }
            }
        }
    }
    Some(out)
}
