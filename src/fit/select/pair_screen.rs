//! The pair look-ahead's linear screen: what two candidates fitted together can explain, from
//! their single fits, before any joint fit.
//!
//! Each member's single fit moved the simulation from the model without it; that change on the
//! screen's data is a secant column of the member (one replay per member). The least-squares
//! combination of a pair's two columns predicts the pair's joint fit: two columns that are
//! nearly orthogonal add up (the greedy rounds find the second member after the first), two
//! that mimic each other explain what their difference does. The look-ahead fits pairs
//! coarsely in the order of these predictions, and leaves out a pair whose prediction cannot
//! come within `pair_full_fit_within` of the best coarse fit so far (on arm2's delay + Coulomb
//! pair, the predictions of the twelve pairs were within 15 % of their coarse fits but one).
//!
//! **The prediction at the trust's edge** ([`PairPrediction::reachable`]). What the pair's
//! columns explain beyond its better member alone (that member's RMSE on the screen's data
//! minus the pair's prediction, rad) is the partner's predicted gain; a coarse fit that confirms
//! its linear model gains at most 1 / `linear_trust` times its prediction (the trust a single
//! candidate's coarse fit is judged by, [`super::trust`]), so the pair's fit is taken to leave at
//! least R = member − (member − pair) / `linear_trust` there. Each test a pair's coarse fit would
//! take is first taken by R, before any replay of the pair: the look-ahead leaves out a pair
//! with R ≥ `pair_gain` × the winner's RMSE there (`pair_screen`) or, keeping only a pair at the
//! floor, R² × n above the floor's allowance ([`super::pair_reach`], `pair_floor`); the joint
//! pairs (no single passed) leave out one with R above (1 − `min_rel_improvement`) × the better
//! member's RMSE ([`PairPrediction::adds_nothing`]: the weaker member is not needed). What this
//! assumes is that the pair's joint optimum lies near the span of its members' single-fit
//! changes: two columns that mimic each other (their overlap) or cancel are in the prediction,
//! a joint optimum far from both single fits (a non-smooth member at another value) is not.
//! On the three-joint leg with a play behind every motor (KR7) the group's exception on the hip
//! is left out this way (predicted 6.36 mrad on the screen's data; its simplex coarse fit, 126
//! rollouts, had left 6.42); on the pendulum with a Coulomb friction (KR3) the servo's gain
//! error beside the friction (predicted 2.12 mrad; the coarse fit, 87 rollouts, left 2.38,
//! above the friction alone); on the leg with a missing rotor inertia (KR8) the gain error +
//! delay pairs beside the inertia, which added 0.4 % to the delay alone in full fits, are left
//! out of the joint pairs.

use std::collections::HashMap;

use rayon::prelude::*;

use crate::fit::effects::Applied;
use crate::sim2real::recording::Recording;

use super::SearchPolicy;
use super::engine::{Engine, set_key};
use super::screen::combine;

/// For each pair `(a, b)` of `sets` added to `applied`, what the linear model of its members'
/// single fits predicts on `short` (see the module docs); `None` where a replay failed or the
/// columns do not line up (the pair is then fitted).
pub(super) fn predicted(
    engine: &Engine,
    short: &[Recording],
    applied: &[Applied],
    sets: &[(Applied, Applied)],
) -> Vec<Option<PairPrediction>> {
    let Some(r0) = engine.residuals(short, applied, &engine.joints, usize::MAX) else {
        return vec![None; sets.len()];
    };
    let key = |a: &Applied| set_key(short, std::slice::from_ref(a));
    let mut members: Vec<&Applied> = Vec::new();
    for (a, b) in sets {
        for m in [a, b] {
            if !members.iter().any(|x| key(x) == key(m)) {
                members.push(m);
            }
        }
    }
    // Each member's column: the change its single fit makes to the simulation (r0 − r).
    let cols: HashMap<String, Vec<f64>> = members
        .par_iter()
        .filter_map(|m| {
            let mut set = applied.to_vec();
            set.push((*m).clone());
            let r = engine.residuals(short, &set, &engine.joints, usize::MAX)?;
            (r.len() == r0.len()).then(|| (key(m), r0.iter().zip(&r).map(|(x, y)| x - y).collect()))
        })
        .collect();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let ss = dot(&r0, &r0);
    let n = r0.len().max(1) as f64;
    let rmse = |sse: f64| (sse.max(0.0) / n).sqrt();
    sets.iter()
        .map(|(a, b)| {
            let (ca, cb) = (cols.get(&key(a))?, cols.get(&key(b))?);
            let g = vec![vec![dot(ca, ca), dot(ca, cb)], vec![dot(cb, ca), dot(cb, cb)]];
            let (explained, _) = combine(&[dot(ca, &r0), dot(cb, &r0)], &g);
            // A member alone at its single fit: |r0 − c|² = |r0|² − 2 c·r0 + |c|².
            let alone = |c: &[f64]| rmse(ss - 2.0 * dot(c, &r0) + dot(c, c));
            let pair = rmse(ss - explained);
            Some(PairPrediction { pair, member: alone(ca).min(alone(cb)).max(pair) })
        })
        .collect()
}

