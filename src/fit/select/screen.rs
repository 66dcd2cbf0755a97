//! The linearised screen: probe simulations give the residual's sensitivity to each (effect,
//! joint) (a finite-difference Jacobian column, on the probes' data: the stretches of every
//! training episode where the residual is largest, see below); every candidate group of one effect — a
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
//! The probes replay only part of the screen's data: from each of its episodes the stretch where
//! the round's residual is largest, [`SearchPolicy::probe_seconds`] in all (2 s of the screen's
//! 10 s by default). A column only ranks candidates and gives the coarse fit its first step;
//! every fit runs on the screen's data. On Asimov's legs that is 105 probe replays of 2 s
//! instead of 10 s.
//!
//! Only sums over the samples are kept (each column's dot product with the residual and with the
//! effect's other columns), so memory does not grow with the recordings' length.
//!
//! [`SearchPolicy::probe_seconds`]: super::policy::SearchPolicy::probe_seconds

use std::collections::BTreeMap;

use rayon::prelude::*;
use serde::Serialize;

use crate::fit::diagnose::Candidate;
use crate::fit::effects::{self, Applied, JointTarget, model_with};
use crate::fit::split::segments;
use crate::sim2real::metrics::gap_mask;
use crate::sim2real::recording::Recording;

use super::{Engine, Errors};

mod probe;
use probe::{Probe, Sims, aligned, dot, dot_r, entry_limbs, limb_batches, probe_batch};
mod at;
mod held;
mod seeded;
pub(super) use held::HeldoutScreen;

/// The screen's data: about `screen_seconds` of `recs` in all, from each episode the stretch
/// where the residual of `e` (summed over the fitted joints' scored samples) is largest — the
/// missing physics shows most where the model is most wrong ([`segments`]).
pub(super) fn screen_data(engine: &Engine, recs: &[Recording], e: &Errors) -> Vec<Recording> {
    stretches(engine, recs, e, engine.opts.policy.screen_seconds)
}

/// About `seconds` of `recs` in all: from each episode the stretch where the residual of `e`
/// (summed over the fitted joints' scored samples) is largest ([`segments`]).
fn stretches(engine: &Engine, recs: &[Recording], e: &Errors, seconds: f64) -> Vec<Recording> {
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
    segments(recs, &weight, seconds)
}

/// Whether `a` holds the same stretches as `b` (a [`segments`] copy of the whole set).
fn same_data(a: &[Recording], b: &[Recording]) -> bool {
    a.len() == b.len()
        && a.iter().zip(b).all(|(x, y)| x.t.len() == y.t.len() && x.t.first() == y.t.first())
}

/// One effect's linear model: per joint and probed parameter ([`Effect::stepped`]) a column,
/// its dot product with the residual (`b[joint][param]`) and with every other column of the
/// effect (`g`, indexed `joint × k + param`), per unit of the parameter; the first `ranked`
/// ([`Effect::screened`]) rank and predict.
#[derive(Debug, Clone, Default)]
struct EffectModel {
    joints: Vec<String>,
    /// Per joint, how far the first parameter may step from its start: (lo − p0, hi − p0).
    room: Vec<(f64, f64)>,
    k: usize,
    ranked: usize,
    b: Vec<Vec<f64>>,
    g: Vec<Vec<f64>>,
    /// Per joint, how many of the effect's fitted parameters its bounds hold (zero width: a
    /// body's place along a direction no rotation moves the body).
    held: Vec<usize>,
}

impl EffectModel {
    /// The fewest parameters the bounds hold on any joint of `group` (0 for a joint not here).
    fn held(&self, group: &[String]) -> usize {
        let at = |j: &String| self.joints.iter().position(|x| x == j).map_or(0, |i| self.held[i]);
        group.iter().map(at).min().unwrap_or(0)
    }
}

/// What the linear model predicts for one candidate (effect, joint group).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Prediction {
    /// Residual RMSE on the screen's data after the linear step: the screen's RMSE scaled by
    /// the relative change the step makes on the probes' data [rad].
    pub train_rmse: f64,
    /// The step of the effect's first parameter that the training residual asks for.
    pub step: f64,
}

