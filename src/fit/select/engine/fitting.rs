//! Fitting one candidate on top of a kept set, and the standard errors of a fit.

use crate::fit::effects::{self, Applied, Effect, JointTarget, model_with};
use crate::fit::optim::{Bounds, HeldJacobian};
use crate::sim2real::metrics::gap_mask;
use crate::sim2real::recording::Recording;

use super::super::at_base::AtBase;
use super::super::solve::{Method, Problem, solve};
use super::{Engine, fit_key};

/// A fit ends on a bound within this distance of it [fraction of the range].
const ON_BOUND: f64 = 1e-3;
/// A secant coarse fit has converged when its step is shorter than this [fraction of the
/// parameter's range]: a convergence tolerance at the resolution of [`super::uncertainty::FD_STEP`], not a
/// decision threshold.
const SECANT_XTOL: f64 = 1e-3;
/// Where a restart grid puts its points for two parameters, and for more [fractions of the
/// range, on a log scale when the lower bound is positive].
const GRID_FINE: [f64; 5] = [0.1, 0.3, 0.5, 0.7, 0.9];
const GRID_COARSE: [f64; 3] = [0.2, 0.5, 0.8];

impl Engine<'_> {
    /// Residual vector (real − sim) on `joints`, subsampled to at most `max_len` entries.
    pub(in crate::fit::select) fn residuals(
        &self,
        recs: &[Recording],
        applied: &[Applied],
        joints: &[String],
        max_len: usize,
    ) -> Option<Vec<f64>> {
        self.residuals_by_episode(recs, applied, joints, max_len).map(|(r, _)| r)
    }

    /// [`Engine::residuals`] with, for each residual, the index of its recording in `recs`
    /// (the clusters of [`cluster_robust_stderr`]).
    pub(in crate::fit::select) fn residuals_by_episode(
        &self,
        recs: &[Recording],
        applied: &[Applied],
        joints: &[String],
        max_len: usize,
    ) -> Option<(Vec<f64>, Vec<usize>)> {
        let e = self.errors(recs, applied)?;
        let mut out = Vec::new();
        for (i, (rec, ep)) in recs.iter().zip(&e.eps).enumerate() {
            let scored = gap_mask(&rec.t, self.opts.gap_mask_s);
            for (k, jt) in rec.joints.iter().enumerate() {
                if joints.contains(&jt.name) {
                    out.extend(
                        jt.q.iter()
                            .zip(&ep.q_sim[k])
                            .zip(&scored)
                            .filter(|(_, s)| **s)
                            .map(|((a, b), _)| a - b)
                            .filter(|x| x.is_finite())
                            .map(|x| (x, i)),
                    );
                }
            }
        }
        let stride = out.len().div_ceil(max_len.max(1)).max(1);
        Some(out.into_iter().step_by(stride).unzip())
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
        self.fit_from(train, base, (effect, group), None)
    }

    /// [`Engine::fit_one`] continued from `start` (a coarse fit of the same candidate, e.g. on
    /// the screen's shorter data): a least-squares fit starts there instead of at the effect's
    /// initial values. Memoised like [`Engine::fit_one`] (the first start of a candidate wins).
    pub fn fit_from(
        &self,
        train: &[Recording],
        base: &[Applied],
        (effect, group): (&'static dyn Effect, &[String]),
        start: Option<&[f64]>,
    ) -> (Vec<f64>, f64) {
        self.fit_memo(train, base, (effect, group), self.opts.policy.max_evals, start)
    }

    /// A re-fit of an answer on other data (the multiple-shooting windows of
    /// [`super::super::reshoot`]): [`Engine::fit_from`] `start` for a smooth or one-parameter
    /// effect; a simplex from `start` for a non-smooth one of two or three parameters, with the
    /// budget of a full fit but neither the nested start nor the alternatives' second simplex —
    /// `start` is already the better of those on the whole episodes, and the windows move the
    /// optimum only a little. Not memoised (the windows are fitted once).
    pub(in crate::fit::select) fn refit_from(
        &self,
        train: &[Recording],
        base: &[Applied],
        (effect, group): (&'static dyn Effect, &[String]),
        start: &[f64],
    ) -> (Vec<f64>, f64) {
        let k = effect.fitted().min(start.len());
        let Some(t) = JointTarget::of(self.robot, &group[0]) else {
            return (vec![], f64::INFINITY);
        };
        if effect.smooth() || !(2..=3).contains(&k) {
            return self.fit_from(train, base, (effect, group), Some(start));
        }
        let m0 = model_with(self.robot, base);
        let (lo, hi) = effect.bounds(&m0, &t);
        let at = AtBase::new(self, train, base, (effect, group), &m0);
        let make = |x: &[f64]| {
            let mut p = start.to_vec();
            p[..k].copy_from_slice(&x[..k]);
            at.set(base, group, p)
        };
        let obj = |x: &[f64]| self.score(train, &make(x));
        let x0: Vec<f64> = (0..k).map(|i| start[i].clamp(lo[i], hi[i])).collect();
        let problem = Problem {
            objective: &obj,
            residuals: None,
            bounds: Bounds { lo: lo[..k].to_vec(), hi: hi[..k].to_vec() },
            held: None,
        };
        // The same simplex as a full fit's (`fit_fresh`), from the answer.
        let r = solve(&problem, &x0, full_fit_simplex(self.opts.policy.max_evals, k));
        let mut p = start.to_vec();
        p[..k].copy_from_slice(&r.x[..k]);
        (p, r.f)
    }

    /// The result of [`Engine::fit_one`] with these arguments if it was already computed.
    pub fn fit_known(
        &self,
        train: &[Recording],
        base: &[Applied],
        effect: &'static dyn Effect,
        group: &[String],
    ) -> Option<(Vec<f64>, f64)> {
        let key =
            fit_key(train, base, effect, group, self.opts.policy.max_evals) + &self.start_tag();
        self.fits.lock().ok()?.get(&key).cloned()
    }

    /// [`Engine::fit_one`] with a budget of `max_evals` objective evaluations for one parameter
    /// (the line search stops earlier at its tolerance), 2 × (k − 1) times that for the simplex on
    /// k = 2 or 3 parameters; Levenberg–Marquardt iterations take k + 1 replays each.
    pub fn fit_budget(
        &self,
        train: &[Recording],
        base: &[Applied],
        effect: &'static dyn Effect,
        group: &[String],
        max_evals: usize,
    ) -> (Vec<f64>, f64) {
        self.fit_memo(train, base, (effect, group), max_evals, None)
    }

    /// [`Engine::fit_budget`] from `start`: for a non-smooth one-parameter candidate a point of
    /// the same line search's grid made on other data (its probes' coarse fit, re-made on the
    /// screen's data): only the grid points around it are replayed ([`Method::LineFrom`]), the
    /// same answer as the whole grid whenever the grid's best point is among them, else the
    /// whole grid; for a smooth one a point on `train` better than its start (the Gauss–Newton
    /// step at its probes' fit), where Levenberg–Marquardt starts, with the same budget. Any
    /// other effect is fitted as by [`Engine::fit_budget`]. Memoised as it.
    pub(in crate::fit::select) fn fit_budget_from(
        &self,
        train: &[Recording],
        base: &[Applied],
        (effect, group): (&'static dyn Effect, &[String]),
        max_evals: usize,
        start: &[f64],
    ) -> (Vec<f64>, f64) {
        self.fit_memo(train, base, (effect, group), max_evals, Some(start))
    }

    /// The coarse fit of a smooth one-parameter `effect` on `group`, started from the screen's
    /// linear model: secant Gauss–Newton steps on the rollout residuals, one replay each. The
    /// first step is the screen's predicted `step` from the effect's start (its probe column is
    /// the first Jacobian); each later column is the secant through the last two points. The
    /// fit stops at the first step whose simulated relative improvement agrees with the one
    /// its linear model predicted ([`SearchPolicy::linear_trust`]: the model held as far as the
    /// step, so the point is as good as a screen needs), at a step of less than a thousandth
    /// of the range, or after `screen_evals` replays, and answers its best point — remembered as
    /// the candidate's coarse fit. `None` (the caller runs the usual coarse fit) when the effect
    /// is not smooth, has more than one parameter, or the group's joints start from different
    /// values.
    ///
    /// A Levenberg–Marquardt coarse fit differentiates anew at every iteration (k + 1 replays);
    /// here the screen already holds the first derivative and the replays of the steps give
    /// the next ones.
    ///
    /// [`SearchPolicy::linear_trust`]: super::super::policy::SearchPolicy::linear_trust
    pub(in crate::fit::select) fn fit_secant(
        &self,
        train: &[Recording],
        base: &[Applied],
        (effect, group): (&'static dyn Effect, &[String]),
        (step, gain): (f64, f64),
    ) -> Option<(Vec<f64>, f64)> {
        if !effect.smooth() || effect.fitted() != 1 || !step.is_finite() || !gain.is_finite() {
            return None;
        }
        let m0 = model_with(self.robot, base);
        let starts: Vec<Vec<f64>> = group
            .iter()
            .map(|j| JointTarget::of(self.robot, j).map(|t| effect.initial(&m0, &t)))
            .collect::<Option<_>>()?;
        let full0 = starts.first()?.clone();
        if full0.is_empty() || starts.iter().any(|s| s.first() != full0.first()) {
            return None;
        }
        let t = JointTarget::of(self.robot, &group[0])?;
        let (lo, hi) = effect.bounds(&m0, &t);
        let (lo, hi) = (lo[0], hi[0]);
        let pol = &self.opts.policy;
        let at = AtBase::new(self, train, base, (effect, group), &m0);
        let make = |x: f64| {
            let mut p = full0.clone();
            p[0] = x;
            at.set(base, group, p)
        };
        let resid = |set: &[Applied]| self.residuals(train, set, &self.joints, usize::MAX);
        let (mut x, mut f) =
            (full0[0].clamp(lo, hi), self.score(train, &make(full0[0].clamp(lo, hi))));
        let mut r = resid(&make(x))?;
        if !f.is_finite() || !(f > 0.0) {
            return None;
        }
        let (mut best_x, mut best_f) = (x, f);
        // The step and the relative improvement its linear model predicts.
        let (mut dx, mut predicted) = (step, gain);
        let agree = |got: f64, want: f64| {
            let small = pol.min_rel_improvement;
            (want.abs() < small && got.abs() < small)
                || (want > 0.0 && got >= pol.linear_trust * want && got * pol.linear_trust <= want)
        };
        for _ in 0..pol.screen_evals.max(1) {
            let x1 = (x + dx).clamp(lo, hi);
            if (x1 - x).abs() <= SECANT_XTOL * (hi - lo) && x1 != full0[0] {
                break;
            }
            let set = make(x1);
            let f1 = self.score(train, &set);
            if !f1.is_finite() {
                break;
            }
            let got = 1.0 - f1 / f;
            if f1 < best_f {
                (best_x, best_f) = (x1, f1);
            }
            if agree(got, predicted) {
                break;
            }
            // The secant column through the last two points, and its Gauss–Newton step.
            let Some(r1) = resid(&set) else { break };
            if r1.len() != r.len() || x1 == x {
                break;
            }
            let h = x1 - x;
            let col: Vec<f64> = r1.iter().zip(&r).map(|(b, a)| (b - a) / h).collect();
            let (cc, cr): (f64, f64) =
                col.iter().zip(&r1).fold((0.0, 0.0), |(cc, cr), (c, v)| (cc + c * c, cr + c * v));
            if !(cc > 0.0) {
                break;
            }
            let ss: f64 = r1.iter().map(|v| v * v).sum();
            dx = -cr / cc;
            predicted =
                if ss > 0.0 { 1.0 - ((ss - cr * cr / cc).max(0.0) / ss).sqrt() } else { 0.0 };
            (x, f, r) = (x1, f1, r1);
        }
        let mut p = full0.clone();
        p[0] = best_x;
        let key = fit_key(train, base, effect, group, pol.screen_evals) + &self.start_tag();
        if let Ok(mut m) = self.fits.lock() {
            m.insert(key, (p.clone(), best_f));
        }
        Some((p, best_f))
    }

    /// The candidate `effect` on `group` at the screen's linear step `steps` (of its first
    /// parameters, from the effect's start on the group's first joint, held inside the bounds),
    /// replayed once on `train`: its parameters and RMSE. `None` when the step moves nothing or
    /// the replay fails.
    pub(in crate::fit::select) fn at_linear_step(
        &self,
        train: &[Recording],
        base: &[Applied],
        (effect, group): (&'static dyn Effect, &[String]),
        steps: &[f64],
    ) -> Option<(Vec<f64>, f64)> {
        let t = JointTarget::of(self.robot, group.first()?)?;
        let m0 = model_with(self.robot, base);
        let p0 = effect.initial(&m0, &t);
        let (lo, hi) = effect.bounds(&m0, &t);
        let mut p = p0.clone();
        for (i, s) in steps.iter().enumerate().take(p.len().min(lo.len()).min(hi.len())) {
            if s.is_finite() && lo[i] <= hi[i] {
                p[i] = (p0[i] + s).clamp(lo[i], hi[i]);
            }
        }
        if p == p0 {
            return None;
        }
        let set = AtBase::new(self, train, base, (effect, group), &m0).set(base, group, p.clone());
        let f = self.score(train, &set);
        f.is_finite().then_some((p, f))
    }

    /// Holds `j`, forward differences of the residual of `effect` on `group` on top of `base`
    /// on `train` (the residual [`Engine::residuals`] of every scored joint, as a least-squares
    /// fit's), for the first iteration of a later least-squares fit of that candidate on the same
    /// data and base ([`HeldJacobian`]: where it applies). The latest held per candidate stands.
    pub(in crate::fit::select) fn hold_jacobian(
        &self,
        (train, base): (&[Recording], &[Applied]),
        (effect, group): (&dyn Effect, &[String]),
        j: HeldJacobian,
    ) {
        let key = fit_key(train, base, effect, group, 0) + &self.start_tag();
        self.jacobians.lock().unwrap_or_else(|e| e.into_inner()).insert(key, j);
    }

    /// The Jacobian held for `effect` on `group` on top of `base` on `train`
    /// ([`Engine::hold_jacobian`]).
    pub(in crate::fit::select) fn held_jacobian(
        &self,
        (train, base): (&[Recording], &[Applied]),
        (effect, group): (&dyn Effect, &[String]),
    ) -> Option<HeldJacobian> {
        let key = fit_key(train, base, effect, group, 0) + &self.start_tag();
        self.jacobians.lock().unwrap_or_else(|e| e.into_inner()).get(&key).cloned()
    }

    /// A fit with `max_evals` from `start` (see [`Engine::fit_from`]), remembered by
    /// [`fit_key`]: the first fit of a candidate on a base answers every later request.
    fn fit_memo(
        &self,
        train: &[Recording],
        base: &[Applied],
        (effect, group): (&'static dyn Effect, &[String]),
        max_evals: usize,
        start: Option<&[f64]>,
    ) -> (Vec<f64>, f64) {
        let key = fit_key(train, base, effect, group, max_evals) + &self.start_tag();
        if let Some(r) = self.fits.lock().ok().and_then(|m| m.get(&key).cloned()) {
            return r;
        }
        let r = self.fit_fresh(train, base, effect, group, max_evals, start);
        if let Ok(mut m) = self.fits.lock() {
            m.insert(key, r.clone());
        }
        r
    }

    fn fit_fresh(
        &self,
        train: &[Recording],
        base: &[Applied],
        effect: &'static dyn Effect,
        group: &[String],
        max_evals: usize,
        start: Option<&[f64]>,
    ) -> (Vec<f64>, f64) {
        let Some(t) = JointTarget::of(self.robot, &group[0]) else {
            return (vec![], f64::INFINITY);
        };
        let m0 = model_with(self.robot, base);
        let full0 = effect.initial(&m0, &t);
        let (lo, hi) = effect.bounds(&m0, &t);
        let k = effect.fitted().min(full0.len());
        let at = AtBase::new(self, train, base, (effect, group), &m0);
        let make = |x: &[f64]| {
            let mut p = full0.clone();
            p[..k].copy_from_slice(&x[..k]);
            at.set(base, group, p)
        };
        let obj = |x: &[f64]| self.score(train, &make(x));
        let clamp = |p: &[f64]| -> Vec<f64> { (0..k).map(|i| p[i].clamp(lo[i], hi[i])).collect() };
        let mut x0: Vec<f64> = clamp(&full0);
        // A second start for the simplex (`Effect::nested_alternatives`) when one of the
        // alternatives scores better than the start chosen here: (start, its error).
        let mut alt: Option<(Vec<f64>, f64)> = None;
        let full_fit = max_evals >= self.opts.policy.max_evals;
        if let Some(seed) = self.nested_start(train, base, (effect, group), max_evals, (&m0, &t)) {
            let s0 = clamp(&seed);
            let (f_init, f_seed) = (obj(&x0), obj(&s0));
            let mut f0 = f_init;
            if f_seed < f_init {
                x0 = s0;
                f0 = f_seed;
            }
            let alternatives = if full_fit { effect.nested_alternatives(&seed) } else { vec![] };
            alt = alternatives
                .iter()
                .filter(|a| a.len() >= k)
                .map(|a| {
                    let a = clamp(a);
                    let f = obj(&a);
                    (a, f)
                })
                .filter(|(_, f)| *f < f0)
                .min_by(|a, b| a.1.total_cmp(&b.1));
        }
        // A full least-squares fit goes on from where a coarse fit of the same candidate
        // stopped (the caller's `start`, which improved on the effect's initial values there),
        // or, when the coarse fit was made on these data, from it if it is better than the start.
        let x_start = x0.clone();
        if full_fit && effect.smooth() && k > 0 {
            let coarse = fit_key(train, base, effect, group, self.opts.policy.screen_evals)
                + &self.start_tag();
            let known = self.fits.lock().ok().and_then(|m| m.get(&coarse).cloned());
            if let Some(p) = start.filter(|p| p.len() >= k) {
                x0 = clamp(p);
            } else if let Some((p, f)) = known
                && p.len() >= k
                && f < obj(&x0)
            {
                x0 = clamp(&p);
            }
        } else if effect.smooth()
            && let Some(p) = start.filter(|p| p.len() >= k && k > 0)
        {
            // A coarse fit from a point of the same candidate on these data that improved on
            // its start (the probes' fit or the Gauss–Newton step from it, `coarse::on_probes`).
            x0 = clamp(p);
        }
        let b = Bounds { lo: lo[..k].to_vec(), hi: hi[..k].to_vec() };
        let res = |x: &[f64]| {
            self.residuals(train, &make(x), &self.joints, usize::MAX).unwrap_or_default()
        };
        // (Its first Jacobian where one is held for the candidate here: `further::model_at`'s.)
        let held = self.held_jacobian((train, base), (effect, group));
        let problem = Problem {
            objective: &obj,
            residuals: Some(&res),
            bounds: b.clone(),
            held: held.as_ref(),
        };
        let (x, f) = match k {
            0 => (vec![], obj(&[])),
            _ if effect.smooth() => {
                // Gauss–Newton / Levenberg–Marquardt on the rollout residuals: k + 1 replays per
                // iteration, converged in a handful (a derivative-free search needs ~40).
                // (A parameter held by bounds of zero width costs no replay.)
                let free = (0..k).filter(|&i| b.hi[i] > b.lo[i]).count();
                let method = Method::LeastSquares {
                    max_iters: (max_evals / (free + 2)).clamp(2, 12),
                    resolve: self.opts.policy.line_resolution,
                };
                let first = solve(&problem, &x0, method);
                // A second basin: a servo gain error of kp × 0.4, kd × 2 on arm3's elbow was
                // fitted from (1, 1) as kp × 0.99, kd × 5.0 — kd on its bound, 1.16 mrad
                // against 0.68 at the truth (a stiffer, heavily damped servo follows a slow one
                // almost as well) — or, on other recordings of it, first stepped to the corner
                // (3, 5) and ran out of iterations walking back down the curved valley at
                // (0.45, 2.26). A full multi-parameter fit that ends on a bound it did not
                // start on, or before converging, is also started from the best point of a
                // grid inside the bounds; the better fit is kept. (Not the coarse screens: they
                // stop after two iterations by design.)
                let again = k >= 2
                    && max_evals >= self.opts.policy.max_evals
                    && (!first.converged || ends_on_bound(&first.x, &x_start, &b));
                match again.then(|| grid_best(&obj, &b)) {
                    Some(Some(g)) => {
                        let second = solve(&problem, &g, method);
                        if second.f < first.f { (second.x, second.f) } else { (first.x, first.f) }
                    }
                    _ => (first.x, first.f),
                }
            }
            1 => {
                let (log, max_evals) = (effect.log_search(), max_evals.min(40));
                // Refined until the minimum is located within `line_resolution` standard
                // errors of the parameter (or the line search's tolerance).
                let resolve = self.opts.policy.line_resolution;
                // A fit from a point of its grid made on other data (a full fit from a coarse
                // fit's point; a coarse fit from the probes' one) replays the grid around it
                // and refines its bracket ([`Method::LineFrom`]) when it holds a minimum.
                let method = match start.filter(|p| !p.is_empty()) {
                    Some(s) => {
                        x0 = clamp(s);
                        Method::LineFrom { log, max_evals, resolve }
                    }
                    None => Method::Line { log, max_evals, resolve },
                };
                let s = solve(&problem, &x0, method);
                (s.x, s.f)
            }
            2 | 3 => {
                // The simplex needs more steps per added dimension: with 2× the budget a
                // 3-parameter Stribeck fit stopped short in its valley (v_s 0.129 for 0.2 on the
                // pendulum benchmark; 4× reaches 0.202 from any start tried).
                let method = full_fit_simplex(max_evals, k);
                let r = solve(&problem, &x0, method);
                match alt {
                    Some((a, _)) => {
                        let r2 = solve(&problem, &a, method);
                        if r2.f < r.f { (r2.x, r2.f) } else { (r.x, r.f) }
                    }
                    None => (r.x, r.f),
                }
            }
            _ => {
                let s = solve(&problem, &x0, Method::Evolution { max_evals: max_evals * 2 });
                (s.x, s.f)
            }
        };
        let mut p = full0.clone();
        p[..k].copy_from_slice(&x[..k]);
        (p, f)
    }

    /// The start [`Effect::nests`] gives a fit of `effect` on `group`: the simpler effect fitted
    /// on the same base and joints (memoised: the search fits it as a candidate of its own),
    /// taken over by `effect` from its parameter defaults ([`Effect::absorb`]).
    /// (A coarse fit starts from the simpler effect's coarse fit: the screen has it already.)
    fn nested_start(
        &self,
        train: &[Recording],
        base: &[Applied],
        (effect, group): (&'static dyn Effect, &[String]),
        max_evals: usize,
        (m0, t): (&mujoco_rs::prelude::MjModel, &JointTarget),
    ) -> Option<Vec<f64>> {
        let simple = effects::by_id(effect.nests()?)?;
        let (p, f) = self.fit_budget(train, base, simple, group, max_evals);
        if p.is_empty() || !f.is_finite() {
            return None;
        }
        let delta: Vec<f64> = p.iter().zip(simple.initial(m0, t)).map(|(a, b)| a - b).collect();
        let zero: Vec<f64> = effect.params().iter().map(|d| d.default).collect();
        effect.absorb(simple, &zero, &delta)
    }

    /// `true` when `effect` finds the targets of every joint of `group` alike
    /// ([`Effect::alike`]: a body effect needs alike links), so that one parameter vector means
    /// the same thing on all of them. The model may give them different values of it (each
    /// joint's own armature): the group then asks whether one value fits them all.
    pub fn shareable(&self, effect: &'static dyn Effect, group: &[String]) -> bool {
        let targets: Vec<JointTarget> =
            group.iter().filter_map(|j| JointTarget::of(self.robot, j)).collect();
        targets.len() == group.len() && targets.windows(2).all(|w| effect.alike(&w[0], &w[1]))
    }

    /// `true` when `effect` starts from the same parameter values on every joint of `group`
    /// (within 1e-9, relative) and the group is [`Engine::shareable`]: the group at its start
    /// is the model as it is.
    pub fn shared_start(
        &self,
        effect: &'static dyn Effect,
        base: &[Applied],
        group: &[String],
    ) -> bool {
        let m0 = model_with(self.robot, base);
        let targets: Vec<JointTarget> =
            group.iter().filter_map(|j| JointTarget::of(self.robot, j)).collect();
        let starts: Vec<Vec<f64>> = targets.iter().map(|t| effect.initial(&m0, t)).collect();
        self.shareable(effect, group)
            && starts.windows(2).all(|w| {
                w[0].len() == w[1].len()
                    && w[0]
                        .iter()
                        .zip(&w[1])
                        .all(|(a, b)| (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1.0))
            })
    }
}

/// Whether some parameter of `x` lies on a bound of `b` (within 0.1 % of its range) that the
/// start `x0` was not on.
pub(super) fn ends_on_bound(x: &[f64], x0: &[f64], b: &Bounds) -> bool {
    (0..x.len()).any(|i| {
        let tol = ON_BOUND * (b.hi[i] - b.lo[i]);
        let on = |v: f64, edge: f64| (v - edge).abs() <= tol;
        (on(x[i], b.lo[i]) && !on(x0[i], b.lo[i])) || (on(x[i], b.hi[i]) && !on(x0[i], b.hi[i]))
    })
}

/// The best point of a grid inside `b` (5 points per parameter for 2 free parameters, 3 for
/// more; at 10–90 % of the range, on a log scale when the lower bound is positive; a parameter
/// held by bounds of zero width at its value): `None` when every point fails.
pub(super) fn grid_best(obj: &dyn Fn(&[f64]) -> f64, b: &Bounds) -> Option<Vec<f64>> {
    let k = b.lo.len();
    let free = (0..k).filter(|&i| b.hi[i] > b.lo[i]).count();
    let fr: &[f64] = if free <= 2 { &GRID_FINE } else { &GRID_COARSE };
    let axis = |i: usize| -> Vec<f64> {
        let (lo, hi) = (b.lo[i], b.hi[i]);
        if hi <= lo {
            return vec![lo];
        }
        fr.iter()
            .map(|&f| if lo > 0.0 { lo * (hi / lo).powf(f) } else { lo + f * (hi - lo) })
            .collect()
    };
    let axes: Vec<Vec<f64>> = (0..k).map(axis).collect();
    let mut best: Option<(f64, Vec<f64>)> = None;
    for n in 0..axes.iter().map(Vec::len).product::<usize>() {
        let mut c = n;
        let p: Vec<f64> = axes
            .iter()
            .map(|a| {
                let v = a[c % a.len()];
                c /= a.len();
                v
            })
            .collect();
        let f = obj(&p);
        if f.is_finite() && best.as_ref().is_none_or(|(bf, _)| f < *bf) {
            best = Some((f, p));
        }
    }
    best.map(|(_, p)| p)
}

/// The simplex of a full fit of a non-smooth effect of `k` (2 or 3) parameters: `max_evals` × 2
/// per dimension beyond the first, an initial simplex of a tenth of each range, stopping when
/// it has shrunk to 1e-3 of the ranges.
fn full_fit_simplex(max_evals: usize, k: usize) -> Method {
    Method::Simplex { max_evals: max_evals * 2 * k.saturating_sub(1).max(1), xtol: 1e-3, step: 0.1 }
}
