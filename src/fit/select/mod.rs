//! Greedy forward selection of missing physics.
//!
//! 1. Split the dataset: every `holdout`-th episode is held out (at least one when there are two
//!    or more); a single episode is cut into time windows instead, every `holdout`-th window
//!    held out. Optionally, training episodes are cut into multiple-shooting windows (each
//!    replay starts from the recorded state).
//! 2. Each round: replay the training set with the effects kept so far, [`diagnose`] the
//!    residuals, take the top-ranked (effect, joint group) candidates, and fit each one's
//!    parameters (golden section for one parameter, Nelder–Mead for two or three, CMA-ES above)
//!    to minimise the position RMSE over the training episodes.
//! 3. A candidate is kept only when, on the held-out episodes, the paired per-window RMSE
//!    improvement is beyond noise ([`improvement_beyond_noise`]), the relative RMSE improvement
//!    is at least `min_rel_improvement`, and the training BIC decreases. Of the kept candidates the
//!    one with the lowest held-out RMSE wins (a simpler one within 1 % of it is preferred).
//! 4. Repeat until nothing helps. Uncertainty: finite-difference Jacobian of the residual vector
//!    at the optimum → [`uncertainty_from_jacobian`].

use std::collections::BTreeMap;

use rayon::prelude::*;

use crate::model::mirror::mirror_name;
use serde::Serialize;

use crate::fit::diagnose::{Candidate, diagnose};
use crate::fit::effects::{self, Applied, Effect, JointTarget, model_with, replay_with};
use crate::fit::optim::{
    Bounds, CmaesOpts, LmOpts, LmResult, NelderMeadOpts, cmaes, golden_section,
    levenberg_marquardt, nelder_mead,
};
use crate::fit::split::{Split, split, windows};
use crate::fit::stats::{
    ar1_variance_inflation, bic, improvement_beyond_noise, uncertainty_from_jacobian, white_floor,
};
use crate::model::Robot;
use crate::sim2real::metrics::gap_mask;
use crate::sim2real::recording::Recording;
use crate::sim2real::replay::{Episode, ReplayOptions};

#[derive(Debug, Clone)]
pub struct FitOptions {
    /// Every N-th episode is held out (N ≥ 2).
    pub holdout: usize,
    /// Effect ids to consider (all when empty).
    pub effects: Vec<String>,
    /// Joints to fit (all recorded joints when empty).
    pub joints: Vec<String>,
    pub replay: ReplayOptions,
    /// Length of the windows of the held-out paired test [s].
    pub window_s: f64,
    /// Multiple shooting: cut training episodes into windows of this length [s].
    pub shooting_s: Option<f64>,
    pub max_rounds: usize,
    pub candidates_per_round: usize,
    /// Minimum relative held-out RMSE improvement for an effect to be kept.
    pub min_rel_improvement: f64,
    /// Objective evaluations per candidate fit.
    pub max_evals: usize,
    /// Joint → motor family (from the spec): a family of three or more fitted joints is also
    /// tried as one group sharing the parameters.
    pub families: BTreeMap<String, String>,
    /// Besides the top `candidates_per_round`, also fit the best-ranked joint group of every
    /// other allowed effect (the linearised ranking misses strongly nonlinear effects).
    pub every_effect: bool,
    /// A candidate that cuts the held-out RMSE by at least this fraction, with more than twice
    /// as many held-out windows improved as worsened, is kept without the paired z test (an
    /// effect confined to a few windows, e.g. saturation, cannot pass it; noise cannot halve the
    /// error on unseen episodes).
    pub decisive_improvement: f64,
    /// After the greedy rounds: drop kept effects whose removal does not hurt held-out beyond
    /// noise, and swap each for a simpler effect that explains the data as well.
    pub simplify: bool,
    /// Samples up to this long after a gap in a recording (dropped rows) are left out of every
    /// error sum ([`gap_mask`]): the command during the gap is unknown [s].
    pub gap_mask_s: f64,
    /// The search stops when every fitted joint's training residual has a mean square within
    /// this factor of its white floor ([`white_floor`]): what is left is noise.
    pub white_ratio: f64,
    /// Called at each step of the search (none: silent).
    pub progress: Option<Progress>,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            holdout: 4,
            effects: vec![],
            joints: vec![],
            replay: ReplayOptions::default(),
            window_s: 0.5,
            shooting_s: None,
            max_rounds: 4,
            candidates_per_round: 4,
            min_rel_improvement: 0.02,
            max_evals: 60,
            families: BTreeMap::new(),
            every_effect: true,
            decisive_improvement: 0.5,
            simplify: true,
            gap_mask_s: 0.1,
            white_ratio: 1.5,
            progress: None,
        }
    }
}

/// One kept effect.
#[derive(Debug, Clone, Serialize)]
pub struct Selected {
    pub effect: String,
    pub joints: Vec<String>,
    pub params: BTreeMap<String, f64>,
    pub stderr: BTreeMap<String, f64>,
    /// `false` when some fitted parameter is not determined by the data.
    pub identifiable: bool,
    pub evidence: BTreeMap<String, f64>,
    /// Relative held-out position-RMSE reduction (0.3 = 30 % lower).
    pub heldout_improvement: f64,
    pub heldout_rmse_before: f64,
    pub heldout_rmse_after: f64,
    /// Mean ± stderr of the paired per-window improvement [rad].
    pub window_improvement: f64,
    pub window_improvement_se: f64,
    pub bic_before: f64,
    pub bic_after: f64,
    #[serde(skip)]
    pub values: Vec<f64>,
}

/// A candidate that was fitted (kept or not), for the log.
#[derive(Debug, Clone, Serialize)]
pub struct Tried {
    pub round: usize,
    /// `add` (greedy round), `drop` (removal test: `kept` = the effect stays) or `swap`
    /// (replacement by a simpler effect: `kept` = the swap was made).
    pub phase: &'static str,
    pub effect: String,
    pub joints: Vec<String>,
    pub params: Vec<f64>,
    pub train_rmse: f64,
    pub heldout_improvement: f64,
    pub significant: bool,
    pub bic_decreased: bool,
    pub kept: bool,
}

pub struct FitOutcome {
    pub train: Vec<Recording>,
    pub heldout: Vec<Recording>,
    /// The held-out set is made of time windows of a single episode.
    pub split_by_time: bool,
    /// Which episodes were held out and why.
    pub split_note: String,
    /// Per fitted joint, of the model as given on the training set: (name, residual mean
    /// square, white floor) [rad²].
    pub floors: Vec<(String, f64, f64)>,
    /// The search ended because the residual reached the white floor on every joint.
    pub stopped_at_floor: bool,
    /// Diagnosis of the first round (the model as given).
    pub diagnosis: Vec<Candidate>,
    pub selected: Vec<Selected>,
    pub applied: Vec<Applied>,
    pub tried: Vec<Tried>,
    pub warnings: Vec<String>,
}

/// Position errors of one simulation of a dataset.
pub struct Errors {
    pub sse: f64,
    pub n: usize,
    /// Per (episode, window, joint) RMSE, with the joint's name.
    pub windows: Vec<(String, f64)>,
    pub eps: Vec<Episode>,
}

impl Errors {
    pub fn rmse(&self) -> f64 {
        if self.n == 0 { f64::INFINITY } else { (self.sse / self.n as f64).sqrt() }
    }
}

/// Where the search is, for a progress display: the phase, the candidate being fitted (if any)
/// with its index among the round's candidates, and the number of dataset simulations so far.
#[derive(Debug, Clone)]
pub struct ProgressInfo {
    pub round: usize,
    pub phase: &'static str,
    pub candidate: Option<(usize, usize, String)>,
    pub simulations: usize,
}

/// A progress callback (`modellint fit` draws it on stderr).
#[derive(Clone)]
pub struct Progress(pub std::sync::Arc<dyn Fn(&ProgressInfo) + Send + Sync>);

impl std::fmt::Debug for Progress {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Progress")
    }
}

/// The fit engine's view of a robot and dataset.
pub struct Engine<'a> {
    pub robot: &'a Robot,
    pub opts: &'a FitOptions,
    /// Joints scored by the objective.
    pub joints: Vec<String>,
    /// Dataset simulations run so far (each replays every episode of a set once).
    sims: std::sync::atomic::AtomicUsize,
}

impl<'a> Engine<'a> {
    pub fn new(robot: &'a Robot, recs: &[Recording], opts: &'a FitOptions) -> Self {
        let mut joints = Vec::new();
        for r in recs {
            for j in &r.joints {
                if (opts.joints.is_empty() || opts.joints.contains(&j.name))
                    && !joints.contains(&j.name)
                {
                    joints.push(j.name.clone());
                }
            }
        }
        Engine { robot, opts, joints, sims: std::sync::atomic::AtomicUsize::new(0) }
    }

