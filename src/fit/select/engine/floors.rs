//! The floors under a residual: what noise, command reconstruction, the start state and the
//! model's own timestep leave on a dataset however right the model is.

use crate::fit::effects::{Applied, model_with};
use crate::fit::rollout::SetSpec;
use crate::fit::stats::{residual_runs, white_floor};
use crate::sim2real::commands::{Fill, pseudo_sign};
use crate::sim2real::metrics::gap_mask;
use crate::sim2real::recording::Recording;
use crate::sim2real::replay::{Episode, ReplayOptions};

use super::super::{Errors, FitOptions, Floor};
use super::{Engine, set_key};

/// The start state's spread per fitted joint: position, and velocity where recorded.
type StartSpread = Vec<(f64, Option<f64>)>;

/// The discretisation decision counts a joint only when its residual mean square is within
/// this factor of its noise floor plus the two replays' difference [ratio of mean squares].
const EXPLAINABLE: f64 = 4.0;

impl Engine<'_> {
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
        // Counted once per set (two threads may measure one together; `moved` is new each time).
        let first = self.first_time(&(set_key(recs, applied) + &self.start_tag() + "#recon"));
        let mut alt = self.sibling(&moved, &alt);
        alt.quiet = !first;
        alt.set_start_model(&self.start_model.lock().unwrap_or_else(|e| e.into_inner()));
        let Some(b) = alt.errors(&moved, applied) else {
            return vec![0.0; self.joints.len()];
        };
        if first {
            self.sims.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        }
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

    /// Per fitted joint, the residual's mean square and its white floor ([`white_floor`], over
    /// the runs of samples between gaps), and the start state's spread (position, and velocity
    /// where recorded): what [`Engine::floors`] takes from the residual without a simulation.
    fn white_parts(&self, recs: &[Recording], errs: &Errors) -> (Vec<(f64, f64)>, StartSpread) {
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
        (white, start)
    }

    /// Per fitted joint: (name, mean square, floors) of the residual of `recs` simulated with
    /// `applied` as `errs`. The floor is the white floor ([`white_floor`], over the runs of
    /// samples between gaps) plus the command-reconstruction and start-state floor
    /// ([`Engine::reconstruction_floor`], of this model: one more simulation), both
    /// remembered per set of effects with their values. (Not per structure alone: whether the
    /// recordings count as finer than the model depends on how well the set fits them, and a
    /// re-fit of the values can change that decision.)
    pub fn floors(&self, recs: &[Recording], applied: &[Applied], errs: &Errors) -> Vec<Floor> {
        let (white, start) = self.white_parts(recs, errs);
        let key = set_key(recs, applied) + &self.start_tag();
        let known = {
            let m = self.recon.lock().unwrap_or_else(|e| e.into_inner());
            m.iter().find(|(k, _)| *k == key).map(|(_, r)| r.clone())
        };
        let recon = match known {
            Some(r) => r,
            None => {
                let r = self.reconstruction_floor(recs, applied, errs, &start);
                self.recon.lock().unwrap_or_else(|e| e.into_inner()).push((key, r.clone()));
                r
            }
        };
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
    /// Each dataset is replayed with `applied` at the model's timestep ("coarse") and, by
    /// extrapolation from one or two finer replays, in continuous time ("fine",
    /// [`Engine::measure_discretisation`]). The recordings count as finer than the model when
    /// on more than half of the joints the fine replay comes closer to them at all
    /// (`ms(coarse) − ms(fine) > 0`), counting only joints whose residual noise plus the two
    /// replays' difference can explain (`ms(coarse) ≤ 4 (base + ms(coarse − fine))`, `base`:
    /// the joint's white and reconstruction floor): a large missing effect makes either replay
    /// closer by chance. No share of the difference is asked of a joint: recordings made at the
    /// model's own step are farther from the fine replay on every joint (the sign alone
    /// separates them), and an effect fitted to the recordings absorbs part of the timestep's
    /// error and takes the same part off how much closer the fine replay comes, so a share
    /// would vote the part out by how well the effects fit rather than by which time the
    /// recordings move in; the majority of joints is what guards against chance. Then
    /// every joint's part is `ms(coarse − fine)`, a property of the model and the motion that an
    /// effect fitted to absorb some of the discretisation does not shrink; else zero.
    /// Recordings simulated at the model's own step (every synth) are farther from the fine
    /// replay: zero. Once per set of effects; a set that cannot be measured (actuators with a
    /// `delay`: their history is sized for the timestep) takes the dataset's latest
    /// measurement, or zero.
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
        let d = match self.measure_discretisation(recs, applied, base) {
            Some(d) => d,
            None => memo(&latest).unwrap_or_else(|| vec![0.0; self.joints.len()]),
        };
        let mut m = self.disc.lock().unwrap_or_else(|e| e.into_inner());
        m.retain(|(x, _)| *x != latest);
        m.push((key, d.clone()));
        m.push((latest, d.clone()));
        d
    }

    /// Per fitted joint, the model's own timestep's part of the residual mean square with
    /// `applied` ([`discretisation_part`] of the replay at the model's timestep and of its
    /// continuous-time limit; `base`: the joints' white and reconstruction floors); `None` when
    /// it cannot be measured.
    ///
    /// The continuous-time limit is measured, not assumed: the dataset is replayed at dt, dt/r
    /// and dt/r² (r: [`SearchPolicy::discretisation_refine`]), and the two refinements' RMS
    /// changes give the integrator's observed convergence ratio ρ = ‖q(dt/r) − q(dt/r²)‖ /
    /// ‖q(dt) − q(dt/r)‖ (r^−p for an order-p method), with which the finest replay is
    /// extrapolated (Richardson): q∞ = q(dt/r²) + ρ / (1 − ρ) · (q(dt/r²) − q(dt/r)). ρ is
    /// taken at most 1/r (first order: MuJoCo has no integrator of lower order; a larger
    /// observed ratio is not converging and is not extrapolated further). The finest replay
    /// alone holds 1/r² of a first-order method's error: on a lightly damped servo at 1 ms
    /// that left 3/8 of the discretisation outside the floor, and the search fitted it as
    /// an action delay.
    ///
    /// The dt/r² replay only sets how far beyond q(dt/r) the limit lies: for any ratio ρ ≤ 1/r
    /// the extrapolation is q∞ = q(dt/r) + t · (q(dt/r) − q(dt)) with t = ρ / (1 − ρ) in
    /// [0, 1/(r − 1)]. When no joint's vote could turn on t ([`zero_at_every_order`]: the part
    /// is zero for every t there), the part is zero without it (one replay of the dataset
    /// saved; on chainsim's round-0 bases, whose missing effect leaves no joint explainable by
    /// the timestep, every time).
    ///
    /// [`SearchPolicy::discretisation_refine`]: super::super::policy::SearchPolicy::discretisation_refine
    fn measure_discretisation(
        &self,
        recs: &[Recording],
        applied: &[Applied],
        base: &[f64],
    ) -> Option<Vec<f64>> {
        let m = model_with(self.robot, applied);
        let dt = m.opt().timestep;
        let r = self.opts.policy.discretisation_refine.max(2);
        if !(dt > 0.0) || recs.is_empty() || m.actuator_history().iter().any(|h| h[0] > 0) {
            return None;
        }
        // One batch: dt / r, and the model's own timestep unless the search has that replay
        // already (without a start estimate, it is the replay of `errors`); dt / r² after it,
        // when the decision needs it.
        let known = if self.estimates_start() { None } else { self.errors(recs, applied) };
        let mut sets = vec![SetSpec { applied, refine: r as u32 }];
        if known.is_none() {
            sets.insert(0, SetSpec::of(applied));
        }
        // Counted once per set measured (two threads may measure one together).
        let first = self.first_time(&(set_key(recs, applied) + &self.start_tag() + "#disc"));
        let mut all = self.service(first).run(&sets, recs, &self.opts.replay).into_iter();
        let mut whole = || -> Option<Vec<Episode>> { all.next()?.into_iter().collect() };
        let coarse = match known {
            Some(e) => e.eps,
            None => whole()?,
        };
        let half = whole()?;
        if first {
            self.sims.fetch_add(sets.len() - 1 + r, std::sync::atomic::Ordering::Relaxed);
        }
        // The scored samples of a joint where every replay of `reps` is finite: (recording
        // index, joint index, sample index).
        let samples = |name: &String, reps: &[&Vec<Episode>]| -> Vec<(usize, usize, usize)> {
            let mut v = Vec::new();
            for (e, rec) in recs.iter().enumerate() {
                let Some(k) = rec.joints.iter().position(|j| &j.name == name) else { continue };
                let scored = gap_mask(&rec.t, self.opts.gap_mask_s);
                // The first sample is the start state in every replay: not counted.
                for (i, &s) in scored.iter().enumerate().skip(1) {
                    let q = rec.joints[k].q.get(i).copied().unwrap_or(f64::NAN);
                    let ok = reps.iter().all(|eps| {
                        eps[e].q_sim.get(k).and_then(|v| v.get(i)).is_some_and(|x| x.is_finite())
                    });
                    if s && q.is_finite() && ok {
                        v.push((e, k, i));
                    }
                }
            }
            v
        };
        // Per joint, on the replays at dt and dt / r: [ms(coarse − real), ms(half − real),
        // mean((real − half)(half − coarse)), ms(half − coarse)].
        let bracket: Vec<[f64; 4]> = self
            .joints
            .iter()
            .map(|name| {
                let idx = samples(name, &[&coarse, &half]);
                let mut s = [0.0; 4];
                for &(e, k, i) in &idx {
                    let q = recs[e].joints[k].q[i];
                    let (a, b) = (coarse[e].q_sim[k][i], half[e].q_sim[k][i]);
                    s[0] += (q - a) * (q - a);
                    s[1] += (q - b) * (q - b);
                    s[2] += (q - b) * (b - a);
                    s[3] += (b - a) * (b - a);
                }
                let n = idx.len().max(1) as f64;
                s.map(|x| x / n)
            })
            .collect();
        if zero_at_every_order(&bracket, base, r) {
            return Some(vec![0.0; self.joints.len()]);
        }
        let fine_set = [SetSpec { applied, refine: (r * r) as u32 }];
        let fine: Vec<Episode> = self
            .service(first)
            .run(&fine_set, recs, &self.opts.replay)
            .pop()?
            .into_iter()
            .collect::<Option<_>>()?;
        if first {
            self.sims.fetch_add(r * r, std::sync::atomic::Ordering::Relaxed);
        }
        let per_joint: Vec<Vec<(usize, usize, usize)>> =
            self.joints.iter().map(|n| samples(n, &[&coarse, &half, &fine])).collect();
        // The observed convergence ratio over every joint.
        let (mut d1, mut d2) = (0.0, 0.0);
        for &(e, k, i) in per_joint.iter().flatten() {
            let (a, b, c) = (coarse[e].q_sim[k][i], half[e].q_sim[k][i], fine[e].q_sim[k][i]);
            d1 += (a - b) * (a - b);
            d2 += (b - c) * (b - c);
        }
        let rho = if d1 > 0.0 { (d2 / d1).sqrt().min(1.0 / r as f64) } else { 0.0 };
        let ext = rho / (1.0 - rho);
        let sums: Vec<[f64; 3]> = per_joint
            .iter()
            .map(|idx| {
                let (mut sc, mut sf, mut scf) = (0.0, 0.0, 0.0);
                for &(e, k, i) in idx {
                    let q = recs[e].joints[k].q[i];
                    let a = coarse[e].q_sim[k][i];
                    let (b, c) = (half[e].q_sim[k][i], fine[e].q_sim[k][i]);
                    let inf = c + ext * (c - b);
                    sc += (q - a) * (q - a);
                    sf += (q - inf) * (q - inf);
                    scf += (a - inf) * (a - inf);
                }
                let n = idx.len().max(1) as f64;
                [sc / n, sf / n, scf / n]
            })
            .collect();
        Some(discretisation_part(&sums, base))
    }

    /// `true` when every fitted joint's residual of `recs` simulated with `applied` as `errs` is within
    /// `white_ratio` of its floor ([`Engine::floors`]): what is left is noise and timing.
    ///
    /// The measured parts of a floor (reconstruction, discretisation) are never negative, so a
    /// residual within `white_ratio` of its white floor alone on every joint is at the floor
    /// whatever they are: then they are not measured (three replays of `recs` saved; the same
    /// answer).
    pub fn at_floor(&self, recs: &[Recording], applied: &[Applied], errs: &Errors) -> bool {
        let ratio = self.opts.policy.white_ratio;
        let (white, _) = self.white_parts(recs, errs);
        if white.iter().all(|&(ms, w)| ms <= ratio * w) {
            return true;
        }
        self.floors(recs, applied, errs).iter().all(|f| f.reached(ratio))
    }
}

