//! The rollout service: every simulation `fit` runs goes through [`Rollouts::run`].
//!
//! A batch is a list of parameter sets (each a list of [`Applied`] effects, possibly with a
//! changed timestep) × a list of episodes. Each set's compiled model copy is made once and
//! shared by its episodes; the (set × episode) rollouts run in parallel on rayon's pool, each
//! with its own `MjData`, and come back in a fixed order (results do not depend on the thread
//! count). The service counts rollouts (one episode replayed once) and the wall time spent in
//! batches, which `fit` reports (JSON `rollouts`).

use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::time::Instant;

use mujoco_rs::prelude::MjModel;
use rayon::prelude::*;
use serde::Serialize;

use crate::fit::effects::{Applied, model_with, replay_with};
use crate::model::Robot;
use crate::sim2real::recording::Recording;
use crate::sim2real::replay::{Episode, ReplayOptions};

/// One parameter set of a batch: the effects, and the timestep divisor (1: the model's own
/// timestep; n: a step n times finer, for the discretisation floor).
#[derive(Clone, Copy)]
pub struct SetSpec<'a> {
    pub applied: &'a [Applied],
    pub refine: u32,
}

impl<'a> SetSpec<'a> {
    pub fn of(applied: &'a [Applied]) -> Self {
        SetSpec { applied, refine: 1 }
    }
}

/// What the service has run so far.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct RolloutStats {
    /// Episodes replayed (one rollout = one episode replayed once with one parameter set).
    pub rollouts: usize,
    /// Batches run (a dataset simulated with one or several parameter sets).
    pub batches: usize,
    /// Wall time spent inside batches [s].
    pub seconds: f64,
    /// Recording time replayed, summed over the rollouts [s]: the search's cost in units that
    /// do not depend on the machine's load (a rollout of a short screen prefix costs less than
    /// one of a whole episode).
    pub simulated_s: f64,
}

/// The rollout service of one `fit` run (shared by every phase of the search).
pub struct Rollouts<'r> {
    robot: &'r Robot,
    /// When set, every replay fails at once (a cancelled fit).
    cancel: Option<crate::fit::select::Cancel>,
    rollouts: AtomicUsize,
    batches: AtomicUsize,
    nanos: AtomicU64,
    /// Recording time replayed [µs].
    sim_us: AtomicU64,
}

impl<'r> Rollouts<'r> {
    pub fn new(robot: &'r Robot) -> Self {
        Rollouts {
            robot,
            cancel: None,
            rollouts: AtomicUsize::new(0),
            batches: AtomicUsize::new(0),
            nanos: AtomicU64::new(0),
            sim_us: AtomicU64::new(0),
        }
    }

    /// The service stops replaying (each replay `None`) once `cancel` is set.
    pub fn with_cancel(mut self, cancel: Option<crate::fit::select::Cancel>) -> Self {
        self.cancel = cancel;
        self
    }

    fn cancelled(&self) -> bool {
        self.cancel.as_ref().is_some_and(|c| c.is_set())
    }

