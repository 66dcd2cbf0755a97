//! Greedy forward selection of missing physics.
//!
//! 1. Split the dataset: every `holdout`-th episode is held out (at least one when there are two
//!    or more); a single episode is cut into time windows instead, every `holdout`-th window
//!    held out. Optionally, training episodes are cut into multiple-shooting windows (each
//!    replay starts from the recorded state).
//! 2. Each round: replay the training set with the effects kept so far, [`diagnose`] the
//!    residuals, take the top-ranked (effect, joint group) candidates, and fit each one's
//!    parameters (a line search — grid, then Brent's method — for one parameter, Nelder–Mead
//!    for two or three, CMA-ES above) to minimise the position RMSE over the training episodes.
//! 3. A candidate is kept only when, on the held-out episodes, the paired per-window RMSE
//!    improvement is beyond noise ([`improvement_beyond_noise`]), the relative RMSE improvement
//!    is at least `min_rel_improvement`, and the training BIC decreases. Of the kept candidates the
//!    one with the lowest held-out RMSE wins (a simpler one within 1 % of it is preferred).
//! 4. Repeat until nothing helps. Uncertainty: finite-difference Jacobian of the residual vector
//!    at the optimum → [`uncertainty_from_jacobian`].
//!
//! This module owns the options, the outcome types and the [`fit`] entry point; the search itself
//! is split by seam: `engine` (simulating a dataset, fitting one candidate, standard errors),
//! `verdict` (the held-out gate), `greedy` (one round), `pairs` (effects fitted together),
//! `simplify` (drop, swap, polish) and `reshoot` (dry friction re-fitted by multiple shooting).
//!
//! [`diagnose`]: crate::fit::diagnose::diagnose
//! [`improvement_beyond_noise`]: crate::fit::stats::improvement_beyond_noise
//! [`uncertainty_from_jacobian`]: crate::fit::stats::uncertainty_from_jacobian

mod at_base;
mod before_full;
pub mod chord;
mod coarse;
mod discretisation;
mod engine;
mod ext_bound;
mod extension;
mod first_step;
mod further;
mod greedy;
mod groups;
mod heldout_linear;
mod joint_floor;
mod lead;
mod outcome;
mod pair_first;
mod pair_reach;
mod pair_restart;
mod pair_screen;
mod pairs;
mod policy;
mod polish;
mod probe_trust;
mod prune;
mod reach;
mod reach_model;
mod reshoot;
mod rival;
mod rival_pairs;
mod screen;
mod secant_bar;
mod simplify;
mod solve;
mod start;
mod start_bound;
mod swap;
mod told;
mod trust;
mod verdict;
mod winner;

use std::collections::BTreeMap;

use crate::fit::effects::{self, Applied, Effect};
use crate::fit::split::{Split, split, split_by_key, windows};
use crate::model::Robot;
use crate::sim2real::recording::Recording;
use crate::sim2real::replay::ReplayOptions;

pub use engine::{Engine, Jacobian};
pub use outcome::{Errors, FitOutcome, Floor, SearchCost, Selected, Tried, Unprobed};
pub use policy::{Phase, SearchPolicy};
pub use verdict::beats_beyond_noise;

use greedy::greedy_round;
use polish::polish;
use simplify::simplify;
use verdict::Verdict;