/// The linear model of every (effect, joint) the round's diagnosis lists.
pub(super) struct Screen {
    models: BTreeMap<&'static str, EffectModel>,
    /// The probes' residual: sum of squares and scored samples.
    train_ss: f64,
    train_n: usize,
    /// The screen's data's residual RMSE [rad], to which the probes' shares are scaled.
    screen_rmse: f64,
    /// The screen's data's residual windows: the independent pieces over which the information
    /// criterion charges a prediction on that data ([`Screen::lead_rmse`]).
    pieces: usize,
}

/// The least-squares combination of columns with Gram matrix `g` and residual products `b`:
/// the residual sum of squares it explains, `bᵀ G⁺ b`, and the coefficients. A column that
/// adds nothing the earlier ones do not span (its pivot below 1e-9 of its own square) is left
/// out at 0.
pub(super) fn combine(b: &[f64], g: &[Vec<f64>]) -> (f64, Vec<f64>) {
    let k = b.len();
    // Cholesky G = L Lᵀ with the dependent columns skipped.
    let mut l = vec![vec![0.0; k]; k];
    let mut used = vec![false; k];
    for i in 0..k {
        let d = g[i][i] - (0..i).map(|p| l[i][p] * l[i][p]).sum::<f64>();
        if !(d > 1e-9 * g[i][i]) || g[i][i] <= 1e-300 {
            continue;
        }
        used[i] = true;
        l[i][i] = d.sqrt();
        for j in i + 1..k {
            l[j][i] = (g[j][i] - (0..i).map(|p| l[j][p] * l[i][p]).sum::<f64>()) / l[i][i];
        }
    }
    // Forward: L y = b; explained = |y|²; back: Lᵀ x = y.
    let mut y = vec![0.0; k];
    for i in (0..k).filter(|&i| used[i]) {
        y[i] = (b[i] - (0..i).filter(|&p| used[p]).map(|p| l[i][p] * y[p]).sum::<f64>()) / l[i][i];
    }
    let mut x = vec![0.0; k];
    for i in (0..k).rev().filter(|&i| used[i]) {
        x[i] =
            (y[i] - (i + 1..k).filter(|&j| used[j]).map(|j| l[j][i] * x[j]).sum::<f64>()) / l[i][i];
    }
    (y.iter().map(|v| v * v).sum(), x)
}

/// The explained sum of squares a `k`-column fit is worth next to a one-column fit, by the
/// information criterion counted over `m` independent pieces ([`bic_pieces`]): of `left` =
/// `ss − explained`, the extra `k − 1` parameters are charged `(k − 1) ln m` of `m ln(left)`,
/// i.e. `left` grows by the factor `m^((k − 1)/m)`.
///
/// [`bic_pieces`]: crate::fit::stats::bic_pieces
pub(super) fn charged(ss: f64, explained: f64, k: usize, m: usize) -> f64 {
    if k <= 1 || m <= 1 {
        return explained;
    }
    let mf = m as f64;
    let left = (ss - explained).max(0.0) * ((k - 1) as f64 * mf.ln() / mf).exp();
    (ss - left).max(0.0)
}

/// What the probes of every effect share ([`Screen::build`]): the probes' data (the stretches
/// of the screen's data where its residual is largest, `probe_seconds` in all: the screen's data
/// itself when not longer, or when the base replay of the stretches fails), its residual with
/// the base, and the scale of the screen's data. One effect's linear model is made from it by
/// [`Probes::model`], independently of every other effect's.
struct Probes<'a> {
    /// The probes' data when it is not the screen's data itself.
    held: Option<std::sync::Arc<Vec<Recording>>>,
    screen: &'a [Recording],
    base: &'a [Applied],
    /// The probes' data's residual with `base` (`None`: the screen's, `sc_err`).
    own_err: Option<Errors>,
    sc_err: &'a Errors,
    r: Vec<Option<f64>>,
    limbs: Vec<Option<usize>>,
    screen_rmse: f64,
    train_ss: f64,
    train_n: usize,
    m0: mujoco_rs::prelude::MjModel,
}

