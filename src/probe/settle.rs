//! Probe `stance-settle`: the robot at its standing keyframe on the floor, position targets
//! held, simulated for 1 s with full contact dynamics.
//!
//! * Measures, per collision geom: mean normal contact force over the last 0.3 s; per foot:
//!   tilt of the foot body from level, contact chatter (contacts appearing or disappearing per
//!   second over the last 0.5 s), deepest penetration; per passive joint: deflection from the
//!   keyframe.
//! * Preconditions every stance verdict records (unmet → inconclusive with the reason): the
//!   model has a floor (a colliding plane or height field on the world body or a static body,
//!   or a box on the world body: lint the scene, not the bare robot file); the run did not diverge; the base is free-floating; the
//!   floor carries at least [`MIN_SUPPORT`] of the robot's weight over the last 0.3 s; the base
//!   stays upright (tilt ≤ [`MAX_TILT_DEG`]°, drop ≤ [`MAX_DROP`] of its keyframe height or
//!   [`MIN_DROP_ALLOWED`]).
//! * Confirms `toe-tilt` when a foot contact geom carries (almost) no load;
//!   `foot-collision-geometry` when contacts chatter or penetrate; measures the deflection of a
//!   passive joint for `passive-joint-spring`.
//! * Budget: 1 s at the model's timestep.

use std::collections::{BTreeMap, BTreeSet};

use super::bench::{Bench, Setup};
use crate::lint::Loaded;
use crate::model::{Robot, mj};

/// The probe: the whole robot standing for 1 s (one run per model).
pub struct StanceSettle;

impl super::Probe for StanceSettle {
    const NAME: &'static str = "stance-settle";
    const WHOLE_MODEL: bool = true;
    const UNAVAILABLE: &'static str = "could not set up the bench";
    type Key = ();
    fn steps(out: &Settle) -> usize {
        out.steps
    }
    type Output = Settle;
    fn run(l: &Loaded, (): ()) -> Option<Settle> {
        let model = super::float::stance_model(l);
        let mut s = match &model {
            super::float::StanceModel::Copy(c) => run(&c.robot)?.remapped(c),
            _ => run(&l.robot)?,
        };
        s.stance.floated = model.floated();
        Some(s)
    }
}

/// What a diverged settle says.
pub const DIVERGED: &str = "the standing simulation diverged";

/// A claim the stance-settle run checks (one run per model, so no key). A diverged run confirms
/// it; otherwise [`StanceClaim::judge_settled`] reads the run.
pub trait StanceClaim: std::fmt::Debug + Send + Sync + 'static {
    /// Called only when every stance precondition (`pre`) was met.
    fn judge_settled(&self, l: &Loaded, s: &Settle, pre: &super::Preconditions) -> super::Verdict;
}

impl<C: StanceClaim> super::Claim for C {
    type Probe = StanceSettle;
    fn key(&self, _: &Loaded) -> Result<(), &'static str> {
        Ok(())
    }
    fn judge(&self, l: &Loaded, s: &Settle) -> super::Verdict {
        let pre = s.preconditions();
        let v = match pre.unmet() {
            Some(p) => super::Verdict::inconclusive(&pre, s.stance_measured(), p.detail.clone()),
            None => self.judge_settled(l, s, &pre),
        };
        super::stance::tag_copy(v, &s.stance)
    }
}

pub use super::stance::{MAX_DROP, MAX_TILT_DEG, MIN_DROP_ALLOWED, MIN_SUPPORT};

/// What the settle measured around one foot: the body, its parent and its children.
#[derive(Debug, Clone)]
pub struct FootView {
    /// The colliding geoms of those bodies.
    pub geoms: Vec<usize>,
    /// Their total mean normal load, N.
    pub load: f64,
    /// Most contact changes per second of any of the bodies.
    pub chatter_per_s: f64,
    /// Deepest penetration of any of the bodies, m.
    pub penetration: f64,
    /// Tilt of the body itself, degrees.
    pub tilt_deg: f64,
    /// The figures above (and each geom's load) by name, for the JSON output.
    pub measured: BTreeMap<String, f64>,
}