    /// Reports progress through `opts.progress`, if any.
    pub fn report(
        &self,
        round: usize,
        phase: &'static str,
        candidate: Option<(usize, usize, String)>,
    ) {
        if let Some(p) = &self.opts.progress {
            (p.0)(&ProgressInfo {
                round,
                phase,
                candidate,
                simulations: self.sims.load(std::sync::atomic::Ordering::Relaxed),
            });
        }
    }

    /// Simulates `recs` with `applied`; `None` when an episode diverged or failed.
    pub fn errors(&self, recs: &[Recording], applied: &[Applied]) -> Option<Errors> {
        self.sims.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let m = model_with(self.robot, applied);
        let eps: Vec<Episode> = recs
            .par_iter()
            .map(|r| {
                replay_with(self.robot, &m, r, applied, &self.opts.replay)
                    .ok()
                    .filter(|e| e.diverged.is_none())
            })
            .collect::<Option<Vec<_>>>()?;
        let mut sse = 0.0;
        let mut n = 0usize;
        let mut win = Vec::new();
        for (rec, ep) in recs.iter().zip(&eps) {
            let scored = gap_mask(&rec.t, self.opts.gap_mask_s);
            for (k, jt) in rec.joints.iter().enumerate() {
                if !self.joints.contains(&jt.name) {
                    continue;
                }
                let t0 = rec.t[0];
                let mut w = (0usize, 0.0, 0usize);
                for i in 0..rec.t.len() {
                    if !scored[i] {
                        continue;
                    }
                    let e = jt.q[i] - ep.q_sim[k][i];
                    if !e.is_finite() {
                        if jt.q[i].is_finite() {
                            return None;
                        }
                        continue;
                    }
                    let wi = ((rec.t[i] - t0) / self.opts.window_s) as usize;
                    if wi != w.0 && w.2 > 0 {
                        win.push((jt.name.clone(), (w.1 / w.2 as f64).sqrt()));
                        w = (wi, 0.0, 0);
                    }
                    w.0 = wi;
                    w.1 += e * e;
                    w.2 += 1;
                    sse += e * e;
                    n += 1;
                }
                if w.2 > 0 {
                    win.push((jt.name.clone(), (w.1 / w.2 as f64).sqrt()));
                }
            }
        }
        Some(Errors { sse, n, windows: win, eps })
    }

    /// Per fitted joint: (name, mean square, white floor) of the residual of `recs` simulated
    /// as `errs` ([`white_floor`], over the runs of samples between gaps).
    pub fn floors(&self, recs: &[Recording], errs: &Errors) -> Vec<(String, f64, f64)> {
        self.joints
            .iter()
            .map(|name| {
                let mut runs = Vec::new();
                for (rec, ep) in recs.iter().zip(&errs.eps) {
                    let Some(k) = rec.joints.iter().position(|j| &j.name == name) else { continue };
                    let scored = gap_mask(&rec.t, self.opts.gap_mask_s);
                    let mut run = Vec::new();
                    for i in 0..rec.t.len() {
                        let e = rec.joints[k].q[i] - ep.q_sim[k][i];
                        if scored[i] && e.is_finite() {
                            run.push(e);
                        } else if !run.is_empty() {
                            runs.push(std::mem::take(&mut run));
                        }
                    }
                    runs.push(run);
                }
                let (ms, w) = white_floor(&runs);
                (name.clone(), ms, w)
            })
            .collect()
    }

    /// Residual vector (real − sim) on `joints`, subsampled to at most `max_len` entries.
    fn residuals(
        &self,
        recs: &[Recording],
        applied: &[Applied],
        joints: &[String],
        max_len: usize,
    ) -> Option<Vec<f64>> {
        let e = self.errors(recs, applied)?;
        let mut out = Vec::new();
        for (rec, ep) in recs.iter().zip(&e.eps) {
            let scored = gap_mask(&rec.t, self.opts.gap_mask_s);
            for (k, jt) in rec.joints.iter().enumerate() {
                if joints.contains(&jt.name) {
                    out.extend(
                        jt.q.iter()
                            .zip(&ep.q_sim[k])
                            .zip(&scored)
                            .filter(|(_, s)| **s)
                            .map(|((a, b), _)| a - b)
                            .filter(|x| x.is_finite()),
                    );
                }
            }
        }
        let stride = out.len().div_ceil(max_len.max(1)).max(1);
        Some(out.into_iter().step_by(stride).collect())
    }

    /// Fits `effect` on `group` on top of `base`: returns the full parameter vector and the
    /// training RMSE.
    pub fn fit_one(
        &self,
        train: &[Recording],
        base: &[Applied],
        effect: &'static dyn Effect,
        group: &[String],
    ) -> (Vec<f64>, f64) {
        self.fit_budget(train, base, effect, group, self.opts.max_evals)
    }

    /// [`Engine::fit_one`] with a budget of `max_evals` objective evaluations (twice that above
    /// one parameter; golden section stops earlier at its tolerance).
    pub fn fit_budget(
        &self,
        train: &[Recording],
        base: &[Applied],
        effect: &'static dyn Effect,
        group: &[String],
        max_evals: usize,
    ) -> (Vec<f64>, f64) {
        let Some(t) = JointTarget::of(self.robot, &group[0]) else {
            return (vec![], f64::INFINITY);
        };
        let m0 = model_with(self.robot, base);
        let full0 = effect.initial(&m0, &t);
        let (lo, hi) = effect.bounds(&m0, &t);
        let k = effect.fitted().min(full0.len());
        let make = |x: &[f64]| {
            let mut p = full0.clone();
            p[..k].copy_from_slice(&x[..k]);
            let mut a = base.to_vec();
            a.push(Applied { effect, joints: group.to_vec(), params: p });
            a
        };
        let obj = |x: &[f64]| self.errors(train, &make(x)).map_or(f64::INFINITY, |e| e.rmse());
        let x0: Vec<f64> = (0..k).map(|i| full0[i].clamp(lo[i], hi[i])).collect();
        let b = Bounds { lo: lo[..k].to_vec(), hi: hi[..k].to_vec() };
        let (x, f) = match k {
            0 => (vec![], obj(&[])),
            _ if effect.smooth() => {
                // Gauss–Newton / Levenberg–Marquardt on the rollout residuals: k + 1 replays per
                // iteration, converged in a handful (a derivative-free search needs ~40).
                let res = |x: &[f64]| {
                    self.residuals(train, &make(x), &self.joints, usize::MAX).unwrap_or_default()
                };
                let o = LmOpts {
                    max_iters: (max_evals / (k + 2)).clamp(2, 12),
                    rel_step: 1e-3,
                    tol: 1e-5,
                };
                let r = levenberg_marquardt(&res, &x0, &b, &o);
                let n = res_len(&r);
                (r.x, if n > 0 { (2.0 * r.cost / n as f64).sqrt() } else { f64::INFINITY })
            }
            1 => {
                let tol = 2e-4 * (hi[0] - lo[0]);
                let (x, f) = golden_section(&|v| obj(&[v]), lo[0], hi[0], tol, max_evals.min(40));
                (vec![x], f)
            }
            2 | 3 => {
                let o = NelderMeadOpts {
                    max_evals: max_evals * 2,
                    xtol: 1e-3,
                    ftol: 1e-12,
                    initial_step: 0.1,
                };
                let r = nelder_mead(&obj, &x0, &b, &o);
                (r.x, r.f)
            }
            _ => {
                let o = CmaesOpts { max_evals: max_evals * 2, ..Default::default() };
                let r = cmaes(&obj, &x0, &b, &o);
                (r.x, r.f)
            }
        };
        let mut p = full0.clone();
        p[..k].copy_from_slice(&x[..k]);
        (p, f)
    }

    /// `true` when `effect` starts from the same parameter values on every joint of `group`
    /// (within 1e-9, relative), so that the group can share one parameter vector.
    pub fn shared_start(
        &self,
        effect: &'static dyn Effect,
        base: &[Applied],
        group: &[String],
    ) -> bool {
        let m0 = model_with(self.robot, base);
        let starts: Vec<Vec<f64>> = group
            .iter()
            .filter_map(|j| JointTarget::of(self.robot, j))
            .map(|t| effect.initial(&m0, &t))
            .collect();
        starts.len() == group.len()
            && starts.windows(2).all(|w| {
                w[0].len() == w[1].len()
                    && w[0]
                        .iter()
                        .zip(&w[1])
                        .all(|(a, b)| (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1.0))
            })
    }