impl<'a> Probes<'a> {
    /// The probes' data of `screen` (`sc_err` its residual with `base`) and its base replay.
    fn new(
        engine: &Engine,
        screen: &'a [Recording],
        base: &'a [Applied],
        sc_err: &'a Errors,
    ) -> Probes<'a> {
        let seconds = engine.opts.policy.probe_seconds;
        let held = engine.probe_set(screen, base, || stretches(engine, screen, sc_err, seconds));
        let own_err = if same_data(&held, screen) { None } else { engine.errors(&held, base) };
        let held = own_err.is_some().then_some(held);
        let mut p = Probes {
            held,
            screen,
            base,
            own_err,
            sc_err,
            r: vec![],
            limbs: vec![],
            screen_rmse: 0.0,
            train_ss: 0.0,
            train_n: 0,
            m0: model_with(engine.robot, base),
        };
        let (train, tr_err) = p.data();
        let r = aligned(engine, train, tr_err);
        p.limbs = entry_limbs(engine, train);
        p.screen_rmse = {
            let rs = aligned(engine, screen, sc_err);
            let n = rs.iter().flatten().count();
            (rs.iter().flatten().map(|x| x * x).sum::<f64>() / n as f64).sqrt()
        };
        p.train_ss = r.iter().flatten().map(|x| x * x).sum();
        p.train_n = r.iter().flatten().count();
        p.r = r;
        p
    }

    /// The probes' data and its residual with the base.
    fn data(&self) -> (&[Recording], &Errors) {
        match (&self.held, &self.own_err) {
            (Some(h), Some(e)) => (&h[..], e),
            _ => (self.screen, self.sc_err),
        }
    }

    /// A screen without any effect's model yet, on these probes.
    fn screen(&self) -> Screen {
        Screen {
            models: BTreeMap::new(),
            train_ss: self.train_ss,
            train_n: self.train_n,
            screen_rmse: self.screen_rmse,
            pieces: self.sc_err.windows.len(),
        }
    }

    /// The linear model of effect `id` from the probes of its uncovered candidates in `diag`,
    /// one candidate joint of every limb at once, its joints in parallel, keeping for each
    /// screened parameter the best of its probe values; sets each probed candidate's
    /// `explained_rms` and evidence ([`Screen::build`]). `None` when no joint has a column.
    /// The entries `seeded` (of [`seeded::seed`]) that its value leaves without a column are
    /// probed again at their own probe values.
    fn model(
        &self,
        engine: &Engine,
        id: &'static str,
        diag: &mut [Candidate],
        covered: &(dyn Fn(&str, &str) -> bool + Sync),
        seeded: &[usize],
    ) -> Option<EffectModel> {
        let batches = batches(engine, id, diag, covered);
        let mut found: BTreeMap<usize, Vec<Option<Probe>>> =
            self.probe(engine, id, diag, &batches).into_iter().collect();
        let again = seeded::unanswered(id, diag, covered, seeded, &found);
        if !again.is_empty() {
            let batches = limb_batches(engine.robot, &again, diag);
            found.extend(self.probe(engine, id, diag, &batches));
        }
        self.assemble(engine, id, diag, covered, &found)
    }

    /// The best probes of every candidate of `batches` (of [`batches`]), the batches in
    /// parallel ([`probe_batch`]).
    fn probe(
        &self,
        engine: &Engine,
        id: &'static str,
        diag: &[Candidate],
        batches: &[Vec<usize>],
    ) -> Vec<(usize, Vec<Option<Probe>>)> {
        let Some(effect) = effects::by_id(id) else { return vec![] };
        let (train, tr_err) = self.data();
        let (r, limbs, base) = (&self.r, &self.limbs, self.base);
        let k = probed_params(effect);
        let probed: Vec<Vec<(usize, Vec<Option<Probe>>)>> = batches
            .par_iter()
            .map(|batch| {
                let sims = Sims { engine, train, base, tr_err, r, limbs };
                probe_batch(&sims, (effect, &self.m0), diag, batch, k)
            })
            .collect();
        probed.into_iter().flatten().collect()
    }

    /// The linear model of effect `id` from the probes `found` (by diagnosis entry) of its
    /// uncovered candidates in `diag` (an entry without probes is not modelled); sets each
    /// modelled candidate's `explained_rms` and evidence. `None` when no joint has a column.
    fn assemble(
        &self,
        engine: &Engine,
        id: &'static str,
        diag: &mut [Candidate],
        covered: &(dyn Fn(&str, &str) -> bool + Sync),
        found: &BTreeMap<usize, Vec<Option<Probe>>>,
    ) -> Option<EffectModel> {
        let (_, tr_err) = self.data();
        let (r, m0) = (&self.r, &self.m0);
        let (train_ss, train_n, screen_rmse) = (self.train_ss, self.train_n, self.screen_rmse);
        let pieces = tr_err.windows.len();
        let effect = effects::by_id(id)?;
        let k = probed_params(effect);
        let kr = effect.screened().clamp(1, k);
        let idx = entries(id, diag, covered);
        let none = vec![];
        let probes: Vec<&Vec<Option<Probe>>> =
            idx.iter().map(|i| found.get(i).unwrap_or(&none)).collect();
        let mut m = EffectModel { k, ranked: kr, ..Default::default() };
        let zero = vec![0.0; r.len()];
        let mut cols: Vec<&Vec<f64>> = Vec::new();
        for (&i, ps) in idx.iter().zip(probes) {
            let c = &mut diag[i];
            // A joint whose first parameter has no column is not modelled (as before the
            // other parameters were screened).
            let Some(Some(p)) = ps.first() else { continue };
            let own: Vec<&Vec<f64>> = (0..k)
                .map(|j| ps.get(j).and_then(|p| p.as_ref()).map_or(&zero, |p| &p.column))
                .collect();
            let b: Vec<f64> = own.iter().map(|col| dot_r(col, r)).collect();
            if train_n > 0 {
                let (rk, pr) = (&own[..kr], &ps[..kr.min(ps.len())]);
                let g: Vec<Vec<f64>> =
                    rk.iter().map(|x| rk.iter().map(|y| dot(x, y)).collect()).collect();
                let single = pr.iter().flatten().map(|p| p.explained).fold(0.0, f64::max);
                // Charged for the ranking parameters probed here (one held by bounds of
                // zero width has no column).
                let kc = pr.iter().flatten().count();
                let all = charged(train_ss, combine(&b[..kr], &g).0, kc, pieces);
                c.evidence.insert("feature_explained_rms".into(), c.explained_rms);
                let coef = dot_r(&p.column, r) / dot(&p.column, &p.column) / p.step;
                c.evidence.insert("sensitivity_coef".into(), coef);
                c.evidence.insert(probe::CHOSEN_PROBE.into(), p.v);
                // On the screen's data's scale: its RMSE times the share of the probes'.
                c.explained_rms =
                    screen_rmse * (single.max(all) / train_ss.max(f64::MIN_POSITIVE)).sqrt();
            }
            let (room, held) = JointTarget::of(engine.robot, &c.joint).map_or(
                ((f64::NEG_INFINITY, f64::INFINITY), 0),
                |t| {
                    let (p0, (lo, hi)) = (effect.initial(m0, &t), effect.bounds(m0, &t));
                    let n = effect.fitted().min(lo.len()).min(hi.len());
                    let held = (0..n).filter(|&i| hi[i] <= lo[i]).count();
                    match (p0.first(), lo.first(), hi.first()) {
                        (Some(p), Some(l), Some(h)) => ((l - p, h - p), held),
                        _ => ((f64::NEG_INFINITY, f64::INFINITY), held),
                    }
                },
            );
            m.held.push(held);
            m.joints.push(c.joint.clone());
            m.room.push(room);
            m.b.push(b);
            cols.extend(own);
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
        (!m.joints.is_empty()).then_some(m)
    }
}

