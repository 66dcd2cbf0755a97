//! The search's policy in one place: every budget and threshold the selection decides with,
//! named, with its meaning, its unit and its default ([`SearchPolicy`]); the search's phases
//! ([`Phase`]); and the typed log of what was tried ([`Tried`], [`Log`]).
//!
//! docs/fitting.md ("The policy") lists the same table. A threshold that is not here is not
//! part of the search.

use serde::Serialize;

/// Every knob of the selection. Ratios of RMSE are of the held-out (or training, where said)
/// position RMSE over the fitted joints; "z" is in standard errors of the paired per-window
/// improvement ([`crate::fit::stats::improvement_beyond_noise`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SearchPolicy {
    // ---- budgets ----
    /// Greedy rounds at most (each adds at most one effect, or one pair) [count]. Default 4.
    pub max_rounds: usize,
    /// Candidates taken from the top of the linearised ranking each round [count]. Default 4.
    pub candidates_per_round: usize,
    /// Objective evaluations of one candidate's full fit [rollouts of the data fitted].
    /// A line search uses at most 40 of them, the simplex 2 × (k − 1) × this on k = 2 or 3
    /// parameters, Levenberg–Marquardt this / (k + 2) iterations (2–12). Default 60.
    pub max_evals: usize,
    /// How finely a one-parameter line search resolves its parameter relative to the
    /// parameter's own uncertainty: Brent's refinement stops once its bracket locates the
    /// minimum within this many standard errors of the best point (strictly lower than the two
    /// next-best points: never on a plateau's tie). The standard error is the profile's: the
    /// parabola through the three best points (where it is convex, the best strictly lowest
    /// between the others; the largest measured so far — below the RMSE's ripple the parabola
    /// measures the ripple) with the training residual's sample count and AR(1) inflation, the
    /// noise model of the reported standard errors. Until a parabola is usable (a plateau, a flat
    /// or non-convex profile) the line search's own tolerance. A Levenberg–Marquardt fit stops
    /// at a rejected trial step when that step and its Gauss–Newton model's optimum both lie
    /// within this many standard errors of its point, the model's at its optimum (the noise of
    /// the residual it predicts there, AR(1)-inflated). 0 never stops early [standard errors].
    /// Default 0.1.
    pub line_resolution: f64,
    /// Objective evaluations of a coarse screening fit [rollouts of the screen's data]. Default 6.
    pub screen_evals: usize,
    /// Seconds of recording the screen simulates for each evaluation: from each of the n
    /// training episodes the stretch of `screen_seconds / n` where the residual is largest (all
    /// of a shorter one); the whole training set when it is not longer. The screen's cost then does not grow with the
    /// length of the logs: candidates' coarse and full fits run there; the round's winner is
    /// re-fitted on the whole training set, and every held-out test uses all the data [s].
    /// Default 10.
    pub screen_seconds: f64,
    /// Seconds of recording each probe of the linearised screen replays: from the screen's
    /// data, the stretch of `probe_seconds / n` of each of its n episodes where the residual is
    /// largest (all of it when not longer). A probe gives one sensitivity column, which only
    /// ranks candidates and starts a coarse fit; the coarse and full fits run on the screen's
    /// data [s]. Default 2.
    pub probe_seconds: f64,
    /// A partner joint "ranks high" when it is among the top `rank_depth ×
    /// candidates_per_round` entries of the ranking [multiple]. Default 4.
    pub rank_depth: usize,
    /// Fewest joints of a motor-family or every-leg group [count]. Default 3.
    pub min_group: usize,
    /// Also fit the best-ranked group of every other allowed effect, and every effect on the
    /// top-ranked joint (the linear ranking is only a guide for strongly nonlinear effects).
    /// Default on.
    pub every_effect: bool,
    /// Run the simplification passes (drop, merge, fold, swap) after the greedy rounds.
    /// Default on.
    pub simplify: bool,
    /// When the candidates lie on more than one joint group, the one whose linearised step
    /// leaves the least of the screen's residual, charged for its parameters by the information
    /// criterion over the screen's windows (any size: a two-parameter servo gain error can
    /// lead), is coarse-fitted, fitted in full on the whole training set and judged before the
    /// others are coarse-fitted; when it is kept and leaves a white residual on every fitted
    /// joint, only other effects on exactly its joints (its aliases) are still screened:
    /// nothing is left that a candidate of as many parameters could explain beyond noise.
    /// Default on.
    pub lead_first: bool,

    // ---- when to stop ----
    /// Every fitted joint's training residual mean square within this factor of its floor
    /// (white + reconstruction + discretisation) stops the search; after round 0 a candidate of
    /// a joint-local effect whose joints all are is not screened (`joint_floor.rs`)
    /// [ratio of mean squares]. Default 1.5.
    pub white_ratio: f64,
    /// Ratio r between the timesteps of the replays that measure the model's own time
    /// discretisation: dt, dt / r and dt / r², extrapolated to continuous time (the
    /// discretisation floor, and the test of a kept effect at dt / r²) [ratio]. Default 2.
    pub discretisation_refine: usize,

    // ---- the held-out gate ----
    /// Smallest relative held-out RMSE improvement for an effect to be kept [fraction].
    /// Default 0.02.
    pub min_rel_improvement: f64,
    /// A candidate that cuts the held-out RMSE (over all joints or over its own windows) by at
    /// least this fraction, with more than twice as many windows improved as worsened, passes
    /// without the paired z test (an effect confined to a few windows cannot pass it)
    /// [fraction]. Default 0.5.
    pub decisive_improvement: f64,
    /// z of a paired held-out comparison between two fitted sets (drop, merge, swap, pair
    /// members, restarts) [standard errors]. A round's own candidates need
    /// [`SearchPolicy::z_needed`], which grows with their number. Default 2.0.
    pub z_decision: f64,
    /// Growth of the round's z with the number of candidates m: z = `z_decision` +
    /// `z_growth` × ln(max(m, 4) / 4) (a Bonferroni-like correction: 2.35 for 8, 2.69 for 16)
    /// [standard errors]. Default 0.5.
    pub z_growth: f64,
    /// A window counts as improved (worsened) when its RMSE changes by more than this fraction
    /// [fraction]. Default 0.02.
    pub window_change: f64,

    // ---- screens (candidates not fitted in full) ----
    /// A candidate is fitted in full only when its coarse fit, or its linearised step, reaches
    /// this share of the best training improvement of the round so far (coarse or full); a
    /// smooth effect's step counts as replayed on the screen's data [fraction]. Default 0.5.
    pub screen_share: f64,
    /// A smooth one-parameter candidate's coarse fit is a few secant Gauss–Newton steps started
    /// from the screen's linear step (one replay each); it stops at the first step that achieves
    /// between this fraction and its inverse of the relative improvement its linear model
    /// predicted (the model held as far as the step; both below `min_rel_improvement` also
    /// agree), or after `screen_evals` replays [ratio]. The same test confirms the linear step
    /// of a smooth candidate of several (all screened) parameters, replayed once, as its coarse
    /// fit, and the coarse fit made on the probes' data of a non-smooth candidate, or of a
    /// smooth one without a confirmed step, by its gain on the screen's data against its gain
    /// there (or its reaching `screen_share`'s bar); else the coarse fit of `screen_evals`
    /// replays of the screen's data follows. A coarse fit the test confirms is fitted in full only when it
    /// lowers the held-out RMSE by more than this × `min_rel_improvement`
    /// (`trust::heldout_needed`); after round 0 a smooth one-parameter candidate's coarse fit
    /// (the start of its full fit's descent along the same line) is fitted in full only when it
    /// passes the round's held-out gate with the z, the decisive improvement and
    /// `min_rel_improvement` taken × this (`trust::at_trust_edge`). A pair's fit is taken to gain at most 1 / this times what the
    /// linear combination of its members' columns predicts beyond its better member
    /// (`pair_screen::PairPrediction::reachable`, before any pair replay). A friction extension
    /// deferred on its plain variant's coarse fit is not judged on the screen's data when the gain
    /// the judgement's own columns allow on the probes' data, taken 1 / this times, cannot reach
    /// the round's bar (`ext_bound::short_of_bar`). In round 0, once a fit set the bar, a smooth
    /// one-parameter candidate whose linear step, replayed on the probes' data, confirms its
    /// prediction there by this test is not coarse-fitted when that prediction, taken 1 / this
    /// times, cannot reach the bar (`probe_trust::out`). After round 0 a smooth several-parameter
    /// candidate is left out at its start when its held-out Gauss–Newton optimum cannot lower the
    /// held-out RMSE by this × `min_rel_improvement` (`start_bound`). Default 0.75 (a "very successful" step of a
    /// trust-region method).
    pub linear_trust: f64,
    /// Once a kept candidate leaves a white training residual (or when a swap is screened), a
    /// candidate whose coarse fit leaves more than this times that training RMSE is not fitted;
    /// judged first on the probes' data against the model at the floor replayed there
    /// (`reach.rs`) [ratio of RMSE]. Default 1.5.
    pub floor_screen_ratio: f64,
    /// The extra effects of `every_effect` are left out when their best joint explains less
    /// than this share of the top candidate's explained RMS [fraction]. Default 0.1.
    pub minor_effect_share: f64,

    // ---- Occam's choices ----
    /// A simpler candidate (or set) whose held-out RMSE is within this factor of the best's,
    /// not worse beyond noise, wins [ratio of RMSE]. Default 1.05.
    pub simpler_within: f64,
    /// Fewer parameters win within this factor; more parameters need to be lower by more
    /// [ratio of RMSE]. Default 1.01.
    pub occam_within: f64,

    // ---- pairs (two effects fitted together) ----
    /// The pair look-ahead combines the best this many single candidates of the round (the
    /// early look-ahead: the lead and this many less one partners); its pair fits grow as
    /// n (n − 1) / 2 [count]. Default 4.
    pub pair_candidates: usize,
    /// A single effect whose held-out improvement is at least this needs no partner
    /// [fraction]. Default 0.95.
    pub pair_needless_improvement: f64,
    /// Pairs whose coarse joint fit is within this factor of the best pair's are fitted fully;
    /// a pair whose linear prediction from its members' single fits exceeds this factor of the
    /// best coarse fit so far is not fitted at all [ratio of training RMSE]. Default 1.25.
    pub pair_full_fit_within: f64,
    /// A pair replaces the single winner only below this factor of its held-out RMSE
    /// [ratio of RMSE]. Default 0.9.
    pub pair_gain: f64,
    /// A single effect re-fitted by a failed pair replaces the winner only below this factor of
    /// its held-out RMSE [ratio of RMSE]. Default 0.95.
    pub restart_gain: f64,

    // ---- joint polish (every kept parameter; Nelder–Mead when one effect is not smooth) ----
    /// Initial simplex step of a full polish [fraction of each parameter's range].
    /// Default 0.02.
    pub polish_step: f64,
    /// Initial simplex step of a pair's coarse polish [fraction of range]. Default 0.05.
    pub coarse_polish_step: f64,
    /// A swap's set is polished when its unpolished held-out RMSE is within this factor of the
    /// current one [ratio of RMSE]. Default 1.10.
    pub swap_polish_within: f64,
}

