//! The fit engine: simulates a dataset with a set of effects and scores it, fits one candidate's
//! parameters, and gives the linearised standard errors of a fit.

use rayon::prelude::*;

use crate::fit::effects::{Applied, Effect};
use crate::fit::rollout::{RolloutStats, Rollouts, SetSpec};
use crate::model::Robot;
use crate::sim2real::recording::Recording;
use crate::sim2real::replay::{BaseMode, Episode};

use super::policy::Phase;
use super::start::{self, StartSens};

mod fitting;
mod floors;
#[cfg(test)]
mod tests;
mod uncertainty;
mod windows;
use super::{Errors, FitOptions, ProgressInfo};
pub use uncertainty::Jacobian;

/// The fit engine's view of a robot and dataset.
pub struct Engine<'a> {
    pub robot: &'a Robot,
    pub opts: &'a FitOptions,
    /// Joints scored by the objective.
    pub joints: Vec<String>,
    /// Every rollout of the search goes through this service (shared with the floor's
    /// alternative replay): it runs them in parallel and counts them.
    rollouts: std::sync::Arc<Rollouts<'a>>,
    /// Replays of a simulation already counted run here, on a service whose counts nobody
    /// reads: see [`Engine::first_time`].
    reruns: Rollouts<'a>,
    /// Every simulation counted so far, by its memo key ([`Engine::first_time`]).
    counted: std::sync::Mutex<std::collections::HashSet<String>>,
    /// Counts nothing: a sibling re-measuring what its parent counted before.
    quiet: bool,
    /// The start-state measurements counted so far, by [`start::key`] and start model (shared
    /// with the floor's alternative replay, like the memo of [`Engine::starts`]).
    starts_counted: std::sync::Arc<std::sync::Mutex<std::collections::HashSet<String>>>,
    /// Dataset simulations the search asked for (each replays every episode of a set once;
    /// the memo answers some without a rollout).
    sims: std::sync::atomic::AtomicUsize,
    /// Results of [`Engine::fit_budget`] by [`fit_key`]: the simplify pass re-fits the same
    /// effect on the same base the greedy rounds already fitted (swapping the only kept effect
    /// for another is the round-1 fit of that other), and a fit is deterministic.
    fits: std::sync::Mutex<std::collections::HashMap<String, (Vec<f64>, f64)>>,
    /// The last [`RECENT`] simulations by [`set_key`]: the search scores the set a fit ended on
    /// right after the fit, and the same base set for each candidate.
    recent: std::sync::Mutex<std::collections::VecDeque<(String, Option<Errors>)>>,
    /// Simulations held for the whole search ([`Engine::errors_held`]): each round's base
    /// replays, which the simplify pass asks for again (dropping the only kept effect is the
    /// first round's base) long after [`RECENT`] others.
    held: std::sync::Mutex<std::collections::HashMap<String, Option<Errors>>>,
    /// The training RMSE of every simulation a fit's objective asked for, by [`set_key`]: the
    /// screen's coarse fit and the full fit that follows it start alike (the same grid, the same
    /// first simplex), so the full fit re-uses the coarse one's rollouts.
    scores: std::sync::Mutex<std::collections::HashMap<String, f64>>,
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
    /// The reconstruction floor ([`Engine::reconstruction_floor`]) by [`set_key`].
    recon: std::sync::Mutex<Vec<(String, Vec<f64>)>>,
    /// Where the search last reported it was ([`Engine::report`]).
    place: std::sync::Mutex<Option<ProgressInfo>>,
    /// The screen's data sets by the training set and effects they were chosen for
    /// ([`Engine::screen_set`]). Held for the whole search: the memo keys a dataset by its
    /// address, which must not be re-used by another set.
    screens: std::sync::Mutex<std::collections::HashMap<String, std::sync::Arc<Vec<Recording>>>>,
    /// Rollouts and recording seconds replayed, booked to each phase
    /// ([`Engine::rollouts_by_phase`]).
    by_phase: std::sync::Mutex<std::collections::BTreeMap<&'static str, (usize, f64)>>,
    /// The same, booked to the greedy round that ran them and the phase
    /// ([`Engine::rollouts_by_round_phase`]).
    by_round: std::sync::Mutex<ByRoundPhase>,
    /// Per candidate (effect and group), whether round 0's coarse fit confirmed its linear
    /// model ([`Engine::note_trust`]).
    trust: std::sync::Mutex<std::collections::HashMap<String, bool>>,
    /// Recording seconds of the counted simulations by the effects they ran with (their
    /// [`effects_key`], the dataset left out): [`Engine::spent_with`].
    spent: std::sync::Mutex<std::collections::HashMap<String, u64>>,
    /// The probes the screen did not replay ([`Engine::note_unprobed`]).
    unprobed: std::sync::Mutex<Vec<super::Unprobed>>,
    /// Jacobians of a candidate's residual made outside its fits, by dataset, base and
    /// candidate ([`Engine::hold_jacobian`]).
    jacobians: std::sync::Mutex<std::collections::HashMap<String, crate::fit::optim::HeldJacobian>>,
}