impl Settle {
    /// The stance preconditions of this run, in order (see the module docs).
    pub fn preconditions(&self) -> super::Preconditions {
        super::stance::preconditions(
            &self.stance,
            &super::stance::Words {
                finite: "the standing simulation stayed finite",
                diverged: DIVERGED,
                fixed_base: "the base is fixed to the world, so standing does not load the feet",
                loaded_when: "after 1 s standing",
                upright_when: "",
            },
        )
    }

    /// The largest drop of the base that still counts as upright, m.
    pub fn max_drop(&self) -> f64 {
        super::stance::max_drop(self.stance.base_height)
    }

    /// The whole-robot figures every stance verdict reports.
    pub fn stance_measured(&self) -> BTreeMap<String, f64> {
        BTreeMap::from([
            ("support_load_n".to_string(), self.stance.support_load),
            ("weight_n".to_string(), self.stance.weight),
            ("base_drop_m".to_string(), self.stance.base_drop),
            ("base_tilt_deg".to_string(), self.stance.base_tilt_deg),
        ])
        .into_iter()
        .chain(super::stance::floor_added(&self.stance).map(|z| ("floor_added_z_m".to_string(), z)))
        .collect()
    }

    /// This run on a floated copy, keyed by the model's ids.
    fn remapped(self, c: &crate::model::floated::FloatedCopy) -> Settle {
        use super::float::remap;
        Settle {
            steps: self.steps,
            stance: self.stance,
            geom_load: remap(self.geom_load, &c.geom_map),
            chatter_per_s: remap(self.chatter_per_s, &c.body_map),
            penetration: remap(self.penetration, &c.body_map),
            body_tilt_deg: remap(self.body_tilt_deg, &c.body_map),
            joint_deflection: remap(self.joint_deflection, &c.joint_map),
        }
    }

    /// The mean load of one geom, N (0 when it never touched anything).
    pub fn load(&self, geom: usize) -> f64 {
        self.geom_load.get(&geom).copied().unwrap_or(0.0)
    }

    /// The measurements around the foot whose body is `body`.
    pub fn foot(&self, robot: &Robot, body: usize) -> FootView {
        let parent = robot.bodies.get(body).map(|b| b.parent);
        let foot: Vec<usize> = robot
            .bodies
            .iter()
            .filter(|b| b.id == body || b.parent == body || (parent == Some(b.id) && b.id != 0))
            .map(|b| b.id)
            .collect();
        let geoms: Vec<usize> = robot
            .geoms
            .iter()
            .filter(|g| foot.contains(&g.body) && crate::model::contact::takes_part(robot, g.id))
            .map(|g| g.id)
            .collect();
        let load: f64 = geoms.iter().map(|g| self.load(*g)).sum();
        let mut m = BTreeMap::new();
        m.insert("foot_load_n".into(), load);
        for g in &geoms {
            let gname = &robot.geoms[*g].name;
            m.insert(
                format!(
                    "load.{}",
                    if gname.is_empty() { format!("geom{g}") } else { gname.clone() }
                ),
                self.load(*g),
            );
        }
        let worst = |per: &BTreeMap<usize, f64>| {
            foot.iter().map(|b| per.get(b).copied().unwrap_or(0.0)).fold(0.0, f64::max)
        };
        let chatter_per_s = worst(&self.chatter_per_s);
        let penetration = worst(&self.penetration);
        let tilt_deg = self.body_tilt_deg.get(&body).copied().unwrap_or(0.0);
        m.insert("chatter_per_s".into(), chatter_per_s);
        m.insert("penetration_m".into(), penetration);
        m.insert("tilt_deg".into(), tilt_deg);
        m.insert("base_drop_m".into(), self.stance.base_drop);
        FootView { geoms, load, chatter_per_s, penetration, tilt_deg, measured: m }
    }
}

#[derive(Debug, Clone, Default)]
pub struct Settle {
    pub steps: usize,
    /// Floor, weight and base figures (support load over the last 0.3 s, the base's final tilt
    /// and drop).
    pub stance: super::stance::Figures,
    /// Mean normal force per geom id over the last 0.3 s, N.
    pub geom_load: BTreeMap<usize, f64>,
    /// Contact set changes per second over the last 0.5 s, per body id of the robot-side geom.
    pub chatter_per_s: BTreeMap<usize, f64>,
    /// Deepest penetration per robot-side body, m.
    pub penetration: BTreeMap<usize, f64>,
    /// Final tilt of each body from its keyframe orientation, degrees.
    pub body_tilt_deg: BTreeMap<usize, f64>,
    /// Final qpos per joint id minus keyframe.
    pub joint_deflection: BTreeMap<usize, f64>,
}