impl Default for SearchPolicy {
    fn default() -> Self {
        SearchPolicy {
            max_rounds: 4,
            candidates_per_round: 4,
            max_evals: 60,
            line_resolution: 0.1,
            screen_evals: 6,
            screen_seconds: 10.0,
            probe_seconds: 2.0,
            rank_depth: 4,
            min_group: 3,
            every_effect: true,
            simplify: true,
            lead_first: true,
            white_ratio: 1.5,
            discretisation_refine: 2,
            min_rel_improvement: 0.02,
            decisive_improvement: 0.5,
            z_decision: 2.0,
            z_growth: 0.5,
            window_change: 0.02,
            screen_share: 0.5,
            linear_trust: 0.75,
            floor_screen_ratio: 1.5,
            minor_effect_share: 0.1,
            simpler_within: 1.05,
            occam_within: 1.01,
            pair_candidates: 4,
            pair_needless_improvement: 0.95,
            pair_full_fit_within: 1.25,
            pair_gain: 0.9,
            restart_gain: 0.95,
            polish_step: 0.02,
            coarse_polish_step: 0.05,
            swap_polish_within: 1.10,
        }
    }
}

impl SearchPolicy {
    /// z the paired held-out test needs when `m` candidates compete in one round:
    /// `z_decision` for up to four, then growing like a Bonferroni correction so that fitting
    /// more candidates does not buy more false discoveries.
    pub fn z_needed(&self, m: usize) -> f64 {
        self.z_decision + self.z_growth * (m.max(4) as f64 / 4.0).ln()
    }

