//! The fit engine: simulates a dataset with a set of effects and scores it, fits one candidate's
//! parameters, and gives the linearised standard errors of a fit.

use rayon::prelude::*;

use crate::fit::diagnose::Candidate;
use crate::fit::effects::{self, Applied, Effect, JointTarget, model_with, replay_with};
use crate::fit::optim::{
    Bounds, CmaesOpts, LmOpts, LmResult, NelderMeadOpts, cmaes, golden_section,
    levenberg_marquardt, nelder_mead,
};
use crate::fit::stats::{
    ar1_variance_inflation, cluster_robust_stderr, residual_runs, uncertainty_from_jacobian,
    white_floor,
};
use crate::model::Robot;
use crate::sim2real::commands::{Fill, pseudo_sign};
use crate::sim2real::metrics::gap_mask;
use crate::sim2real::recording::Recording;
use crate::sim2real::replay::{BaseMode, Episode, ReplayOptions};

use super::start::{self, StartSens};
use super::{Errors, FitOptions, Floor, ProgressInfo};

/// The fit engine's view of a robot and dataset.
pub struct Engine<'a> {
    pub robot: &'a Robot,
    pub opts: &'a FitOptions,
    /// Joints scored by the objective.
    pub joints: Vec<String>,
    /// Dataset simulations run so far (each replays every episode of a set once).
    sims: std::sync::atomic::AtomicUsize,
    /// Results of [`Engine::fit_budget`] by [`fit_key`]: the simplify pass re-fits the same
    /// effect on the same base the greedy rounds already fitted (swapping the only kept effect
    /// for another is the round-1 fit of that other), and a fit is deterministic.
    fits: std::sync::Mutex<std::collections::HashMap<String, (Vec<f64>, f64)>>,
    /// The last [`RECENT`] simulations by [`set_key`]: the search scores the set a fit ended on
    /// right after the fit, and the same base set for each candidate.
    recent: std::sync::Mutex<std::collections::VecDeque<(String, Option<Errors>)>>,
    /// Start-state sensitivities by recording ([`start::key`]) and start model
    /// ([`Engine::set_start_model`]), measured once each (`None`: not measurable, the recording replays from its first row).
    /// Shared with the floor's alternative replay, whose recordings differ only in the first row
    /// and the commands.
    starts: std::sync::Arc<std::sync::Mutex<StartMemo>>,
    /// The kept effects that let a joint stick ([`Effect::holds_start`]), with which the start
    /// sensitivities are measured ([`Engine::set_start_model`]).
    start_model: std::sync::Mutex<Vec<Applied>>,
    /// The discretisation floor ([`Engine::discretisation_floor`]) by [`set_key`], and by
    /// dataset alone (the latest measured).
    disc: std::sync::Mutex<Vec<(String, Vec<f64>)>>,
}

type StartMemo = std::collections::HashMap<String, Option<std::sync::Arc<StartSens>>>;

/// How many recent simulations [`Engine::errors`] keeps.
const RECENT: usize = 16;

/// The identity of one simulation: the dataset (by address: the search holds its sets for its
/// whole run) and the effects with their parameters' exact bits.
fn set_key(recs: &[Recording], applied: &[Applied]) -> String {
    use std::fmt::Write;
    let mut k = format!("{:p}/{}", recs.as_ptr(), recs.len());
    for a in applied {
        let _ = write!(k, "|{}@{}:", a.effect.id(), a.joints.join(","));
        for v in &a.params {
            let _ = write!(k, "{:x},", v.to_bits());
        }
    }
    k
}

