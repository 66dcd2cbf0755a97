//! Probe `foot-slide`: the robot stands at its keyframe on the floor for [`SETTLE_S`], then
//! every free-floating body is pushed sideways (+x) with [`PUSH_SHARE`] of its subtree's weight
//! for [`PUSH_S`], targets held.
//!
//! * Measures, per robot geom touching a world geom during the push: the contact dimension
//!   and the sliding friction MuJoCo built for the contact (`mjContact.dim`,
//!   `mjContact.friction[0]`: after condim/priority/max combination and any `<pair>`), and per
//!   body its horizontal travel during the push. A contact of dim 1 has no friction cone and
//!   slides under any push; a dim ≥ 3 contact holds a push below μ × its normal load.
//! * Preconditions (unmet → inconclusive with the reason): a floor, a finite run, a free base,
//!   the floor carrying ≥ [`MIN_SUPPORT`](super::stance::MIN_SUPPORT) of the weight before the push, the base upright after
//!   it, and — per measurement — the subject's geoms touching the ground during the push.
//! * Used by `foot-collision-geometry`'s condim and friction findings (facts of the file: a
//!   measurement, never a verdict).
//! * Budget: [`SETTLE_S`] + [`PUSH_S`] at the model's timestep.

use std::collections::BTreeMap;

use super::bench::{Bench, Setup};
use super::stance::is_ground;
use crate::lint::Loaded;
use crate::model::{JointType, Robot, mj};

/// Standing time before the push, s.
pub const SETTLE_S: f64 = 0.5;
/// Push duration, s.
pub const PUSH_S: f64 = 0.5;
/// Horizontal push as a share of the pushed subtree's weight: far inside any foot friction
/// cone (μ ≈ 0.4–1), and small enough not to tip a standing humanoid.
pub const PUSH_SHARE: f64 = 0.05;

/// The probe: one run per model.
pub struct FootSlide;

impl super::Probe for FootSlide {
    const NAME: &'static str = "foot-slide";
    const WHOLE_MODEL: bool = true;
    const UNAVAILABLE: &'static str = "could not set up the bench";
    type Key = ();
    type Output = Slide;
    fn steps(out: &Slide) -> usize {
        out.steps
    }
    fn run(l: &Loaded, (): ()) -> Option<Slide> {
        let model = super::float::stance_model(l);
        let mut s = match &model {
            super::float::StanceModel::Copy(c) => {
                let s = run(&c.robot)?;
                Slide {
                    built: super::float::remap(s.built, &c.geom_map),
                    travel: super::float::remap(s.travel, &c.body_map),
                    ..s
                }
            }
            _ => run(&l.robot)?,
        };
        s.stance.floated = model.floated();
        Some(s)
    }
}

/// The contacts MuJoCo built for one robot geom against the ground during the push.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Built {
    /// Largest contact dimension seen (1, 3, 4 or 6).
    pub dim: i32,
    /// Smallest contact dimension seen.
    pub dim_min: i32,
    /// Sliding friction of the contacts (the last one seen).
    pub friction: f64,
    /// Number of contact-steps seen.
    pub count: usize,
}

#[derive(Debug, Clone, Default)]
pub struct Slide {
    pub steps: usize,
    /// Floor, weight and base figures (support load over the last 0.2 s before the push, the
    /// base's tilt and drop after it).
    pub stance: super::stance::Figures,
    /// Robot geom id → the ground contacts MuJoCo built for it during the push.
    pub built: BTreeMap<usize, Built>,
    /// Body id → horizontal travel during the push, m.
    pub travel: BTreeMap<usize, f64>,
}

impl Slide {
    /// The whole-run preconditions (floor, finite, free base, loaded, upright).
    pub fn preconditions(&self) -> super::Preconditions {
        super::stance::preconditions(
            &self.stance,
            &super::stance::Words {
                finite: "the run stayed finite",
                diverged: "the push simulation diverged",
                fixed_base: "the base is fixed to the world: nothing can slide",
                loaded_when: "before the push",
                upright_when: "after the push ",
            },
        )
    }
}