#[derive(Debug, Clone)]
pub struct FitOptions {
    /// Every N-th episode is held out (N ≥ 2).
    pub holdout: usize,
    /// Hold out the episodes whose metadata key (`.0`) has the value `.1` instead
    /// ([`crate::fit::split::split_by_key`]).
    pub holdout_by: Option<(String, String)>,
    /// Effect ids to consider (all when empty).
    pub effects: Vec<String>,
    /// Joints to fit (all recorded joints when empty).
    pub joints: Vec<String>,
    pub replay: ReplayOptions,
    /// Length of the windows of the held-out paired test [s].
    pub window_s: f64,
    /// Multiple shooting: cut training episodes into windows of this length [s].
    pub shooting_s: Option<f64>,
    /// Joint → motor family (from the spec): a family of `policy.min_group` or more fitted
    /// joints is also tried as one group sharing the parameters.
    pub families: BTreeMap<String, String>,
    /// Samples up to this long after a gap in a recording (dropped rows) are left out of every
    /// error sum ([`gap_mask`]): the command during the gap is unknown [s].
    ///
    /// [`gap_mask`]: crate::sim2real::metrics::gap_mask
    pub gap_mask_s: f64,
    /// Estimate each episode's start state (first position and velocity of every recorded
    /// joint) from the whole episode, with the first row as its prior, instead of starting the
    /// replay exactly at the first row's noisy reading ([`start`]). Off by default: re-run in
    /// full with it on (docs/fitting.md, step 2), every benchmark gave the same answers. The
    /// response it corrects with is measured on the model with the kept effects that let a
    /// joint stick ([`Engine::set_start_model`]).
    ///
    /// [`Engine::set_start_model`]: Engine::set_start_model
    pub estimate_start: bool,
    /// Every budget and threshold of the search ([`SearchPolicy`]).
    pub policy: SearchPolicy,
    /// Told fit: no search, fit exactly these (effect id, joint group) on the training set,
    /// jointly when there are several, and report their held-out improvement (`fit --told`).
    pub told: Vec<(String, Vec<String>)>,
    /// Where each told fit starts (by index of `told`; none or empty: the effect's initial
    /// values) — a re-fit of an answer on other settings starts at that answer.
    pub told_start: Vec<Vec<f64>>,
    /// Called at each step of the search (none: silent).
    pub progress: Option<Progress>,
    /// Set from outside (the Python API on Ctrl-C) to stop the search: every replay after it
    /// fails at once, so the search runs out within a replay's time; the outcome is then
    /// meaningless and the caller discards it ([`Cancel::is_set`]).
    pub cancel: Option<Cancel>,
}

/// A flag that stops a running fit ([`FitOptions::cancel`]).
#[derive(Debug, Clone, Default)]
pub struct Cancel(pub std::sync::Arc<std::sync::atomic::AtomicBool>);

impl Cancel {
    pub fn set(&self) {
        self.0.store(true, std::sync::atomic::Ordering::Relaxed);
    }
    pub fn is_set(&self) -> bool {
        self.0.load(std::sync::atomic::Ordering::Relaxed)
    }
}

impl FitOptions {
    /// Joint → motor family from a hardware spec, for every joint of `names` the spec assigns a
    /// motor (what `modellint fit` passes as [`FitOptions::families`]; empty without a spec).
    pub fn motor_families(
        spec: Option<&crate::spec::Spec>,
        names: &[String],
    ) -> BTreeMap<String, String> {
        let Some(s) = spec else { return BTreeMap::new() };
        names
            .iter()
            .filter_map(|n| s.joint(n).and_then(|f| f.motor).map(|m| (n.clone(), m)))
            .collect()
    }
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            holdout: 4,
            holdout_by: None,
            effects: vec![],
            joints: vec![],
            replay: ReplayOptions::default(),
            window_s: 0.5,
            shooting_s: None,
            families: BTreeMap::new(),
            gap_mask_s: 0.1,
            estimate_start: false,
            policy: SearchPolicy::default(),
            told: vec![],
            told_start: vec![],
            progress: None,
            cancel: None,
        }
    }
}

/// Where the search is, for a progress display: the phase, the candidate being fitted (if any)
/// with its index among the round's candidates, and the number of dataset simulations so far.
#[derive(Debug, Clone)]
pub struct ProgressInfo {
    pub round: usize,
    pub phase: Phase,
    pub candidate: Option<(usize, usize, String)>,
    /// Dataset simulations asked for so far.
    pub simulations: usize,
    /// Episodes replayed so far (rollouts of the rollout service).
    pub rollouts: usize,
}

/// A progress callback (`modellint fit` draws it on stderr).
#[derive(Clone)]
pub struct Progress(pub std::sync::Arc<dyn Fn(&ProgressInfo) + Send + Sync>);

impl std::fmt::Debug for Progress {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Progress")
    }
}

