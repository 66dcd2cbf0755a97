//! The probes of the linearised screen ([`super::Screen::build`]): one simulation per probe
//! value moves one candidate joint of every limb at once, and each joint's sensitivity column
//! is the change on its own limb's samples of the probes' data.

use crate::fit::diagnose::Candidate;
use crate::fit::effects::{self, Applied, JointTarget, Seen};
use crate::sim2real::metrics::gap_mask;
use crate::sim2real::recording::Recording;

use super::super::at_base::seen;
use super::super::{Engine, Errors, Unprobed};

/// The residual of one simulated dataset, sample by sample over (episode, fitted joint, scored
/// sample); `None` where the recording or the replay is not finite or the sample follows a gap.
pub(super) fn aligned(engine: &Engine, recs: &[Recording], e: &Errors) -> Vec<Option<f64>> {
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
pub(super) fn change(
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

pub(super) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

pub(super) fn dot_r(a: &[f64], r: &[Option<f64>]) -> f64 {
    a.iter().zip(r).map(|(x, y)| x * y.unwrap_or(0.0)).sum()
}

/// The diagnosis evidence naming the value of its first parameter at which a candidate's
/// best probe was made ([`super::Screen::build`]); a later screen of the same candidate (the
/// held-out set's, on the same base) probes that value alone, not each of [`Effect::probes`].
///
/// [`Effect::probes`]: crate::fit::effects::Effect::probes
pub(in crate::fit::select) const CHOSEN_PROBE: &str = "probe";

/// One probe of a candidate's parameter: the probe value, its step from the start, the
/// training column (per unit of the parameter).
pub(super) struct Probe {
    pub(super) v: f64,
    pub(super) step: f64,
    pub(super) column: Vec<f64>,
    pub(super) explained: f64,
}

/// The limb ([`Robot::limb_of`]) of each sample of [`aligned`]'s order.
///
/// [`Robot::limb_of`]: crate::model::Robot::limb_of
pub(super) fn entry_limbs(engine: &Engine, recs: &[Recording]) -> Vec<Option<usize>> {
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
pub(super) fn limb_batches(
    robot: &crate::model::Robot,
    idx: &[usize],
    diag: &[Candidate],
) -> Vec<Vec<usize>> {
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

/// What a probe simulation needs: the engine, the screen's data and its residual with `base`
/// (`tr_err`, `r` in [`aligned`] order) and the limb of each of those samples.
pub(super) struct Sims<'a> {
    pub(super) engine: &'a Engine<'a>,
    pub(super) train: &'a [Recording],
    pub(super) base: &'a [Applied],
    pub(super) tr_err: &'a Errors,
    pub(super) r: &'a [Option<f64>],
    pub(super) limbs: &'a [Option<usize>],
}

/// Probes the candidates `batch` of one effect together, each of its first `k` parameters in
/// turn: for each parameter and probe index, one simulation with every member's parameter moved
/// to its own probe value; a member's column is the change on the samples of its limb (all
/// samples when it is probed alone). When a joint simulation fails, the members are probed one
/// by one. A move that provably changes nothing ([`effects::Effect::unmoved`]: its column is
/// exactly zero, which no probe keeps) is not replayed and is noted ([`Engine::note_unprobed`]).
/// Returns each member's best probe per parameter (empty for a joint without a target).
pub(super) fn probe_batch(
    sims: &Sims,
    (effect, m0): (&'static dyn effects::Effect, &mujoco_rs::prelude::MjModel),
    diag: &[Candidate],
    batch: &[usize],
    k: usize,
) -> Vec<(usize, Vec<Option<Probe>>)> {
    let Sims { engine, train, base, tr_err, r, limbs } = *sims;
    // (candidate, start values, bounds) of the members with a target.
    type Member = (usize, Vec<f64>, (Vec<f64>, Vec<f64>));
    let (members, targets): (Vec<Member>, Vec<JointTarget>) = batch
        .iter()
        .filter_map(|&i| {
            let t = JointTarget::of(engine.robot, &diag[i].joint)?;
            Some(((i, effect.initial(m0, &t), effect.bounds(m0, &t)), t))
        })
        .unzip();
    let seen: Vec<Seen> = members.iter().map(|m| seen(tr_err, base, &diag[m.0].joint)).collect();
    let seconds: f64 =
        train.iter().map(|r| r.t.last().unwrap_or(&0.0) - r.t.first().unwrap_or(&0.0)).sum();
    let alone = members.len() == 1;
    let kk = members.iter().map(|m| m.1.len()).min().unwrap_or(0).min(k);
    let mut best: Vec<Vec<Option<Probe>>> =
        members.iter().map(|_| (0..kk).map(|_| None).collect()).collect();
    for j in 0..kk {
        // Each member's probe values of parameter j.
        let values: Vec<Vec<f64>> = members
            .iter()
            .map(|(i, p0, (lo, hi))| {
                if j == 0 {
                    // A candidate the round's training screen probed (the held-out set's
                    // linear model, [`super::super::trust::heldout_columns`]): at the value
                    // chosen there.
                    match diag[*i].evidence.get(CHOSEN_PROBE) {
                        Some(&v) if v.is_finite() => vec![v],
                        _ => effect.probes(p0[0], lo[0], hi[0], &diag[*i].evidence),
                    }
                } else {
                    vec![effects::probe_step(p0[j], lo[j], hi[j])]
                }
            })
            .collect();
        let depth = values.iter().map(Vec::len).max().unwrap_or(0);
        for d in 0..depth {
            // (member, value, step) of the members moved by this probe.
            let moved: Vec<(usize, f64, f64)> = members
                .iter()
                .enumerate()
                .filter_map(|(n, (_, p0, _))| {
                    let v = *values[n].get(d)?;
                    (v != p0[j]).then_some((n, v, v - p0[j]))
                })
                .filter(|&(n, v, _)| {
                    let (i, p0, _) = &members[n];
                    let Some(why) = effect.unmoved(m0, &targets[n], p0, (j, v), seen[n]) else {
                        return true;
                    };
                    let param = effect.params().get(j).map_or("", |p| p.name);
                    let joint = diag[*i].joint.clone();
                    let (effect, value) = (effect.id(), v);
                    engine.note_unprobed(Unprobed::new(effect, joint, param, value, why, seconds));
                    false
                })
                .collect();
            if moved.is_empty() {
                continue;
            }
            let set = |which: &[(usize, f64, f64)]| {
                let mut a = base.to_vec();
                for &(n, v, _) in which {
                    let (i, p0, _) = &members[n];
                    let mut p = p0.clone();
                    p[j] = v;
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
                            let col = change(engine, train, tr_err, &e, r);
                            changes.push((one.0, one.1, one.2, col));
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
                if best[n][j].as_ref().is_none_or(|b| explained > b.explained) {
                    column.iter_mut().for_each(|x| *x /= step);
                    best[n][j] = Some(Probe { v, step, column, explained });
                }
            }
        }
    }
    members.iter().map(|m| m.0).zip(best).collect()
}

#[cfg(test)]
mod tests {
    use super::CHOSEN_PROBE;
    use crate::fit::diagnose::diagnose;
    use crate::fit::effects::{Effect, ViscousDamping};
    use crate::fit::select::screen::Screen;
    use crate::fit::select::{Engine, FitOptions};
    use crate::sim2real::recording::Recording;

    /// A candidate that a screen probed already carries the value of its best probe, and a later
    /// screen of it (the held-out set's) probes that value alone: one replay of the probes' data
    /// at the value named, whatever the effect's own probe would be.
    #[test]
    fn a_candidate_probed_before_is_probed_at_its_chosen_value_alone() {
        let (robot, recs) =
            crate::synth::recorded::pendulum(Some((ViscousDamping.id(), vec![0.05])), 3, 7);
        let opts = FitOptions::default();
        let engine = Engine::new(&robot, &recs, &opts);
        let base = engine.errors_held(&recs, &[]).expect("replay");
        let allowed = vec![ViscousDamping.id().to_string()];
        let mut diag =
            diagnose(&robot, &recs, &base.eps, &engine.joints, &allowed, opts.gap_mask_s);
        let _ = Screen::build(&engine, &recs, &[], &base, &mut diag, &|_, _| false);
        let first = diag[0].evidence[CHOSEN_PROBE];
        assert!(first.is_finite() && first != 0.0, "{first}");
        // The same candidate named at twice that value, screened on the same data again.
        let chosen = 2.0 * first;
        diag[0].evidence.insert(CHOSEN_PROBE.into(), chosen);
        let secs = |r: &[Recording]| r.iter().map(|x| x.t.last().unwrap() - x.t[0]).sum::<f64>();
        let probes = engine.probe_set_held(&recs, &[]).expect("made by the screen");
        let before = engine.rollout_stats().simulated_s;
        let _ = Screen::build(&engine, &recs, &[], &base, &mut diag, &|_, _| false);
        let cost = engine.rollout_stats().simulated_s - before;
        assert_eq!(diag[0].evidence[CHOSEN_PROBE], chosen);
        assert!((cost - secs(&probes)).abs() < 1e-6, "{cost} s for one probe of {}", secs(&probes));
    }
}
