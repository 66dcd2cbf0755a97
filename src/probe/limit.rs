//! Probe `limit-approach`: command one joint to each end of its actuator's control range and
//! record where the joint goes and whether it meets a hard stop.
//!
//! * Drives: the joint's actuator to each end of its ctrlrange (the joint's range × gear when the
//!   actuator has no ctrlrange) for [`APPROACH_S`], other DoFs frozen, contacts off, gravity on;
//!   longer when the joint's own damping caps its speed (force limit / damping, the speed at
//!   which damping takes the whole force limit): twice the time to cover the distance at that
//!   speed, at most [`MAX_APPROACH_S`].
//! * Measures, per end: the commanded target referred to the joint, the joint position the run
//!   ends at, the smallest and largest position reached, whether MuJoCo's joint-limit
//!   constraint became active with force, and the joint velocity at its first activation
//!   (impact velocity).
//! * Preconditions it records for a soft-limit measurement: the joint has a hard stop; at each
//!   end the joint came within 5 % of its range of the commanded target (else the servo could
//!   not drive the command there, and the run says nothing about the stop).
//! * The soft-limit findings are facts of the file: the probe measures their consequence (the
//!   stop engaged, at what speed) and never refutes them.
//! * Budget: 2 × 1 s at the model's timestep (2 × 10 s at most for a damping-capped joint).

use super::bench::{self, Bench, Setup};
use crate::lint::Loaded;
use crate::model::{Robot, mj};

/// How long each end's run lasts, s.
pub const APPROACH_S: f64 = 1.0;
/// Longest run of one end, s, for a joint whose damping caps its speed.
pub const MAX_APPROACH_S: f64 = 10.0;

/// Seconds to give one end's run over `distance` (rad or m): [`APPROACH_S`], or twice the time
/// at the joint's damping-capped speed `force_limit / damping`, up to [`MAX_APPROACH_S`].
pub fn approach_seconds(distance: f64, force_limit: Option<f64>, damping: f64) -> f64 {
    let capped = match force_limit {
        Some(f) if f > 0.0 && damping > 0.0 => 2.0 * distance.abs() * damping / f,
        _ => 0.0,
    };
    if capped.is_finite() { capped.clamp(APPROACH_S, MAX_APPROACH_S) } else { APPROACH_S }
}

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

/// One end of the control range.
#[derive(Debug, Clone, Default)]
pub struct EndRun {
    /// Commanded target referred to the joint (ctrl / gear for a position servo), rad or m.
    pub target: f64,
    /// Joint position at the end of the run.
    pub reached: f64,
    /// Smallest and largest joint position of this end's run (the keyframe position included).
    pub q_lo: f64,
    pub q_hi: f64,
    pub hit: bool,
    pub impact_velocity: f64,
    pub max_limit_force: f64,
}

#[derive(Debug, Clone, Default)]
pub struct LimitHit {
    pub steps: usize,
    pub hit: bool,
    pub impact_velocity: f64,
    pub max_limit_force: f64,
    /// Smallest and largest joint position over both runs.
    pub q_min: f64,
    pub q_max: f64,
    /// The joint has a range (`limited`).
    pub stop_exists: bool,
    pub range: [f64; 2],
    /// The runs at the lower and upper end of the control range.
    pub ends: [EndRun; 2],
}

impl LimitHit {
    /// Where each end's run could get: the commanded target, or the hard stop in front of it.
    pub fn reachable(&self, k: usize) -> f64 {
        let t = self.ends[k].target;
        if self.stop_exists { t.clamp(self.range[0], self.range[1]) } else { t }
    }
    /// How far (rad or m) each end's run stayed from where it could get: 0 when the joint
    /// reached or passed it (a soft stop lets the joint pass its range a little).
    pub fn shortfall(&self) -> [f64; 2] {
        [0, 1].map(|k| {
            let goal = self.reachable(k);
            let e = &self.ends[k];
            if goal < e.q_lo {
                e.q_lo - goal
            } else if goal > e.q_hi {
                goal - e.q_hi
            } else {
                0.0
            }
        })
    }
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
        (a.ctrl_for_joint(j.range[0]), a.ctrl_for_joint(j.range[1]))
    };
    let g = if a.gear != 0.0 { a.gear } else { 1.0 };
    // The joint position a ctrl commands: a servo's setpoint over gear (ctrl / gear for a
    // `<position>`; a scaled servo's setpoint is gain/kp × ctrl).
    let target_of = |ctrl: f64| a.servo.map_or(ctrl, |s| s.setpoint(ctrl)) / g;
    let mut out = LimitHit {
        q_min: f64::INFINITY,
        q_max: f64::NEG_INFINITY,
        stop_exists: j.limited,
        range: j.range,
        ..Default::default()
    };
    let force_limit =
        crate::rules::limits::effort_limit_mismatch::joint_torque_limit(robot, j.id).map(|x| x.0);
    for (k, ctrl) in [lo, hi].into_iter().enumerate() {
        let mut d = b.data(robot);
        let q0 = bench::qpos(&d, j.qposadr);
        let secs = approach_seconds(target_of(ctrl) - q0, force_limit, j.damping);
        let n = (secs / b.dt()).ceil() as usize;
        let mut first = true;
        let mut end = EndRun { target: target_of(ctrl), q_lo: q0, q_hi: q0, ..Default::default() };
        for _ in 0..n {
            bench::set_ctrl(&mut d, act, ctrl);
            b.step(&mut d);
            out.steps += 1;
            let q = bench::qpos(&d, j.qposadr);
            if q.is_finite() {
                out.q_min = out.q_min.min(q);
                out.q_max = out.q_max.max(q);
                end.q_lo = end.q_lo.min(q);
                end.q_hi = end.q_hi.max(q);
            }
            for (ty, id, f) in mj::constraint_forces(&d) {
                if ty == 3 && id == j.id as i32 && f.abs() > 1e-9 {
                    if first {
                        end.impact_velocity = bench::qvel(&d, j.dofadr).abs();
                        first = false;
                    }
                    end.hit = true;
                    end.max_limit_force = end.max_limit_force.max(f.abs());
                }
            }
        }
        end.reached = bench::qpos(&d, j.qposadr);
        out.hit |= end.hit;
        out.impact_velocity = out.impact_velocity.max(end.impact_velocity);
        out.max_limit_force = out.max_limit_force.max(end.max_limit_force);
        out.ends[k] = end;
    }
    // Position servos only: a motor's "ctrl / gear" is a torque, not a target.
    if a.servo.is_none() {
        for e in &mut out.ends {
            e.target = f64::NAN;
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_damping_capped_joint_gets_the_time_to_cross() {
        // 150 N·m against 200 N·m·s/rad: 0.75 rad/s; 4.7 rad twice over takes 12.5 s: capped.
        assert_eq!(approach_seconds(4.7, Some(150.0), 200.0), MAX_APPROACH_S);
        // 28 N·m against 15 N·m·s/rad: 1.87 rad/s; 3 rad twice over: 3.2 s.
        assert!((approach_seconds(-3.0, Some(28.0), 15.0) - 2.0 * 3.0 * 15.0 / 28.0).abs() < 1e-12);
        // Fast joints, no damping or no force limit: the default second.
        assert_eq!(approach_seconds(1.0, Some(40.0), 1.0), APPROACH_S);
        assert_eq!(approach_seconds(3.0, None, 200.0), APPROACH_S);
        assert_eq!(approach_seconds(3.0, Some(150.0), 0.0), APPROACH_S);
    }
}
