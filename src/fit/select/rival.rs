//! The rivals beaten at their coarse fit ([`super::winner::beaten_at_coarse`]), judged at the
//! round's end only where the pair look-ahead could pair them.
//!
//! A candidate that a kept one of the round beats decisively on held-out at its coarse fit
//! cannot win the round: the winner is the best on held-out or within `simpler_within` of it,
//! and a full fit would have to halve the held-out error the coarse fit leaves to come near
//! the one that beat it. Neither does it name a rival (that takes an equivalent one). Kept, it
//! plays one part: a member of a pair in the round's pair look-ahead
//! ([`super::pairs::pair_lookahead`]), which pairs a kept candidate judged at its coarse fit
//! only (a) with a kept partner of a mimicking pair ([`effects::mimicking_pairs`]) on a joint
//! of its group, (b) as one effect on a group and on a member of it, or (c) as a member of a
//! mimicking pair fitted on the joints of a winner of two or more parameters that the pair may
//! replace (at most one parameter more than the winner). So each such rival is first logged
//! with its held-out verdict at its coarse fit (the screen replayed it there), and its
//! judgement — the replay on the whole training set, the gate, the finer-step test — waits
//! for the round's winner: it is made only when the look-ahead runs (the winner leaves more
//! than `pair_needless_improvement` of the held-out error) and could pair it with the winner
//! or another kept candidate (or another beaten rival, which may be kept) by (a)–(c). Its
//! record then replaces the verdict logged for it, in place. Whatever the look-ahead cannot
//! pair it with, its judgement could not change: the round's answer and every kept set are
//! those of judging it at once. (On the chain leg whose three motors carry gear play, the
//! gain error on all three joints beside the kept play: its partners, a delay and Coulomb
//! friction, are left out by the screen.) Nor is one judged whose every pair the look-ahead
//! would leave out by its members' linear screen ([`super::rival_pairs`]).

use crate::fit::effects::{self, Applied, Effect};
use crate::fit::stats::bic;

use super::discretisation::{Judged, beyond_discretisation};
use super::groups::Cand;
use super::pairs::needless;
use super::policy::Phase;
use super::rival_pairs;
use super::screen::Prediction;
use super::verdict::verdict;
use super::winner::on_whole_set;
use super::{Errors, FitOutcome, Floor, Search, Selected, Tried};

/// A rival beaten at its coarse fit: the candidate, its coarse fit's parameters, its linear
/// prediction and the index of its `tried` entry (its held-out verdict at the coarse fit).
pub(super) struct Beaten {
    pub(super) cand: Cand,
    pub(super) params: Vec<f64>,
    pub(super) predicted: Option<Prediction>,
    pub(super) logged: usize,
}

/// What the round holds when its beaten rivals are judged: its base set, the base's training
/// and held-out errors, its floors, the gate's z and the round.
pub(super) struct RoundAt<'a> {
    pub(super) applied: &'a [Applied],
    pub(super) errs: (&'a Errors, &'a Errors),
    pub(super) floors: &'a [Floor],
    pub(super) z: f64,
    pub(super) round: usize,
}

/// Whether the pair look-ahead after the round, with winner `w`, could pair `e` on `group`
/// (a candidate judged at its coarse fit) with one of `others` (the round's other kept
/// candidates and beaten rivals), by (a)–(c) of the module's list.
pub(super) fn may_pair<'a>(
    (e, group): (&dyn Effect, &[String]),
    w: (&dyn Effect, &[String]),
    mut others: impl Iterator<Item = (&'a str, &'a [String])>,
) -> bool {
    let nested = |g: &[String], h: &[String]| g.len() < h.len() && g.iter().all(|j| h.contains(j));
    let mimics = effects::mimicking_pairs();
    let partners: Vec<&str> = mimics
        .iter()
        .filter_map(|(a, b)| {
            (a.id() == e.id()).then(|| b.id()).or_else(|| (b.id() == e.id()).then(|| a.id()))
        })
        .collect();
    // (c): on the winner's joints, one of a mimicking pair of at most one parameter more.
    let k = w.0.fitted();
    let stands_in = k >= 2
        && w.1 == group
        && mimics.iter().any(|(a, b)| {
            (a.id() == e.id() || b.id() == e.id()) && a.fitted() + b.fitted() <= k + 1
        });
    stands_in
        || others.any(|(x, g)| {
            (partners.contains(&x) && g.iter().any(|j| group.contains(j)))
                || (x == e.id() && (nested(g, group) || nested(group, g)))
        })
}

