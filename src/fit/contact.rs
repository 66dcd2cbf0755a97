//! What the kept effects leave at the feet's contact with the ground. A foot standing on the
//! floor (a recorded joint's child body with ground-touching geoms,
//! [`crate::fit::effects::JointTarget::ground`]) has an orientation the recorded joints fix
//! when every hinge from the world to it is recorded (a planar free base on slide and hinge
//! joints, a leg on a pinned foot): the log's foot turns as the log's joints say, the model's as
//! the replay's. Where the floor is softer than the model's contact the recorded soles tilt as
//! heel or toe sinks and the replayed ones stay flat; a body effect on the base changes little
//! of that (floatsim's clean `KFR0`: 1.81 → 1.73 mrad with the stand-in centre of mass), yet it
//! can take up the joints' share of it — the floor's compliance presented as a body's physics. `fit` therefore compares the feet's orientation residual with what the
//! floors of the joints on their path explain (the same `white_ratio` as each joint's
//! unexplained residual, [`crate::fit::unexplained`]) and, above it, says so and names the kept
//! effects that may stand in for the floor.

use mujoco_rs::prelude::*;

use crate::fit::effects::{Applied, JointTarget, WriteBack};
use crate::fit::stats::white_floor;
use crate::model::{JointType, Robot};
use crate::sim2real::recording::Recording;
use crate::sim2real::replay::Episode;

/// One foot whose orientation residual the kept effects leave above its joints' floors.
#[derive(Debug, Clone, PartialEq)]
pub struct FootResidual {
    /// The foot's body and the recorded joint whose child it is.
    pub foot: String,
    pub joint: String,
    /// The recorded hinges from the world to it, root first.
    pub joints: Vec<String>,
    /// Held-out RMS of the angle between the recorded and the replayed foot, with the kept
    /// effects and with the model as given [rad].
    pub residual_rms: f64,
    pub before_rms: f64,
    /// The residual's white part, RMS [rad]: the recorded joints' noise and quantisation (the
    /// replayed foot of a standing leg is held by the contact, so the replay's own floors —
    /// command reconstruction, timestep — do not reach it).
    pub floor_rms: f64,
    /// The kept effects other than a ground contact, as `effect on joints`.
    pub kept: Vec<String>,
}

impl FootResidual {
    /// One entry of the JSON `unexplained_contact` (a fit's and each `--holdout-by` fold's).
    pub fn json(&self) -> serde_json::Value {
        serde_json::json!({"foot": self.foot, "joint": self.joint, "joints": self.joints, "residual_rms": self.residual_rms, "before_rms": self.before_rms, "floor_rms": self.floor_rms, "kept": self.kept})
    }

    /// The warning line: where, how large, against what, and what may stand in for it.
    pub fn message(&self) -> String {
        let mut s = format!(
            "unexplained residual at the ground contact of {}: its orientation from the recorded {} is {:.3} mrad RMS from the fitted model's on the held-out episodes ({:.3} mrad with the model as given), {:.1}× the {:.3} mrad its joints' noise explains — the model's ground contact is not this floor's",
            self.foot,
            self.joints.join(", "),
            1e3 * self.residual_rms,
            1e3 * self.before_rms,
            self.residual_rms / self.floor_rms.max(1e-300),
            1e3 * self.floor_rms
        );
        if !self.kept.is_empty() {
            s.push_str(&format!(
                "; what {} fits may be the floor's compliance standing in: compare `--told ground_contact@{}`",
                self.kept.join(", "),
                self.joint
            ));
        }
        s
    }
}

/// A foot: its body and the `qposadr` and name of each hinge from the world to it, when every
/// one of them is recorded (`None` otherwise, or across a ball or free joint).
fn foot_path(robot: &Robot, body: usize, recorded: &[&str]) -> Option<Vec<(usize, String)>> {
    let mut path = Vec::new();
    let mut b = body;
    for _ in 0..robot.bodies.len() {
        if b == 0 {
            path.reverse();
            return Some(path);
        }
        for j in robot.joints.iter().filter(|j| j.body == b) {
            match j.jtype {
                JointType::Hinge if recorded.contains(&j.name.as_str()) => {
                    path.push((j.qposadr, j.name.clone()))
                }
                JointType::Slide => {}
                _ => return None,
            }
        }
        b = robot.bodies.get(b)?.parent;
    }
    None
}

/// The rotation from `a` to `b` (row-major rotation matrices) as a rotation vector in `a`'s
/// frame [rad]: `Aᵀ B`'s axis times its angle (trace and skew part, exact near 0).
fn rotation_between(a: &[f64; 9], b: &[f64; 9]) -> [f64; 3] {
    let r = |i: usize, j: usize| (0..3).map(|k| a[3 * k + i] * b[3 * k + j]).sum::<f64>();
    let v = [r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1)];
    let s = 0.5 * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let angle = s.atan2(0.5 * (r(0, 0) + r(1, 1) + r(2, 2) - 1.0));
    let k = if s > 1e-12 { 0.5 * angle / s } else { 0.5 };
    v.map(|x| k * x)
}