/// [`Engine::discretisation_floor`]'s decision on the per-joint mean squares `sums` (coarse −
/// real, fine − real, coarse − fine) and the joints' white + reconstruction floors `base`.
pub(super) fn discretisation_part(sums: &[[f64; 3]], base: &[f64]) -> Vec<f64> {
    let moved = sums.iter().filter(|s| s[2] > 0.0).count();
    let votes = sums
        .iter()
        .zip(base)
        .filter(|([c, f, d], b)| *d > 0.0 && *c <= EXPLAINABLE * (*b + d) && c > f)
        .count();
    if moved > 0 && 2 * votes > moved {
        sums.iter().map(|s| s[2]).collect()
    } else {
        vec![0.0; sums.len()]
    }
}

/// Whether [`discretisation_part`] is zero whatever the replay at dt / r² shows, for an
/// integrator of order one or more refined by `r`: then the continuous-time limit is
/// q∞ = q(dt/r) + t · (q(dt/r) − q(dt)) for some t in [0, 1/(r − 1)], and `bracket` gives,
/// per joint, [c, f₀, x, d] = [ms(q(dt) − real), ms(q(dt/r) − real), mean((real − q(dt/r)) ·
/// (q(dt/r) − q(dt))), ms(q(dt/r) − q(dt))], so that at t the fine replay's mean square is
/// f(t) = f₀ − 2 t x + t² d and the replays' difference (1 + t)² d. A joint can vote only when
/// some t makes it explainable (c ≤ 4 (base + (1 + t)² d), from some t on) and closer to the
/// fine replay (f(t) ≤ c, least at t = x / d); the part is zero when no joint moved or those
/// that can vote are at most half of the joints that moved.
pub(super) fn zero_at_every_order(bracket: &[[f64; 4]], base: &[f64], r: usize) -> bool {
    let top = 1.0 / (r.max(2) as f64 - 1.0);
    let moved = bracket.iter().filter(|s| s[3] > 0.0).count();
    let can_vote = bracket
        .iter()
        .zip(base)
        .filter(|([c, f0, x, d], b)| {
            if !(*d > 0.0) {
                return false;
            }
            // The first t at which the joint is explainable.
            let need = c / EXPLAINABLE - *b;
            let from = if need > 0.0 { ((need / d).sqrt() - 1.0).max(0.0) } else { 0.0 };
            if from > top {
                return false;
            }
            let t = (x / d).clamp(from, top);
            f0 - 2.0 * t * x + t * t * d <= *c
        })
        .count();
    moved == 0 || 2 * can_vote <= moved
}