    /// Linearised explained mean square of the residual by a probe step of candidate `c`
    /// (`None` when the probe changes nothing or diverges): returns (explained MS, coefficient).
    fn sensitivity(
        &self,
        train: &[Recording],
        base: &[Applied],
        base_err: &Errors,
        c: &Candidate,
    ) -> Option<(f64, f64)> {
        let effect = effects::by_id(c.effect)?;
        let t = JointTarget::of(self.robot, &c.joint)?;
        let m0 = model_with(self.robot, base);
        let mut p = effect.initial(&m0, &t);
        let (lo, hi) = effect.bounds(&m0, &t);
        if effect.id() == "torque_limit" {
            p[0] = c.evidence.get("tau_p80").copied().filter(|v| *v > lo[0])?;
        } else {
            let step = 0.05 * (hi[0] - lo[0]);
            p[0] = if p[0] + step <= hi[0] { p[0] + step } else { p[0] - step };
        }
        let mut a = base.to_vec();
        a.push(Applied { effect, joints: vec![c.joint.clone()], params: p });
        let e = self.errors(train, &a)?;
        let (mut rs, mut ss) = (0.0, 0.0);
        let mut n = 0usize;
        for ((rec, e0), e1) in train.iter().zip(&base_err.eps).zip(&e.eps) {
            let scored = gap_mask(&rec.t, self.opts.gap_mask_s);
            for (k, jt) in rec.joints.iter().enumerate() {
                if !self.joints.contains(&jt.name) {
                    continue;
                }
                for i in (0..rec.t.len()).filter(|&i| scored[i]) {
                    let r = jt.q[i] - e0.q_sim[k][i];
                    let s = e1.q_sim[k][i] - e0.q_sim[k][i];
                    if r.is_finite() && s.is_finite() {
                        rs += r * s;
                        ss += s * s;
                        n += 1;
                    }
                }
            }
        }
        if ss <= 1e-300 || n == 0 {
            return None;
        }
        Some((rs * rs / ss / n as f64, rs / ss))
    }

    /// Linearised standard errors of the fitted parameters of `applied.last()`.
    fn uncertainty(&self, train: &[Recording], applied: &[Applied]) -> (Vec<f64>, bool) {
        let last = applied.last().expect("non-empty");
        let effect = last.effect;
        let t = JointTarget::of(self.robot, &last.joints[0]).expect("joint");
        let m0 = model_with(self.robot, &applied[..applied.len() - 1]);
        let (lo, hi) = effect.bounds(&m0, &t);
        let k = effect.fitted().min(last.params.len());
        let Some(r0) = self.residuals(train, applied, &last.joints, 20_000) else {
            return (vec![f64::INFINITY; k], false);
        };
        let mut cols = Vec::with_capacity(k);
        for i in 0..k {
            let range = hi[i] - lo[i];
            let mut h = 1e-3 * range.max(1e-9);
            if last.params[i] + h > hi[i] {
                h = -h;
            }
            let mut a = applied.to_vec();
            a.last_mut().unwrap().params[i] += h;
            match self.residuals(train, &a, &last.joints, 20_000) {
                // Residuals are real − sim, so ∂r/∂p = −∂sim/∂p; the sign does not matter for J^T J.
                Some(r1) if r1.len() == r0.len() => {
                    cols.push(r1.iter().zip(&r0).map(|(a, b)| (a - b) / h).collect::<Vec<f64>>())
                }
                _ => return (vec![f64::INFINITY; k], false),
            }
        }
        let jac: Vec<Vec<f64>> =
            (0..r0.len()).map(|row| cols.iter().map(|c| c[row]).collect()).collect();
        let ranges: Vec<f64> = (0..k).map(|i| hi[i] - lo[i]).collect();
        // Serially correlated residuals: scaling them by √inflation scales s² (and so the
        // covariance s²(JᵀJ)⁺ and the identifiability check) by the AR(1) inflation.
        let c = ar1_variance_inflation(&r0).sqrt();
        let r0: Vec<f64> = r0.iter().map(|x| x * c).collect();
        let u = uncertainty_from_jacobian(&jac, &r0, k, &ranges);
        let ident = u.identifiable.iter().all(|&x| x);
        (u.stderr, ident)
    }
}

/// Number of residuals behind an [`LmResult`] (the rows of its Jacobian).
fn res_len(r: &LmResult) -> usize {
    r.jacobian.len()
}