/// Judges the rivals `beaten` that the pair look-ahead after the round could pair
/// ([`may_pair`]) with winner `w` as a candidate of the round is judged (the replay on the
/// whole training set, the held-out gate with the training BIC, the finer-step test), and
/// returns the round's kept candidates for the look-ahead: `kept` (each with its `tried`
/// index) and the rivals kept now, in the order of the log.
pub(super) fn judge_beaten(
    s: &Search,
    at: &RoundAt,
    (mut kept, w): (Vec<(usize, Selected)>, &Selected),
    beaten: Vec<Beaten>,
    out: &mut FitOutcome,
) -> Vec<Selected> {
    let winner = effects::by_id(&w.effect);
    let ids: Vec<(&str, &[String])> = kept
        .iter()
        .map(|(_, k)| (k.effect.as_str(), &k.joints[..]))
        .chain(beaten.iter().map(|b| (b.cand.0.id(), &b.cand.1[..])))
        .collect();
    let mut judged = Vec::new();
    for (i, b) in beaten.iter().enumerate() {
        let (e, group) = (b.cand.0, &b.cand.1[..]);
        let me = kept.len() + i;
        let others = ids.iter().enumerate().filter(|(k, _)| *k != me).map(|(_, x)| *x);
        if needless(s.engine.opts, w)
            || winner.is_none_or(|x| !may_pair((e, group), (x, &w.joints), others))
        {
            continue;
        }
        // Not where every pair it could form is one the look-ahead leaves out by its linear
        // screen ([`rival_pairs`]): its pairs are logged so.
        let pol = &s.engine.opts.policy;
        let coarse = &out.tried[b.logged];
        let passed = coarse.significant && coarse.heldout_improvement >= pol.min_rel_improvement;
        let beaten_others = beaten.iter().enumerate().filter(|(k, _)| *k != i);
        let pairs_beaten = winner.is_some_and(|x| {
            may_pair(
                (e, group),
                (x, &w.joints),
                beaten_others.map(|(_, o)| (o.cand.0.id(), &o.cand.1[..])),
            )
        });
        s.engine.report(at.round, Phase::Pair, None);
        let flags = (passed, pairs_beaten);
        if let Some(left) = rival_pairs::judgement_needless(s, at, b, (w, &kept), flags) {
            out.tried.extend(left);
            continue;
        }
        s.engine.report(at.round, Phase::Judge, None);
        if let Some(sel) = judge(s, at, b, out) {
            judged.push((b.logged, sel));
        }
    }
    kept.extend(judged);
    kept.sort_by_key(|(i, _)| *i);
    kept.into_iter().map(|(_, k)| k).collect()
}