pub fn run(robot: &Robot) -> Option<Slide> {
    let b = Bench::new(robot, Setup::default())?;
    let mut d = b.data(robot);
    let dt = b.dt();
    let n_settle = (SETTLE_S / dt).ceil() as usize;
    let n_push = (PUSH_S / dt).ceil() as usize;
    let load_from = n_settle.saturating_sub((0.2 / dt).ceil() as usize);
    let nbody = mj::raw(&b.m).nbody as usize;
    let gbody = super::stance::ground_side_bodies(robot, b.m.geom_bodyid());
    let g = robot.opt.gravity;
    let gmag = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
    let free: Vec<&crate::model::Joint> =
        robot.joints.iter().filter(|j| j.jtype == JointType::Free).collect();
    let start = super::stance::start(robot);
    let base_z0 = start.base_z0;
    let mut out = Slide { stance: start.figures(), ..Default::default() };
    // Each free body is pushed with a share of its subtree's weight.
    let subtree = |root: usize| -> f64 {
        robot
            .bodies
            .iter()
            .filter(|b| {
                let mut x = b.id;
                loop {
                    if x == root {
                        return true;
                    }
                    if x == 0 {
                        return false;
                    }
                    x = robot.bodies[x].parent;
                }
            })
            .map(|b| b.mass)
            .sum()
    };
    let pushes: Vec<(usize, f64)> =
        free.iter().map(|j| (j.body, PUSH_SHARE * subtree(j.body) * gmag)).collect();
    let warn0 = super::bench::warnings(&d);
    let mut support_sum = 0.0;
    let mut x_start: Vec<f64> = Vec::new();
    for step in 0..n_settle + n_push {
        if step == n_settle {
            x_start = d.xpos().as_flattened().to_vec();
            let xf = d.xfrc_applied_mut();
            for &(body, f) in &pushes {
                if let Some(w) = xf.get_mut(body) {
                    w[0] = f;
                }
            }
        }
        b.step(&mut d);
        out.steps += 1;
        if super::bench::warnings(&d) > warn0 {
            out.stance.diverged = true;
            return Some(out);
        }
        for (ci, c) in d.contact().iter().enumerate() {
            let (g1, g2) = (c.geom[0], c.geom[1]);
            if g1 < 0 || g2 < 0 {
                continue;
            }
            let (g1, g2) = (g1 as usize, g2 as usize);
            let mine = match (is_ground(robot, g1), is_ground(robot, g2)) {
                (true, false) => g2,
                (false, true) => g1,
                _ => continue,
            };
            if gbody.get(mine).copied().unwrap_or(0) == 0 {
                continue;
            }
            if step >= load_from && step < n_settle {
                support_sum += d.contact_force(ci)[0].abs();
            }
            if step >= n_settle {
                let e = out.built.entry(mine).or_insert(Built {
                    dim: c.dim,
                    dim_min: c.dim,
                    friction: c.friction[0],
                    count: 0,
                });
                e.dim = e.dim.max(c.dim);
                e.dim_min = e.dim_min.min(c.dim);
                e.friction = c.friction[0];
                e.count += 1;
            }
        }
    }
    out.stance.support_load = support_sum / (n_settle - load_from).max(1) as f64;
    let x1 = d.xpos().as_flattened();
    for bi in 1..nbody {
        let (dx, dy) = (x1[3 * bi] - x_start[3 * bi], x1[3 * bi + 1] - x_start[3 * bi + 1]);
        out.travel.insert(bi, (dx * dx + dy * dy).sqrt());
    }
    if let (Some(z0), Some(fj)) = (base_z0, free.first()) {
        let q = d.qpos();
        out.stance.base_drop = z0 - q[fj.qposadr + 2];
        // Tilt of the base's z axis from vertical-at-keyframe.
        let x = d.xmat().as_flattened();
        let bi = fj.body;
        let zz = x.get(9 * bi + 8).copied().unwrap_or(1.0).clamp(-1.0, 1.0);
        let k = &robot.key.qpos[fj.qposadr + 3..fj.qposadr + 7];
        // Keyframe z-axis z component from the quaternion (w, x, y, z).
        let z0z = (1.0 - 2.0 * (k[1] * k[1] + k[2] * k[2])).clamp(-1.0, 1.0);
        out.stance.base_tilt_deg = (zz.acos().to_degrees() - z0z.acos().to_degrees()).abs();
    }
    Some(out)
}
