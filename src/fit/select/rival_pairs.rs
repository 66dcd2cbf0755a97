//! A beaten rival whose every pair the look-ahead would leave out by its linear screen: its
//! judgement is not made.
//!
//! A rival beaten at its coarse fit is judged at the round's end (the replay on the whole
//! training set, the held-out gate, the finer-step test) only to be a member of a pair in the
//! round's pair look-ahead ([`super::rival`]). Kept, it enters the look-ahead in nothing but
//! the pairs (a) and (b) of [`super::rival::may_pair`] with the round's kept candidates (it is
//! not among the top four the look-ahead pairs whatever their effects, being judged at its
//! coarse fit), or (c) as a fresh member on a winner of two or more parameters. The
//! look-ahead takes every pair first by its members' linear screen ([`pair_screen`]): a pair
//! whose prediction at the trust's edge ([`PairPrediction::reach`], `linear_trust`) cannot
//! leave less than `pair_gain` × the winner's RMSE on the screen's data is logged
//! (`pair_screen`) and not fitted; it replays nothing beyond its members' columns, moves no
//! other pair's prediction (each is its two columns) nor the best coarse fit the others are
//! held to (only a fitted pair sets it). So when the rival, at its coarse fit, forms only such
//! pairs — or none (a look-ahead that stops at the winner's floor forms none) — the look-ahead
//! with it kept is the look-ahead without it: its judgement cannot change the round's answer
//! nor any kept set, and is not made. Its `tried` entry stays the held-out verdict at its
//! coarse fit; its pairs are logged as the look-ahead would have logged them.
//!
//! Where this holds, and where the rival is judged as before: the prediction is made at the
//! rival's coarse fit, the values at which the judgement keeps it whenever they lower the whole
//! training set's error; taken only for a rival that its coarse fit's held-out replay already
//! passes (significant, `min_rel_improvement`), whose values a judgement has no cause to move.
//! Not where (c) applies (the look-ahead's member there is the rival itself when kept, a fresh
//! fit when not), nor where the rival may pair with another beaten rival (which may be kept, at
//! values its own judgement sets), nor where a pair's prediction fails.

use crate::fit::effects::{self, Applied, Effect};

use super::pair_screen::{self, PairPrediction};
use super::pairs::predicted_out;
use super::policy::{Phase, SearchPolicy};
use super::rival::{Beaten, RoundAt};
use super::screen::screen_data;
use super::{Search, Selected, Tried};

/// The pairs the look-ahead forms with the rival `rival` from the round's kept candidates
/// (`kept`, in the order of the log; `at`: the rival's place among them), as it forms them:
/// an effect on a group and the same effect on a member of it become the group with an
/// exception (the member, then the rest of the group at its value), a listed mimicking pair
/// ([`effects::mimicking_pairs`]) stays as it is met in the log's order; pairs that share no
/// joint, or of two friction models, are not formed.
pub(super) fn rival_sets(rival: &Applied, kept: &[Applied], at: usize) -> Vec<(Applied, Applied)> {
    let mimic = effects::mimicking_pairs();
    let inside = |a: &Applied, b: &Applied| {
        a.effect.id() == b.effect.id()
            && a.joints.len() < b.joints.len()
            && a.joints.iter().all(|j| b.joints.contains(j))
    };
    let listed = |a: &Applied, b: &Applied| {
        mimic.iter().any(|(x, y)| x.id() == a.effect.id() && y.id() == b.effect.id())
            || inside(a, b)
    };
    let mut sets = Vec::new();
    for (k, other) in kept.iter().enumerate() {
        // The look-ahead meets the pair first from the member earlier in the log.
        let (a, b) = if k < at { (other, rival) } else { (rival, other) };
        let (a, b) = if listed(a, b) {
            (a, b)
        } else if listed(b, a) {
            (b, a)
        } else {
            continue;
        };
        if !a.joints.iter().any(|x| b.joints.contains(x)) {
            continue;
        }
        if a.effect.id() == b.effect.id() {
            let (small, big) = if inside(a, b) { (a, b) } else { (b, a) };
            let mut rest = big.clone();
            rest.joints.retain(|j| !small.joints.contains(j));
            sets.push((small.clone(), rest));
        } else if !(a.effect.friction() && b.effect.friction()) {
            sets.push((a.clone(), b.clone()));
        }
    }
    sets
}