    /// How deep in the ranking a partner joint still counts as ranking high [entries].
    pub fn rank_window(&self) -> usize {
        self.candidates_per_round * self.rank_depth
    }

    /// Whether a candidate with held-out RMSE `rmse` and `k` fitted parameters beats the best
    /// so far (`None`: there is none): fewer parameters win within `occam_within`, more
    /// parameters need a lower RMSE by more than that, the same number any lower RMSE.
    pub fn beats(&self, (rmse, k): (f64, usize), best: Option<(f64, usize)>) -> bool {
        let w = self.occam_within;
        match best {
            None => true,
            Some((r, kb)) => (k < kb && rmse <= r * w) || (rmse < r && !(k > kb && rmse > r / w)),
        }
    }
}

/// Every field of [`SearchPolicy`] as (name, unit, meaning): docs/fitting.md's policy table is
/// generated from it with the defaults ([`SearchPolicy::table`]); a test keeps it complete.
pub const FIELDS: &[(&str, &str, &str)] = &[
    ("max_rounds", "count", "greedy rounds at most (each adds one effect or one pair)"),
    (
        "candidates_per_round",
        "count",
        "candidates taken from the top of the linearised ranking each round",
    ),
    (
        "max_evals",
        "rollouts of the data fitted",
        "budget of one candidate's full fit: line search ≤ 40, simplex 2 (k − 1) × this, Levenberg–Marquardt this / (k + 2) iterations (2–12)",
    ),
    (
        "line_resolution",
        "standard errors",
        "a one-parameter line search stops once its bracket locates the minimum within this many standard errors of its best point (strictly lower than the next two); the standard error from the parabola through the three best points (convex, the best strictly lowest between the others; the largest so far) and the training residual's sample count and AR(1) inflation; until such a parabola (a plateau, a flat or non-convex profile) its tolerance; a Levenberg–Marquardt fit stops at a rejected step when it and its Gauss–Newton model's optimum lie within this many of the model's standard errors at that optimum (the noise of the residual it predicts there, AR(1)-inflated); 0: never early",
    ),
    ("screen_evals", "rollouts of the screen's data", "budget of a coarse screening fit"),
    (
        "screen_seconds",
        "s",
        "recording the screen simulates per evaluation: from each of the n training episodes the stretch of screen_seconds / n with the largest residual (the whole set when not longer); coarse and full candidate fits and the pair look-ahead's coarse polish run there, the round's winner is re-fitted on the whole training set, held-out tests use all data",
    ),
    (
        "probe_seconds",
        "s",
        "recording each probe of the linearised screen replays: from each of the screen's n episodes the stretch of probe_seconds / n with the largest residual (all of it when not longer); the probes' columns rank candidates and start coarse fits, which run on the screen's data",
    ),
    (
        "rank_depth",
        "× candidates_per_round",
        "a partner joint ranks high within this depth of the ranking",
    ),
    ("min_group", "joints", "fewest joints of a motor-family or every-leg group"),
    (
        "every_effect",
        "on/off",
        "also fit the best group of every other effect, and every effect on the top-ranked joint",
    ),
    ("simplify", "on/off", "run drop, merge, fold and swap after the greedy rounds"),
    (
        "lead_first",
        "on/off",
        "when the candidates lie on more than one joint group, the one with the best linear prediction (any size, charged for its parameters) is fitted on the whole training set and judged first; when it leaves a white residual on every joint, only other effects on its joints are screened",
    ),
    (
        "white_ratio",
        "ratio of mean squares",
        "stop when every joint's training residual is within this factor of its floor; after round 0, a joint effect's candidate whose joints all are is not screened",
    ),
    (
        "discretisation_refine",
        "ratio",
        "the model's time discretisation is measured by replays at dt, dt / r and dt / r² (extrapolated to continuous time); a kept effect must also pass the held-out gate at dt / r²",
    ),
    (
        "min_rel_improvement",
        "fraction",
        "smallest relative held-out RMSE improvement that keeps an effect",
    ),
    (
        "decisive_improvement",
        "fraction",
        "a held-out improvement this large (most windows better) passes without the z test",
    ),
    ("z_decision", "standard errors", "z of a paired held-out comparison between two fitted sets"),
    (
        "z_growth",
        "standard errors",
        "a round's z: z_decision + z_growth × ln(max(m, 4) / 4) for m candidates",
    ),
    (
        "window_change",
        "fraction",
        "a window counts as improved or worsened beyond this relative change",
    ),
    (
        "screen_share",
        "fraction",
        "a candidate is fitted fully only when its coarse fit, or its linearised step (replayed once on the screen's data), reaches this share of the round's best training improvement so far (coarse or full)",
    ),
    (
        "linear_trust",
        "ratio",
        "a smooth one-parameter candidate's coarse fit is secant Gauss-Newton steps from the screen's linear step (one replay each), stopping at the first step that achieves between this and its inverse times the relative improvement its linear model predicted (both below min_rel_improvement also agree), or after screen_evals replays; the same test confirms a several-parameter smooth candidate's linear step (one replay) and the coarse fit on the probes' data of a non-smooth candidate or of a smooth one without a confirmed step (its gain on the screen's data against its gain there) as the coarse fit, else screen_evals replays of the screen's data follow; a coarse fit it confirms is fitted in full only when it lowers the held-out RMSE by more than this × min_rel_improvement, and after round 0 a smooth one-parameter candidate's coarse fit only when it passes the round's held-out gate with its z, decisive improvement and min_rel_improvement taken × this; a pair's fit is taken to gain at most 1 / this times the gain its members' columns predict beyond its better member, judged before any pair replay; a friction extension deferred on its plain variant's coarse fit is not judged on the screen's data when the gain its own columns allow on the probes' data, taken 1 / this times, cannot reach the round's bar; in round 0, once a fit set the bar, a smooth one-parameter candidate whose linear step replayed on the probes' data confirms its prediction there is not coarse-fitted when that prediction, taken 1 / this times, cannot reach the bar; after round 0 a smooth several-parameter candidate is left out at its start, before its coarse fit, when its held-out Gauss-Newton optimum cannot lower the held-out RMSE by this × min_rel_improvement (start_bound.rs), or at its coarse fit by the same model there (before_full.rs), and its full fit's first iteration, when it confirms its Gauss-Newton model up to that model's optimum, is continued only when its step's held-out replay passes the round's held-out gate with its z, decisive improvement and min_rel_improvement taken × this (first_step.rs)",
    ),
    (
        "floor_screen_ratio",
        "ratio of RMSE",
        "after a white-residual winner (or for a swap), a coarse fit above this × its training RMSE is not fitted fully; first judged on the probes' data against the model at the floor replayed there (reach.rs)",
    ),
    (
        "minor_effect_share",
        "fraction",
        "every_effect leaves out effects explaining less than this share of the top candidate",
    ),
    (
        "simpler_within",
        "ratio of RMSE",
        "a simpler candidate or set within this factor of the best, not worse beyond noise, wins",
    ),
    (
        "occam_within",
        "ratio of RMSE",
        "fewer parameters win within this factor; more need to be lower by more",
    ),
    (
        "pair_candidates",
        "count",
        "the pair look-ahead combines the round's best this many singles (the early one: the lead and this many less one partners); its pair fits grow as n (n − 1) / 2",
    ),
    (
        "pair_needless_improvement",
        "fraction",
        "a single effect improving held-out by this much needs no partner",
    ),
    (
        "pair_full_fit_within",
        "ratio of RMSE",
        "pairs whose coarse joint fit is within this factor of the best pair's are fitted fully; a pair whose linear prediction from its members' single fits exceeds this factor of the best coarse fit so far is not fitted",
    ),
    (
        "pair_gain",
        "ratio of RMSE",
        "a pair replaces the single winner only below this factor of its held-out RMSE",
    ),
    (
        "restart_gain",
        "ratio of RMSE",
        "a single effect re-fitted in a failed pair replaces the winner only below this factor",
    ),
    ("polish_step", "fraction of range", "initial simplex step of a joint polish"),
    ("coarse_polish_step", "fraction of range", "initial simplex step of a pair's coarse polish"),
    (
        "swap_polish_within",
        "ratio of RMSE",
        "a swap's set is polished when its unpolished held-out RMSE is within this factor",
    ),
];