/// How many of `effect`'s parameters are probed ([`Effect::stepped`], at least the screened).
///
/// [`Effect::stepped`]: crate::fit::effects::Effect::stepped
fn probed_params(effect: &dyn effects::Effect) -> usize {
    effect.stepped().max(effect.screened()).clamp(1, effect.fitted().max(1))
}

/// The uncovered entries of effect `id` in `diag`.
fn entries(
    id: &str,
    diag: &[Candidate],
    covered: &(dyn Fn(&str, &str) -> bool + Sync),
) -> Vec<usize> {
    (0..diag.len()).filter(|&i| diag[i].effect == id && !covered(id, &diag[i].joint)).collect()
}

/// The probe simulations of effect `id`'s uncovered entries in `diag`: one simulation probes
/// one candidate joint of every limb at once, a column being the change on its own limb's
/// samples ([`limb_batches`]).
fn batches(
    engine: &Engine,
    id: &str,
    diag: &[Candidate],
    covered: &(dyn Fn(&str, &str) -> bool + Sync),
) -> Vec<Vec<usize>> {
    limb_batches(engine.robot, &entries(id, diag, covered), diag)
}

impl Screen {
    /// Probes every uncovered candidate of `diag` on the probes' data — from the screen's data
    /// `screen` (`sc_err` its residual with `base`) the stretches of largest residual,
    /// [`SearchPolicy::probe_seconds`] in all — one effect at a time, its joints in parallel, keeping for each
    /// screened parameter the best of its probe values; sets each candidate's `explained_rms`
    /// to the linear explained RMS of the best combination of its columns, a combination of
    /// more than one charged by the information criterion over the residual's windows
    /// ([`charged`]). The linear model's residual, its RMSE and the predictions are those of
    /// the probes' data.
    ///
    /// [`SearchPolicy::probe_seconds`]: super::policy::SearchPolicy::probe_seconds
    #[cfg(test)]
    pub(super) fn build(
        engine: &Engine,
        screen: &[Recording],
        base: &[Applied],
        sc_err: &Errors,
        diag: &mut [Candidate],
        covered: &(dyn Fn(&str, &str) -> bool + Sync),
    ) -> Screen {
        Screen::build_after(engine, (screen, base, sc_err), diag, covered, &[])
    }