/// Runs the whole selection on `recs`.
pub fn fit(robot: &Robot, recs: &[Recording], opts: &FitOptions) -> FitOutcome {
    // A floating base the replay holds (a robot on a stand) gets the stand's inertia.
    let held = crate::sim2real::replay::held(robot, opts.replay.base);
    let robot = held.as_ref().unwrap_or(robot);
    let engine = Engine::new(robot, recs, opts);
    let by_key = opts.holdout_by.as_ref().map(|(k, v)| split_by_key(recs, k, v));
    let Split { train: train0, heldout, by_time, note } = match by_key {
        Some(Ok(s)) => s,
        Some(Err(e)) => {
            let mut out = FitOutcome::empty(String::new());
            out.warnings.push(e);
            return out;
        }
        None => split(recs, opts.holdout),
    };
    let train: Vec<Recording> = match opts.shooting_s {
        Some(w) if w > 0.0 => train0.iter().flat_map(|r| windows(r, w)).collect(),
        _ => train0,
    };
    let mut out = FitOutcome {
        train: train.clone(),
        heldout: heldout.clone(),
        split_by_time: by_time,
        ..FitOutcome::empty(note)
    };
    if train.is_empty() || heldout.is_empty() {
        out.warnings.push("not enough data for a train/held-out split (need 2 episodes, or one of several seconds)".into());
        return out;
    }
    let allowed: Vec<String> = if opts.effects.is_empty() {
        effects::all().iter().filter(|e| e.by_default()).map(|e| e.id().to_string()).collect()
    } else {
        opts.effects.clone()
    };
    // Effects that cannot act on this data (no torque-off interval, no declared motor).
    let (allowed, inapplicable): (Vec<String>, Vec<String>) =
        allowed.into_iter().partition(|id| effects::by_id(id).is_none_or(|e| e.applies(recs)));
    if !opts.effects.is_empty() && !inapplicable.is_empty() {
        out.warnings.push(format!(
            "not tried, cannot act on these recordings: {}",
            inapplicable.join(", ")
        ));
    }
    let search = Search { engine: &engine, train: &train, heldout: &heldout, allowed: &allowed };
    if !opts.told.is_empty() {
        told::fit_told(&search, &opts.told, &mut out);
        if !out.applied.is_empty() {
            engine.report(0, Phase::StandardErrors, None);
            final_uncertainty(&engine, &train, &mut out);
        }
        engine.report(0, Phase::Done, None);
        out.cost = search_cost(&engine, &out);
        return out;
    }
    let mut round = 0;
    loop {
        while round < opts.policy.max_rounds {
            engine.set_start_model(&out.applied);
            engine.report(round, Phase::Diagnose, None);
            let (base, logged) = (out.applied.clone(), out.tried.len());
            let added = greedy_round(&search, round, &mut out);
            for t in &mut out.tried[logged..] {
                t.simulated_s = effects::by_id(&t.effect)
                    .map(|e| engine.spent_with(&base, (e, &t.joints)))
                    .map(|s| (s * 10.0).round() / 10.0);
            }
            round += 1;
            if !added {
                break;
            }
        }
        engine.set_start_model(&out.applied);
        if out.applied.len() >= 2 {
            engine.report(round, Phase::Polish, None);
            polish(&search, &mut out);
        }
        if !opts.policy.simplify || out.applied.is_empty() {
            break;
        }
        // A change re-opens the greedy search (bounded by `max_rounds`).
        engine.set_start_model(&out.applied);
        engine.report(round, Phase::Simplify, None);
        if !simplify(&search, round, &mut out) || round >= opts.policy.max_rounds {
            break;
        }
    }
    engine.set_start_model(&out.applied);
    if opts.shooting_s.is_none() {
        reshoot::reshoot_friction(&search, &train, round, &mut out);
    }
    engine.set_start_model(&out.applied);
    if !out.applied.is_empty() {
        engine.report(round, Phase::StandardErrors, None);
        final_uncertainty(&engine, &train, &mut out);
        // The floors reported are those of the final model: with an effect missing, the
        // residual's white part carries some of the model error too.
        out.floors = match engine.errors(&train, &out.applied) {
            Some(e) => engine.floors(&train, &out.applied, &e),
            None => vec![],
        };
    }
    engine.report(round, Phase::Done, None);
    out.cost = search_cost(&engine, &out);
    out
}

