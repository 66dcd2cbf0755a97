//! The linearised screen: probe simulations give the residual's sensitivity to each (effect,
//! joint) (a finite-difference Jacobian column, on the screen's data: the stretch of every
//! training episode where the residual is largest); every candidate group of one effect — a
//! joint, a mirror pair, a motor family, every leg, every joint — is the sum of its joints'
//! columns (one shared parameter moved on all of them, to first order). On that linear model
//! each candidate gets, without a fit of its own, the residual it would leave.
//!
//! One simulation probes one joint of every limb at once ([`crate::model::Robot::limb_of`]:
//! the head, each arm, the waist, each leg): a joint's column is the change on its own limb's
//! samples. What a probe on one limb does to another runs only through the held base or a
//! servo-held joint where they meet, and is left out of both columns; a robot with one limb (an
//! arm, a pendulum) is probed one joint at a time, exactly. On a 23-joint humanoid that is 6
//! simulations per effect instead of 23.
//!
//! Only sums over the samples are kept (each column's dot product with the residual and with the
//! effect's other columns), so memory does not grow with the recordings' length.

use std::collections::BTreeMap;

use rayon::prelude::*;
use serde::Serialize;

use crate::fit::diagnose::Candidate;
use crate::fit::effects::{self, Applied, JointTarget, model_with};
use crate::fit::split::segments;
use crate::sim2real::metrics::gap_mask;
use crate::sim2real::recording::Recording;

use super::{Engine, Errors};

/// The residual of one simulated dataset, sample by sample over (episode, fitted joint, scored
/// sample); `None` where the recording or the replay is not finite or the sample follows a gap.
fn aligned(engine: &Engine, recs: &[Recording], e: &Errors) -> Vec<Option<f64>> {
    let mut out = Vec::new();
    for (rec, ep) in recs.iter().zip(&e.eps) {
        let scored = gap_mask(&rec.t, engine.opts.gap_mask_s);
        for (k, jt) in rec.joints.iter().enumerate() {
            if !engine.joints.contains(&jt.name) {
                continue;
            }
            out.extend((0..rec.t.len()).map(|i| {
                let r = jt.q[i] - ep.q_sim[k][i];
                (scored[i] && r.is_finite()).then_some(r)
            }));
        }
    }
    out
}

/// Change of the simulated positions from `base` to `moved`, on the samples of [`aligned`]
/// (zero where the residual is not scored or the moved replay is not finite).
fn change(
    engine: &Engine,
    recs: &[Recording],
    base: &Errors,
    moved: &Errors,
    r: &[Option<f64>],
) -> Vec<f64> {
    let mut out = Vec::with_capacity(r.len());
    for ((rec, e0), e1) in recs.iter().zip(&base.eps).zip(&moved.eps) {
        for (k, jt) in rec.joints.iter().enumerate() {
            if !engine.joints.contains(&jt.name) {
                continue;
            }
            out.extend((0..rec.t.len()).map(|i| {
                let s = e1.q_sim[k][i] - e0.q_sim[k][i];
                if s.is_finite() { s } else { 0.0 }
            }));
        }
    }
    for (s, r) in out.iter_mut().zip(r) {
        if r.is_none() {
            *s = 0.0;
        }
    }
    out
}

/// The screen's data: about `screen_seconds` of `recs` in all, from each episode the stretch
/// where the residual of `e` (summed over the fitted joints' scored samples) is largest — the
/// missing physics shows most where the model is most wrong ([`segments`]).
pub(super) fn screen_data(engine: &Engine, recs: &[Recording], e: &Errors) -> Vec<Recording> {
    let weight: Vec<Vec<f64>> = recs
        .iter()
        .zip(&e.eps)
        .map(|(rec, ep)| {
            let scored = gap_mask(&rec.t, engine.opts.gap_mask_s);
            let mut w = vec![0.0; rec.t.len()];
            for (k, jt) in rec.joints.iter().enumerate() {
                if !engine.joints.contains(&jt.name) {
                    continue;
                }
                for (i, wi) in w.iter_mut().enumerate() {
                    let r = jt.q[i] - ep.q_sim[k][i];
                    if scored[i] && r.is_finite() {
                        *wi += r * r;
                    }
                }
            }
            w
        })
        .collect();
    segments(recs, &weight, engine.opts.policy.screen_seconds)
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn dot_r(a: &[f64], r: &[Option<f64>]) -> f64 {
    a.iter().zip(r).map(|(x, y)| x * y.unwrap_or(0.0)).sum()
}

/// One effect's linear model: per joint, the column's dot product with the residual (`b`) and
/// with the effect's other columns (`g`), per unit of the effect's first parameter.
#[derive(Debug, Clone, Default)]
struct EffectModel {
    joints: Vec<String>,
    b: Vec<f64>,
    g: Vec<Vec<f64>>,
}

/// What the linear model predicts for one candidate (effect, joint group).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Prediction {
    /// Residual RMSE on the screen's data after the linear step [rad].
    pub train_rmse: f64,
    /// The step of the effect's first parameter that the training residual asks for.
    pub step: f64,
}