    /// [`Screen::build`] after an earlier round's screen, whose diagnosis `earlier` names the
    /// value of each candidate's best probe: an effect of several probe values is probed at
    /// that value alone where it still gives a column ([`seeded`]).
    pub(super) fn build_after(
        engine: &Engine,
        (screen, base, sc_err): (&[Recording], &[Applied], &Errors),
        diag: &mut [Candidate],
        covered: &(dyn Fn(&str, &str) -> bool + Sync),
        earlier: &[Candidate],
    ) -> Screen {
        let probes = Probes::new(engine, screen, base, sc_err);
        let seeded = seeded::seed(engine, &probes.m0, diag, covered, earlier);
        let mut ids: Vec<&'static str> = diag.iter().map(|c| c.effect).collect();
        ids.sort_unstable();
        ids.dedup();
        let mut out = probes.screen();
        for id in ids {
            if let Some(m) = probes.model(engine, id, diag, covered, &seeded) {
                out.models.insert(id, m);
            }
        }
        out
    }

    /// The training RMSE of the prediction `p` of `effect` on `group` (on the screen's data's
    /// scale), charged for its `k` fitted parameters by the information criterion over the
    /// screen's data's m windows ([`charged`]: what is left grows by m^((k − 1)/m)), so that
    /// candidates of different sizes compare: the lead's measure ([`super::lead`]) of
    /// [`Screen::predict_from`]'s prediction ([`Screen::lead_rmse_beside`]).
    pub(super) fn lead_rmse(&self, effect: &str, group: &[String], k: usize, p: Prediction) -> f64 {
        // A parameter held by bounds of zero width on the group is not charged.
        let k = k.saturating_sub(self.models.get(effect).map_or(0, |m| m.held(group)));
        let ss = self.train_ss;
        if !(ss > 0.0) || !(self.screen_rmse > 0.0) {
            return p.train_rmse;
        }
        let left = ss * (p.train_rmse / self.screen_rmse).powi(2);
        let explained = charged(ss, (ss - left).max(0.0), k, self.pieces);
        self.screen_rmse * ((ss - explained).max(0.0) / ss).sqrt()
    }

    /// The RMSE of the screen's residual before any step [rad].
    pub(super) fn base_rmse(&self) -> f64 {
        if self.train_n == 0 { f64::NAN } else { self.screen_rmse }
    }

    /// The linear prediction for `effect` on `group` (one parameter vector shared by the
    /// group: each parameter's column the sum of the group's columns; the least-squares step of
    /// all screened parameters, uncharged — the fit that follows fits them all); `None` when a
    /// joint of the group has no column.
    pub(super) fn predict(&self, effect: &str, group: &[String]) -> Option<Prediction> {
        self.linear(effect, group, false).map(|(p, _)| p)
    }