/// One beaten rival judged as the round judges a candidate after its fit; its `tried` entry
/// is replaced by that record; `Some` (its record) when kept.
fn judge(s: &Search, at: &RoundAt, b: &Beaten, out: &mut FitOutcome) -> Option<Selected> {
    let engine = s.engine;
    let (e, group, ev) = (b.cand.0, &b.cand.1, &b.cand.2);
    let (tr_err, ho_err) = at.errs;
    let not_tested = |p: Vec<f64>| Tried {
        predicted: b.predicted,
        ..Tried::not_tested(at.round, Phase::AddCoarse, e.id(), group, p, f64::NAN)
    };
    let base_train = tr_err.rmse();
    let Some((p, tr_a)) = on_whole_set(s, at.applied, (e, group), b.params.clone(), base_train)
    else {
        out.tried[b.logged] = not_tested(b.params.clone());
        return None;
    };
    let mut trial = at.applied.to_vec();
    trial.push(Applied { effect: e, joints: group.clone(), params: p.clone() });
    let ho_a = engine.errors(s.heldout, &trial)?;
    let k_before: usize = at.applied.iter().map(|a| a.effect.fitted()).sum();
    let bic_before = bic(tr_err.n, tr_err.sse, k_before);
    let bic_after = bic(tr_a.n, tr_a.sse, k_before + e.fitted());
    let gate = engine.opts.policy.gate_z(at.z);
    let v = verdict(ho_err, &ho_a, group, gate);
    let keep =
        v.significant && v.rel >= engine.opts.policy.min_rel_improvement && bic_after < bic_before;
    let judged =
        Judged { base: at.applied, trial: &trial, gate, floors: at.floors, round: at.round };
    let keep = keep && beyond_discretisation(engine, s.heldout, &judged, out);
    out.tried[b.logged] = Tried {
        train_rmse: tr_a.rmse(),
        heldout_improvement: v.rel,
        significant: v.significant,
        bic_decreased: bic_after < bic_before,
        ..not_tested(p)
    };
    let a = trial.last().expect("pushed");
    keep.then(|| {
        Selected::new(a, ev.clone(), &v, ho_err.rmse(), ho_a.rmse(), (bic_before, bic_after))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::effects::{
        ActionDelay, Armature, Backlash, CoulombFriction, GainError, PositionOffset,
        StribeckFriction, TorqueLimit,
    };

    fn j(g: &[&str]) -> Vec<String> {
        g.iter().map(|x| x.to_string()).collect()
    }

    fn may(
        e: &dyn Effect,
        g: &[String],
        w: (&dyn Effect, &[String]),
        others: &[(&dyn Effect, &Vec<String>)],
    ) -> bool {
        may_pair((e, g), w, others.iter().map(|(x, h)| (x.id(), &h[..])))
    }

    #[test]
    fn a_beaten_rival_is_judged_only_where_the_pair_look_ahead_could_pair_it() {
        let (knee, hip, both, ankle) =
            (j(&["knee"]), j(&["hip"]), j(&["hip", "knee"]), j(&["ankle"]));
        let all = j(&["hip", "knee", "ankle"]);
        let lead = (&Backlash as &dyn Effect, &all[..]);
        // The gain error beside the kept play on every joint: no delay or Coulomb friction
        // kept, the winner of one parameter: nothing to pair with.
        assert!(!may(&GainError, &all, lead, &[(&Backlash, &all), (&Armature, &all)]));
        // ... its partner kept on a joint of its group (either order of the listed pair).
        assert!(may(&GainError, &all, lead, &[(&Backlash, &all), (&ActionDelay, &knee)]));
        assert!(may(&CoulombFriction, &knee, lead, &[(&GainError, &both)]));
        assert!(may(&Armature, &both, lead, &[(&StribeckFriction, &hip)]));
        // ... but not on other joints.
        assert!(!may(&GainError, &hip, lead, &[(&ActionDelay, &ankle)]));
        // An effect of no mimicking pair: only the same effect on a group holding its joint,
        // or on a member of its group.
        assert!(!may(&TorqueLimit, &knee, lead, &[(&Armature, &knee), (&Backlash, &both)]));
        assert!(may(&TorqueLimit, &knee, lead, &[(&TorqueLimit, &both)]));
        assert!(may(&TorqueLimit, &both, lead, &[(&TorqueLimit, &hip)]));
        assert!(!may(&TorqueLimit, &knee, lead, &[(&TorqueLimit, &ankle)]));
        assert!(!may(&TorqueLimit, &knee, lead, &[(&TorqueLimit, &knee)]));
        // The play on the hip inside the kept play on every joint: a group with an exception.
        assert!(may(&Backlash, &hip, lead, &[(&Backlash, &all)]));
        // A winner of two parameters on its joints, which a mimicking pair of at most three
        // may replace: a member on exactly those joints pairs, whatever else is kept.
        let stribeck = (&StribeckFriction as &dyn Effect, &both[..]);
        assert!(StribeckFriction.fitted() >= 2);
        assert!(may(&GainError, &both, stribeck, &[]));
        assert!(may(&Backlash, &both, stribeck, &[]));
        assert!(!may(&GainError, &knee, stribeck, &[]));
        assert!(!may(&TorqueLimit, &both, stribeck, &[]));
        // ... not beside a winner of one parameter.
        assert!(!may(&GainError, &both, (&Backlash, &both), &[]));
        assert!(!may(&PositionOffset, &ankle, lead, &[(&GainError, &ankle)]));
    }
}