/// The linear model of every (effect, joint) the round's diagnosis lists.
pub(super) struct Screen {
    models: BTreeMap<&'static str, EffectModel>,
    train_ss: f64,
    train_n: usize,
}

/// One probe of a candidate: the probe value, its step from the start, the training column.
struct Probe {
    v: f64,
    step: f64,
    column: Vec<f64>,
    explained: f64,
}

/// The limb ([`Robot::limb_of`]) of each sample of [`aligned`]'s order.
///
/// [`Robot::limb_of`]: crate::model::Robot::limb_of
fn entry_limbs(engine: &Engine, recs: &[Recording]) -> Vec<Option<usize>> {
    let mut out = Vec::new();
    for rec in recs {
        for jt in &rec.joints {
            if engine.joints.contains(&jt.name) {
                let l = engine.robot.limb_of(&jt.name);
                out.extend(std::iter::repeat_n(l, rec.t.len()));
            }
        }
    }
    out
}

/// The candidates `idx` (indices into `diag`, one effect) in batches that one simulation can
/// probe together: the k-th batch holds the k-th candidate joint of every limb. A joint without
/// a limb is probed alone.
fn limb_batches(robot: &crate::model::Robot, idx: &[usize], diag: &[Candidate]) -> Vec<Vec<usize>> {
    let mut by_limb: Vec<(Option<usize>, Vec<usize>)> = Vec::new();
    for &i in idx {
        match robot.limb_of(&diag[i].joint) {
            Some(l) => match by_limb.iter_mut().find(|(x, _)| *x == Some(l)) {
                Some((_, v)) => v.push(i),
                None => by_limb.push((Some(l), vec![i])),
            },
            None => by_limb.push((None, vec![i])),
        }
    }
    let depth = by_limb.iter().map(|(_, v)| v.len()).max().unwrap_or(0);
    (0..depth).map(|k| by_limb.iter().filter_map(|(_, v)| v.get(k).copied()).collect()).collect()
}