/// A candidate: effect, joint group, evidence.
type Cand = (&'static dyn Effect, Vec<String>, BTreeMap<String, f64>);

/// z the paired held-out test needs when `m` candidates compete in one round: 2 for up to four,
/// then growing like a Bonferroni correction (2.35 for 8, 2.69 for 16) so that fitting more
/// candidates does not buy more false discoveries.
pub fn z_needed(m: usize) -> f64 {
    2.0 + 0.5 * (m.max(4) as f64 / 4.0).ln()
}

/// Held-out comparison of `after` against `before` on the windows of `group`.
struct Verdict {
    /// Mean ± s.e. of the paired per-window RMSE improvement [rad].
    mean: f64,
    se: f64,
    /// Relative held-out RMSE improvement over all fitted joints.
    rel: f64,
    significant: bool,
}

/// `significant`: the paired per-window improvement (absolute, or of the log error) exceeds `z`
/// standard errors, or the improvement is decisive (relative ≥ `decisive`, with more than twice
/// as many windows improved as worsened).
fn verdict(before: &Errors, after: &Errors, group: &[String], z: f64, decisive: f64) -> Verdict {
    let on = |w: &[(String, f64)]| {
        w.iter().filter(|(j, _)| group.contains(j)).map(|(_, v)| *v).collect::<Vec<f64>>()
    };
    let (wb, wa) = (on(&before.windows), on(&after.windows));
    let (mean, se, _) = improvement_beyond_noise(&wb, &wa);
    let ln = |w: &[f64]| w.iter().map(|v| v.max(1e-12).ln()).collect::<Vec<f64>>();
    let (lmean, lse, _) = improvement_beyond_noise(&ln(&wb), &ln(&wa));
    let beyond = |m: f64, s: f64| m > 0.0 && m > z * s;
    let rel = (before.rmse() - after.rmse()) / before.rmse().max(1e-300);
    let (mut up, mut down) = (0usize, 0usize);
    for (b, a) in wb.iter().zip(&wa) {
        let tol = 1e-3 * b.abs();
        if b - a > tol {
            up += 1;
        } else if a - b > tol {
            down += 1;
        }
    }
    let decisive_ok = rel >= decisive && up > 2 * down;
    Verdict { mean, se, rel, significant: beyond(mean, se) || beyond(lmean, lse) || decisive_ok }
}

/// `true` when a fitted parameter of `a` sits on its bound (within 0.5 % of the range): the
/// effect was stretched to explain something else.
fn at_bound(engine: &Engine, base: &[Applied], a: &Applied) -> bool {
    let Some(t) = JointTarget::of(engine.robot, &a.joints[0]) else { return false };
    let m0 = model_with(engine.robot, base);
    let (lo, hi) = a.effect.bounds(&m0, &t);
    (0..a.effect.fitted().min(a.params.len())).any(|k| {
        let tol = 5e-3 * (hi[k] - lo[k]);
        a.params[k] <= lo[k] + tol || a.params[k] >= hi[k] - tol
    })
}

/// Runs the whole selection on `recs`.
pub fn fit(robot: &Robot, recs: &[Recording], opts: &FitOptions) -> FitOutcome {
    let engine = Engine::new(robot, recs, opts);
    let Split { train: train0, heldout, by_time, note } = split(recs, opts.holdout);
    let train: Vec<Recording> = match opts.shooting_s {
        Some(w) if w > 0.0 => train0.iter().flat_map(|r| windows(r, w)).collect(),
        _ => train0,
    };
    let mut out = FitOutcome {
        train: train.clone(),
        heldout: heldout.clone(),
        split_by_time: by_time,
        split_note: note,
        floors: vec![],
        stopped_at_floor: false,
        diagnosis: vec![],
        selected: vec![],
        applied: vec![],
        tried: vec![],
        warnings: vec![],
    };
    if train.is_empty() || heldout.is_empty() {
        out.warnings.push("not enough data for a train/held-out split (need 2 episodes, or one of several seconds)".into());
        return out;
    }
    let allowed: Vec<String> = if opts.effects.is_empty() {
        effects::all().iter().map(|e| e.id().to_string()).collect()
    } else {
        opts.effects.clone()
    };
    let mut round = 0;
    loop {
        while round < opts.max_rounds {
            engine.report(round, "diagnose", None);
            let added = greedy_round(&engine, &train, &heldout, &allowed, round, &mut out);
            round += 1;
            if !added {
                break;
            }
        }
        if out.applied.len() >= 2 {
            engine.report(round, "polish", None);
            polish(&engine, &train, &heldout, &mut out);
        }
        if !opts.simplify || out.applied.is_empty() {
            break;
        }
        // A change re-opens the greedy search (bounded by `max_rounds`).
        engine.report(round, "simplify", None);
        if !simplify(&engine, &train, &heldout, &allowed, round, &mut out)
            || round >= opts.max_rounds
        {
            break;
        }
    }
    engine.report(round, "done", None);
    out
}

/// One greedy round: diagnose, fit the candidates, keep the best that passes the held-out gate.
/// Returns `true` when an effect was added.
fn greedy_round(
    engine: &Engine,
    train: &[Recording],
    heldout: &[Recording],
    allowed: &[String],
    round: usize,
    out: &mut FitOutcome,
) -> bool {
    let opts = engine.opts;
    let robot = engine.robot;
    let applied = out.applied.clone();
    let Some(tr_err) = engine.errors(train, &applied) else {
        out.warnings.push("the training replay diverged with the current model; stopping".into());
        return false;
    };
    let Some(ho_err) = engine.errors(heldout, &applied) else {
        out.warnings.push("the held-out replay diverged with the current model; stopping".into());
        return false;
    };
    // Nothing left to explain: on every fitted joint the training residual is (nearly) white,
    // at the floor that noise, quantisation and command reconstruction impose on this dataset.
    let floors = engine.floors(train, &tr_err);
    if round == 0 {
        out.floors = floors.clone();
    }
    if floors.iter().all(|(_, ms, w)| *ms <= opts.white_ratio * w) {
        out.stopped_at_floor = true;
        return false;
    }
    let diag = diagnose(robot, train, &tr_err.eps, &engine.joints, allowed, opts.gap_mask_s);
    let covered = |id: &str, j: &str| {
        applied.iter().any(|a| a.effect.id() == id && a.joints.iter().any(|x| x == j))
    };
    // Re-rank the diagnosis by the linearised (Gauss–Newton) explained residual: the
    // residual projected on the simulated sensitivity to a probe step of the effect.
    // One probe simulation per (effect, joint), independent of each other: run them in
    // parallel (each replay is itself parallel over episodes; results in a fixed order).
    let mut diag = diag;
    let probes: Vec<Option<(f64, f64)>> = diag
        .par_iter()
        .map(|c| {
            if covered(c.effect, &c.joint) {
                None
            } else {
                engine.sensitivity(train, &applied, &tr_err, c)
            }
        })
        .collect();
    for (c, sens) in diag.iter_mut().zip(probes) {
        if covered(c.effect, &c.joint) {
            c.explained_rms = 0.0;
            continue;
        }
        if let Some((ems, coef)) = sens {
            c.evidence.insert("feature_explained_rms".into(), c.explained_rms);
            c.evidence.insert("sensitivity_coef".into(), coef);
            c.explained_rms = ems.sqrt();
        }
    }
    diag.sort_by(|a, b| b.explained_rms.total_cmp(&a.explained_rms));
    if round == 0 {
        out.diagnosis = diag.clone();
    }
    // Candidate (effect, group) list, best first.
    let mut cands: Vec<Cand> = Vec::new();
    let push = |c: &Candidate, cands: &mut Vec<Cand>| {
        if covered(c.effect, &c.joint) || c.explained_rms <= 1e-9 {
            return;
        }
        let Some(e) = effects::by_id(c.effect) else { return };
        let mut group = vec![c.joint.clone()];
        if let Some(p) = mirror_name(&c.joint)
            && engine.joints.contains(&p)
            && !covered(c.effect, &p)
            && diag
                .iter()
                .take(opts.candidates_per_round * 4)
                .any(|d| d.effect == c.effect && d.joint == p)
        {
            group.push(p);
            group.sort();
        }
        if cands.iter().any(|(e2, g, _)| e2.id() == e.id() && g.iter().any(|x| group.contains(x))) {
            return;
        }
        let mut ev = c.evidence.clone();
        ev.insert("explained_rms".into(), c.explained_rms);
        ev.insert("residual_rms".into(), c.residual_rms);
        // The joint's motor family as one more group (shared parameters).
        let fam: Vec<String> = match opts.families.get(&c.joint) {
            Some(f) => engine
                .joints
                .iter()
                .filter(|j| opts.families.get(*j) == Some(f) && !covered(c.effect, j))
                .cloned()
                .collect(),
            None => vec![],
        };
        let fam_new =
            fam.len() >= 3 && !cands.iter().any(|(e2, g, _)| e2.id() == e.id() && *g == fam);
        // Every recorded joint as one group sharing the parameters (an effect the whole robot
        // has, such as a missing damping or friction, a delay or a servo gain error) — when the
        // model gives those joints the same starting value, so that one knob is meaningful.
        let all: Vec<String> =
            engine.joints.iter().filter(|j| !covered(c.effect, j)).cloned().collect();
        let all_new = all.len() >= 2
            && all.len() > group.len()
            && all != fam
            && !cands.iter().any(|(e2, g, _)| e2.id() == e.id() && *g == all)
            && engine.shared_start(e, &applied, &all);
        cands.push((e, group, ev.clone()));
        if fam_new {
            cands.push((e, fam, ev.clone()));
        }
        if all_new {
            let mut ev = ev;
            ev.insert("all_joints_group".into(), 1.0);
            cands.push((e, all, ev));
        }
    };
    for c in &diag {
        if cands.len() >= opts.candidates_per_round {
            break;
        }
        push(c, &mut cands);
    }
    let n_top = cands.len();
    if opts.every_effect {
        // The best-ranked joint of every other effect: the linearised ranking is only a guide
        // (a doubled inertia or a saturation is far from linear).
        // Effects whose best joint explains less than a tenth of the top candidate are left out.
        let top = diag
            .iter()
            .filter(|c| !covered(c.effect, &c.joint))
            .map(|c| c.explained_rms)
            .fold(0.0, f64::max);
        for id in allowed {
            if cands.iter().any(|(e, ..)| e.id() == id) {
                continue;
            }
            if let Some(c) = diag.iter().find(|c| {
                c.effect == id
                    && !covered(c.effect, &c.joint)
                    && c.explained_rms > 1e-9
                    && c.explained_rms >= 0.1 * top
            }) {
                push(c, &mut cands);
            }
        }
    }
    if cands.is_empty() {
        return false;
    }
    let z = z_needed(cands.len());
    let k_before: usize = applied.iter().map(|a| a.effect.fitted()).sum();
    let bic_before = bic(tr_err.n, tr_err.sse, k_before);
    let mut accepted: Vec<(Selected, bool, Errors)> = Vec::new();
    // Every single fit of the round, for the joint pairs when no single one passes.
    let mut fitted: Vec<Applied> = Vec::new();
    // Screen for the extra (every-effect) multi-parameter candidates: a coarse fit (10
    // evaluations per parameter) must reach at least half of the best training improvement of
    // the fully fitted ones.
    let base_train = tr_err.rmse();
    let mut best_train = base_train;
    // Fewest parameters of a kept candidate whose training residual is white on every joint.
    let mut floor_k: Option<usize> = None;
    let mut ci = 0;
    while ci < cands.len() {
        let (e, group, ev) = cands[ci].clone();
        engine.report(
            round,
            "fit",
            Some((ci + 1, cands.len(), format!("{} on {}", e.id(), group.join(",")))),
        );
        let extra = ci >= n_top;
        ci += 1;
        // A kept candidate already left a white training residual: one with more parameters
        // cannot explain more, and Occam's choice would not take it (`tried`: phase "floor").
        if floor_k.is_some_and(|k| e.fitted() > k) {
            out.tried.push(Tried {
                round,
                phase: "floor",
                effect: e.id().into(),
                joints: group.clone(),
                params: vec![],
                train_rmse: f64::NAN,
                heldout_improvement: f64::NAN,
                significant: false,
                bic_decreased: false,
                kept: false,
            });
            continue;
        }
        // (Only multi-parameter effects: a 1-D fit is a 9-point grid plus golden section anyway,
        // and a coarse one misses scale parameters near zero, such as a small armature.)
        if extra && e.fitted() >= 2 {
            let (p, f) = engine.fit_budget(train, &applied, e, &group, 10);
            if p.is_empty() || !f.is_finite() || base_train - f < 0.5 * (base_train - best_train) {
                out.tried.push(Tried {
                    round,
                    phase: "screen",
                    effect: e.id().into(),
                    joints: group.clone(),
                    params: p,
                    train_rmse: f,
                    heldout_improvement: f64::NAN,
                    significant: false,
                    bic_decreased: false,
                    kept: false,
                });
                continue;
            }
        }
        let (p, train_rmse) = engine.fit_one(train, &applied, e, &group);
        if p.is_empty() || !train_rmse.is_finite() {
            continue;
        }
        best_train = best_train.min(train_rmse);
        fitted.push(Applied { effect: e, joints: group.clone(), params: p.clone() });
        let mut trial = applied.clone();
        trial.push(Applied { effect: e, joints: group.clone(), params: p.clone() });
        let (Some(tr_a), Some(ho_a)) =
            (engine.errors(train, &trial), engine.errors(heldout, &trial))
        else {
            continue;
        };
        let bic_after = bic(tr_a.n, tr_a.sse, k_before + e.fitted());
        // Paired test on the windows of the candidate's joints (others barely move).
        let v = verdict(&ho_err, &ho_a, &group, z, opts.decisive_improvement);
        let keep = v.significant && v.rel >= opts.min_rel_improvement && bic_after < bic_before;
        out.tried.push(Tried {
            round,
            phase: "add",
            effect: e.id().into(),
            joints: group.clone(),
            params: p.clone(),
            train_rmse,
            heldout_improvement: v.rel,
            significant: v.significant,
            bic_decreased: bic_after < bic_before,
            kept: false,
        });
        if keep && engine.floors(train, &tr_a).iter().all(|(_, ms, w)| *ms <= opts.white_ratio * w)
        {
            floor_k = Some(floor_k.map_or(e.fitted(), |k| k.min(e.fitted())));
        }
        if keep {
            // Mirror completion: a kept one-joint candidate is also fitted on its left/right
            // pair, which then competes with it on held-out (the diagnosis ranks the two sides
            // separately and can miss the partner of an effect both sides have).
            if let [j] = group.as_slice()
                && let Some(p) = mirror_name(j)
                && engine.joints.contains(&p)
                && !covered(e.id(), &p)
                && !cands.iter().any(|(e2, g, _)| e2.id() == e.id() && g.contains(&p))
            {
                let mut g = vec![j.clone(), p];
                g.sort();
                let mut ev2 = ev.clone();
                ev2.insert("mirror_completion".into(), 1.0);
                cands.push((e, g, ev2));
            }
            let a = trial.last().expect("pushed");
            let bound = at_bound(engine, &applied, a);
            accepted.push((
                Selected::new(a, ev, &v, ho_err.rmse(), ho_a.rmse(), (bic_before, bic_after)),
                bound,
                ho_a,
            ));
        }
    }
    let kept_all: Vec<Selected> = accepted.iter().map(|(s, ..)| s.clone()).collect();
    // A candidate with a parameter on its bound only wins when no interior one is kept.
    if accepted.iter().any(|(_, b, _)| !b) {
        accepted.retain(|(_, b, _)| !b);
    }
    let Some(ib) = (0..accepted.len()).min_by(|&a, &b| {
        accepted[a].0.heldout_rmse_after.total_cmp(&accepted[b].0.heldout_rmse_after)
    }) else {
        return joint_pairs(
            engine,
            train,
            heldout,
            &applied,
            &fitted,
            (&tr_err, &ho_err),
            z,
            round,
            out,
        );
    };
    // Occam: the simplest candidate within 5 % of the best held-out RMSE that the best does not
    // beat beyond noise (paired test, z = 2) and whose training BIC is not higher (the training
    // set is larger than the held-out one: a better fit that pays for its parameters there is
    // not noise).
    let (best_s, _, best_e) = &accepted[ib];
    let equivalent = |i: usize| {
        let (s, _, e) = &accepted[i];
        if i == ib {
            return true;
        }
        let group: Vec<String> = s.joints.iter().chain(&best_s.joints).cloned().collect();
        s.heldout_rmse_after <= best_s.heldout_rmse_after * 1.05
            && s.bic_after <= best_s.bic_after
            && !verdict(e, best_e, &group, 2.0, f64::INFINITY).significant
    };
    let win = (0..accepted.len())
        .filter(|&i| equivalent(i))
        .min_by(|&a, &b| {
            let ka = effects::by_id(&accepted[a].0.effect).map_or(9, |e| e.fitted());
            let kb = effects::by_id(&accepted[b].0.effect).map_or(9, |e| e.fitted());
            ka.cmp(&kb)
                .then(accepted[a].0.heldout_rmse_after.total_cmp(&accepted[b].0.heldout_rmse_after))
        })
        .expect("the best is equivalent to itself");
    let mut accepted: Vec<Selected> = accepted.into_iter().map(|(s, ..)| s).collect();
    let mut s = accepted.swap_remove(win);
    if let Some(pair) =
        pair_lookahead(engine, train, heldout, &applied, &kept_all, &s, z, round, out)
    {
        for (mut p, a) in pair {
            out.applied.push(a);
            set_uncertainty(engine, train, &mut p, &out.applied, &mut out.warnings);
            out.selected.push(p);
        }
        return true;
    }
    if let Some(t) = out.tried.iter_mut().rev().find(|t| {
        t.round == round && t.phase == "add" && t.effect == s.effect && t.joints == s.joints
    }) {
        t.kept = true;
    }
    let e = effects::by_id(&s.effect).expect("known");
    out.applied.push(Applied { effect: e, joints: s.joints.clone(), params: s.values.clone() });
    set_uncertainty(engine, train, &mut s, &out.applied, &mut out.warnings);
    out.selected.push(s);
    true
}

/// Look-ahead for two effects that only make sense together (extra inertia *and* damping: each
/// alone is mimicked by a delay or a gain error). The top four kept candidates of the round are
/// paired when they act on the same joints, each pair is fitted jointly from the two single
/// fits, and the best pair replaces the single winner when it is ≥ 10 % better on held-out
/// (and beyond noise), and each member is needed in it (removing either is worse beyond
/// noise). The pair with fewer parameters wins within 1 %.
#[allow(clippy::too_many_arguments)]
fn pair_lookahead(
    engine: &Engine,
    train: &[Recording],
    heldout: &[Recording],
    applied: &[Applied],
    kept: &[Selected],
    single: &Selected,
    z: f64,
    round: usize,
    out: &mut FitOutcome,
) -> Option<Vec<(Selected, Applied)>> {
    let opts = engine.opts;
    let mut top: Vec<&Selected> = kept.iter().collect();
    top.sort_by(|a, b| a.heldout_rmse_after.total_cmp(&b.heldout_rmse_after));
    top.truncate(4);
    // A single effect that leaves under 5 % of the error needs no partner.
    if single.heldout_improvement >= 0.95 {
        return None;
    }
    let as_applied = |s: &Selected| Applied {
        effect: effects::by_id(&s.effect).expect("known"),
        joints: s.joints.clone(),
        params: s.values.clone(),
    };
    let mut with_single = applied.to_vec();
    with_single.push(as_applied(single));
    // Nor does one that leaves a white training residual on every fitted joint: what is left
    // is noise, quantisation and command reconstruction (the floor that stops the rounds), and a
    // partner has nothing to explain. (The held-out test cannot show this: its improvement is
    // bounded by the same floor, e.g. 94 % on arm2's elbow damping.)
    let t_single = engine.errors(train, &with_single)?;
    if engine.floors(train, &t_single).iter().all(|(_, ms, w)| *ms <= opts.white_ratio * w) {
        return None;
    }
    let h_single = engine.errors(heldout, &with_single)?;
    let h_base = engine.errors(heldout, applied)?;
    let t_base = engine.errors(train, applied)?;
    let k_before: usize = applied.iter().map(|a| a.effect.fitted()).sum();
    let mut best: Option<(Vec<Applied>, f64, usize)> = None;
    engine.report(round, "pair look-ahead", None);
    for i in 0..top.len() {
        for j in i + 1..top.len() {
            let (a, b) = (top[i], top[j]);
            if a.effect == b.effect || !a.joints.iter().any(|x| b.joints.contains(x)) {
                continue;
            }
            let mut set = applied.to_vec();
            set.push(as_applied(a));
            set.push(as_applied(b));
            let set = polish_set(engine, train, heldout, set, 0.05);
            let (Some(h), Some(t)) = (engine.errors(heldout, &set), engine.errors(train, &set))
            else {
                continue;
            };
            let k = effects::by_id(&a.effect).map_or(9, |e| e.fitted())
                + effects::by_id(&b.effect).map_or(9, |e| e.fitted());
            let group: Vec<String> = a.joints.iter().chain(&b.joints).cloned().collect();
            let v = verdict(&h_single, &h, &group, z, opts.decisive_improvement);
            let bic_ok = bic(t.n, t.sse, k_before + k) < bic(t_base.n, t_base.sse, k_before);
            // Each member needed: the pair beats the set without it beyond noise.
            let needed = (0..2).all(|m| {
                let mut wo = set.clone();
                wo.remove(applied.len() + m);
                engine.errors(heldout, &wo).is_some_and(|hw| {
                    let vw = verdict(
                        &hw,
                        &h,
                        &set[applied.len() + m].joints,
                        2.0,
                        opts.decisive_improvement,
                    );
                    vw.significant && vw.rel >= opts.min_rel_improvement
                })
            });
            let ok = h.rmse() < 0.9 * h_single.rmse() && v.significant && bic_ok && needed;
            out.tried.push(Tried {
                round,
                phase: "pair",
                effect: format!("{}+{}", a.effect, b.effect),
                joints: group.clone(),
                params: set[applied.len()..]
                    .iter()
                    .flat_map(|x| x.params.iter().take(x.effect.fitted()).copied())
                    .collect(),
                train_rmse: t.rmse(),
                heldout_improvement: (h_base.rmse() - h.rmse()) / h_base.rmse().max(1e-300),
                significant: v.significant,
                bic_decreased: bic_ok,
                kept: false,
            });
            if !ok {
                continue;
            }
            let better = match &best {
                None => true,
                Some((_, r, kb)) => {
                    (k < *kb && h.rmse() <= r * 1.01)
                        || (h.rmse() < *r && !(k > *kb && h.rmse() > r / 1.01))
                }
            };
            if better {
                best = Some((set, h.rmse(), k));
            }
        }
    }
    let (set, rmse, _) = best?;
    let n = applied.len();
    let label = format!("{}+{}", set[n].effect.id(), set[n + 1].effect.id());
    if let Some(t) = out.tried.iter_mut().rev().find(|t| t.phase == "pair" && t.effect == label) {
        t.kept = true;
    }
    out.warnings.push(format!(
        "{} and {} on {} fitted together: held-out RMSE {:.3e} rad, vs {:.3e} with {} alone",
        set[n].effect.id(),
        set[n + 1].effect.id(),
        set[n].joints.join(","),
        rmse,
        h_single.rmse(),
        single.effect
    ));
    let t_pair = engine.errors(train, &set)?;
    let h_pair = engine.errors(heldout, &set)?;
    let k_pair: usize = set.iter().map(|a| a.effect.fitted()).sum();
    let mut res = Vec::new();
    for m in 0..2 {
        let a = set[n + m].clone();
        let mut wo = set.clone();
        wo.remove(n + m);
        let (hw, tw) = (engine.errors(heldout, &wo)?, engine.errors(train, &wo)?);
        let v = verdict(&hw, &h_pair, &a.joints, 2.0, opts.decisive_improvement);
        let evidence = kept
            .iter()
            .find(|s| s.effect == a.effect.id() && s.joints == a.joints)
            .map(|s| s.evidence.clone())
            .unwrap_or_default();
        let bics =
            (bic(tw.n, tw.sse, k_pair - a.effect.fitted()), bic(t_pair.n, t_pair.sse, k_pair));
        let s = Selected::new(&a, evidence, &v, hw.rmse(), rmse, bics);
        res.push((s, a));
    }
    // The polish may have moved the effects kept earlier: carry them over.
    out.applied[..n].clone_from_slice(&set[..n]);
    sync_selected(out);
    Some(res)
}

/// Pairs of effects that mimic each other alone but not together: a servo gain error and a
/// delay both shift the phase; friction and inertia both slow the response; a dead band and an
/// offset both bias it; damping and inertia both change the decay.
const JOINT_PAIRS: [(&str, &str); 6] = [
    ("gain_error", "action_delay"),
    ("coulomb_friction", "armature"),
    ("stribeck_friction", "armature"),
    ("backlash", "position_offset"),
    ("viscous_damping", "armature"),
    ("gain_error", "coulomb_friction"),
];

/// When no single candidate passed the held-out gate: fit the [`JOINT_PAIRS`] whose members were
/// both fitted on the same joint group this round, jointly from their single fits, and keep the
/// best pair that passes the gate as a whole (beyond noise against the model without it, BIC
/// down) with each member needed (removing either is worse beyond noise).
#[allow(clippy::too_many_arguments)]
fn joint_pairs(
    engine: &Engine,
    train: &[Recording],
    heldout: &[Recording],
    applied: &[Applied],
    fitted: &[Applied],
    (tr_err, ho_err): (&Errors, &Errors),
    z: f64,
    round: usize,
    out: &mut FitOutcome,
) -> bool {
    let opts = engine.opts;
    let n = applied.len();
    let k_before: usize = applied.iter().map(|a| a.effect.fitted()).sum();
    let bic_before = bic(tr_err.n, tr_err.sse, k_before);
    let mut best: Option<(Vec<Applied>, Errors, Verdict, f64)> = None;
    engine.report(round, "joint pairs", None);
    for (ea, eb) in JOINT_PAIRS {
        for a in fitted.iter().filter(|x| x.effect.id() == ea) {
            let Some(b) = fitted.iter().find(|x| x.effect.id() == eb && x.joints == a.joints)
            else {
                continue;
            };
            let mut set = applied.to_vec();
            set.push(a.clone());
            set.push(b.clone());
            let set = fit_jointly(engine, train, set, n);
            let (Some(h), Some(t)) = (engine.errors(heldout, &set), engine.errors(train, &set))
            else {
                continue;
            };
            let k = a.effect.fitted() + b.effect.fitted();
            let v = verdict(ho_err, &h, &a.joints, z, opts.decisive_improvement);
            let bic_after = bic(t.n, t.sse, k_before + k);
            let needed = (0..2).all(|m| {
                let mut wo = set.clone();
                wo.remove(n + m);
                engine.errors(heldout, &wo).is_some_and(|hw| {
                    let vw = verdict(&hw, &h, &a.joints, 2.0, opts.decisive_improvement);
                    vw.significant && vw.rel >= opts.min_rel_improvement
                })
            });
            let ok = v.significant
                && v.rel >= opts.min_rel_improvement
                && bic_after < bic_before
                && needed;
            out.tried.push(Tried {
                round,
                phase: "joint_pair",
                effect: format!("{ea}+{eb}"),
                joints: a.joints.clone(),
                params: set[n..]
                    .iter()
                    .flat_map(|x| x.params.iter().take(x.effect.fitted()).copied())
                    .collect(),
                train_rmse: t.rmse(),
                heldout_improvement: v.rel,
                significant: v.significant,
                bic_decreased: bic_after < bic_before,
                kept: false,
            });
            if ok && best.as_ref().is_none_or(|(_, hb, ..)| h.rmse() < hb.rmse()) {
                best = Some((set, h, v, bic_after));
            }
        }
    }
    let Some((set, h, v, bic_after)) = best else { return false };
    let label = format!("{}+{}", set[n].effect.id(), set[n + 1].effect.id());
    if let Some(t) = out
        .tried
        .iter_mut()
        .rev()
        .find(|t| t.phase == "joint_pair" && t.effect == label && t.joints == set[n].joints)
    {
        t.kept = true;
    }
    out.warnings.push(format!(
        "no single effect passed; {} and {} on {} pass together: held-out RMSE {:.3e} → {:.3e} rad",
        set[n].effect.id(),
        set[n + 1].effect.id(),
        set[n].joints.join(","),
        ho_err.rmse(),
        h.rmse()
    ));
    for m in 0..2 {
        let a = set[n + m].clone();
        let mut sel = Selected::new(
            &a,
            BTreeMap::new(),
            &v,
            ho_err.rmse(),
            h.rmse(),
            (bic_before, bic_after),
        );
        out.applied.push(a);
        set_uncertainty(engine, train, &mut sel, &out.applied, &mut out.warnings);
        out.selected.push(sel);
    }
    true
}

/// One fitted parameter of a set of applied effects: (effect index, parameter index, lo, hi).
type Slot = (usize, usize, f64, f64);

/// The fitted parameters of `set[first..]` with their bounds; effect `ai`'s bounds come from the
/// model with `set[..base(ai)]` applied. `None` when an effect's joint is not in the model.
fn param_slots(
    engine: &Engine,
    set: &[Applied],
    first: usize,
    base: impl Fn(usize) -> usize,
) -> Option<Vec<Slot>> {
    let mut slots = Vec::new();
    for (ai, a) in set.iter().enumerate().skip(first) {
        let t = JointTarget::of(engine.robot, &a.joints[0])?;
        let m0 = model_with(engine.robot, &set[..base(ai)]);
        let (lo, hi) = a.effect.bounds(&m0, &t);
        for k in 0..a.effect.fitted().min(a.params.len()) {
            slots.push((ai, k, lo[k], hi[k]));
        }
    }
    Some(slots)
}

/// `set` with the parameters of `slots` set to `x`.
fn with_params(set: &[Applied], slots: &[Slot], x: &[f64]) -> Vec<Applied> {
    let mut a = set.to_vec();
    for (&(ai, k, ..), v) in slots.iter().zip(x) {
        a[ai].params[k] = *v;
    }
    a
}

/// Fits the effects `set[first..]` jointly on `train` (the ones before stay fixed), starting from
/// their current parameters: Levenberg–Marquardt when all are smooth, else Nelder–Mead. Returns
/// the set unchanged when the joint fit does not lower the training error.
fn fit_jointly(
    engine: &Engine,
    train: &[Recording],
    set: Vec<Applied>,
    first: usize,
) -> Vec<Applied> {
    let Some(slots) = param_slots(engine, &set, first, |_| first) else { return set };
    let make = |x: &[f64]| with_params(&set, &slots, x);
    let x0: Vec<f64> =
        slots.iter().map(|&(ai, k, lo, hi)| set[ai].params[k].clamp(lo, hi)).collect();
    let b =
        Bounds { lo: slots.iter().map(|s| s.2).collect(), hi: slots.iter().map(|s| s.3).collect() };
    let obj = |x: &[f64]| engine.errors(train, &make(x)).map_or(f64::INFINITY, |e| e.rmse());
    let f0 = obj(&x0);
    let (x, f) = if set[first..].iter().all(|a| a.effect.smooth()) {
        let res = |x: &[f64]| {
            engine.residuals(train, &make(x), &engine.joints, usize::MAX).unwrap_or_default()
        };
        let o = LmOpts { max_iters: 12, rel_step: 1e-3, tol: 1e-5 };
        let r = levenberg_marquardt(&res, &x0, &b, &o);
        let n = res_len(&r);
        (r.x, if n > 0 { (2.0 * r.cost / n as f64).sqrt() } else { f64::INFINITY })
    } else {
        let o = NelderMeadOpts {
            max_evals: engine.opts.max_evals * 3,
            xtol: 1e-4,
            ftol: 1e-12,
            initial_step: 0.1,
        };
        let r = nelder_mead(&obj, &x0, &b, &o);
        (r.x, r.f)
    };
    if !(f < f0) {
        return set;
    }
    make(&x)
}

/// Standard errors of `s`, the effect of `applied.last()`.
fn set_uncertainty(
    engine: &Engine,
    train: &[Recording],
    s: &mut Selected,
    applied: &[Applied],
    warnings: &mut Vec<String>,
) {
    let e = applied.last().expect("non-empty").effect;
    let (se, ident) = engine.uncertainty(train, applied);
    s.stderr = e.params().iter().zip(&se).map(|(d, v)| (d.name.to_string(), *v)).collect();
    s.identifiable = ident;
    if !ident {
        warnings.push(format!(
            "{} on {}: parameters not identifiable from this data (excite the joint more)",
            s.effect,
            s.joints.join(",")
        ));
    }
}

/// Fitted parameters of `a` by name.
fn named_params(a: &Applied) -> BTreeMap<String, f64> {
    a.effect
        .params()
        .iter()
        .zip(&a.params)
        .take(a.effect.fitted())
        .map(|(d, v)| (d.name.to_string(), *v))
        .collect()
}

impl Selected {
    /// Record of the kept effect `a`: `v` compares the held-out set without it (RMSE `before`)
    /// and with it (`after`); `bics` = training BIC (without, with). Standard errors come later
    /// ([`set_uncertainty`]).
    fn new(
        a: &Applied,
        evidence: BTreeMap<String, f64>,
        v: &Verdict,
        before: f64,
        after: f64,
        bics: (f64, f64),
    ) -> Self {
        Selected {
            effect: a.effect.id().into(),
            joints: a.joints.clone(),
            params: named_params(a),
            stderr: BTreeMap::new(),
            identifiable: true,
            evidence,
            heldout_improvement: v.rel,
            heldout_rmse_before: before,
            heldout_rmse_after: after,
            window_improvement: v.mean,
            window_improvement_se: v.se,
            bic_before: bics.0,
            bic_after: bics.1,
            values: a.params.clone(),
        }
    }
}

/// Copies the parameters of `out.applied` into `out.selected` (same order).
fn sync_selected(out: &mut FitOutcome) {
    for (s, a) in out.selected.iter_mut().zip(&out.applied) {
        s.values = a.params.clone();
        s.params.extend(named_params(a));
    }
}

/// Occam's pass over the kept effects, judged on the held-out set:
/// * **drop** an effect whose removal does not make the held-out error worse beyond noise (it
///   was needed only before a later effect explained the same thing);
/// * **swap** an effect for one with fewer parameters on the same joints (re-fitted, then all
///   parameters polished together) when the simpler set is not worse beyond noise: held-out
///   RMSE within min(1 % of it, 5 % of what the effect explains) and no significant paired
///   difference. Example: Stribeck friction with its velocity scale at the bound is Coulomb
///   friction; a servo gain error whose only change is kd is joint damping.
///
/// Returns `true` when the set changed.
fn simplify(
    engine: &Engine,
    train: &[Recording],
    heldout: &[Recording],
    allowed: &[String],
    round: usize,
    out: &mut FitOutcome,
) -> bool {
    let mut changed = false;
    // Each swap removes at least one parameter, so this ends.
    loop {
        changed |= drop_pass(engine, train, heldout, round, out);
        if !swap_pass(engine, train, heldout, allowed, round, out) {
            return changed;
        }
        changed = true;
    }
}

/// Drops, last kept first. Returns `true` when an effect was dropped.
fn drop_pass(
    engine: &Engine,
    train: &[Recording],
    heldout: &[Recording],
    round: usize,
    out: &mut FitOutcome,
) -> bool {
    let opts = engine.opts;
    let mut changed = false;
    let mut i = out.applied.len();
    while i > 0 {
        i -= 1;
        let mut without = out.applied.clone();
        without.remove(i);
        let (Some(h_full), Some(h_wo), Some(t_full), Some(t_wo)) = (
            engine.errors(heldout, &out.applied),
            engine.errors(heldout, &without),
            engine.errors(train, &out.applied),
            engine.errors(train, &without),
        ) else {
            continue;
        };
        let a = &out.applied[i];
        let v = verdict(&h_wo, &h_full, &a.joints, 2.0, opts.decisive_improvement);
        let k_full: usize = out.applied.iter().map(|a| a.effect.fitted()).sum();
        let bic_dec =
            bic(t_full.n, t_full.sse, k_full) < bic(t_wo.n, t_wo.sse, k_full - a.effect.fitted());
        let keep = v.significant && v.rel >= opts.min_rel_improvement;
        out.tried.push(Tried {
            round,
            phase: "drop",
            effect: a.effect.id().into(),
            joints: a.joints.clone(),
            params: a.params.clone(),
            train_rmse: t_full.rmse(),
            heldout_improvement: v.rel,
            significant: v.significant,
            bic_decreased: bic_dec,
            kept: keep,
        });
        if !keep {
            out.warnings.push(format!(
                "{} on {} dropped: with the other effects, removing it changes the held-out RMSE by {:+.1} % (not beyond noise)",
                a.effect.id(),
                a.joints.join(","),
                -100.0 * v.rel
            ));
            out.applied.remove(i);
            out.selected.remove(i);
            changed = true;
        }
    }
    changed
}

/// Swaps for simpler effects. Returns `true` when a swap was made.
fn swap_pass(
    engine: &Engine,
    train: &[Recording],
    heldout: &[Recording],
    allowed: &[String],
    round: usize,
    out: &mut FitOutcome,
) -> bool {
    let opts = engine.opts;
    let mut changed = false;
    let mut i = 0;
    while i < out.applied.len() {
        let cur = out.applied[i].clone();
        let k_cur = cur.effect.fitted();
        let mut others = out.applied.clone();
        others.remove(i);
        let (Some(h_cur), Some(h_wo)) =
            (engine.errors(heldout, &out.applied), engine.errors(heldout, &others))
        else {
            i += 1;
            continue;
        };
        // Within 5 % of the current held-out RMSE, not worse beyond noise, and a training BIC
        // that is not higher (as in the greedy winner's choice).
        let tol = 0.05 * h_cur.rmse();
        let k_all: usize = out.applied.iter().map(|a| a.effect.fitted()).sum();
        let bic_cur = engine
            .errors(train, &out.applied)
            .map_or(f64::NEG_INFINITY, |e| bic(e.n, e.sse, k_all));
        let mut best: Option<(Vec<Applied>, f64, usize)> = None;
        for e in effects::all() {
            if !allowed.iter().any(|a| a == e.id())
                || e.id() == cur.effect.id()
                || e.fitted() >= k_cur
            {
                continue;
            }
            if others
                .iter()
                .any(|a| a.effect.id() == e.id() && a.joints.iter().any(|j| cur.joints.contains(j)))
            {
                continue;
            }
            let (p, tr) = engine.fit_one(train, &others, e, &cur.joints);
            if p.is_empty() || !tr.is_finite() {
                continue;
            }
            let mut set = others.clone();
            set.push(Applied { effect: e, joints: cur.joints.clone(), params: p });
            let Some(h0) = engine.errors(heldout, &set) else { continue };
            // Hopeless before polishing: skip the joint re-fit.
            let set = if h0.rmse() <= h_cur.rmse() * 1.10 && set.len() >= 2 {
                polish_set(engine, train, heldout, set, 0.02)
            } else {
                set
            };
            let Some(h1) = engine.errors(heldout, &set) else { continue };
            // Is the current set better than the swap beyond noise?
            let worse = verdict(&h1, &h_cur, &cur.joints, 2.0, f64::INFINITY);
            let k_set = k_all - k_cur + e.fitted();
            let bic_ok =
                engine.errors(train, &set).is_some_and(|t| bic(t.n, t.sse, k_set) <= bic_cur);
            let ok = h1.rmse() <= h_cur.rmse() + tol && !worse.significant && bic_ok;
            out.tried.push(Tried {
                round,
                phase: "swap",
                effect: e.id().into(),
                joints: cur.joints.clone(),
                params: set.last().expect("pushed").params.clone(),
                train_rmse: tr,
                heldout_improvement: (h_cur.rmse() - h1.rmse()) / h_cur.rmse().max(1e-300),
                significant: worse.significant,
                bic_decreased: bic_ok,
                kept: false,
            });
            let better = match &best {
                None => true,
                Some((_, r, k)) => e.fitted() < *k || (e.fitted() == *k && h1.rmse() < *r),
            };
            if ok && better {
                best = Some((set, h1.rmse(), e.fitted()));
            }
        }
        let Some((set, rmse_new, _)) = best else {
            i += 1;
            continue;
        };
        let new = set.last().expect("non-empty").clone();
        if let Some(t) =
            out.tried.iter_mut().rev().find(|t| {
                t.phase == "swap" && t.effect == new.effect.id() && t.joints == new.joints
            })
        {
            t.kept = true;
        }
        out.warnings.push(format!(
            "{} on {} replaced by the simpler {} (held-out RMSE {:.3e} → {:.3e} rad)",
            cur.effect.id(),
            cur.joints.join(","),
            new.effect.id(),
            h_cur.rmse(),
            rmse_new
        ));
        let old = out.selected.remove(i);
        out.applied = set;
        sync_selected(out);
        let (Some(t_wo), Some(t_new), Some(h_new)) = (
            engine.errors(train, &others),
            engine.errors(train, &out.applied),
            engine.errors(heldout, &out.applied),
        ) else {
            // Cannot happen (both were just simulated); keep the old effect's record shape.
            out.selected.push(old);
            changed = true;
            continue;
        };
        let k_new: usize = out.applied.iter().map(|a| a.effect.fitted()).sum();
        let v = verdict(&h_wo, &h_new, &new.joints, 2.0, opts.decisive_improvement);
        let evidence = BTreeMap::from([(format!("replaces_{}", cur.effect.id()), 1.0)]);
        let bics =
            (bic(t_wo.n, t_wo.sse, k_new - new.effect.fitted()), bic(t_new.n, t_new.sse, k_new));
        let mut s = Selected::new(&new, evidence, &v, h_wo.rmse(), h_new.rmse(), bics);
        set_uncertainty(engine, train, &mut s, &out.applied, &mut out.warnings);
        out.selected.push(s);
        changed = true;
        // `i` now holds the next effect; the new one (last) is revisited at the end.
    }
    changed
}

/// Joint re-fit of every kept effect's fitted parameters (Nelder–Mead from the greedy values);
/// kept only when both the training and the held-out RMSE do not get worse.
fn polish(engine: &Engine, train: &[Recording], heldout: &[Recording], out: &mut FitOutcome) {
    out.applied = polish_set(engine, train, heldout, std::mem::take(&mut out.applied), 0.02);
    sync_selected(out);
}

fn polish_set(
    engine: &Engine,
    train: &[Recording],
    heldout: &[Recording],
    applied: Vec<Applied>,
    step: f64,
) -> Vec<Applied> {
    let Some(slots) = param_slots(engine, &applied, 0, |ai| ai) else { return applied };
    let make = |x: &[f64]| with_params(&applied, &slots, x);
    let x0: Vec<f64> = slots.iter().map(|&(ai, k, ..)| applied[ai].params[k]).collect();
    let b =
        Bounds { lo: slots.iter().map(|s| s.2).collect(), hi: slots.iter().map(|s| s.3).collect() };
    let obj = |x: &[f64]| engine.errors(train, &make(x)).map_or(f64::INFINITY, |e| e.rmse());
    let f0 = obj(&x0);
    let o = NelderMeadOpts {
        max_evals: engine.opts.max_evals * 2,
        xtol: 1e-4,
        ftol: 1e-12,
        initial_step: step,
    };
    let r = nelder_mead(&obj, &x0, &b, &o);
    if r.f.is_nan() || r.f >= f0 {
        return applied;
    }
    let new = make(&r.x);
    let (Some(h0), Some(h1)) = (engine.errors(heldout, &applied), engine.errors(heldout, &new))
    else {
        return applied;
    };
    if h1.rmse() > h0.rmse() {
        return applied;
    }
    new
}

#[cfg(test)]
mod tests {
    use super::*;

    fn errs(w: &[f64]) -> Errors {
        let sse: f64 = w.iter().map(|v| v * v * 10.0).sum();
        Errors {
            sse,
            n: 10 * w.len(),
            windows: w.iter().map(|v| ("a".to_string(), *v)).collect(),
            eps: vec![],
        }
    }

    #[test]
    fn z_grows_with_the_number_of_candidates() {
        assert_eq!(z_needed(1), 2.0);
        assert_eq!(z_needed(4), 2.0);
        assert!((z_needed(8) - 2.3466).abs() < 1e-3);
        assert!(z_needed(16) > z_needed(8));
    }

    #[test]
    fn verdict_paired_decisive_and_noise() {
        let g = vec!["a".to_string()];
        // Consistent 10 % improvement in every window: significant by the paired test.
        let before: Vec<f64> = (0..16).map(|i| 1.0 + 0.05 * (i % 3) as f64).collect();
        let after: Vec<f64> = before.iter().map(|v| 0.9 * v).collect();
        assert!(verdict(&errs(&before), &errs(&after), &g, 2.0, 0.5).significant);
        // A saturation event: 3 of 16 windows improve 20-fold, the rest are unchanged. The
        // paired tests fail (too few informative windows), the decisive path accepts.
        let mut before = vec![1.0; 16];
        let mut after = vec![1.0; 16];
        for (i, big) in [(2, 40.0), (7, 25.0), (11, 60.0)] {
            before[i] = big;
            after[i] = 1.0;
        }
        assert!(!verdict(&errs(&before), &errs(&after), &g, 2.0, f64::INFINITY).significant);
        assert!(verdict(&errs(&before), &errs(&after), &g, 2.0, 0.5).significant);
        // Noise: as many windows worse as better, tiny mean change: not significant.
        let before: Vec<f64> = (0..16).map(|i| 1.0 + 0.01 * ((i * 7) % 5) as f64).collect();
        let after: Vec<f64> = before
            .iter()
            .enumerate()
            .map(|(i, v)| v + if i % 2 == 0 { 0.01 } else { -0.011 })
            .collect();
        assert!(!verdict(&errs(&before), &errs(&after), &g, 2.0, 0.5).significant);
        // A big improvement on one window and worse on most others is not decisive.
        let mut after = before.clone();
        after[0] = 0.0;
        for v in after.iter_mut().skip(1).take(8) {
            *v *= 1.05;
        }
        let mut b2 = before.clone();
        b2[0] = 10.0;
        assert!(!verdict(&errs(&b2), &errs(&after), &g, 2.0, 0.5).significant);
    }

    #[test]
    fn mirror_names() {
        assert_eq!(mirror_name("left_knee").as_deref(), Some("right_knee"));
        assert_eq!(mirror_name("r_hip_pitch").as_deref(), Some("l_hip_pitch"));
        assert_eq!(mirror_name("hip_L").as_deref(), Some("hip_R"));
        assert_eq!(mirror_name("elbow_pitch"), None);
        // Booster T1 and Unitree H1 spellings (the fit pairs their legs).
        assert_eq!(mirror_name("Left_Knee_Pitch").as_deref(), Some("Right_Knee_Pitch"));
        assert_eq!(mirror_name("right_knee_joint").as_deref(), Some("left_knee_joint"));
    }
}