    pub fn robot(&self) -> &'r Robot {
        self.robot
    }

    /// Replays every episode of `recs` with every parameter set of `sets`, in parallel, under
    /// the replay protocol `opts`: `out[s][e]` is episode `e` under set `s`, `None` when it
    /// failed or diverged.
    pub fn run(
        &self,
        sets: &[SetSpec<'_>],
        recs: &[Recording],
        opts: &ReplayOptions,
    ) -> Vec<Vec<Option<Episode>>> {
        if sets.is_empty() || recs.is_empty() {
            return vec![vec![]; sets.len()];
        }
        let t0 = Instant::now();
        let models: Vec<MjModel> = sets
            .par_iter()
            .map(|s| {
                let mut m = model_with(self.robot, s.applied);
                if s.refine > 1 {
                    let dt = m.opt().timestep;
                    m.opt_mut().timestep = dt / f64::from(s.refine);
                }
                m
            })
            .collect();
        let jobs: Vec<(usize, usize)> =
            (0..sets.len()).flat_map(|s| (0..recs.len()).map(move |e| (s, e))).collect();
        let eps: Vec<Option<Episode>> = jobs
            .par_iter()
            .map(|&(s, e)| {
                if self.cancelled() {
                    return None;
                }
                replay_with(self.robot, &models[s], &recs[e], sets[s].applied, opts)
                    .ok()
                    .filter(|ep| ep.diverged.is_none())
            })
            .collect();
        self.rollouts.fetch_add(jobs.len(), Ordering::Relaxed);
        self.batches.fetch_add(1, Ordering::Relaxed);
        let per_set: u64 = recs.iter().map(duration_us).sum();
        self.sim_us.fetch_add(per_set * sets.len() as u64, Ordering::Relaxed);
        let ns = u64::try_from(t0.elapsed().as_nanos()).unwrap_or(u64::MAX);
        self.nanos.fetch_add(ns, Ordering::Relaxed);
        let mut it = eps.into_iter();
        (0..sets.len()).map(|_| it.by_ref().take(recs.len()).collect()).collect()
    }

    /// Replays `recs` with one parameter set; `None` when any episode failed or diverged.
    pub fn run_one(
        &self,
        set: SetSpec<'_>,
        recs: &[Recording],
        opts: &ReplayOptions,
    ) -> Option<Vec<Episode>> {
        self.run(&[set], recs, opts).pop()?.into_iter().collect()
    }

    /// Replays one recording with `applied` on a model compiled by the caller (the start
    /// estimate replays variants of one recording on one model).
    pub fn run_on(
        &self,
        model: &MjModel,
        rec: &Recording,
        applied: &[Applied],
        opts: &ReplayOptions,
    ) -> Option<Episode> {
        if self.cancelled() {
            return None;
        }
        let t0 = Instant::now();
        let ep = replay_with(self.robot, model, rec, applied, opts)
            .ok()
            .filter(|e| e.diverged.is_none());
        self.rollouts.fetch_add(1, Ordering::Relaxed);
        self.sim_us.fetch_add(duration_us(rec), Ordering::Relaxed);
        let ns = u64::try_from(t0.elapsed().as_nanos()).unwrap_or(u64::MAX);
        self.nanos.fetch_add(ns, Ordering::Relaxed);
        ep
    }

    pub fn stats(&self) -> RolloutStats {
        RolloutStats {
            rollouts: self.rollouts.load(Ordering::Relaxed),
            batches: self.batches.load(Ordering::Relaxed),
            seconds: self.nanos.load(Ordering::Relaxed) as f64 * 1e-9,
            simulated_s: self.sim_us.load(Ordering::Relaxed) as f64 * 1e-6,
        }
    }
}

/// A recording's span from its first to its last row [µs].
fn duration_us(r: &Recording) -> u64 {
    match (r.t.first(), r.t.last()) {
        (Some(a), Some(b)) if b > a => ((b - a) * 1e6).round() as u64,
        _ => 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::effects::{by_id, hinge_recording, hinge_robot};

    #[test]
    fn a_batch_gives_each_set_its_own_episodes_in_order_and_counts_them() {
        let dir = std::env::temp_dir().join(format!("modellint-rollout-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let robot = hinge_robot(&dir, "batch.xml", "", "", r#"kp="20" kv="0.3""#);
        let t: Vec<f64> = (0..200).map(|i| i as f64 * 0.005).collect();
        let cmd: Vec<f64> = t.iter().map(|&x| 0.3 * (3.0 * x).sin()).collect();
        let recs = vec![hinge_recording(t.clone(), cmd.clone()), hinge_recording(t, cmd)];
        let damping = by_id("viscous_damping").expect("effect");
        let set =
            |d: f64| vec![Applied { effect: damping, joints: vec!["j".into()], params: vec![d] }];
        let (a, b) = (set(0.0), set(5.0));
        let svc = Rollouts::new(&robot);
        let o = ReplayOptions::default();
        let out = svc.run(&[SetSpec::of(&a), SetSpec::of(&b)], &recs, &o);
        assert_eq!(out.len(), 2);
        assert!(out.iter().all(|s| s.len() == 2 && s.iter().all(Option::is_some)));
        // Each set alone gives the same episodes as in the batch.
        let lone = svc.run_one(SetSpec::of(&b), &recs, &o).expect("replay");
        let q = |e: &Episode| e.q_sim[0].clone();
        assert_eq!(q(out[1][0].as_ref().unwrap()), q(&lone[0]));
        assert_ne!(q(out[0][0].as_ref().unwrap()), q(&lone[0]), "damping changes the motion");
        let s = svc.stats();
        assert_eq!((s.rollouts, s.batches), (6, 2));
        // 6 rollouts of 199 × 5 ms.
        assert!((s.simulated_s - 6.0 * 0.995).abs() < 1e-9, "{}", s.simulated_s);
        assert!(s.seconds > 0.0);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