    /// The least-squares step of every probed parameter of `effect` on `group` (from the
    /// effect's start; [`Effect::stepped`]) and what it predicts: [`Screen::predict`]'s when
    /// the ranking columns are all that is probed.
    pub(super) fn steps(&self, effect: &str, group: &[String]) -> Option<(Prediction, Vec<f64>)> {
        self.linear(effect, group, true)
    }

    /// The prediction and steps of the ranking columns, or of every probed one (`all`).
    fn linear(&self, effect: &str, group: &[String], all: bool) -> Option<(Prediction, Vec<f64>)> {
        let m = self.models.get(effect)?;
        let ix: Vec<usize> = group
            .iter()
            .map(|j| m.joints.iter().position(|x| x == j))
            .collect::<Option<Vec<_>>>()?;
        let (k, s) = (if all { m.k } else { m.ranked }, m.k);
        let b: Vec<f64> = (0..k).map(|p| ix.iter().map(|&i| m.b[i][p]).sum()).collect();
        let g: Vec<Vec<f64>> = (0..k)
            .map(|p| {
                (0..k)
                    .map(|q| {
                        ix.iter()
                            .flat_map(|&i| ix.iter().map(move |&j| (i, j)))
                            .map(|(i, j)| m.g[i * s + p][j * s + q])
                            .sum()
                    })
                    .collect()
            })
            .collect();
        if g[0][0] <= 1e-300 || self.train_n == 0 {
            return None;
        }
        let (mut explained, mut x) = combine(&b, &g);
        // One parameter: the step stays inside the parameter's bounds (the group's shared
        // value inside every member's), and explains 2 s b − s² g there. A residual that asks
        // for negative friction is not explained by friction.
        if k == 1 {
            let lo = ix.iter().map(|&i| m.room[i].0).fold(f64::NEG_INFINITY, f64::max);
            let hi = ix.iter().map(|&i| m.room[i].1).fold(f64::INFINITY, f64::min);
            if lo <= hi && !(lo..=hi).contains(&x[0]) {
                let s = x[0].clamp(lo, hi);
                explained = (2.0 * s * b[0] - s * s * g[0][0]).max(0.0);
                x[0] = s;
            }
        }
        let train_left = (self.train_ss - explained).max(0.0);
        let train_rmse =
            self.screen_rmse * (train_left / self.train_ss.max(f64::MIN_POSITIVE)).sqrt();
        Some((Prediction { train_rmse, step: x[0] }, x))
    }
}

#[cfg(test)]
mod tests {
    use super::{EffectModel, Screen, charged, combine};

    /// Two columns: the residual r = 2 a + 3 c is explained whole by the pair, by neither alone.
    #[test]
    fn the_best_combination_of_columns_explains_what_each_alone_does_not() {
        let a = [1.0, 0.0, 1.0, 0.5];
        let c = [0.0, 1.0, 1.0, -0.5];
        let r: Vec<f64> = a.iter().zip(&c).map(|(x, y)| 2.0 * x + 3.0 * y).collect();
        let d = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>();
        let b = [d(&a, &r), d(&c, &r)];
        let g = vec![vec![d(&a, &a), d(&a, &c)], vec![d(&c, &a), d(&c, &c)]];
        let (e, x) = combine(&b, &g);
        let ss = d(&r, &r);
        assert!((e - ss).abs() < 1e-12 * ss, "{e} of {ss}");
        assert!((x[0] - 2.0).abs() < 1e-12 && (x[1] - 3.0).abs() < 1e-12, "{x:?}");
        assert!(b[0] * b[0] / g[0][0] < 0.9 * ss && b[1] * b[1] / g[1][1] < 0.9 * ss);
        // A repeated column adds nothing and is left at 0.
        let (e2, x2) = combine(&[b[0], b[0]], &[vec![g[0][0]; 2], vec![g[0][0]; 2]]);
        assert!((e2 - b[0] * b[0] / g[0][0]).abs() < 1e-12 * ss && x2[1] == 0.0, "{x2:?}");
        // A zero column (a parameter without a probe) too.
        let (e3, _) = combine(&[b[0], 0.0], &[vec![g[0][0], 0.0], vec![0.0, 0.0]]);
        assert!((e3 - b[0] * b[0] / g[0][0]).abs() < 1e-12 * ss);
    }