impl SearchPolicy {
    /// The policy as a markdown table (name, default, unit, meaning), in [`FIELDS`] order.
    pub fn table(&self) -> String {
        let v = serde_json::to_value(self).unwrap_or_default();
        let mut s = String::from("| setting | default | unit | meaning |\n|---|---|---|---|\n");
        for (name, unit, meaning) in FIELDS {
            s.push_str(&format!("| `{name}` | {} | {unit} | {meaning} |\n", v[*name]));
        }
        s
    }
}

/// Where the search is. Progress lines name it; the log's entries carry the phase that tried
/// them (JSON: snake_case names).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Phase {
    /// The residual is ranked by the linearised screen.
    Diagnose,
    /// A candidate of a greedy round fitted in full and put to the held-out gate.
    Add,
    /// The round's lead fitted in full on the whole training set ([`super::lead`]); booked
    /// apart from `add` (never a `tried` phase).
    LeadFit,
    /// The replays that judge a candidate's full fit: on the whole training set, on the
    /// held-out set, at a finer timestep, the floors of the set with it and the reach of a kept
    /// one (booked apart from `add`; never a `tried` phase).
    Judge,
    /// The early pair look-ahead of a kept lead with its coarse-fitted rivals
    /// ([`super::pair_first`]; booked apart from `pair`, never a `tried` phase).
    EarlyPair,
    /// The round's winner re-fitted on the whole training set (`winner::refine`; never a
    /// `tried` phase).
    Refine,
    /// The standard errors of a round's kept effect (never a `tried` phase).
    RoundErrors,
    /// The reach's coarse fits on the probes' data before the screen's ([`super::reach`];
    /// booked apart from `screen`, never a `tried` phase).
    Reach,
    /// A candidate of a greedy round put to the held-out gate at its coarse fit, not fitted in
    /// full: a kept candidate of the round beats it there decisively on held-out.
    AddCoarse,
    /// Not fitted in full: its coarse fit did not reach the round's screen.
    Screen,
    /// Not fitted: a kept candidate with fewer parameters already left a white residual.
    Floor,
    /// Not screened after round 0: every joint of the candidate is at its floor (its training
    /// residual within `white_ratio` of it, the search's stop applied joint by joint;
    /// `joint_floor.rs`).
    JointFloor,
    /// Not fitted in full: its coarse fit could not come near a kept white-residual candidate.
    FloorScreen,
    /// Not coarse-fitted on the screen's data: beside a kept lead, its coarse fit on the
    /// probes' data leaves more than the screen's bar allows on the whole screen's data.
    ReachScreen,
    /// Not fitted in full: its coarse fit, replayed on the held-out set, does not lower the
    /// held-out error at all.
    HeldoutScreen,
    /// Not fitted in full after round 0: a smooth candidate of one fitted parameter whose coarse
    /// fit, replayed on the held-out set at the finer timestep (`discretisation_refine`), does
    /// not pass the round's gate there at the trust's edge (`linear_trust`; `before_full.rs`):
    /// its gain at the model's step is the integration step's (a note says so);
    /// `heldout_improvement` holds its relative improvement at the finer step.
    DiscretisationScreen,
    /// Not fitted in full after round 0: a smooth candidate of several fitted parameters whose
    /// held-out optimum by the Gauss–Newton model at its start (`start_bound.rs`, no coarse fit
    /// made) or its coarse fit (`before_full.rs`; one held-out replay per parameter) does not
    /// lower the held-out RMSE by `linear_trust` × `min_rel_improvement`, or whose full fit's
    /// first iteration confirms its Gauss–Newton model up to the model's optimum at a step whose
    /// held-out replay does not pass the round's gate at the trust's edge (`first_step.rs`: the
    /// fit is not continued); `heldout_improvement` holds that optimum's (or that step's)
    /// relative improvement.
    HeldoutBound,
    /// Not coarse-fitted in a later round: its linear model, which round 0's coarse fit
    /// confirmed (`linear_trust`), predicts a gain that even at the trust's edge reaches neither
    /// the round's bar so far nor `min_rel_improvement`.
    TrustScreen,
    /// Not coarse-fitted after round 0: the held-out set's own linear model (its columns probed
    /// on the held-out recordings) lets no value of the candidate's parameters lower the held-out
    /// RMSE by `min_rel_improvement`, even at the trust's edge (1 / `linear_trust` times its
    /// least-squares gain; `heldout_improvement` holds that reach), and that linear model is
    /// confirmed — by round 0's coarse fit, or by one replay of the training linear step on the
    /// held-out probes' data agreeing with its prediction. Its probes and that replay are
    /// booked here.
    HeldoutLinear,
    /// Passed the held-out gate at the model's timestep but not at a finer one: the model's
    /// own time discretisation, not physics (a note). Also a merge that failed at the model's
    /// timestep, tested again at the finer one (`kept` = merged there).
    Discretisation,
    /// Two effects fitted together (the pair look-ahead).
    Pair,
    /// Not fitted in full: the early pair look-ahead's pair whose coarse fit — or, before it,
    /// its linear prediction at the trust's edge (`pair_screen.rs`) — leaves more on the
    /// screen's data than the floor allows on the whole training set (`pair_reach.rs`).
    PairFloor,
    /// Not fitted in full: a pair whose coarse fit (or, before it, its linear prediction at the
    /// trust's edge) leaves no less on the screen's data than `pair_gain` × the round's winner
    /// alone does there (`pair_reach.rs`); a joint pair whose prediction at the trust's edge
    /// does not lower its better member's RMSE there by `min_rel_improvement` (`pairs.rs`).
    PairScreen,
    /// A single effect re-fitted by a failed pair, competing with the round's winner.
    PairRestart,
    /// The same effect on two joints fitted jointly when no single one passed.
    JointPair,
    /// Joint polish of every kept parameter.
    Polish,
    /// The simplification passes as a whole.
    Simplify,
    /// Removal test (`kept` = the effect stays).
    Drop,
    /// Removal with the other effects fitted again (`kept` = the effect stays).
    DropRefit,
    /// One effect on two joint sets as one group (`kept` = merged).
    Merge,
    /// An effect taken over by another on the same joints (`kept` = folded).
    Fold,
    /// A friction variant beside plain friction replaced by the plain one (`kept` = replaced).
    PlainFriction,
    /// Replacement by a simpler effect (`kept` = the swap was made).
    Swap,
    /// A swap not fitted in full: its coarse fit could not come close.
    SwapScreen,
    /// Dry friction re-fitted on short windows (`kept` = the re-fit replaced its values).
    Reshoot,
    /// An effect the user named (`fit --told`), fitted without a search.
    Told,
    /// Standard errors of the kept set.
    StandardErrors,
    /// The search has ended.
    Done,
}