/// The foot's orientation residual over `recs` replayed as `eps`, per component of the
/// rotation vector, in runs of consecutive samples (what [`white_floor`] takes).
fn residual_runs(
    robot: &Robot,
    d: &mut MjData<&MjModel>,
    foot: usize,
    path: &[(usize, String)],
    (recs, eps): (&[Recording], &[Episode]),
) -> [Vec<Vec<f64>>; 3] {
    let mut runs: [Vec<Vec<f64>>; 3] = Default::default();
    let pose = |d: &mut MjData<&MjModel>, q: &[f64]| -> Option<[f64; 9]> {
        d.qpos_mut().copy_from_slice(&robot.key.qpos);
        for ((adr, _), v) in path.iter().zip(q) {
            *d.qpos_mut().get_mut(*adr)? = *v;
        }
        d.kinematics();
        d.xmat().get(foot).copied()
    };
    for (rec, ep) in recs.iter().zip(eps) {
        let idx: Option<Vec<(usize, usize)>> = path
            .iter()
            .map(|(_, name)| {
                let r = rec.joints.iter().position(|j| &j.name == name)?;
                Some((r, ep.joints.iter().position(|j| j == name)?))
            })
            .collect();
        let Some(idx) = idx else { continue };
        runs.iter_mut().for_each(|c| c.push(vec![]));
        for i in 0..rec.t.len() {
            let real: Option<Vec<f64>> =
                idx.iter().map(|&(r, _)| rec.joints[r].q.get(i).copied()).collect();
            let sim: Option<Vec<f64>> =
                idx.iter().map(|&(_, e)| ep.q_sim.get(e)?.get(i).copied()).collect();
            let rot = match (real, sim) {
                (Some(a), Some(b)) if a.iter().chain(&b).all(|v| v.is_finite()) => {
                    pose(d, &a).zip(pose(d, &b)).map(|(x, y)| rotation_between(&x, &y))
                }
                _ => None,
            };
            for (c, run) in runs.iter_mut().enumerate() {
                match rot {
                    Some(v) => run.last_mut().expect("one").push(v[c]),
                    None if !run.last().is_some_and(Vec::is_empty) => run.push(vec![]),
                    None => {}
                }
            }
        }
    }
    runs
}

/// (mean square, white part) of the foot's orientation residual: the components' sums.
fn foot_floor(runs: &[Vec<Vec<f64>>; 3]) -> (f64, f64) {
    runs.iter().map(|r| white_floor(r)).fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1))
}

/// The feet whose held-out orientation residual with `applied` (`after`; `before` with the
/// model as given) has a mean square above `ratio` × its white part (noise and quantisation
/// of the recorded joints, [`white_floor`]), in the recorded joints' order.
pub fn unexplained_feet(
    robot: &Robot,
    (recs, before, after): (&[Recording], &[Episode], &[Episode]),
    applied: &[Applied],
    ratio: f64,
) -> Vec<FootResidual> {
    let Some(first) = recs.first() else { return vec![] };
    let recorded: Vec<&str> = first.joints.iter().map(|j| j.name.as_str()).collect();
    let kept: Vec<String> = applied
        .iter()
        .filter(|a| a.effect.write_back(&a.params) != WriteBack::Geoms)
        .map(|a| format!("{} on {}", a.effect.id(), a.joints.join("+")))
        .collect();
    let mut d = MjData::new(&robot.mj);
    let mut out = Vec::new();
    for name in &recorded {
        let Some(t) = JointTarget::of(robot, name).filter(|t| !t.ground.is_empty()) else {
            continue;
        };
        let Some(foot) = t.body.map(|b| b.body) else { continue };
        let Some(path) = foot_path(robot, foot, &recorded) else { continue };
        let (ms, white) = foot_floor(&residual_runs(robot, &mut d, foot, &path, (recs, after)));
        let (ms0, _) = foot_floor(&residual_runs(robot, &mut d, foot, &path, (recs, before)));
        if !(ms > ratio * white) {
            continue;
        }
        out.push(FootResidual {
            foot: robot.bodies.get(foot).map_or_else(|| format!("body {foot}"), |b| b.name.clone()),
            joint: name.to_string(),
            joints: path.into_iter().map(|(_, j)| j).collect(),
            residual_rms: ms.sqrt(),
            before_rms: ms0.sqrt(),
            floor_rms: white.sqrt(),
            kept: kept.clone(),
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rotation between two rotations about y by 0.3 and 0.3 + 1e-4 rad is 1e-4 about y
    /// (to 1e-12: no acos near 1); a rotation from itself is 0, and 2 rad comes out whole.
    #[test]
    fn the_rotation_between_two_orientations_is_exact_when_small() {
        let ry = |a: f64| {
            let (s, c) = a.sin_cos();
            [c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c]
        };
        let v = rotation_between(&ry(0.3), &ry(0.3001));
        assert!((v[1] - 1e-4).abs() < 1e-12 && v[0].abs() < 1e-15 && v[2].abs() < 1e-15, "{v:?}");
        assert_eq!(rotation_between(&ry(0.3), &ry(0.3)), [0.0; 3]);
        assert!((rotation_between(&ry(0.0), &ry(2.0))[1] - 2.0).abs() < 1e-12);
    }
}