/// Whether the look-ahead leaves out the pair predicted `p` (holding the winner: `held`) by
/// its linear screen, the winner alone leaving `f_single` on the screen's data.
pub(super) fn left_out(p: PairPrediction, held: bool, f_single: f64, pol: &SearchPolicy) -> bool {
    p.reach(held, f_single, pol) >= pol.pair_gain * f_single
}

/// The records of the pairs the look-ahead after winner `w` would form with the beaten rival
/// `b` and leave out by their linear screen, when it forms no other (see the module docs):
/// its judgement is then not made. `None` (it is judged) otherwise; `passed`: its coarse fit's
/// held-out verdict passes the gate (significant, `min_rel_improvement`); `pairs_beaten`: it
/// may pair with another beaten rival.
pub(super) fn judgement_needless(
    s: &Search,
    at: &RoundAt,
    b: &Beaten,
    (w, kept): (&Selected, &[(usize, Selected)]),
    (passed, pairs_beaten): (bool, bool),
) -> Option<Vec<Tried>> {
    let (engine, pol) = (s.engine, &s.engine.opts.policy);
    let (e, group) = (b.cand.0, &b.cand.1[..]);
    let winner = effects::by_id(&w.effect)?;
    let stands_in = super::rival::may_pair((e, group), (winner, &w.joints), std::iter::empty());
    if pairs_beaten || stands_in || !passed {
        return None;
    }
    let as_applied = |k: &Selected| {
        let effect: &'static dyn Effect = effects::by_id(&k.effect)?;
        Some(Applied { effect, joints: k.joints.clone(), params: k.values.clone() })
    };
    let mut with_single = at.applied.to_vec();
    with_single.push(as_applied(w)?);
    // The look-ahead stops at a winner that leaves a white training residual.
    let t_single = engine.errors(s.train, &with_single)?;
    if engine.at_floor(s.train, &with_single, &t_single) {
        return Some(vec![]);
    }
    let rival = Applied { effect: e, joints: group.to_vec(), params: b.params.clone() };
    let others: Vec<Applied> = kept.iter().map(|(_, k)| as_applied(k)).collect::<Option<_>>()?;
    let place = kept.iter().filter(|(i, _)| *i < b.logged).count();
    let sets = rival_sets(&rival, &others, place);
    if sets.is_empty() {
        return Some(vec![]);
    }
    let short = engine.screen_set(s.train, at.applied, || screen_data(engine, s.train, at.errs.0));
    let f_single = engine.errors(&short, &with_single)?.rmse();
    let predicted = pair_screen::predicted(engine, &short, at.applied, &sets);
    let single = with_single.last()?;
    let mut out = Vec::new();
    for ((a, c), p) in sets.iter().zip(predicted) {
        let held = pair_screen::holds((a, c), single);
        if !left_out(p?, held, f_single, pol) {
            return None;
        }
        let joints: Vec<String> = a.joints.iter().chain(&c.joints).cloned().collect();
        out.push(predicted_out((at.round, Phase::PairScreen), (a, c), &joints, p?));
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::effects::{
        ActionDelay, Armature, Backlash, CoulombFriction, GainError, StribeckFriction,
    };

    fn on(effect: &'static dyn Effect, j: &[&str], v: f64) -> Applied {
        let joints = j.iter().map(|s| s.to_string()).collect();
        Applied { effect, joints, params: vec![v; effect.params().len()] }
    }

    fn ids(sets: &[(Applied, Applied)]) -> Vec<(String, Vec<String>, String, Vec<String>)> {
        let id = |a: &Applied| (a.effect.id().to_string(), a.joints.clone());
        sets.iter().map(|(a, b)| (id(a).0, id(a).1, id(b).0, id(b).1)).collect()
    }

    /// The rival inside a kept group of its effect forms the group with an exception (the
    /// rival, then the rest of the group at the kept value), wherever it stands in the log; a
    /// listed mimicking pair on a shared joint is formed in the order the look-ahead meets it
    /// (the listed order, whichever member comes first); nothing on disjoint joints, of
    /// another effect that mimics nothing, or the same effect on the same joints.
    #[test]
    fn the_rival_forms_the_pairs_the_look_ahead_forms() {
        let s = |x: &str| x.to_string();
        let all = on(&Backlash, &["hip", "knee", "ankle"], 0.03);
        let hip = on(&Backlash, &["hip"], 0.04);
        for at in [0, 1] {
            let sets = rival_sets(&hip, std::slice::from_ref(&all), at);
            let want =
                (s(Backlash.id()), vec![s("hip")], s(Backlash.id()), vec![s("knee"), s("ankle")]);
            assert_eq!(ids(&sets), vec![want], "at {at}");
            assert_eq!((sets[0].0.params[0], sets[0].1.params[0]), (0.04, 0.03));
        }
        // The rival holding a kept member of its effect: that member is the exception.
        let knee = on(&Backlash, &["knee"], 0.05);
        let sets = rival_sets(&all, std::slice::from_ref(&knee), 0);
        let want =
            (s(Backlash.id()), vec![s("knee")], s(Backlash.id()), vec![s("hip"), s("ankle")]);
        assert_eq!(ids(&sets), vec![want]);
        // A mimicking pair: (gain error, delay) as listed, either way round in the log.
        let gain = on(&GainError, &["knee"], 0.9);
        let delay = on(&ActionDelay, &["knee", "ankle"], 0.01);
        for (rival, kept) in [(&gain, &delay), (&delay, &gain)] {
            for at in [0, 1] {
                let sets = rival_sets(rival, std::slice::from_ref(kept), at);
                assert_eq!(sets.len(), 1, "{} at {at}", rival.effect.id());
                assert_eq!(
                    (sets[0].0.effect.id(), sets[0].1.effect.id()),
                    (GainError.id(), ActionDelay.id())
                );
            }
        }
        // Nothing: disjoint joints, an unlisted pair, the same group twice.
        assert!(rival_sets(&gain, &[on(&ActionDelay, &["hip"], 0.01)], 0).is_empty());
        assert!(
            rival_sets(&on(&Backlash, &["knee"], 0.04), std::slice::from_ref(&hip), 0).is_empty()
        );
        let stribeck = on(&StribeckFriction, &["knee"], 0.1);
        assert!(rival_sets(&on(&CoulombFriction, &["knee"], 0.1), &[stribeck], 0).is_empty());
        assert!(rival_sets(&hip, std::slice::from_ref(&hip), 0).is_empty());
        // One pair per listed kept partner.
        let arm = on(&Armature, &["knee"], 0.01);
        let coulomb = on(&CoulombFriction, &["knee"], 0.1);
        assert_eq!(rival_sets(&coulomb, &[arm, gain.clone(), delay], 1).len(), 2);
    }

    /// A pair is left out when its prediction at the trust's edge leaves at least `pair_gain`
    /// × the winner's RMSE; holding the winner, its gain counts from the winner's RMSE.
    #[test]
    fn a_pair_is_left_out_as_the_look_ahead_leaves_it_out() {
        let pol = SearchPolicy::default();
        let f_single = 1.0;
        // Beyond the member by d: the edge leaves member − d / trust.
        let at = |member: f64, d: f64| PairPrediction { pair: member - d, member };
        let edge = (1.0 - pol.pair_gain) * pol.linear_trust;
        assert!(left_out(at(1.0, 0.99 * edge), false, f_single, &pol));
        assert!(!left_out(at(1.0, 1.01 * edge), false, f_single, &pol));
        // Its better member far above the winner: unheld, the gain beyond that member puts it
        // within reach; holding the winner, the gain counts from the winner's RMSE, a little.
        let p = PairPrediction { pair: 0.95, member: 1.5 };
        assert!(!left_out(p, false, f_single, &pol));
        assert!(left_out(p, true, f_single, &pol));
        let p = PairPrediction { pair: 0.5, member: 1.5 };
        assert!(!left_out(p, true, f_single, &pol));
    }
}