/// The memo key of a fit: the training set (by address: the search holds one for its whole
/// run), the base effects with their parameters' exact bits, the effect, its joints and budget.
fn fit_key(
    train: &[Recording],
    base: &[Applied],
    effect: &dyn Effect,
    group: &[String],
    max_evals: usize,
) -> String {
    format!("{}||{}@{}#{}", set_key(train, base), effect.id(), group.join(","), max_evals)
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
        Engine {
            robot,
            opts,
            joints,
            sims: std::sync::atomic::AtomicUsize::new(0),
            fits: Default::default(),
            recent: Default::default(),
            starts: Default::default(),
            start_model: Default::default(),
            disc: Default::default(),
        }
    }

    /// The start estimate measures its sensitivities with the effects of `kept` that let a
    /// joint stick ([`Effect::holds_start`], e.g. dry friction): a sticking joint keeps its
    /// start error until it breaks away, while on the smooth model the error dies out. Called
    /// by the search whenever its kept set may have changed; the sensitivities are measured
    /// again (once per recording) when these effects or their values change.
    pub fn set_start_model(&self, kept: &[Applied]) {
        let held: Vec<Applied> = kept.iter().filter(|a| a.effect.holds_start()).cloned().collect();
        *self.start_model.lock().unwrap_or_else(|e| e.into_inner()) = held;
    }

    /// The start model's part of every memo key (empty without the start estimate, or
    /// without a sticking effect kept).
    fn start_tag(&self) -> String {
        let m = self.start_model.lock().unwrap_or_else(|e| e.into_inner());
        self.tag_of(&m)
    }

    /// [`Engine::start_tag`] of the start model `m`.
    fn tag_of(&self, m: &[Applied]) -> String {
        if !self.estimates_start() || m.is_empty() {
            return String::new();
        }
        format!("#start:{}", set_key(&[], m))
    }

    fn estimates_start(&self) -> bool {
        // A free base is chaotic: a start estimated from a linear response is not.
        self.opts.estimate_start && self.opts.replay.base != BaseMode::Free
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
        let key = set_key(recs, applied) + &self.start_tag();
        if let Some(e) = self
            .recent
            .lock()
            .ok()
            .and_then(|r| r.iter().find(|(k, _)| *k == key).map(|(_, e)| e.clone()))
        {
            return e;
        }
        let e = self.simulate(recs, applied);
        if let Ok(mut r) = self.recent.lock() {
            if r.len() >= RECENT {
                r.pop_front();
            }
            r.push_back((key, e.clone()));
        }
        e
    }

    fn simulate(&self, recs: &[Recording], applied: &[Applied]) -> Option<Errors> {
        self.sims.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let m = model_with(self.robot, applied);
        let mut eps: Vec<Episode> = recs
            .par_iter()
            .map(|r| {
                replay_with(self.robot, &m, r, applied, &self.opts.replay)
                    .ok()
                    .filter(|e| e.diverged.is_none())
            })
            .collect::<Option<Vec<_>>>()?;
        if self.estimates_start() {
            let (sens, model) = self.start_sensitivities(recs);
            // A joint takes part only when the sticking effects on it are those the
            // sensitivities were measured with (by effect: their values may move a little).
            let sticks = |set: &[Applied], name: &String| -> Vec<&'static str> {
                let mut ids: Vec<&'static str> = set
                    .iter()
                    .filter(|a| a.effect.holds_start() && a.joints.contains(name))
                    .map(|a| a.effect.id())
                    .collect();
                ids.sort_unstable();
                ids
            };
            eps.par_iter_mut().zip(recs).zip(&sens).for_each(|((ep, rec), s)| {
                if let Some(s) = s {
                    let kept: Vec<bool> = rec
                        .joints
                        .iter()
                        .map(|j| sticks(applied, &j.name) == sticks(&model, &j.name))
                        .collect();
                    s.apply(rec, ep, &kept);
                }
            });
        }
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
                // One sample index into four parallel arrays (t, mask, real, sim).
                #[allow(clippy::needless_range_loop)]
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

    /// The start-state sensitivities of `recs` ([`StartSens`]) on the start model, measured
    /// on first use, and that model.
    fn start_sensitivities(
        &self,
        recs: &[Recording],
    ) -> (Vec<Option<std::sync::Arc<StartSens>>>, Vec<Applied>) {
        // One read: the model and its memo tag belong together.
        let model = self.start_model.lock().unwrap_or_else(|e| e.into_inner()).clone();
        let tag = self.tag_of(&model);
        let keys: Vec<String> = recs.iter().map(|r| start::key(r) + &tag).collect();
        let missing: Vec<usize> = {
            let memo = self.starts.lock().unwrap_or_else(|e| e.into_inner());
            let mut seen = std::collections::HashSet::new();
            (0..recs.len())
                .filter(|&i| !memo.contains_key(&keys[i]) && seen.insert(&keys[i]))
                .collect()
        };
        let measured: Vec<Option<std::sync::Arc<StartSens>>> = missing
            .par_iter()
            .map(|&i| {
                StartSens::measure(
                    self.robot,
                    &recs[i],
                    &self.opts.replay,
                    self.opts.gap_mask_s,
                    &self.joints,
                    &model,
                )
                .map(std::sync::Arc::new)
            })
            .collect();
        if let Some(nj) = missing.iter().map(|&i| recs[i].joints.len()).max() {
            // One replay of the first row and two per recorded joint.
            self.sims.fetch_add(1 + 2 * nj, std::sync::atomic::Ordering::Relaxed);
        }
        let mut memo = self.starts.lock().unwrap_or_else(|e| e.into_inner());
        for (i, s) in missing.into_iter().zip(measured) {
            memo.insert(keys[i].clone(), s);
        }
        (keys.iter().map(|k| memo.get(k).cloned().flatten()).collect(), model)
    }

    /// Per scored joint: the mean square of the error that command reconstruction and the
    /// replay's start state alone leave on `recs` simulated with `applied` (`errs`).
    ///
    /// A control tick without a row has a command somewhere between the commands of the known
    /// ticks around it; the replay takes one guess ([`Fill::Ramps`]). The same model is replayed
    /// once more with every held (step) gap filled from its *other* end ([`Fill::Next`]), and
    /// half the mean square of the difference between the two simulations is the floor: the
    /// truth lies between the two ends, and a lightly damped servo rings after every step whose
    /// tick is unknown. A gap filled as smooth motion is moved in that replay by √2 × the
    /// cubic's error on the known ticks nearby, so that it counts its whole expected error (a
    /// command with tick-to-tick roughness: the independent simulator's smoothed random walk).
    ///
    /// The replay starts every episode from its first row, whose position carries the noise
    /// and quantisation of any reading and whose velocity the velocity noise (or, without a
    /// velocity column, the difference of two noisy positions); a lightly damped servo rings
    /// from that start error for seconds. In the same second replay each episode's first
    /// position and velocity are moved by √2 × their own noise (`start`: per scored joint, the
    /// RMS white floor of the position and of the velocity residual, `None` without a velocity
    /// column), with a sign from the episode and joint. Zero when no gap is held, the command
    /// is smooth and the readings are exact.
    ///
    /// [`Fill::Ramps`]: crate::sim2real::commands::Fill::Ramps
    /// [`Fill::Next`]: crate::sim2real::commands::Fill::Next
    pub fn reconstruction_floor(
        &self,
        recs: &[Recording],
        applied: &[Applied],
        errs: &Errors,
        start: &[(f64, Option<f64>)],
    ) -> Vec<f64> {
        let alt = FitOptions {
            replay: ReplayOptions { command_fill: Fill::Next, ..self.opts.replay.clone() },
            progress: None,
            ..self.opts.clone()
        };
        let moved: Vec<Recording> = recs
            .iter()
            .enumerate()
            .map(|(e, rec)| {
                let mut r = rec.clone();
                for (k, name) in self.joints.iter().enumerate() {
                    let (Some(jt), Some(&(sq, sqd))) =
                        (r.joints.iter_mut().find(|j| &j.name == name), start.get(k))
                    else {
                        continue;
                    };
                    let sign =
                        |salt: u64| pseudo_sign(((e as u64) << 24) ^ ((k as u64) << 4) ^ salt);
                    // A recording without commands replays its positions as the commands:
                    // keep the first command where it was.
                    if jt.q_cmd.is_none() {
                        jt.q_cmd = Some(jt.q.clone());
                    }
                    if let Some(q0) = jt.q.first_mut()
                        && sq.is_finite()
                    {
                        *q0 += std::f64::consts::SQRT_2 * sq * sign(1);
                    }
                    if let (Some(qd0), Some(sqd)) =
                        (jt.qd.as_mut().and_then(|v| v.first_mut()), sqd)
                        && sqd.is_finite()
                    {
                        *qd0 += std::f64::consts::SQRT_2 * sqd * sign(2);
                    }
                }
                r
            })
            .collect();
        let mut alt = Engine::new(self.robot, &moved, &alt);
        alt.starts = self.starts.clone();
        alt.set_start_model(&self.start_model.lock().unwrap_or_else(|e| e.into_inner()));
        let Some(b) = alt.errors(&moved, applied) else {
            return vec![0.0; self.joints.len()];
        };
        self.sims.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.joints
            .iter()
            .map(|name| {
                let (mut ss, mut n) = (0.0, 0usize);
                for ((rec, ea), eb) in recs.iter().zip(&errs.eps).zip(&b.eps) {
                    let Some(k) = rec.joints.iter().position(|j| &j.name == name) else { continue };
                    let scored = gap_mask(&rec.t, self.opts.gap_mask_s);
                    for (i, s) in scored.iter().enumerate() {
                        let d = ea.q_sim[k][i] - eb.q_sim[k][i];
                        if *s && d.is_finite() {
                            ss += d * d;
                            n += 1;
                        }
                    }
                }
                if n == 0 { 0.0 } else { 0.5 * ss / n as f64 }
            })
            .collect()
    }

    /// Per fitted joint: (name, mean square, floors) of the residual of `recs` simulated with
    /// `applied` as `errs`. The floor is the white floor ([`white_floor`], over the runs of
    /// samples between gaps) plus the command-reconstruction and start-state floor
    /// ([`Engine::reconstruction_floor`], of this model: one more simulation).
    pub fn floors(&self, recs: &[Recording], applied: &[Applied], errs: &Errors) -> Vec<Floor> {
        // Runs of the residual between gaps, per scored joint: of the position, and of the
        // velocity where the recording has one.
        let runs = |name: &String, vel: bool| -> Vec<Vec<f64>> {
            let mut runs = Vec::new();
            for (rec, ep) in recs.iter().zip(&errs.eps) {
                let Some(k) = rec.joints.iter().position(|j| &j.name == name) else { continue };
                let real =
                    if vel { rec.joints[k].qd.as_deref() } else { Some(&rec.joints[k].q[..]) };
                let (Some(real), sim) = (real, if vel { &ep.qd_sim[k] } else { &ep.q_sim[k] })
                else {
                    continue;
                };
                let scored = gap_mask(&rec.t, self.opts.gap_mask_s);
                runs.extend(residual_runs(&scored, real, sim));
            }
            runs
        };
        let white: Vec<(f64, f64)> =
            self.joints.iter().map(|n| white_floor(&runs(n, false))).collect();
        let start: Vec<(f64, Option<f64>)> = self
            .joints
            .iter()
            .zip(&white)
            .map(|(n, w)| {
                let v = runs(n, true);
                let has_qd = v.iter().any(|r| !r.is_empty());
                (w.1.sqrt(), has_qd.then(|| white_floor(&v).1.sqrt()))
            })
            .collect();
        let recon = self.reconstruction_floor(recs, applied, errs, &start);
        let base: Vec<f64> = white.iter().zip(&recon).map(|(w, r)| w.1 + r).collect();
        let disc = self.discretisation_floor(recs, applied, &base);
        self.joints
            .iter()
            .zip(white.iter().zip(&recon))
            .zip(&disc)
            .map(|((name, (&(ms, white), rc)), d)| Floor {
                joint: name.clone(),
                ms,
                white,
                reconstruction: *rc,
                discretisation: *d,
            })
            .collect()
    }

    /// Per fitted joint, the model's own timestep's part of the residual mean square when the
    /// recordings move in finer time than the model, as hardware moves in continuous time.
    /// Each dataset is replayed with `applied` at the model's timestep and at a quarter of it.
    /// The recordings count as finer than the model when on more than half of the joints the
    /// finer replay comes closer to them by at least half of the two replays' own mean square
    /// difference (`ms(coarse) − ms(fine) ≥ ½ ms(coarse − fine)`), counting only joints whose
    /// residual noise plus that difference can explain (`ms(coarse) ≤ 4 (base + ms(coarse −
    /// fine))`, `base`: the joint's white and reconstruction floor): a large missing effect
    /// makes either replay closer by chance. Then every joint's part is `ms(coarse − fine)`, a
    /// property of the model and the motion that an effect fitted to absorb some of the
    /// discretisation does not shrink; else zero. Recordings simulated at the model's own step
    /// (every synth) are farther from the finer replay: zero. Once per set of effects; a set
    /// that cannot be measured (actuators with a `delay`: their history is sized for the
    /// timestep) takes the dataset's latest measurement, or zero.
    ///
    /// Why: an independent simulator's clean humanoid legs integrated at an eighth of the
    /// model's 2 ms step sit 1.2 mrad from the 2 ms replay; without this part `fit` explained
    /// it as damping and a 0.6 ms action delay on all twelve joints; measured per joint as how
    /// much closer the finer replay comes, knee damping fitted as 8.3 for 8 took the knees'
    /// part to zero and the next round kept a delay and a gain error on every joint.
    pub fn discretisation_floor(
        &self,
        recs: &[Recording],
        applied: &[Applied],
        base: &[f64],
    ) -> Vec<f64> {
        // The dataset's latest measurement, for a set that cannot be measured.
        let (latest, key) = (set_key(recs, &[]) + "#latest", set_key(recs, applied));
        let memo = |k: &str| -> Option<Vec<f64>> {
            let m = self.disc.lock().unwrap_or_else(|e| e.into_inner());
            m.iter().find(|(x, _)| x == k).map(|(_, d)| d.clone())
        };
        if let Some(d) = memo(&key) {
            return d;
        }
        let d = match self.measure_discretisation(recs, applied) {
            Some(sums) => discretisation_part(&sums, base),
            None => memo(&latest).unwrap_or_else(|| vec![0.0; self.joints.len()]),
        };
        let mut m = self.disc.lock().unwrap_or_else(|e| e.into_inner());
        m.retain(|(x, _)| *x != latest);
        m.push((key, d.clone()));
        m.push((latest, d.clone()));
        d
    }

    /// Per fitted joint, the mean squares (coarse − real, fine − real, coarse − fine) of the
    /// replays at the model's timestep and at a quarter of it with `applied`; `None` when they
    /// cannot be made.
    fn measure_discretisation(
        &self,
        recs: &[Recording],
        applied: &[Applied],
    ) -> Option<Vec<[f64; 3]>> {
        let m = model_with(self.robot, applied);
        let dt = m.opt().timestep;
        if !(dt > 0.0) || recs.is_empty() || m.actuator_history().iter().any(|h| h[0] > 0) {
            return None;
        }
        let mut fine = m.clone();
        fine.opt_mut().timestep = dt / crate::sim2real::replay::REFINE;
        let run = |model: &mujoco_rs::prelude::MjModel| -> Option<Vec<Episode>> {
            recs.par_iter()
                .map(|r| {
                    replay_with(self.robot, model, r, applied, &self.opts.replay)
                        .ok()
                        .filter(|e| e.diverged.is_none())
                })
                .collect()
        };
        let (coarse, fine) = (run(&m)?, run(&fine)?);
        self.sims.fetch_add(
            1 + crate::sim2real::replay::REFINE as usize,
            std::sync::atomic::Ordering::Relaxed,
        );
        let sums = self
            .joints
            .iter()
            .map(|name| {
                let (mut sc, mut sf, mut scf, mut n) = (0.0, 0.0, 0.0, 0usize);
                for ((rec, c), f) in recs.iter().zip(&coarse).zip(&fine) {
                    let Some(k) = rec.joints.iter().position(|j| &j.name == name) else { continue };
                    let scored = gap_mask(&rec.t, self.opts.gap_mask_s);
                    // The first sample is the start state in both replays: not counted.
                    let rows = rec.joints[k].q.iter().zip(&c.q_sim[k]).zip(&f.q_sim[k]);
                    for (((&q, &a), &b), &s) in rows.zip(&scored).skip(1) {
                        if s && q.is_finite() && a.is_finite() && b.is_finite() {
                            sc += (q - a) * (q - a);
                            sf += (q - b) * (q - b);
                            scf += (a - b) * (a - b);
                            n += 1;
                        }
                    }
                }
                let n = n.max(1) as f64;
                [sc / n, sf / n, scf / n]
            })
            .collect();
        Some(sums)
    }

    /// `true` when every fitted joint's residual of `recs` simulated with `applied` as `errs` is within
    /// `white_ratio` of its floor ([`Engine::floors`]): what is left is noise and timing.
    pub fn at_floor(&self, recs: &[Recording], applied: &[Applied], errs: &Errors) -> bool {
        self.floors(recs, applied, errs).iter().all(|f| f.reached(self.opts.white_ratio))
    }

    /// Residual vector (real − sim) on `joints`, subsampled to at most `max_len` entries.
    pub(super) fn residuals(
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
    pub(super) fn residuals_by_episode(
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
        self.fit_budget(train, base, effect, group, self.opts.max_evals)
    }

    /// The result of [`Engine::fit_one`] with these arguments if it was already computed.
    pub fn fit_known(
        &self,
        train: &[Recording],
        base: &[Applied],
        effect: &'static dyn Effect,
        group: &[String],
    ) -> Option<(Vec<f64>, f64)> {
        let key = fit_key(train, base, effect, group, self.opts.max_evals) + &self.start_tag();
        self.fits.lock().ok()?.get(&key).cloned()
    }

    /// [`Engine::fit_one`] with a budget of `max_evals` objective evaluations for one parameter
    /// (golden section stops earlier at its tolerance), 2 × (k − 1) times that for the simplex on
    /// k = 2 or 3 parameters; Levenberg–Marquardt iterations take k + 1 replays each.
    pub fn fit_budget(
        &self,
        train: &[Recording],
        base: &[Applied],
        effect: &'static dyn Effect,
        group: &[String],
        max_evals: usize,
    ) -> (Vec<f64>, f64) {
        let key = fit_key(train, base, effect, group, max_evals) + &self.start_tag();
        if let Some(r) = self.fits.lock().ok().and_then(|m| m.get(&key).cloned()) {
            return r;
        }
        let r = self.fit_fresh(train, base, effect, group, max_evals);
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
        let clamp = |p: &[f64]| -> Vec<f64> { (0..k).map(|i| p[i].clamp(lo[i], hi[i])).collect() };
        let mut x0: Vec<f64> = clamp(&full0);
        // A second start for the simplex (`Effect::nested_alternatives`) when one of the
        // alternatives scores better than the start chosen here: (start, its error).
        let mut alt: Option<(Vec<f64>, f64)> = None;
        let full_fit = max_evals >= self.opts.max_evals;
        if let Some(seed) = self.nested_start(train, base, effect, group, &m0, &t) {
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
                    rel_step: crate::fit::optim::ROLLOUT_REL_STEP,
                    tol: 1e-5,
                    final_jacobian: false,
                    stat_tol: crate::fit::optim::ROLLOUT_STAT_TOL,
                    short_step: crate::fit::optim::ROLLOUT_SHORT_STEP,
                };
                let lm = |start: &[f64]| {
                    let r = levenberg_marquardt(&res, start, &b, &o);
                    let n = res_len(&r);
                    let f = if n > 0 { (2.0 * r.cost / n as f64).sqrt() } else { f64::INFINITY };
                    (r.x, f, r.converged)
                };
                let (x, f, converged) = lm(&x0);
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
                    && max_evals >= self.opts.max_evals
                    && (!converged || ends_on_bound(&x, &x0, &b));
                match again.then(|| grid_best(&obj, &b)) {
                    Some(Some(g)) => {
                        let (x2, f2, _) = lm(&g);
                        if f2 < f { (x2, f2) } else { (x, f) }
                    }
                    _ => (x, f),
                }
            }
            1 if effect.log_search() && lo[0] > 0.0 && hi[0] > lo[0] => {
                // Grid and golden section on ln v: a narrow optimum a decade below the top of
                // the range falls between two points of a uniform grid.
                let (a, b) = (lo[0].ln(), hi[0].ln());
                let tol = 2e-4 * (b - a);
                let (u, f) = golden_section(&|u| obj(&[u.exp()]), a, b, tol, max_evals.min(40));
                (vec![u.exp().clamp(lo[0], hi[0])], f)
            }
            1 => {
                let tol = 2e-4 * (hi[0] - lo[0]);
                let (x, f) = golden_section(&|v| obj(&[v]), lo[0], hi[0], tol, max_evals.min(40));
                (vec![x], f)
            }
            2 | 3 => {
                // The simplex needs more steps per added dimension: with 2× the budget a
                // 3-parameter Stribeck fit stopped short in its valley (v_s 0.129 for 0.2 on the
                // pendulum benchmark; 4× reaches 0.202 from any start tried).
                let o = NelderMeadOpts {
                    max_evals: max_evals * 2 * (k - 1),
                    xtol: 1e-3,
                    ftol: 1e-12,
                    initial_step: 0.1,
                };
                let r = nelder_mead(&obj, &x0, &b, &o);
                match alt {
                    Some((a, _)) => {
                        let r2 = nelder_mead(&obj, &a, &b, &o);
                        if r2.f < r.f { (r2.x, r2.f) } else { (r.x, r.f) }
                    }
                    None => (r.x, r.f),
                }
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

    /// The start [`Effect::nests`] gives a fit of `effect` on `group`: the simpler effect fitted
    /// on the same base and joints (memoised: the search fits it as a candidate of its own),
    /// taken over by `effect` from its parameter defaults ([`Effect::absorb`]).
    fn nested_start(
        &self,
        train: &[Recording],
        base: &[Applied],
        effect: &'static dyn Effect,
        group: &[String],
        m0: &mujoco_rs::prelude::MjModel,
        t: &JointTarget,
    ) -> Option<Vec<f64>> {
        let simple = effects::by_id(effect.nests()?)?;
        let (p, f) = self.fit_budget(train, base, simple, group, self.opts.max_evals);
        if p.is_empty() || !f.is_finite() {
            return None;
        }
        let delta: Vec<f64> = p.iter().zip(simple.initial(m0, t)).map(|(a, b)| a - b).collect();
        let zero: Vec<f64> = effect.params().iter().map(|d| d.default).collect();
        effect.absorb(simple, &zero, &delta)
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

    /// Linearised explained mean square of the residual by a probe step of candidate `c`, the
    /// best of the effect's probes (`None` when no probe changes anything or all diverge):
    /// returns (explained MS, coefficient, probe value).
    pub(super) fn sensitivity(
        &self,
        train: &[Recording],
        base: &[Applied],
        base_err: &Errors,
        c: &Candidate,
    ) -> Option<(f64, f64, f64)> {
        let effect = effects::by_id(c.effect)?;
        let t = JointTarget::of(self.robot, &c.joint)?;
        let m0 = model_with(self.robot, base);
        let p0 = effect.initial(&m0, &t);
        let (lo, hi) = effect.bounds(&m0, &t);
        let mut best: Option<(f64, f64, f64)> = None;
        for v in effect.probes(p0[0], lo[0], hi[0], &c.evidence) {
            let mut p = p0.clone();
            p[0] = v;
            let mut a = base.to_vec();
            a.push(Applied { effect, joints: vec![c.joint.clone()], params: p });
            let Some(e) = self.errors(train, &a) else { continue };
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
                continue;
            }
            let ems = rs * rs / ss / n as f64;
            if best.is_none_or(|b| ems > b.0) {
                best = Some((ems, rs / ss, v));
            }
        }
        best
    }

    /// Linearised standard errors of the fitted parameters of `applied.last()`, the others held
    /// at their values (used while the search runs; [`Engine::uncertainty_all`] gives the final
    /// ones).
    pub(super) fn uncertainty(&self, train: &[Recording], applied: &[Applied]) -> (Vec<f64>, bool) {
        let last = applied.len() - 1;
        self.uncertainty_of(train, applied, &[last]).pop().expect("one effect")
    }

    /// Linearised standard errors of every applied effect's fitted parameters, from one joint
    /// Jacobian: a parameter correlated with another effect's (an armature and a gain error on
    /// one joint) gets the wider marginal error, not the one conditional on the other held fixed.
    pub(super) fn uncertainty_all(
        &self,
        train: &[Recording],
        applied: &[Applied],
    ) -> Vec<(Vec<f64>, bool)> {
        let all: Vec<usize> = (0..applied.len()).collect();
        self.uncertainty_of(train, applied, &all)
    }

    /// Standard errors (and identifiability) of the fitted parameters of the effects `which`,
    /// jointly, from finite-difference columns of the residual on their joints: the larger of
    /// `s²(JᵀJ)⁺` with s² inflated for serial correlation (AR(1)) and the cluster-robust
    /// estimate with one cluster per training episode ([`cluster_robust_stderr`]).
    fn uncertainty_of(
        &self,
        train: &[Recording],
        applied: &[Applied],
        which: &[usize],
    ) -> Vec<(Vec<f64>, bool)> {
        // (effect index, parameter index, bound range) of every column.
        let mut slots: Vec<(usize, usize, f64, f64)> = Vec::new();
        let mut joints: Vec<String> = Vec::new();
        for &ai in which {
            let a = &applied[ai];
            let t = JointTarget::of(self.robot, &a.joints[0]).expect("joint");
            let m0 = model_with(self.robot, &applied[..ai]);
            let (lo, hi) = a.effect.bounds(&m0, &t);
            for i in 0..a.effect.fitted().min(a.params.len()) {
                slots.push((ai, i, lo[i], hi[i]));
            }
            for j in &a.joints {
                if !joints.contains(j) {
                    joints.push(j.clone());
                }
            }
        }
        let failed = || {
            which
                .iter()
                .map(|&ai| {
                    let a = &applied[ai];
                    (vec![f64::INFINITY; a.effect.fitted().min(a.params.len())], false)
                })
                .collect()
        };
        let Some((r0, episode)) = self.residuals_by_episode(train, applied, &joints, 20_000) else {
            return failed();
        };
        let mut cols = Vec::with_capacity(slots.len());
        for &(ai, i, lo, hi) in &slots {
            let mut h = 1e-3 * (hi - lo).max(1e-9);
            if applied[ai].params[i] + h > hi {
                h = -h;
            }
            let mut a = applied.to_vec();
            a[ai].params[i] += h;
            match self.residuals(train, &a, &joints, 20_000) {
                // Residuals are real − sim, so ∂r/∂p = −∂sim/∂p; the sign does not matter for J^T J.
                Some(r1) if r1.len() == r0.len() => {
                    cols.push(r1.iter().zip(&r0).map(|(a, b)| (a - b) / h).collect::<Vec<f64>>())
                }
                _ => return failed(),
            }
        }
        let k = slots.len();
        let jac: Vec<Vec<f64>> =
            (0..r0.len()).map(|row| cols.iter().map(|c| c[row]).collect()).collect();
        let ranges: Vec<f64> = slots.iter().map(|s| s.3 - s.2).collect();
        // Serially correlated residuals: scaling them by √inflation scales s² (and so the
        // covariance s²(JᵀJ)⁺ and the identifiability check) by the AR(1) inflation.
        let c = ar1_variance_inflation(&r0).sqrt();
        let scaled: Vec<f64> = r0.iter().map(|x| x * c).collect();
        let mut u = uncertainty_from_jacobian(&jac, &scaled, k, &ranges);
        // Episodes that disagree about a parameter (or an error that lasts a whole episode)
        // widen it beyond what the pooled residuals show: the larger of the two is reported,
        // and a parameter whose error then exceeds half its range is not identifiable.
        if let Some(robust) = cluster_robust_stderr(&jac, &r0, &episode, k) {
            u.widen(&robust, &ranges);
        }
        which
            .iter()
            .map(|&ai| {
                let idx: Vec<usize> = (0..k).filter(|&s| slots[s].0 == ai).collect();
                (idx.iter().map(|&s| u.stderr[s]).collect(), idx.iter().all(|&s| u.identifiable[s]))
            })
            .collect()
    }
}

/// [`Engine::discretisation_floor`]'s decision on the per-joint mean squares `sums` (coarse −
/// real, fine − real, coarse − fine) and the joints' white + reconstruction floors `base`.
fn discretisation_part(sums: &[[f64; 3]], base: &[f64]) -> Vec<f64> {
    let moved = sums.iter().filter(|s| s[2] > 0.0).count();
    let votes = sums
        .iter()
        .zip(base)
        .filter(|([c, f, d], b)| *d > 0.0 && *c <= 4.0 * (*b + d) && c - f >= 0.5 * d)
        .count();
    if moved > 0 && 2 * votes > moved {
        sums.iter().map(|s| s[2]).collect()
    } else {
        vec![0.0; sums.len()]
    }
}

/// Whether some parameter of `x` lies on a bound of `b` (within 0.1 % of its range) that the
/// start `x0` was not on.
fn ends_on_bound(x: &[f64], x0: &[f64], b: &Bounds) -> bool {
    (0..x.len()).any(|i| {
        let tol = 1e-3 * (b.hi[i] - b.lo[i]);
        let on = |v: f64, edge: f64| (v - edge).abs() <= tol;
        (on(x[i], b.lo[i]) && !on(x0[i], b.lo[i])) || (on(x[i], b.hi[i]) && !on(x0[i], b.hi[i]))
    })
}

/// The best point of a grid inside `b` (5 points per parameter for 2 parameters, 3 for more; at
/// 10–90 % of the range, on a log scale when the lower bound is positive): `None` when every
/// point fails.
fn grid_best(obj: &dyn Fn(&[f64]) -> f64, b: &Bounds) -> Option<Vec<f64>> {
    let k = b.lo.len();
    let fr: &[f64] = if k <= 2 { &[0.1, 0.3, 0.5, 0.7, 0.9] } else { &[0.2, 0.5, 0.8] };
    let axis = |i: usize| -> Vec<f64> {
        let (lo, hi) = (b.lo[i], b.hi[i]);
        fr.iter()
            .map(|&f| if lo > 0.0 { lo * (hi / lo).powf(f) } else { lo + f * (hi - lo) })
            .collect()
    };
    let axes: Vec<Vec<f64>> = (0..k).map(axis).collect();
    let mut best: Option<(f64, Vec<f64>)> = None;
    for n in 0..fr.len().pow(k as u32) {
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

/// Number of residuals behind an [`LmResult`] (the rows of its Jacobian).
pub(super) fn res_len(r: &LmResult) -> usize {
    r.n_resid
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::source::SourceMap;
    use crate::sim2real::recording::read_csv;
    use crate::synth::{self, Settings};

    /// The lightly damped pendulum servo, clean (the exact model), logged exactly at the control
    /// ticks (no command to reconstruct) with velocity noise `qd_noise` and nothing else.
    fn pendulum_at_ticks(qd_noise: f64) -> (crate::model::Robot, Vec<Recording>) {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let path = root.join("fixtures/synth/pendulum_servo.xml");
        let robot = crate::model::load(&mut SourceMap::default(), &path, None).expect("pendulum");
        let joints = vec!["servo".to_string()];
        let s = Settings {
            episodes: 3,
            duration_s: 3.0,
            log_at_ticks: true,
            noise: 0.0,
            quant_bits: 0,
            qd_noise,
            drop: 0.0,
            seed: 5,
            ..Settings::default()
        };
        let ds = synth::generate(&robot, &joints, &[], &s, &|_, _| {}).expect("synth");
        // One directory per call: tests run in parallel, several with the same noise.
        static CALL: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let dir = std::env::temp_dir().join(format!(
            "modellint_floor_{}_{}_{}",
            qd_noise.to_bits(),
            std::process::id(),
            CALL.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
        ));
        let files = synth::write::write(&ds, &dir).expect("write");
        let recs: Vec<Recording> = files.iter().map(|f| read_csv(f).expect("read")).collect();
        let _ = std::fs::remove_dir_all(&dir);
        (robot, recs)
    }

    /// [`pendulum_at_ticks`]' replay floor [rad RMS] with the replay started at the first row.
    fn start_floor(qd_noise: f64) -> f64 {
        let (robot, recs) = pendulum_at_ticks(qd_noise);
        let opts = FitOptions { estimate_start: false, ..FitOptions::default() };
        let engine = Engine::new(&robot, &recs, &opts);
        let errs = engine.errors(&recs, &[]).expect("replay");
        let f = engine.floors(&recs, &[], &errs);
        assert_eq!(f.len(), 1);
        f[0].reconstruction.sqrt()
    }

    #[test]
    fn a_fit_stuck_on_a_bound_gets_a_grid_start() {
        let b = Bounds { lo: vec![0.3, 0.2], hi: vec![3.0, 5.0] };
        // Ended on kd's upper bound from (1, 1): a restart; started there, or interior: none.
        assert!(ends_on_bound(&[0.99, 5.0], &[1.0, 1.0], &b));
        assert!(ends_on_bound(&[0.3004, 1.2], &[1.0, 1.0], &b));
        assert!(!ends_on_bound(&[0.99, 5.0], &[1.0, 5.0], &b));
        assert!(!ends_on_bound(&[0.4, 2.0], &[1.0, 1.0], &b));
        // Two basins: a narrow one at (0.4, 2) and a wide shallow one towards the corner. The
        // grid is log-spaced on positive bounds and its best point is in the narrow basin.
        let obj = |x: &[f64]| {
            let narrow = ((x[0] / 0.4).ln().powi(2) + (x[1] / 2.0).ln().powi(2)).min(0.6);
            narrow + 0.3 * (1.0 - x[1] / 5.0)
        };
        let g = grid_best(&obj, &b).expect("finite");
        assert_eq!(g.len(), 2);
        assert!((g[0] / 0.4).ln().abs() < 0.2 && (g[1] / 2.0).ln().abs() < 0.3, "{g:?}");
        // Three parameters on a zero lower bound: 3 linear points each, at 20 / 50 / 80 % (27
        // evaluations, all inside the box).
        let lin = Bounds { lo: vec![0.0, 0.0, 0.0], hi: vec![1.0, 1.0, 1.0] };
        let count = std::cell::Cell::new(0usize);
        let _ = grid_best(
            &|x: &[f64]| {
                count.set(count.get() + 1);
                if x.iter().all(|v| (0.2..=0.8).contains(v)) { 1.0 } else { f64::NAN }
            },
            &lin,
        );
        assert_eq!(count.get(), 27);
        // Every point fails: no start.
        assert!(grid_best(&|_: &[f64]| f64::NAN, &b).is_none());
        // Two parameters on positive bounds: 5 points each at 10 … 90 % of the log range.
        let g = grid_best(&|x: &[f64]| x[0] + x[1], &b).expect("finite");
        assert!((g[0] - 0.3 * 10f64.powf(0.1)).abs() < 1e-12, "{g:?}");
    }

    /// Exact positions, exact commands, the exact model: the only error left is the first row's
    /// noisy velocity, ringing in the lightly damped servo. Started at the first row, the
    /// residual is that ringing; with the start estimated from the episode it must vanish (the
    /// true start explains the data exactly), and the floor's start part with it.
    #[test]
    fn an_estimated_start_removes_the_first_rows_noise() {
        let (robot, recs) = pendulum_at_ticks(0.04);
        let rms = |estimate_start: bool| {
            let opts = FitOptions { estimate_start, ..FitOptions::default() };
            let engine = Engine::new(&robot, &recs, &opts);
            let errs = engine.errors(&recs, &[]).expect("replay");
            let f = engine.floors(&recs, &[], &errs);
            (errs.rmse(), f[0].reconstruction.sqrt())
        };
        let (read, read_floor) = rms(false);
        let (est, est_floor) = rms(true);
        assert!(read > 2e-5, "the first row's velocity noise rings: {read}");
        assert!(est < read / 10.0, "estimated start: {est} vs first row {read}");
        assert!(est_floor < read_floor / 3.0, "floor {est_floor} vs {read_floor}");
    }

    /// A joint whose model can stick (here Coulomb friction, kept at zero so that the
    /// simulation is the nominal one) is left out of the start estimate: its residual is the
    /// one of the replay started at the first row, to the last bit; with a smooth effect kept
    /// (viscous damping, also zero) the start is still estimated.
    #[test]
    fn a_joint_that_can_stick_keeps_its_first_row() {
        let (robot, recs) = pendulum_at_ticks(0.04);
        let kept = |id: &str| Applied {
            effect: crate::fit::effects::by_id(id).expect("effect"),
            joints: vec!["servo".into()],
            params: vec![0.0],
        };
        let rms = |estimate_start: bool, applied: &[Applied]| {
            let opts = FitOptions { estimate_start, ..FitOptions::default() };
            Engine::new(&robot, &recs, &opts).errors(&recs, applied).expect("replay").rmse()
        };
        let read = rms(false, &[]);
        assert_eq!(rms(true, &[kept("coulomb_friction")]).to_bits(), read.to_bits());
        assert_eq!(rms(true, &[kept("backlash")]).to_bits(), read.to_bits());
        assert!(rms(true, &[kept("viscous_damping")]) < read / 10.0);
        // Once the friction is kept, the sensitivities are measured with it and the joint
        // takes part again; a model without it is now the one left alone.
        let opts = FitOptions { estimate_start: true, ..FitOptions::default() };
        let engine = Engine::new(&robot, &recs, &opts);
        engine.set_start_model(&[kept("coulomb_friction"), kept("viscous_damping")]);
        let with = engine.errors(&recs, &[kept("coulomb_friction")]).expect("replay").rmse();
        assert!(with < read / 10.0, "{with} vs {read}");
        let without = engine.errors(&recs, &[]).expect("replay").rmse();
        assert_eq!(without.to_bits(), read.to_bits());
    }

    /// The replay starts from the first row; a noisy first velocity makes a lightly damped servo
    /// ring, and the floor counts it: nothing with exact readings logged at the ticks, and an
    /// RMS that doubles with the velocity noise (the response is linear in the start error).
    /// A servo too stiff for its model's 5 ms step, recorded in nearly continuous time: MuJoCo
    /// stepped by hand at 5 ms / 16, one row at each 100 Hz tick with the tick's command and a
    /// small noise. The model's own replay misses it by its discretisation alone; the floor
    /// counts that part (about the replays' own difference) and the search stops there with
    /// nothing fitted. Recorded at the model's own steps, the floor has no timestep part.
    #[test]
    fn recordings_in_continuous_time_count_the_timestep_as_floor() {
        let xml = r#"<mujoco><option gravity="0 0 0" timestep="0.005" integrator="implicitfast"/>
  <worldbody><body><joint name="j" type="hinge" axis="0 1 0" damping="0.02"/>
<geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.02" mass="0.5"/></body></worldbody>
  <actuator><position joint="j" kp="20" kv="0.3"/></actuator></mujoco>"#;
        let (robot, dir) = crate::sim2real::replay::tests::robot_from_xml("disc-floor", xml);
        // `sub` physics steps per model step; rows at the ticks (10 ms = 2 model steps).
        let record = |sub: usize| -> Vec<Recording> {
            let mut m = robot.mj.clone();
            m.opt_mut().timestep = 0.005 / sub as f64;
            (0..4)
                .map(|e| {
                    let ticks = 300usize;
                    // A new level every 0.2–0.3 s, from a fixed sequence.
                    let cmd: Vec<f64> = (0..ticks)
                        .map(|k| 0.4 * ((k / (20 + 5 * e) + e) as f64 * 2.3).sin())
                        .collect();
                    let mut d = mujoco_rs::prelude::MjData::new(&m);
                    let (mut q, mut qd) = (Vec::new(), Vec::new());
                    for (k, c) in cmd.iter().enumerate() {
                        let noise = 2e-4 * pseudo_sign((e * 1000 + k) as u64);
                        q.push(d.qpos()[0] + noise);
                        qd.push(d.qvel()[0]);
                        d.ctrl_mut()[0] = *c;
                        for _ in 0..2 * sub {
                            d.step();
                        }
                    }
                    let mut j = crate::sim2real::recording::JointTrace::new("j", q);
                    j.q_cmd = Some(cmd);
                    j.qd = Some(qd);
                    Recording {
                        source: format!("ep{e}.csv").into(),
                        meta: Default::default(),
                        control_rate_hz: Some(100.0),
                        control_t0_s: Some(0.0),
                        t: (0..ticks).map(|k| k as f64 * 0.01).collect(),
                        joints: vec![j],
                        base: None,
                    }
                })
                .collect()
        };
        let opts = FitOptions { estimate_start: false, ..FitOptions::default() };
        let floor_of = |recs: &[Recording]| {
            let engine = Engine::new(&robot, recs, &opts);
            let errs = engine.errors(recs, &[]).expect("replay");
            engine.floors(recs, &[], &errs).remove(0)
        };
        // Continuous time: the residual is well above noise, the timestep part carries it.
        let cont = record(16);
        let f = floor_of(&cont);
        // (The replay at a quarter of the step is not continuous either: it takes about
        // two thirds of the residual.)
        assert!(f.ms > 5.0 * (f.white + f.reconstruction), "{f:?}");
        assert!(f.discretisation > 0.5 * f.ms && f.discretisation <= f.ms, "{f:?}");
        assert!(f.reached(opts.white_ratio), "{f:?}");
        let out = super::super::fit(&robot, &cont, &opts);
        assert!(out.selected.is_empty() && out.stopped_at_floor, "{:?}", out.selected);
        // The model's own steps: no timestep part, the floor is the noise.
        let own = record(1);
        let f = floor_of(&own);
        assert_eq!(f.discretisation, 0.0, "{f:?}");
        assert!(f.reached(opts.white_ratio), "{f:?}");
        std::fs::remove_dir_all(&dir).ok();
    }

    /// The timestep's part: the recordings count as finer than the model on a majority of
    /// the joints that moved (the finer replay closer by at least half the replays'
    /// difference, on joints whose residual that difference and the floor can explain); then
    /// every joint gets its replays' difference. Hand-made mean squares [coarse, fine, diff].
    #[test]
    fn the_timestep_part_needs_most_joints_closer_to_the_finer_replay() {
        let base = [1.0, 1.0, 1.0];
        // Two of three joints closer to the finer replay by its whole shift: all three count.
        let finer = [[3.0, 1.0, 2.0], [2.0, 1.5, 0.5], [1.5, 1.4, 0.5]];
        assert_eq!(discretisation_part(&finer, &base), vec![2.0, 0.5, 0.5]);
        // One of three (the others farther from the finer replay): none.
        let one = [[3.0, 1.0, 2.0], [1.0, 1.5, 0.5], [1.0, 1.5, 0.5]];
        assert_eq!(discretisation_part(&one, &base), vec![0.0; 3]);
        // Closer by less than half the shift: no vote.
        let little = [[3.0, 2.5, 2.0], [2.0, 1.9, 0.5], [1.5, 1.4, 0.5]];
        assert_eq!(discretisation_part(&little, &base), vec![0.0; 3]);
        // A residual far beyond the floor and the shift (a missing effect): no vote, however
        // much closer the finer replay happens to be.
        let big = [[40.0, 30.0, 2.0], [30.0, 25.0, 0.5], [1.5, 1.2, 0.5]];
        assert_eq!(discretisation_part(&big, &base), vec![0.0; 3]);
        // No joint moved between the replays.
        assert_eq!(discretisation_part(&[[1.0, 1.0, 0.0]], &[1.0]), vec![0.0]);
    }

    #[test]
    fn the_floor_counts_the_start_state_noise() {
        let exact = start_floor(0.0);
        assert!(exact < 1e-6, "{exact}");
        let (a, b) = (start_floor(0.02), start_floor(0.04));
        assert!(a > 2e-5, "{a}");
        assert!((b / a - 2.0).abs() < 0.3, "{a} {b}");
    }
}