/// What the search behind `out` cost.
fn search_cost(engine: &Engine, out: &FitOutcome) -> SearchCost {
    let by_phase = engine.rollouts_by_phase();
    let by_round = engine.rollouts_by_round();
    let mut by_round_phase: BTreeMap<String, BTreeMap<&'static str, f64>> = BTreeMap::new();
    for ((r, p), (_, s)) in engine.rollouts_by_round_phase() {
        by_round_phase.entry(r).or_default().insert(p, (s * 10.0).round() / 10.0);
    }
    SearchCost {
        simulations: engine.simulations(),
        rollouts: engine.rollout_stats(),
        fits_saved_by_screens: out
            .tried
            .iter()
            .filter(|t| {
                matches!(
                    t.phase,
                    Phase::Screen
                        | Phase::Floor
                        | Phase::JointFloor
                        | Phase::FloorScreen
                        | Phase::ReachScreen
                        | Phase::HeldoutScreen
                        | Phase::DiscretisationScreen
                        | Phase::HeldoutBound
                        | Phase::TrustScreen
                        | Phase::HeldoutLinear
                        | Phase::SwapScreen
                )
            })
            .count(),
        rollouts_by_phase: by_phase.iter().map(|(k, v)| (*k, v.0)).collect(),
        simulated_s_by_phase: by_phase
            .iter()
            .map(|(k, v)| (*k, (v.1 * 10.0).round() / 10.0))
            .collect(),
        rollouts_by_round: by_round.iter().map(|(k, v)| (k.clone(), v.0)).collect(),
        simulated_s_by_round: by_round
            .iter()
            .map(|(k, v)| (k.clone(), (v.1 * 10.0).round() / 10.0))
            .collect(),
        simulated_s_by_round_phase: by_round_phase,
        unprobed: engine.unprobed(),
    }
}

/// The standard errors of every kept effect at the final parameters, from one joint Jacobian
/// (the ones set while searching were taken when each effect was added, conditional on the
/// others; a later polish, swap or drop moves the values they belong to).
fn final_uncertainty(engine: &Engine, train: &[Recording], out: &mut FitOutcome) {
    const UNIDENT: &str = "parameters not identifiable from this data";
    let (all, jacobian) = engine.uncertainty_all(train, &out.applied);
    out.jacobian = jacobian;
    out.warnings.retain(|w| !w.contains(UNIDENT));
    for ((s, a), (se, ident)) in out.selected.iter_mut().zip(&out.applied).zip(all) {
        set_stderr(s, a.effect, &se, &ident);
        if !s.identifiable {
            out.warnings.push(format!(
                "{} on {}: {UNIDENT}: {} (excite the joint more)",
                s.effect,
                s.joints.join(","),
                s.unidentified.join(", ")
            ));
        }
    }
}

/// `s`'s standard errors and which of its parameters the data determine (`ident`, per fitted
/// parameter of `effect`).
fn set_stderr(s: &mut Selected, effect: &dyn Effect, se: &[f64], ident: &[bool]) {
    s.stderr = effect.params().iter().zip(se).map(|(d, v)| (d.name.to_string(), *v)).collect();
    s.unidentified = effect
        .params()
        .iter()
        .zip(ident)
        .filter(|(_, ok)| !**ok)
        .map(|(d, _)| d.name.to_string())
        .collect();
    s.identifiable = s.unidentified.is_empty();
}

/// What every step of the search works on: the engine, the training and held-out recordings,
/// and the effects it may try.
#[derive(Clone, Copy)]
pub(super) struct Search<'a> {
    pub(super) engine: &'a Engine<'a>,
    pub(super) train: &'a [Recording],
    pub(super) heldout: &'a [Recording],
    pub(super) allowed: &'a [String],
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
    set_stderr(s, e, &se, &ident);
    if !s.identifiable {
        warnings.push(format!(
            "{} on {}: parameters not identifiable from this data: {} (excite the joint more)",
            s.effect,
            s.joints.join(","),
            s.unidentified.join(", ")
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
            unidentified: vec![],
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