/// Whether the pair `(a, b)` holds the winner `w` at some of its values: `w` is a member, or
/// the pair is `w`'s effect on a group with an exception (the same effect on one part of `w`'s
/// joints and on the rest: both at `w`'s value are `w`).
pub(super) fn holds((a, b): (&Applied, &Applied), w: &Applied) -> bool {
    let same = |x: &Applied| x.effect.id() == w.effect.id() && x.joints == w.joints;
    fn sorted(mut j: Vec<&String>) -> Vec<&String> {
        j.sort();
        j.dedup();
        j
    }
    same(a)
        || same(b)
        || (a.effect.id() == w.effect.id()
            && b.effect.id() == w.effect.id()
            && !a.joints.iter().any(|j| b.joints.contains(j))
            && sorted(a.joints.iter().chain(&b.joints).collect())
                == sorted(w.joints.iter().collect()))
}

/// What the linear model of a pair's members predicts on the screen's data [rad RMSE].
#[derive(Debug, Clone, Copy)]
pub(super) struct PairPrediction {
    /// The pair: the least-squares combination of its members' columns.
    pub(super) pair: f64,
    /// The better member alone at its single fit (at least `pair`).
    pub(super) member: f64,
}

impl PairPrediction {
    /// The least RMSE the pair's fit can leave on the screen's data by this prediction: the
    /// gain the linear model predicts beyond the better member (`member` − `pair`) taken at the
    /// trust's edge, 1 / `linear_trust` times it — as a candidate's coarse fit that confirms
    /// its linear model gains at most that much ([`super::trust`]) [rad RMSE].
    pub(super) fn reachable(&self, pol: &SearchPolicy) -> f64 {
        (self.member - (self.member - self.pair) / pol.linear_trust).max(0.0)
    }

    /// The prediction with the start `rmse` (the round's winner on the screen's data, when the
    /// pair holds it: [`holds`]) as the member to gain beyond, when lower: the pair's fit
    /// reaches it at the winner's values.
    pub(super) fn beyond_winner(self, rmse: f64) -> Self {
        let member = self.member.min(rmse).max(self.pair);
        PairPrediction { member, ..self }
    }

    /// The least RMSE the look-ahead takes the pair's fit to leave on the screen's data
    /// ([`PairPrediction::reachable`]), its gain counted from the winner's RMSE there
    /// (`f_single`) when the pair holds the winner (`held`, [`holds`]:
    /// [`PairPrediction::beyond_winner`]) [rad RMSE].
    pub(super) fn reach(self, held: bool, f_single: f64, pol: &SearchPolicy) -> f64 {
        if held { self.beyond_winner(f_single) } else { self }.reachable(pol)
    }

    /// Whether, by [`PairPrediction::reachable`], the pair's fit cannot lower the better
    /// member's RMSE on the screen's data by `min_rel_improvement`: the weaker member is not
    /// needed in it (removing it is worse by less than the gate asks).
    pub(super) fn adds_nothing(&self, pol: &SearchPolicy) -> bool {
        self.reachable(pol) > (1.0 - pol.min_rel_improvement) * self.member
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reachable RMSE takes the predicted gain beyond the better member at the trust's
    /// edge; a pair adds nothing when even that gain stays below the gate's improvement.
    #[test]
    fn the_reachable_rmse_takes_the_gain_beyond_the_member_at_the_trust_edge() {
        let pol = SearchPolicy::default();
        let lt = pol.linear_trust;
        let p = PairPrediction { pair: 0.9, member: 1.0 };
        assert!((p.reachable(&pol) - (1.0 - 0.1 / lt)).abs() < 1e-12);
        assert!(!p.adds_nothing(&pol));
        // A gain beyond the member just short of / just past trust × the gate's improvement.
        let small = pol.min_rel_improvement * lt;
        let short_of = PairPrediction { pair: 1.0 - 0.9 * small, member: 1.0 };
        let past = PairPrediction { pair: 1.0 - 1.1 * small, member: 1.0 };
        assert!(short_of.adds_nothing(&pol) && !past.adds_nothing(&pol));
        // Never below zero.
        assert_eq!(PairPrediction { pair: 0.0, member: 1.0 }.reachable(&pol), 0.0);
    }

    /// A pair holds the winner when the winner is a member, or when it is the winner's effect
    /// on a split of the winner's joints (a group with an exception); not another effect, nor a
    /// split that misses or shares a joint. From the winner, the predicted gain is taken beyond
    /// the winner's RMSE when that is lower than the better member's.
    #[test]
    fn a_pair_holds_the_winner_as_a_member_or_as_a_split_group() {
        use crate::fit::effects::{ActionDelay, Backlash, Effect, GainError};
        let on = |effect: &'static dyn Effect, j: &[&str]| Applied {
            effect,
            joints: j.iter().map(|s| s.to_string()).collect(),
            params: effect.params().iter().map(|p| p.default).collect(),
        };
        let w = on(&Backlash, &["hip", "knee", "ankle"]);
        assert!(holds((&on(&Backlash, &["knee"]), &on(&Backlash, &["hip", "ankle"])), &w));
        assert!(holds((&on(&GainError, &["hip"]), &w.clone()), &w));
        assert!(!holds((&on(&Backlash, &["knee"]), &on(&Backlash, &["hip"])), &w));
        assert!(!holds((&on(&Backlash, &["knee", "hip"]), &on(&Backlash, &["hip", "ankle"])), &w));
        assert!(!holds((&on(&GainError, &["knee"]), &on(&ActionDelay, &["hip", "ankle"])), &w));
        let p = PairPrediction { pair: 0.9, member: 1.2 };
        assert_eq!(p.beyond_winner(1.0).member, 1.0);
        assert_eq!(p.beyond_winner(1.5).member, 1.2);
        assert_eq!(p.beyond_winner(0.5).member, 0.9);
    }

