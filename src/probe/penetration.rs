//! Probe `keyframe-penetration`: does MuJoCo really push on a pair of the robot's own geoms
//! that overlap at the keyframe? The robot is put on a stand (base pinned, so falling and floor
//! contact play no part) at the keyframe with the keyframe's commands held; MuJoCo's normal
//! contact force between the two geoms is read from its active contacts at the keyframe, then
//! the model is stepped for 0.1 s while `mj_geomDistance` tracks how fast the pair is pushed
//! apart. Confirmed when the solver applies a force (the pair either jumps apart or stays
//! jammed, adding that force and its friction to every motion of the two links); refuted when
//! the contact is inactive (e.g. a `gap` larger than the overlap) and no force acts.

use super::bench::{Bench, Setup};
use crate::lint::Loaded;
use crate::model::{Robot, mj};

/// The probe: one pair of the robot's geoms at the keyframe (key: the two geom ids).
pub struct KeyframePenetration;

impl super::Probe for KeyframePenetration {
    const NAME: &'static str = "keyframe-penetration";
    const UNAVAILABLE: &'static str = "could not set up the bench";
    type Key = (usize, usize);
    fn steps(out: &Penetration) -> usize {
        out.steps
    }
    type Output = Penetration;
    fn run(l: &Loaded, (a, b): (usize, usize)) -> Option<Penetration> {
        run(&l.robot, a, b)
    }
}

/// Probe duration [s].
pub const DURATION: f64 = 0.1;
/// Separation speed above which the pair is said to jump apart [m/s].
pub const JOLT_SPEED: f64 = 0.01;

#[derive(Debug, Clone)]
pub struct Penetration {
    /// Signed distance at the keyframe [m] (negative: overlap).
    pub depth0: f64,
    /// Deepest penetration of the pair in MuJoCo's contact list at the keyframe [m] (what the
    /// rule reports; NaN when the list has no contact of the pair).
    pub contact_depth: f64,
    /// Sum of MuJoCo's normal contact forces between the two geoms at the keyframe [N].
    pub contact_force: f64,
    /// Largest rate at which the signed distance grew [m/s].
    pub separation_speed: f64,
    /// Signed distance after the probe [m].
    pub dist_end: f64,
    /// Time until the pair no longer overlaps [s], if it did within the probe.
    pub clear_time: Option<f64>,
    pub steps: usize,
}

pub fn run(robot: &Robot, a: usize, b: usize) -> Option<Penetration> {
    let ngeom = robot.geoms.len();
    if a >= ngeom || b >= ngeom || a == b {
        return None;
    }
    let bench = Bench::new(robot, Setup { pin_base: true, ..Default::default() })?;
    let mut d = bench.data(robot);
    // Active contacts only (efc_address ≥ 0): those the constraint solver applies force through.
    let cons: Vec<(i32, i32, bool)> =
        d.contact().iter().map(|c| (c.geom1, c.geom2, c.efc_address >= 0)).collect();
    let contact_depth = d
        .contact()
        .iter()
        .filter(|c| {
            let (g1, g2) = (c.geom1 as usize, c.geom2 as usize);
            (g1, g2) == (a, b) || (g1, g2) == (b, a)
        })
        .map(|c| -c.dist)
        .fold(f64::NAN, f64::max);
    let contact_force: f64 = cons
        .iter()
        .enumerate()
        .filter(|(_, (g1, g2, active))| {
            *active
                && ((*g1 as usize, *g2 as usize) == (a, b)
                    || (*g1 as usize, *g2 as usize) == (b, a))
        })
        .map(|(i, _)| mj::contact_normal_force(&d, i))
        .sum();
    let distmax = 1.0;
    let depth0 = mj::geom_distance(&mut d, a, b, distmax);
    let dt = bench.dt();
    let n = (DURATION / dt).ceil() as usize;
    let mut prev = depth0;
    let mut separation_speed: f64 = 0.0;
    let mut clear_time = None;
    let mut steps = 0;
    for k in 0..n {
        bench.step(&mut d);
        steps += 1;
        let dist = mj::geom_distance(&mut d, a, b, distmax);
        if !dist.is_finite() {
            break;
        }
        separation_speed = separation_speed.max((dist - prev) / dt);
        if clear_time.is_none() && dist >= 0.0 && depth0 < 0.0 {
            clear_time = Some((k + 1) as f64 * dt);
        }
        prev = dist;
    }
    Some(Penetration {
        depth0,
        contact_depth,
        contact_force,
        separation_speed,
        dist_end: prev,
        clear_time,
        steps,
    })
}