pub fn run(robot: &Robot) -> Option<Settle> {
    let b = Bench::new(robot, Setup::default())?;
    let mut d = b.data(robot);
    let dt = b.dt();
    let n = (1.0 / dt).ceil() as usize;
    let load_from = n - (0.3 / dt).ceil() as usize;
    let chatter_from = n - (0.5 / dt).ceil() as usize;
    let nbody = mj::raw(&b.m).nbody as usize;
    let gbody = super::stance::ground_side_bodies(robot, b.m.geom_bodyid());
    let x0: Vec<f64> = d.xmat().as_flattened().to_vec();
    let start = super::stance::start(robot);
    let base_z0 = start.base_z0;
    let mut out = Settle { stance: start.figures(), ..Default::default() };
    let mut support_sum = 0.0;
    let mut load_sum: BTreeMap<usize, f64> = BTreeMap::new();
    let mut prev: BTreeSet<(usize, usize)> = BTreeSet::new();
    let mut changes: BTreeMap<usize, usize> = BTreeMap::new();
    let warn0 = super::bench::warnings(&d);
    for step in 0..n {
        b.step(&mut d);
        out.steps += 1;
        if super::bench::warnings(&d) > warn0 {
            out.stance.diverged = true;
            return Some(out);
        }
        let cons = d.contact();
        let mut now = BTreeSet::new();
        for (ci, c) in cons.iter().enumerate() {
            let (g1, g2) = (c.geom[0], c.geom[1]);
            if g1 < 0 || g2 < 0 {
                continue;
            }
            let (g1, g2) = (g1 as usize, g2 as usize);
            now.insert((g1.min(g2), g1.max(g2)));
            let world = |g: usize| gbody[g] == 0;
            if step >= load_from && world(g1) != world(g2) {
                support_sum += d.contact_force(ci)[0].abs();
            }
            for g in [g1, g2] {
                let body = gbody[g].max(0) as usize;
                if body == 0 {
                    continue;
                }
                let pen = (-c.dist).max(0.0);
                let e = out.penetration.entry(body).or_insert(0.0);
                *e = e.max(pen);
                if step >= load_from {
                    let f = d.contact_force(ci);
                    *load_sum.entry(g).or_insert(0.0) += f[0].abs();
                }
            }
        }
        if step >= chatter_from {
            for &(g1, g2) in now.symmetric_difference(&prev) {
                for g in [g1, g2] {
                    let body = gbody[g].max(0) as usize;
                    if body != 0 {
                        *changes.entry(body).or_insert(0) += 1;
                    }
                }
            }
        }
        prev = now;
    }
    let nload = (n - load_from) as f64;
    out.stance.support_load = support_sum / nload;
    out.geom_load = load_sum.into_iter().map(|(g, s)| (g, s / nload)).collect();
    let window = (n - chatter_from) as f64 * dt;
    out.chatter_per_s = changes.into_iter().map(|(b, c)| (b, c as f64 / window)).collect();
    let x1 = d.xmat().as_flattened();
    for bi in 1..nbody {
        // Angle between the body's z axis now and at the keyframe.
        let z0 = [x0[9 * bi + 2], x0[9 * bi + 5], x0[9 * bi + 8]];
        let z1 = [x1[9 * bi + 2], x1[9 * bi + 5], x1[9 * bi + 8]];
        let dot = (z0[0] * z1[0] + z0[1] * z1[1] + z0[2] * z1[2]).clamp(-1.0, 1.0);
        out.body_tilt_deg.insert(bi, dot.acos().to_degrees());
    }
    let q = d.qpos();
    for j in &robot.joints {
        if j.is_scalar() {
            out.joint_deflection
                .insert(j.id, q[j.qposadr] - robot.key.qpos.get(j.qposadr).copied().unwrap_or(0.0));
        }
    }
    if let (Some(z0), Some(fj)) =
        (base_z0, robot.joints.iter().find(|j| j.jtype == crate::model::JointType::Free))
    {
        out.stance.base_drop = z0 - q[fj.qposadr + 2];
        out.stance.base_tilt_deg = out.body_tilt_deg.get(&fj.body).copied().unwrap_or(0.0);
    }
    Some(out)
}