    /// A joint pair whose weaker member adds nothing beyond the better one is judged from the
    /// members' single fits and not fitted: on the pendulum servo recorded with a gain error
    /// (kp × 0.8, kd × 0.7), a delay mimics part of it alone, but beside the gain error it
    /// explains nothing more. The premise is checked apart, by the joint fit the screen saves
    /// (Levenberg–Marquardt on the whole training set): there the delay is not needed.
    #[test]
    fn a_joint_pair_whose_partner_adds_nothing_is_not_fitted() {
        use crate::fit::effects::{ActionDelay, Effect, GainError};
        use crate::fit::select::policy::Phase;
        use crate::fit::select::verdict::verdict;
        use crate::fit::select::{FitOptions, FitOutcome};
        let (robot, recs) =
            crate::synth::recorded::pendulum(Some((GainError.id(), vec![0.8, 0.7])), 4, 11);
        let j = vec!["servo".to_string()];
        let (train, heldout) = recs.split_at(3);
        let opts = FitOptions::default();
        let engine = Engine::new(&robot, &recs, &opts);
        let single = |effect: &'static dyn Effect| {
            let (p, _) = engine.fit_one(train, &[], effect, &j);
            Applied { effect, joints: j.clone(), params: p }
        };
        let fitted = vec![single(&GainError), single(&ActionDelay)];
        // The delay alone mimics part of the gain error (else there is nothing to judge).
        let base = engine.errors(train, &[]).expect("replay");
        let delay = engine.errors(train, &fitted[1..]).expect("replay");
        assert!(delay.rmse() < 0.9 * base.rmse(), "{} of {}", delay.rmse(), base.rmse());
        let ho = engine.errors(heldout, &[]).expect("replay");
        let floors = engine.floors(train, &[], &base);
        let mut out = FitOutcome::empty(String::new());
        let before = engine.rollout_stats().simulated_s;
        let kept = super::super::pairs::joint_pairs(
            &engine,
            (train, train, heldout),
            (&[], &fitted),
            (&base, &ho),
            &floors,
            opts.policy.z_decision,
            0,
            &mut out,
        );
        let cost = engine.rollout_stats().simulated_s - before;
        assert!(!kept && out.applied.is_empty(), "{:?}", out.tried);
        let screened = out.tried.iter().find(|t| t.phase == Phase::PairScreen).expect("screened");
        assert!(screened.predicted.is_some() && screened.train_rmse.is_nan(), "{screened:?}");
        assert!(!out.tried.iter().any(|t| t.phase == Phase::JointPair), "{:?}", out.tried);
        // No pair replayed: at most one replay of each member (its column) on the training set.
        let secs: f64 = train.iter().map(|r| r.t.last().unwrap() - r.t[0]).sum();
        assert!(cost <= 2.0 * secs + 1e-6, "{cost} s replayed for {secs} s of training data");
        // The joint fit the screen saved: the delay is not needed beside the gain error.
        let pair = crate::fit::select::polish::fit_jointly(&engine, train, fitted.clone(), 0);
        let h = engine.errors(heldout, &pair).expect("replay");
        let without = engine.errors(heldout, &pair[..1]).expect("replay");
        let v = verdict(&without, &h, &j, opts.policy.gate());
        assert!(
            !(v.significant && v.rel >= opts.policy.min_rel_improvement),
            "the delay was needed: {} vs {} ({:?})",
            h.rmse(),
            without.rmse(),
            pair.iter().map(|a| a.params.clone()).collect::<Vec<_>>()
        );
    }
}
