//! Probe `actuator-direction`: drive one actuator alone by a small positive command and record
//! which joints move and in which direction.
//!
//! * Drives: one actuator (position: target + 0.05 in actuator units; motor: +5 % of its force or
//!   control range), every other actuator held at the keyframe; floating base pinned, gravity and
//!   contacts off so only the actuator moves anything.
//! * Measures: displacement of every hinge/slide joint after 0.3 s; the actuator's force and the
//!   constraints (equalities, the target joint's range limit) that push at the end, so a target
//!   that did not move can say why.
//! * Confirms: a sign flip against the spec's `direction`, an actuator that moves nothing (only
//!   one with no target: a target that did not move leaves the claim untested).
//! * Budget: 0.3 s at the model's timestep.

use super::bench::{self, Bench, Setup};
use crate::lint::Loaded;
use crate::model::{ActuatorKind, Robot, mj};

/// The probe: one actuator driven alone (key: the actuator's id).
pub struct ActuatorDirection;

impl super::Probe for ActuatorDirection {
    const NAME: &'static str = "actuator-direction";
    const UNAVAILABLE: &'static str = "could not set up the bench";
    type Key = usize;
    fn steps(out: &Direction) -> usize {
        out.steps
    }
    type Output = Direction;
    fn run(l: &Loaded, actuator: usize) -> Option<Direction> {
        run(&l.robot, actuator)
    }
}

#[derive(Debug, Clone)]
pub struct Direction {
    pub steps: usize,
    /// (joint id, displacement in rad or m) for joints that moved more than 1e-4.
    pub moved: Vec<(usize, f64)>,
    /// The actuator's force at the end of the run (`actuator_force`, in its own units).
    pub actuator_force: f64,
    /// The constraints holding at the end of the run, in MuJoCo's row order: `equality `name``
    /// for an equality with a non-zero force, `range limit of `joint`` for the target joint's
    /// stop.
    pub holding: Vec<String>,
}

/// Displacement above which a joint is said to have moved [rad or m].
pub const MOVED: f64 = 1e-4;
/// Constraint or actuator force below which it is taken as zero [N or N·m].
const NO_FORCE: f64 = 1e-9;

pub fn run(robot: &Robot, act: usize) -> Option<Direction> {
    let a = robot.actuators.get(act)?;
    let b = Bench::new(
        robot,
        Setup { pin_base: true, no_contact: true, no_gravity: true, ..Default::default() },
    )?;
    let mut d = b.data(robot);
    let c0 = bench::ctrl(&d, act);
    let cmd = match a.kind {
        ActuatorKind::Position { .. } => c0 + 0.05,
        _ => {
            let span = if a.forcelimited {
                a.forcerange[1].abs().max(a.forcerange[0].abs()) / a.gear.abs().max(1e-9)
            } else if a.ctrllimited {
                (a.ctrlrange[1] - a.ctrlrange[0]).abs() / 2.0
            } else {
                1.0
            };
            c0 + 0.05 * span
        }
    };
    let q0: Vec<f64> = robot.joints.iter().map(|j| bench::qpos(&d, j.qposadr)).collect();
    let n = (0.3 / b.dt()).ceil() as usize;
    for _ in 0..n {
        bench::set_ctrl(&mut d, act, cmd);
        b.step(&mut d);
    }
    let moved = robot
        .joints
        .iter()
        .filter(|j| j.is_scalar())
        .map(|j| (j.id, bench::qpos(&d, j.qposadr) - q0[j.id]))
        .filter(|(_, dq)| dq.abs() > MOVED || !dq.is_finite())
        .collect();
    let actuator_force = d.actuator_force().get(act).copied().unwrap_or(f64::NAN);
    let mut holding: Vec<String> = Vec::new();
    for (ty, id, f) in mj::constraint_forces(&d) {
        if f.abs() <= NO_FORCE {
            continue;
        }
        // mjtConstraint: 0 equality, 3 joint limit.
        let what = match ty {
            0 => robot.equalities.get(id as usize).map(|e| {
                if e.name.is_empty() {
                    format!("equality #{id}")
                } else {
                    format!("equality `{}`", e.name)
                }
            }),
            3 if id == a.target => {
                robot.joints.get(id as usize).map(|j| format!("range limit of `{}`", j.name))
            }
            _ => None,
        };
        if let Some(w) = what
            && !holding.contains(&w)
        {
            holding.push(w);
        }
    }
    Some(Direction { steps: n, moved, actuator_force, holding })
}