    /// The charge: nothing for one column; for a second, what is left grows by m^(1/m).
    #[test]
    fn a_second_column_is_charged_by_the_information_criterion() {
        assert_eq!(charged(10.0, 4.0, 1, 100), 4.0);
        let m = 100.0_f64;
        let want = 10.0 - 6.0 * m.powf(1.0 / m);
        assert!((charged(10.0, 4.0, 2, 100) - want).abs() < 1e-12);
        assert!(charged(10.0, 4.0, 2, 100) < 4.0 && charged(10.0, 4.0, 3, 100) < want);
        assert_eq!(charged(10.0, 0.0, 2, 100), 0.0);
    }

    /// A screen of one one-parameter effect `e` on members `a` and `b` (for the tests): member
    /// a's column `c` against the residual `r`, member b's column of the same norm and
    /// orthogonal to both, each member within its room (step bounds from its start); returns
    /// the screen and the residual's sum of squares.
    pub(in crate::fit::select) fn two_member_screen(
        c: &[f64],
        r: &[f64],
        room: [(f64, f64); 2],
    ) -> (Screen, f64) {
        let d = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>();
        let m = EffectModel {
            joints: vec!["a".into(), "b".into()],
            room: room.to_vec(),
            k: 1,
            ranked: 1,
            b: vec![vec![d(c, r)], vec![0.0]],
            g: vec![vec![d(c, c), 0.0], vec![0.0, d(c, c)]],
            held: vec![0, 0],
        };
        let ss = d(r, r);
        let screen_rmse = (ss / r.len() as f64).sqrt();
        let s = Screen {
            models: [("e", m)].into(),
            train_ss: ss,
            train_n: r.len(),
            screen_rmse,
            pieces: 1,
        };
        (s, ss)
    }

    /// A one-parameter prediction stays inside the parameter's bounds: a residual that asks for
    /// a step below the lower bound (negative friction) is explained only as far as the bound
    /// allows; a group's shared value keeps inside every member's bounds.
    #[test]
    fn a_one_parameter_prediction_respects_the_bounds() {
        let c = [1.0, -0.5, 0.25, 2.0];
        let screen = |step: f64, room: (f64, f64)| {
            let r: Vec<f64> = c.iter().map(|x| step * x).collect();
            two_member_screen(&c, &r, [room, (room.0, room.1 * 0.5)])
        };
        let rmse = |ss: f64| (ss / c.len() as f64).sqrt();
        // Inside the bounds: the residual explained whole, the step the one asked for.
        let (s, _) = screen(2.0, (-1.0, 10.0));
        let p = s.predict("e", &["a".into()]).expect("modelled");
        assert!(p.train_rmse < 1e-9 && (p.step - 2.0).abs() < 1e-12, "{p:?}");
        // Asking for −2 where the parameter cannot go below its start: nothing explained.
        let (s, ss) = screen(-2.0, (0.0, 10.0));
        let p = s.predict("e", &["a".into()]).expect("modelled");
        assert!((p.train_rmse - rmse(ss)).abs() < 1e-12 && p.step == 0.0, "{p:?}");
        // Half-way room: the step stops at the bound and explains 2 s b − s² g = 3/4 of it.
        let (s, ss) = screen(-2.0, (-1.0, 10.0));
        let p = s.predict("e", &["a".into()]).expect("modelled");
        assert!((p.train_rmse - rmse(0.25 * ss)).abs() < 1e-12 && p.step == -1.0, "{p:?}");
        // A group: the shared step keeps inside the narrower member's room (b's upper bound 1).
        let (s, _) = screen(4.0, (-1.0, 2.0));
        let p = s.predict("e", &["a".into(), "b".into()]).expect("modelled");
        assert!(p.step == 1.0, "{p:?}");
        // Probes on stretches whose residual is twice the screen's: the prediction is the
        // screen's RMSE scaled by the relative change on the probes' data.
        let (mut s, ss) = screen(-2.0, (-1.0, 10.0));
        s.screen_rmse = 0.5 * rmse(ss);
        assert_eq!(s.base_rmse(), 0.5 * rmse(ss));
        let p = s.predict("e", &["a".into()]).expect("modelled");
        assert!((p.train_rmse - 0.5 * rmse(0.25 * ss)).abs() < 1e-12, "{p:?}");
    }
}
