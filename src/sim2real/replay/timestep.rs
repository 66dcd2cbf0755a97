//! Whether the model's timestep is fine enough for the recorded motion: the replay at a quarter
//! of the timestep against the replay at the model's own. A real robot moves in continuous
//! time; when the model's discretisation alone moves the replay by a good part of its gap to
//! the recordings, that part is no physics the model lacks (`fit` counts it in its floor:
//! `fit::select::Engine::discretisation_floor`). Measured on an independent simulator's
//! clean humanoid legs (kp 150–250 servos, `implicitfast`, 2 ms): recorded at 0.5 ms steps, the
//! 2 ms replay sat 1.40 mrad (MAE) from them against 0.59 at matched steps, and `fit` reported
//! a 0.6 ms action delay and kd × 1.007 on all twelve joints.

use serde::Serialize;

use crate::model::Robot;
use crate::model::mj;
use crate::sim2real::recording::Recording;

use super::{Episode, ReplayOptions, Replayer, replay_all};

/// Divisor of the timestep for the reference replay.
pub const REFINE: f64 = 4.0;

/// A joint's discretisation error next to its gap to the recordings.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct JointTimestep {
    pub name: String,
    /// Mean |q(timestep) − q(timestep / 4)| over the samples [rad].
    pub discretisation_mae: f64,
    /// Mean |q(timestep) − q recorded| [rad].
    pub gap_mae: f64,
}

/// [`timestep_check`]'s result.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct TimestepCheck {
    pub timestep: f64,
    pub fine_timestep: f64,
    pub per_joint: Vec<JointTimestep>,
}

/// Replays `recs` with the model at its timestep (or takes `base`, that replay already made,
/// one episode per recording) and at a quarter of it. `None` when either
/// replay fails or diverges, or the model has actuators with a `delay` (their history buffer
/// is sized for the model's timestep).
pub fn timestep_check(
    robot: &Robot,
    recs: &[Recording],
    opts: &ReplayOptions,
    base: Option<&[Episode]>,
) -> Option<TimestepCheck> {
    let dt = mj::raw(&robot.mj).opt.timestep;
    // An actuator `delay` keeps a history of `nsample` steps: at a quarter of the timestep it
    // would cover a quarter of the delay.
    let delayed = robot.mj.actuator_history().iter().any(|h| h[0] > 0);
    if !(dt > 0.0) || recs.is_empty() || delayed {
        return None;
    }
    let mut fine = robot.mj.clone();
    fine.opt_mut().timestep = dt / REFINE;
    let owned: Vec<Episode>;
    let base: &[Episode] = match base {
        Some(b) if b.len() == recs.len() => b,
        _ => {
            owned = replay_all(&Replayer::new(robot), recs, opts, None)
                .into_iter()
                .collect::<Result<_, _>>()
                .ok()?;
            &owned
        }
    };
    let refined: Vec<_> = replay_all(&Replayer::with_model(robot, &fine), recs, opts, None)
        .into_iter()
        .collect::<Result<_, _>>()
        .ok()?;
    let mut per_joint: Vec<(String, f64, f64, usize)> = Vec::new();
    for ((rec, a), b) in recs.iter().zip(base).zip(&refined) {
        if a.diverged.is_some() || b.diverged.is_some() {
            return None;
        }
        for (j, jt) in rec.joints.iter().enumerate() {
            let k = match per_joint.iter().position(|x| x.0 == jt.name) {
                Some(k) => k,
                None => {
                    per_joint.push((jt.name.clone(), 0.0, 0.0, 0));
                    per_joint.len() - 1
                }
            };
            // The first sample is the start state in both: not counted.
            for i in 1..rec.t.len() {
                let e = &mut per_joint[k];
                e.1 += (a.q_sim[j][i] - b.q_sim[j][i]).abs();
                e.2 += (a.q_sim[j][i] - jt.q[i]).abs();
                e.3 += 1;
            }
        }
    }
    Some(TimestepCheck {
        timestep: dt,
        fine_timestep: dt / REFINE,
        per_joint: per_joint
            .into_iter()
            .filter(|x| x.3 > 0)
            .map(|(name, d, g, n)| JointTimestep {
                name,
                discretisation_mae: d / n as f64,
                gap_mae: g / n as f64,
            })
            .collect(),
    })
}

/// Share of a joint's gap its discretisation error must reach for a note.
const NOTE_SHARE: f64 = 0.25;

/// A note when the discretisation error reaches a quarter of the gap on some joint. (A note,
/// not a warning: recordings simulated at the model's own timestep are at their noise floor
/// with the discretisation twice that; hardware logs are not, and there it says how much of
/// the gap the timestep may be.)
pub fn timestep_note(c: &TimestepCheck) -> Option<String> {
    let mut hit: Vec<&JointTimestep> = c
        .per_joint
        .iter()
        .filter(|j| j.gap_mae > 0.0 && j.discretisation_mae >= NOTE_SHARE * j.gap_mae)
        .collect();
    if hit.is_empty() {
        return None;
    }
    hit.sort_by(|a, b| {
        (b.discretisation_mae / b.gap_mae.max(1e-12))
            .total_cmp(&(a.discretisation_mae / a.gap_mae.max(1e-12)))
    });
    let list: Vec<String> = hit
        .iter()
        .take(4)
        .map(|j| {
            format!("{} {:.2} of {:.2} mrad", j.name, 1e3 * j.discretisation_mae, 1e3 * j.gap_mae)
        })
        .collect();
    let more = if hit.len() > 4 { format!(" and {} more", hit.len() - 4) } else { String::new() };
    Some(format!(
        "the model's timestep ({:.3} ms) moves the replay itself: at {:.3} ms it lands, on {} \
         of {} joints, a quarter of the gap to the recordings or more away (MAE, timestep vs \
         gap: {}{more}). If the recordings come from hardware, which moves in continuous time, \
         up to that much of the gap is the discretisation (`fit` counts it as floor, not \
         physics, when the recordings are closer to the finer replay); a smaller timestep \
         removes it",
        1e3 * c.timestep,
        1e3 * c.fine_timestep,
        hit.len(),
        c.per_joint.len(),
        list.join(", ")
    ))
}
