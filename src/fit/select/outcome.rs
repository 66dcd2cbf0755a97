//! What a fit returns: the kept effects ([`Selected`]), every candidate tried ([`Tried`]), the
//! floors ([`Floor`]), the search's cost ([`SearchCost`]) and the dataset errors ([`Errors`]).

use std::collections::BTreeMap;

use serde::Serialize;

use crate::fit::effects::Applied;
use crate::fit::rollout::RolloutStats;
use crate::sim2real::replay::Episode;

use crate::fit::diagnose::Candidate;
use crate::sim2real::recording::Recording;

use super::{Jacobian, Phase, engine, screen};
/// One kept effect.
#[derive(Debug, Clone, Serialize)]
pub struct Selected {
    pub effect: String,
    pub joints: Vec<String>,
    pub params: BTreeMap<String, f64>,
    pub stderr: BTreeMap<String, f64>,
    /// `false` when some fitted parameter is not determined by the data.
    pub identifiable: bool,
    /// The fitted parameters the data do not determine (standard error above half the
    /// parameter's range, or no Jacobian): reported as not identified, not as a value.
    pub unidentified: Vec<String>,
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
    /// `add` (greedy round), `add_coarse` (a greedy round's candidate gated at its coarse
    /// fit: a kept candidate beats it decisively there), `screen` / `floor` (not fitted fully / not fitted: see
    /// docs/fitting.md), `pair`, `joint_pair`, `drop` (removal test: `kept` = the effect
    /// stays), `drop_refit` (removal with the other effects fitted again: `kept` = the effect
    /// stays), `merge` (one effect on two joint sets as one group: `kept` = merged), `fold`
    /// (an effect taken over by another on the same joints: `kept` = folded), `plain_friction`
    /// (a load-shaped friction beside Coulomb friction replaced by Coulomb friction of its
    /// joints' own: `kept` = replaced), `swap`
    /// (replacement by a simpler effect: `kept` = the swap was made), `swap_screen` or `reshoot`
    /// (a friction effect re-fitted on short windows: `kept` = the re-fit replaced its values).
    pub phase: Phase,
    pub effect: String,
    pub joints: Vec<String>,
    pub params: Vec<f64>,
    pub train_rmse: f64,
    pub heldout_improvement: f64,
    pub significant: bool,
    pub bic_decreased: bool,
    pub kept: bool,
    /// What the linearised screen predicted for this candidate before its fit (greedy rounds
    /// only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub predicted: Option<screen::Prediction>,
    /// Recording seconds replayed with this candidate on its round's base, in every phase of
    /// the round (its probes, coarse and full fits, held-out and other judging replays; a
    /// simulation counted once, as `search.simulated_s` counts it: [`Engine::spent_with`]).
    /// Greedy rounds' single candidates only; several entries of one candidate in a round
    /// (`discretisation` beside `add`) show the same total.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub simulated_s: Option<f64>,
}

impl Tried {
    /// A candidate left out before the held-out test (`screen`: a coarse fit did not reach half
    /// the best training improvement; `floor`: a kept candidate already left a white residual).
    pub(super) fn not_tested(
        round: usize,
        phase: Phase,
        effect: &str,
        joints: &[String],
        params: Vec<f64>,
        train_rmse: f64,
    ) -> Tried {
        Tried {
            round,
            phase,
            effect: effect.into(),
            joints: joints.to_vec(),
            params,
            train_rmse,
            heldout_improvement: f64::NAN,
            significant: false,
            bic_decreased: false,
            kept: false,
            predicted: None,
            simulated_s: None,
        }
    }
}

/// What is left to explain on one fitted joint: its residual and the floors under it, as mean
/// squares [rad²].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Floor {
    pub joint: String,
    /// Residual mean square of the model as simulated.
    pub ms: f64,
    /// White floor ([`crate::fit::stats::white_floor`]): noise and quantisation.
    pub white: f64,
    /// Command-reconstruction and start-state floor ([`Engine::reconstruction_floor`]).
    pub reconstruction: f64,
    /// Discretisation floor ([`Engine::discretisation_floor`]): what the model's own timestep
    /// explains when the recordings move in continuous time.
    pub discretisation: f64,
}

impl Floor {
    /// The residual is within `ratio` of the floor (white + reconstruction + discretisation).
    pub fn reached(&self, ratio: f64) -> bool {
        self.ms <= ratio * (self.white + self.reconstruction + self.discretisation)
    }
}

pub struct FitOutcome {
    pub train: Vec<Recording>,
    pub heldout: Vec<Recording>,
    /// The held-out set is made of time windows of a single episode.
    pub split_by_time: bool,
    /// Which episodes were held out and why.
    pub split_note: String,
    /// Per fitted joint, the training residual and its floor with the effects kept (the model
    /// as given when nothing is).
    pub floors: Vec<Floor>,
    /// The search ended because the residual reached the white floor on every joint.
    pub stopped_at_floor: bool,
    /// The structure ([`engine::shape_key`]: effects and joints) of the set whose last added effect was judged at the floor
    /// when it was kept, with its training RMSE then: the next round stops without measuring
    /// the floors again.
    pub(crate) at_floor: Option<(String, f64)>,
    /// Diagnosis of the first round (the model as given).
    pub diagnosis: Vec<Candidate>,
    pub selected: Vec<Selected>,
    pub applied: Vec<Applied>,
    pub tried: Vec<Tried>,
    /// Something the user should act on or know is wrong (a diverged replay, a parameter the
    /// data cannot identify, too little data to split).
    pub warnings: Vec<String>,
    /// The search's decisions, for the record (a merge, a swap for a simpler effect, a drop, a
    /// re-fit): printed as notes, not warnings — a correct fit makes several.
    pub notes: Vec<String>,
    /// What the search cost.
    pub cost: SearchCost,
    /// The final standard errors' Jacobian of every kept parameter at the answer (training set).
    pub jacobian: Option<Jacobian>,
}