impl Phase {
    /// The phase as the log and the progress line spell it.
    pub fn name(self) -> &'static str {
        match self {
            Phase::Diagnose => "diagnose",
            Phase::Add => "add",
            Phase::LeadFit => "lead_fit",
            Phase::Judge => "judge",
            Phase::EarlyPair => "early_pair",
            Phase::Refine => "refine",
            Phase::RoundErrors => "round_standard_errors",
            Phase::Reach => "reach",
            Phase::AddCoarse => "add_coarse",
            Phase::Screen => "screen",
            Phase::Floor => "floor",
            Phase::JointFloor => "joint_floor",
            Phase::FloorScreen => "floor_screen",
            Phase::ReachScreen => "reach_screen",
            Phase::HeldoutScreen => "heldout_screen",
            Phase::DiscretisationScreen => "discretisation_screen",
            Phase::HeldoutBound => "heldout_bound",
            Phase::TrustScreen => "trust_screen",
            Phase::HeldoutLinear => "heldout_linear",
            Phase::Discretisation => "discretisation",
            Phase::Pair => "pair",
            Phase::PairFloor => "pair_floor",
            Phase::PairScreen => "pair_screen",
            Phase::PairRestart => "pair_restart",
            Phase::JointPair => "joint_pair",
            Phase::Polish => "polish",
            Phase::Simplify => "simplify",
            Phase::Drop => "drop",
            Phase::DropRefit => "drop_refit",
            Phase::Merge => "merge",
            Phase::Fold => "fold",
            Phase::PlainFriction => "plain_friction",
            Phase::Swap => "swap",
            Phase::SwapScreen => "swap_screen",
            Phase::Reshoot => "reshoot",
            Phase::Told => "told",
            Phase::StandardErrors => "standard_errors",
            Phase::Done => "done",
        }
    }
}