/// Rollouts and recording seconds by round ([`round_key`]) and phase name.
pub type ByRoundPhase = std::collections::BTreeMap<(String, &'static str), (usize, f64)>;

type StartMemo = std::collections::HashMap<String, Option<std::sync::Arc<StartSens>>>;

/// The key a phase's replays are booked to by round: the greedy round's number (`"0"`, `"1"`, …)
/// for the phases a round runs (its diagnosis and floors, screen, full fits, pairs), `"end"`
/// for what runs after the rounds (polish, simplify, reshoot, standard errors, the final floors;
/// a round re-opened by simplify books to its own number).
pub(in crate::fit) fn round_key(phase: Phase, round: usize) -> String {
    match phase {
        Phase::Diagnose
        | Phase::Screen
        | Phase::Add
        | Phase::LeadFit
        | Phase::Judge
        | Phase::EarlyPair
        | Phase::Refine
        | Phase::RoundErrors
        | Phase::Reach
        | Phase::Pair
        | Phase::JointPair
        | Phase::HeldoutLinear
        | Phase::Told => round.to_string(),
        _ => END_KEY.to_string(),
    }
}

/// [`round_key`] of what runs after the greedy rounds.
pub(in crate::fit) const END_KEY: &str = "end";

/// How many recent simulations [`Engine::errors`] keeps.
const RECENT: usize = 16;

/// The identity of one simulation: the dataset (by address: the search holds its sets for its
/// whole run) and the effects with their parameters' exact bits.
pub(in crate::fit::select) fn set_key(recs: &[Recording], applied: &[Applied]) -> String {
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

/// The parameters at which `effect` on `group` changes nothing on a model whose compiled form
/// is `m0` (the base's): its start ([`Effect::initial`]) when that is the same on every joint
/// of the group and the effect is neutral on each of its joints ([`Effect::neutral_at`]).
pub(in crate::fit::select) fn neutral_params(
    robot: &Robot,
    m0: &mujoco_rs::prelude::MjModel,
    (effect, group): (&dyn Effect, &[String]),
) -> Option<Vec<f64>> {
    let mut starts = group.iter().map(|j| {
        let t = crate::fit::effects::JointTarget::of(robot, j)?;
        effect.neutral_at(m0, &t).then(|| effect.initial(m0, &t))
    });
    let first = starts.next()??;
    starts.all(|s| s.as_ref() == Some(&first)).then_some(first)
}

/// `base` with `effect` on `group` at `p` — or `base` itself when `p` is the candidate's
/// [`neutral_params`]: the same replay, which the search holds already (a fit's first point
/// costs no simulation).
pub(in crate::fit::select) fn with_candidate(
    base: &[Applied],
    (effect, group): (&'static dyn Effect, &[String]),
    p: Vec<f64>,
    neutral: Option<&[f64]>,
) -> Vec<Applied> {
    let mut a = base.to_vec();
    if neutral != Some(p.as_slice()) {
        a.push(Applied { effect, joints: group.to_vec(), params: p });
    }
    a
}

/// The structure of a simulation, without the values: the dataset (by address) and the
/// effects with their joints. The floors' measured parts are remembered by it.
pub(in crate::fit::select) fn shape_key(recs: &[Recording], applied: &[Applied]) -> String {
    let mut k = format!("{:p}/{}", recs.as_ptr(), recs.len());
    for a in applied {
        k += &format!("|{}@{}", a.effect.id(), a.joints.join(","));
    }
    k
}

/// The effects of a simulation with their joints, without the values or the dataset.
fn effects_key(applied: &[Applied]) -> String {
    applied.iter().map(|a| format!("|{}@{}", a.effect.id(), a.joints.join(","))).collect()
}

/// The memo key of a fit: the training set (by address: the search holds one for its whole
/// run), the base effects with their parameters' exact bits, the effect, its joints and budget.
pub(super) fn fit_key(
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
            rollouts: std::sync::Arc::new(Rollouts::new(robot).with_cancel(opts.cancel.clone())),
            reruns: Rollouts::new(robot).with_cancel(opts.cancel.clone()),
            counted: Default::default(),
            quiet: false,
            starts_counted: Default::default(),
            sims: std::sync::atomic::AtomicUsize::new(0),
            fits: Default::default(),
            recent: Default::default(),
            held: Default::default(),
            scores: Default::default(),
            starts: Default::default(),
            start_model: Default::default(),
            disc: Default::default(),
            recon: Default::default(),
            place: Default::default(),
            by_phase: Default::default(),
            by_round: Default::default(),
            trust: Default::default(),
            spent: Default::default(),
            unprobed: Default::default(),
            jacobians: Default::default(),
            screens: Default::default(),
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

    /// Reports progress through `opts.progress`, if any, and remembers where the search is:
    /// every dataset simulation after it reports the same place with its counts updated
    /// ([`Engine::heartbeat`]).
    pub fn report(&self, round: usize, phase: Phase, candidate: Option<(usize, usize, String)>) {
        let info = ProgressInfo {
            round,
            phase,
            candidate,
            simulations: self.sims.load(std::sync::atomic::Ordering::Relaxed),
            rollouts: self.rollouts.stats().rollouts,
        };
        self.account();
        if let Some(p) = &self.opts.progress {
            (p.0)(&info);
        }
        *self.place.lock().unwrap_or_else(|e| e.into_inner()) = Some(info);
    }

    /// Books the rollouts (and recording seconds) run since the last report to the phase
    /// reported then, and to its round ([`round_key`]).
    fn account(&self) {
        let now = self.rollouts.stats();
        let place = self
            .place
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .as_ref()
            .map(|p| (p.phase, p.round));
        let mut b = self.by_phase.lock().unwrap_or_else(|e| e.into_inner());
        let done = b.values().map(|v| v.0).sum::<usize>();
        let done_s = b.values().map(|v| v.1).sum::<f64>();
        if let Some((ph, round)) = place
            && now.rollouts > done
        {
            let (n, s) = (now.rollouts - done, (now.simulated_s - done_s).max(0.0));
            let e = b.entry(ph.name()).or_default();
            e.0 += n;
            e.1 += s;
            let mut r = self.by_round.lock().unwrap_or_else(|e| e.into_inner());
            let e = r.entry((round_key(ph, round), ph.name())).or_default();
            e.0 += n;
            e.1 += s;
        }
    }

    /// Rollouts and recording seconds replayed, by the phase of the search that ran them.
    pub fn rollouts_by_phase(&self) -> std::collections::BTreeMap<&'static str, (usize, f64)> {
        self.account();
        self.by_phase.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }

    /// Rollouts and recording seconds replayed, by the greedy round that ran them ([`round_key`]).
    pub fn rollouts_by_round(&self) -> std::collections::BTreeMap<String, (usize, f64)> {
        let mut m = std::collections::BTreeMap::<String, (usize, f64)>::new();
        for ((round, _), (n, s)) in self.rollouts_by_round_phase() {
            let e = m.entry(round).or_default();
            e.0 += n;
            e.1 += s;
        }
        m
    }

    /// Rollouts and recording seconds replayed, by round ([`round_key`]) and phase.
    pub fn rollouts_by_round_phase(&self) -> ByRoundPhase {
        self.account();
        self.by_round.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }

    /// Records whether the linear model of `effect` on `group` was `trusted` (its coarse fit's
    /// gain agreed with the one it predicted, [`SearchPolicy::linear_trust`]); the first record
    /// of a candidate stands.
    ///
    /// [`SearchPolicy::linear_trust`]: super::policy::SearchPolicy::linear_trust
    pub(in crate::fit::select) fn note_trust(
        &self,
        (effect, group): (&dyn Effect, &[String]),
        trusted: bool,
    ) {
        let key = format!("{}@{}", effect.id(), group.join(","));
        self.trust.lock().unwrap_or_else(|e| e.into_inner()).entry(key).or_insert(trusted);
    }

    /// Recording seconds of the simulations counted so far (as the rollout counts are,
    /// [`Engine::first_time`]) that ran `base` with `effect` on `group` added, at any values,
    /// on any dataset: what that candidate cost on that base.
    pub(in crate::fit::select) fn spent_with(
        &self,
        base: &[Applied],
        (effect, group): (&'static dyn Effect, &[String]),
    ) -> f64 {
        let mut set = base.to_vec();
        set.push(Applied { effect, joints: group.to_vec(), params: vec![] });
        let spent = self.spent.lock().unwrap_or_else(|e| e.into_inner());
        spent.get(&effects_key(&set)).map_or(0.0, |&us| us as f64 * 1e-6)
    }

    /// Notes a probe the screen did not replay, at the place last reported ([`Engine::report`]).
    pub(in crate::fit::select) fn note_unprobed(&self, mut u: super::Unprobed) {
        if let Some(p) = self.place.lock().unwrap_or_else(|e| e.into_inner()).as_ref() {
            (u.round, u.phase) = (round_key(p.phase, p.round), p.phase.name());
        }
        self.unprobed.lock().unwrap_or_else(|e| e.into_inner()).push(u);
    }

    /// The probes noted by [`Engine::note_unprobed`], in (round, effect, joint, parameter,
    /// value) order (the screen notes them from parallel batches).
    pub(in crate::fit::select) fn unprobed(&self) -> Vec<super::Unprobed> {
        let mut v = self.unprobed.lock().unwrap_or_else(|e| e.into_inner()).clone();
        let key = |u: &super::Unprobed| (u.round.clone(), u.effect, u.joint.clone(), u.param);
        v.sort_by(|a, b| key(a).cmp(&key(b)).then(a.value.total_cmp(&b.value)));
        v
    }

    /// What [`Engine::note_trust`] recorded for `effect` on `group`, if anything.
    pub(in crate::fit::select) fn trusted(
        &self,
        (effect, group): (&dyn Effect, &[String]),
    ) -> Option<bool> {
        let key = format!("{}@{}", effect.id(), group.join(","));
        self.trust.lock().unwrap_or_else(|e| e.into_inner()).get(&key).copied()
    }

    /// Reports the place of the last [`Engine::report`] again with the counts of now (the
    /// display decides how often to draw).
    fn heartbeat(&self) {
        let Some(p) = &self.opts.progress else { return };
        let place = self.place.lock().unwrap_or_else(|e| e.into_inner()).clone();
        if let Some(mut info) = place {
            info.simulations = self.sims.load(std::sync::atomic::Ordering::Relaxed);
            info.rollouts = self.rollouts.stats().rollouts;
            (p.0)(&info);
        }
    }

    /// Dataset simulations asked for so far.
    pub fn simulations(&self) -> usize {
        self.sims.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// What the rollout service has run so far.
    pub fn rollout_stats(&self) -> RolloutStats {
        self.rollouts.stats()
    }

    /// An engine on other recordings or replay options that shares this one's rollout
    /// service and start-state memo (the floor's alternative replay).
    pub(in crate::fit::select) fn sibling(&self, recs: &[Recording], opts: &'a FitOptions) -> Self {
        let mut e = Engine::new(self.robot, recs, opts);
        e.rollouts = self.rollouts.clone();
        e.starts = self.starts.clone();
        e.starts_counted = self.starts_counted.clone();
        e
    }

    /// The screen's data for `train` simulated with `applied` (made by `make` on first use, then
    /// the same set: its simulations are remembered).
    pub(in crate::fit::select) fn screen_set(
        &self,
        train: &[Recording],
        applied: &[Applied],
        make: impl FnOnce() -> Vec<Recording>,
    ) -> std::sync::Arc<Vec<Recording>> {
        self.held_set("", train, applied, make)
    }

    /// The probes' data ([`SearchPolicy::probe_seconds`]) for the screen's data `screen`
    /// simulated with `applied`, held like [`Engine::screen_set`].
    ///
    /// [`SearchPolicy::probe_seconds`]: super::policy::SearchPolicy::probe_seconds
    pub(in crate::fit::select) fn probe_set(
        &self,
        screen: &[Recording],
        applied: &[Applied],
        make: impl FnOnce() -> Vec<Recording>,
    ) -> std::sync::Arc<Vec<Recording>> {
        self.held_set("probe:", screen, applied, make)
    }

    /// The probes' data of [`Engine::probe_set`] when a screen made it already; `None` else.
    pub(in crate::fit::select) fn probe_set_held(
        &self,
        screen: &[Recording],
        applied: &[Applied],
    ) -> Option<std::sync::Arc<Vec<Recording>>> {
        let key = "probe:".to_string() + &set_key(screen, applied) + &self.start_tag();
        self.screens.lock().ok().and_then(|m| m.get(&key).cloned())
    }

    /// A data set derived from `train` for `applied`, made on first use and held for the whole
    /// search (the memo keys a dataset by its address); `kind` tells the derivations apart.
    fn held_set(
        &self,
        kind: &str,
        train: &[Recording],
        applied: &[Applied],
        make: impl FnOnce() -> Vec<Recording>,
    ) -> std::sync::Arc<Vec<Recording>> {
        let key = kind.to_string() + &set_key(train, applied) + &self.start_tag();
        if let Some(s) = self.screens.lock().ok().and_then(|m| m.get(&key).cloned()) {
            return s;
        }
        let s = std::sync::Arc::new(make());
        // Two threads may make the set at once: the first one kept is everyone's (one address
        // for the memo's keys), the other is dropped unused by anyone after this call.
        match self.screens.lock() {
            Ok(mut m) => m.entry(key).or_insert(s).clone(),
            Err(_) => s,
        }
    }

    /// Simulates `recs` with `applied`; `None` when an episode diverged or failed.
    pub fn errors(&self, recs: &[Recording], applied: &[Applied]) -> Option<Errors> {
        self.errors_at(recs, applied, 1)
    }

    /// [`Engine::errors`], held for the whole search (a round's base replays).
    pub fn errors_held(&self, recs: &[Recording], applied: &[Applied]) -> Option<Errors> {
        let e = self.errors(recs, applied);
        let key = set_key(recs, applied) + &self.start_tag();
        if let Ok(mut h) = self.held.lock() {
            h.insert(key, e.clone());
        }
        e
    }

    /// [`Engine::errors`] of a simulation this search has counted already (a replay of it, if
    /// the memo let it go, is not counted again); `None`, without a replay, for one never asked.
    pub(in crate::fit::select) fn errors_counted(
        &self,
        recs: &[Recording],
        applied: &[Applied],
    ) -> Option<Errors> {
        let key = set_key(recs, applied) + &self.start_tag();
        let known = self.counted.lock().unwrap_or_else(|e| e.into_inner()).contains(&key);
        if known { self.errors(recs, applied) } else { None }
    }

    /// [`Engine::errors`] with the model's timestep divided by `refine`.
    pub fn errors_at(
        &self,
        recs: &[Recording],
        applied: &[Applied],
        refine: u32,
    ) -> Option<Errors> {
        let mut key = set_key(recs, applied) + &self.start_tag();
        if refine > 1 {
            key += &format!("#dt/{refine}");
        }
        if let Some(e) = self.held.lock().ok().and_then(|h| h.get(&key).cloned()) {
            return e;
        }
        if let Some(e) = self
            .recent
            .lock()
            .ok()
            .and_then(|r| r.iter().find(|(k, _)| *k == key).map(|(_, e)| e.clone()))
        {
            return e;
        }
        let first = self.first_time(&key);
        let e = self.simulate(recs, applied, refine, first);
        if let Ok(mut r) = self.recent.lock() {
            if r.len() >= RECENT {
                r.pop_front();
            }
            r.push_back((key, e.clone()));
        }
        e
    }

    /// Whether the simulation of memo key `key` is asked for the first time in this search
    /// (and marks it asked). Only a first simulation is counted (rollouts, recording seconds,
    /// simulations): a memo misses a simulation it saw before when two candidates fitted in
    /// parallel reach it together, or when [`RECENT`] others evicted it, and both depend on the
    /// threads' timing. Counting distinct simulations makes the counts a function of the
    /// recordings and the search alone, the same on every run (a re-replay's cost is left out).
    fn first_time(&self, key: &str) -> bool {
        !self.quiet
            && self.counted.lock().unwrap_or_else(|e| e.into_inner()).insert(key.to_string())
    }

    /// The rollout service that runs (and counts) a simulation asked for the first time
    /// (`first`), or runs uncounted a replay of one counted before.
    pub(in crate::fit::select) fn service(&self, first: bool) -> &Rollouts<'a> {
        if first { &self.rollouts } else { &self.reruns }
    }

    /// The RMSE of `recs` simulated with `applied` (infinite when it diverged), remembered for
    /// the whole search.
    pub(in crate::fit::select) fn score(&self, recs: &[Recording], applied: &[Applied]) -> f64 {
        let key = set_key(recs, applied) + &self.start_tag();
        if let Some(f) = self.scores.lock().ok().and_then(|m| m.get(&key).copied()) {
            return f;
        }
        let f = self.errors(recs, applied).map_or(f64::INFINITY, |e| e.rmse());
        if let Ok(mut m) = self.scores.lock() {
            m.insert(key, f);
        }
        f
    }

    fn simulate(
        &self,
        recs: &[Recording],
        applied: &[Applied],
        refine: u32,
        first: bool,
    ) -> Option<Errors> {
        if first {
            self.sims.fetch_add(refine.max(1) as usize, std::sync::atomic::Ordering::Relaxed);
            // (In whole microseconds, as the rollout service counts them: a sum that does not
            // depend on the order in which parallel fits reach their simulations.)
            let us: u64 = recs
                .iter()
                .map(|r| match (r.t.first(), r.t.last()) {
                    (Some(a), Some(b)) if b > a => ((b - a) * 1e6).round() as u64,
                    _ => 0,
                })
                .sum();
            let mut spent = self.spent.lock().unwrap_or_else(|e| e.into_inner());
            *spent.entry(effects_key(applied)).or_default() += us;
        }
        let set = SetSpec { applied, refine: refine.max(1) };
        let eps = self.service(first).run_one(set, recs, &self.opts.replay);
        self.heartbeat();
        let mut eps: Vec<Episode> = eps?;
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
        self.errors_of(recs, eps)
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
        // Each missing one, and whether its measurement is the first (counted; another thread
        // may be measuring it too).
        let missing: Vec<(usize, bool)> = {
            let memo = self.starts.lock().unwrap_or_else(|e| e.into_inner());
            let mut counted = self.starts_counted.lock().unwrap_or_else(|e| e.into_inner());
            let mut seen = std::collections::HashSet::new();
            (0..recs.len())
                .filter(|&i| !memo.contains_key(&keys[i]) && seen.insert(&keys[i]))
                .map(|i| (i, !self.quiet && counted.insert(keys[i].clone())))
                .collect()
        };
        let measured: Vec<Option<std::sync::Arc<StartSens>>> = missing
            .par_iter()
            .map(|&(i, first)| {
                StartSens::measure(
                    self.service(first),
                    &recs[i],
                    &self.opts.replay,
                    self.opts.gap_mask_s,
                    &self.joints,
                    &model,
                )
                .map(std::sync::Arc::new)
            })
            .collect();
        let mut memo = self.starts.lock().unwrap_or_else(|e| e.into_inner());
        for ((i, _), s) in missing.into_iter().zip(measured) {
            memo.insert(keys[i].clone(), s);
        }
        (keys.iter().map(|k| memo.get(k).cloned().flatten()).collect(), model)
    }
}