/// Probes the candidates `batch` of one effect together: for each probe index, one simulation
/// with every member moved to its own probe value; a member's column is the change on the
/// samples of its limb (all samples when it is probed alone). When a joint simulation fails,
/// the members are probed one by one. Returns each member's best probe.
#[allow(clippy::too_many_arguments)]
fn probe_batch(
    engine: &Engine,
    train: &[Recording],
    base: &[Applied],
    tr_err: &Errors,
    (effect, m0): (&'static dyn effects::Effect, &mujoco_rs::prelude::MjModel),
    diag: &[Candidate],
    batch: &[usize],
    (r, limbs): (&[Option<f64>], &[Option<usize>]),
) -> Vec<(usize, Option<Probe>)> {
    // (candidate, start values, probe values) of the members with a target.
    let members: Vec<(usize, Vec<f64>, Vec<f64>)> = batch
        .iter()
        .filter_map(|&i| {
            let c = &diag[i];
            let t = JointTarget::of(engine.robot, &c.joint)?;
            let p0 = effect.initial(m0, &t);
            let (lo, hi) = effect.bounds(m0, &t);
            let vs = effect.probes(p0[0], lo[0], hi[0], &c.evidence);
            Some((i, p0, vs))
        })
        .collect();
    let alone = members.len() == 1;
    let mut best: Vec<Option<Probe>> = members.iter().map(|_| None).collect();
    let depth = members.iter().map(|m| m.2.len()).max().unwrap_or(0);
    for k in 0..depth {
        let moved: Vec<(usize, f64, f64)> = members
            .iter()
            .enumerate()
            .filter_map(|(n, (_, p0, vs))| {
                let v = *vs.get(k)?;
                (v != p0[0]).then_some((n, v, v - p0[0]))
            })
            .collect();
        let set = |which: &[(usize, f64, f64)]| {
            let mut a = base.to_vec();
            for &(n, v, _) in which {
                let (i, p0, _) = &members[n];
                let mut p = p0.clone();
                p[0] = v;
                a.push(Applied { effect, joints: vec![diag[*i].joint.clone()], params: p });
            }
            a
        };
        // (member, value, step, change on the scored samples)
        let mut changes: Vec<(usize, f64, f64, Vec<f64>)> = Vec::new();
        match engine.errors(train, &set(&moved)) {
            Some(e) => {
                let all = change(engine, train, tr_err, &e, r);
                for &(n, v, step) in &moved {
                    let mut col = all.clone();
                    if !alone {
                        let own = engine.robot.limb_of(&diag[members[n].0].joint);
                        for (x, l) in col.iter_mut().zip(limbs) {
                            if *l != own {
                                *x = 0.0;
                            }
                        }
                    }
                    changes.push((n, v, step, col));
                }
            }
            None if moved.len() > 1 => {
                for one in &moved {
                    if let Some(e) = engine.errors(train, &set(std::slice::from_ref(one))) {
                        changes.push((one.0, one.1, one.2, change(engine, train, tr_err, &e, r)));
                    }
                }
            }
            None => {}
        }
        for (n, v, step, mut column) in changes {
            let ss = dot(&column, &column);
            if ss <= 1e-300 {
                continue;
            }
            let rs = dot_r(&column, r);
            let explained = rs * rs / ss;
            if best[n].as_ref().is_none_or(|b| explained > b.explained) {
                column.iter_mut().for_each(|x| *x /= step);
                best[n] = Some(Probe { v, step, column, explained });
            }
        }
    }
    members.iter().map(|m| m.0).zip(best).collect()
}

impl Screen {
    /// Probes every uncovered candidate of `diag` on `train` (the screen's data; `tr_err` its
    /// residual with `base`), one effect at a time, its joints in parallel, keeping the best of
    /// the effect's probe values; sets each candidate's `explained_rms` to the linear explained
    /// RMS.
    pub(super) fn build(
        engine: &Engine,
        train: &[Recording],
        base: &[Applied],
        tr_err: &Errors,
        diag: &mut [Candidate],
        covered: &(dyn Fn(&str, &str) -> bool + Sync),
    ) -> Screen {
        let r = aligned(engine, train, tr_err);
        let limbs = entry_limbs(engine, train);
        let train_ss: f64 = r.iter().flatten().map(|x| x * x).sum();
        let train_n = r.iter().flatten().count();
        let mut models: BTreeMap<&'static str, EffectModel> = BTreeMap::new();
        let mut ids: Vec<&'static str> = diag.iter().map(|c| c.effect).collect();
        ids.sort_unstable();
        ids.dedup();
        let m0 = model_with(engine.robot, base);
        for id in ids {
            let Some(effect) = effects::by_id(id) else { continue };
            let idx: Vec<usize> = (0..diag.len())
                .filter(|&i| diag[i].effect == id && !covered(id, &diag[i].joint))
                .collect();
            // One simulation probes one candidate joint of every limb at once: a column is
            // the change on its own limb's samples ([`limb_batches`]).
            let batches = limb_batches(engine.robot, &idx, diag);
            let probed: Vec<Vec<(usize, Option<Probe>)>> = batches
                .par_iter()
                .map(|batch| {
                    probe_batch(
                        engine,
                        train,
                        base,
                        tr_err,
                        (effect, &m0),
                        diag,
                        batch,
                        (&r, &limbs),
                    )
                })
                .collect();
            let mut found: BTreeMap<usize, Probe> = BTreeMap::new();
            for (i, p) in probed.into_iter().flatten() {
                if let Some(p) = p {
                    found.insert(i, p);
                }
            }
            let probes: Vec<Option<Probe>> = idx.iter().map(|i| found.remove(i)).collect();
            let mut m = EffectModel::default();
            let mut cols: Vec<&Vec<f64>> = Vec::new();
            for (&i, p) in idx.iter().zip(&probes) {
                let c = &mut diag[i];
                let Some(p) = p else { continue };
                if train_n > 0 {
                    c.evidence.insert("feature_explained_rms".into(), c.explained_rms);
                    let coef = dot_r(&p.column, &r) / dot(&p.column, &p.column) / p.step;
                    c.evidence.insert("sensitivity_coef".into(), coef);
                    c.evidence.insert("probe".into(), p.v);
                    c.explained_rms = (p.explained / train_n as f64).sqrt();
                }
                m.joints.push(c.joint.clone());
                m.b.push(dot_r(&p.column, &r));
                cols.push(&p.column);
            }
            let n = cols.len();
            m.g = vec![vec![0.0; n]; n];
            for a in 0..n {
                for b in a..n {
                    let g = dot(cols[a], cols[b]);
                    m.g[a][b] = g;
                    m.g[b][a] = g;
                }
            }
            if n > 0 {
                models.insert(id, m);
            }
        }
        Screen { models, train_ss, train_n }
    }

    /// The linear prediction for `effect` on `group` (one parameter shared by the group); `None`
    /// when a joint of the group has no column.
    pub(super) fn predict(&self, effect: &str, group: &[String]) -> Option<Prediction> {
        let m = self.models.get(effect)?;
        let ix: Vec<usize> = group
            .iter()
            .map(|j| m.joints.iter().position(|x| x == j))
            .collect::<Option<Vec<_>>>()?;
        let b: f64 = ix.iter().map(|&i| m.b[i]).sum();
        let g: f64 =
            ix.iter().flat_map(|&i| ix.iter().map(move |&j| (i, j))).map(|(i, j)| m.g[i][j]).sum();
        if g <= 1e-300 || self.train_n == 0 {
            return None;
        }
        let train_left = (self.train_ss - b * b / g).max(0.0);
        Some(Prediction { train_rmse: (train_left / self.train_n as f64).sqrt(), step: b / g })
    }
}