/// What a progress line says the search is doing in a phase.
impl std::fmt::Display for Phase {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Phase::Add => "fit",
            Phase::Pair => "pair look-ahead",
            Phase::JointPair => "joint pairs",
            Phase::DropRefit => "drop with re-fit",
            Phase::StandardErrors => "standard errors",
            p => p.name(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn z_grows_with_the_number_of_candidates() {
        let p = SearchPolicy::default();
        assert_eq!(p.z_needed(1), 2.0);
        assert_eq!(p.z_needed(4), 2.0);
        assert!((p.z_needed(8) - 2.3466).abs() < 1e-3);
        assert!((p.z_needed(16) - 2.6931).abs() < 1e-3);
    }

    #[test]
    fn fewer_parameters_win_within_one_percent() {
        let p = SearchPolicy::default();
        assert!(p.beats((1.0, 2), None));
        // Fewer parameters: within 1 % is enough.
        assert!(p.beats((1.009, 1), Some((1.0, 2))));
        assert!(!p.beats((1.02, 1), Some((1.0, 2))));
        // More parameters: must be lower by more than 1 %.
        assert!(!p.beats((0.995, 3), Some((1.0, 2))));
        assert!(p.beats((0.98, 3), Some((1.0, 2))));
        // Same count: any lower RMSE.
        assert!(p.beats((0.999, 2), Some((1.0, 2))));
        assert!(!p.beats((1.0, 2), Some((1.0, 2))));
    }

    /// Every policy field is in the table, and docs/fitting.md holds the generated table
    /// (`MODELLINT_UPDATE_DOCS=1` rewrites it).
    #[test]
    fn the_policy_table_is_complete_and_in_the_docs() {
        let v = serde_json::to_value(SearchPolicy::default()).unwrap();
        let keys: Vec<&String> = v.as_object().unwrap().keys().collect();
        assert_eq!(keys.len(), FIELDS.len());
        for k in keys {
            assert!(FIELDS.iter().any(|(n, ..)| n == k), "{k} is not in FIELDS");
        }
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/fitting.md");
        let doc = std::fs::read_to_string(&path).expect("docs/fitting.md");
        let table = SearchPolicy::default().table();
        let want = crate::fit::effects::docs::splice(&doc, "policy", &table)
            .expect("docs/fitting.md: no `<!-- generated: policy -->`");
        if want != doc && std::env::var_os("MODELLINT_UPDATE_DOCS").is_some() {
            std::fs::write(&path, &want).expect("write docs/fitting.md");
            return;
        }
        assert!(want == doc, "docs/fitting.md's policy table differs: MODELLINT_UPDATE_DOCS=1");
    }

    #[test]
    fn phases_serialise_as_their_names() {
        for p in [Phase::Add, Phase::FloorScreen, Phase::PairRestart, Phase::StandardErrors] {
            assert_eq!(serde_json::to_value(p).unwrap(), serde_json::json!(p.name()));
        }
    }
}