/// What a search cost: simulations asked for, rollouts run, and the full fits its screens
/// saved (JSON `search`).
#[derive(Debug, Clone, Default, Serialize)]
pub struct SearchCost {
    /// Dataset simulations the search asked for (the memo answers repeats without rollouts).
    pub simulations: usize,
    /// What the rollout service ran (episodes replayed, batches, wall time in batches).
    #[serde(flatten)]
    pub rollouts: RolloutStats,
    /// Candidates left without a full nonlinear fit by a screen (phases `screen`, `floor`,
    /// `joint_floor`, `floor_screen`, `reach_screen`, `heldout_screen`, `discretisation_screen`,
    /// `heldout_bound`, `trust_screen`, `heldout_linear`, `swap_screen`).
    pub fits_saved_by_screens: usize,
    /// Rollouts by the phase that ran them (`diagnose` includes the floors and the
    /// linearised ranking's probes; `add` the candidates' fits and held-out tests).
    pub rollouts_by_phase: BTreeMap<&'static str, usize>,
    /// Recording seconds replayed by phase (the screen's rollouts are short).
    pub simulated_s_by_phase: BTreeMap<&'static str, f64>,
    /// Rollouts by the greedy round that ran them (`"0"`, `"1"`, …: its diagnosis and floors,
    /// screen, full fits and pairs; `"end"`: polish, simplify, reshoot, standard errors, the
    /// final floors and the checks after the search).
    pub rollouts_by_round: BTreeMap<String, usize>,
    /// Recording seconds replayed by round, as `rollouts_by_round`.
    pub simulated_s_by_round: BTreeMap<String, f64>,
    /// Recording seconds replayed by round (as `simulated_s_by_round`) and, within it, by phase.
    pub simulated_s_by_round_phase: BTreeMap<String, BTreeMap<&'static str, f64>>,
    /// The screen's probes not replayed because their move provably changes nothing
    /// ([`Unprobed`]), in (round, effect, joint, parameter, value) order.
    pub unprobed: Vec<Unprobed>,
}

/// A probe of the linearised screen not replayed: its move of the parameter provably leaves
/// the replay as it was ([`Effect::unmoved`]), so its column is the zero column a replay would
/// give and no probe is kept for it.
///
/// [`Effect::unmoved`]: crate::fit::effects::Effect::unmoved
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Unprobed {
    /// The round (as `simulated_s_by_round`) and the phase whose screen asked for it.
    pub round: String,
    pub phase: &'static str,
    pub effect: &'static str,
    pub joint: String,
    /// The parameter moved and the probe's value.
    pub param: &'static str,
    pub value: f64,
    pub why: crate::fit::effects::Unmoved,
    /// Recording seconds the probe would have replayed (its data's length) [s].
    pub seconds: f64,
}

impl Unprobed {
    /// A probe of `effect`'s `param` at `value` on `joint`, not replayed for `why`; its place
    /// is set when noted ([`super::Engine::note_unprobed`]).
    pub fn new(
        effect: &'static str,
        joint: String,
        param: &'static str,
        value: f64,
        why: crate::fit::effects::Unmoved,
        seconds: f64,
    ) -> Unprobed {
        Unprobed { round: String::new(), phase: "", effect, joint, param, value, why, seconds }
    }
}

impl SearchCost {
    /// Adds `rollouts` and `simulated_s` run after the search (`phase`: a check made on its
    /// outcome, in round `"end"`) to the totals by phase and by round; the caller adds them to
    /// [`SearchCost::rollouts`].
    pub(crate) fn book_after(&mut self, phase: &'static str, rollouts: usize, simulated_s: f64) {
        let tenth = |x: f64| (x * 10.0).round() / 10.0;
        *self.rollouts_by_phase.entry(phase).or_default() += rollouts;
        let s = self.simulated_s_by_phase.entry(phase).or_default();
        *s = tenth(*s + simulated_s);
        *self.rollouts_by_round.entry(engine::END_KEY.to_string()).or_default() += rollouts;
        let s = self.simulated_s_by_round.entry(engine::END_KEY.to_string()).or_default();
        *s = tenth(*s + simulated_s);
        let end = self.simulated_s_by_round_phase.entry(engine::END_KEY.to_string()).or_default();
        let s = end.entry(phase).or_default();
        *s = tenth(*s + simulated_s);
    }
}

impl FitOutcome {
    /// Appends `t` to the log of what was tried; returns its index (the search marks an entry
    /// `kept` through it).
    pub(super) fn log(&mut self, t: Tried) -> usize {
        self.tried.push(t);
        self.tried.len() - 1
    }

    pub(super) fn empty(split_note: String) -> Self {
        FitOutcome {
            train: vec![],
            heldout: vec![],
            split_by_time: false,
            split_note,
            floors: vec![],
            stopped_at_floor: false,
            at_floor: None,
            diagnosis: vec![],
            selected: vec![],
            applied: vec![],
            tried: vec![],
            warnings: vec![],
            notes: vec![],
            cost: SearchCost::default(),
            jacobian: None,
        }
    }
}

/// Position errors of one simulation of a dataset.
#[derive(Clone)]
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
