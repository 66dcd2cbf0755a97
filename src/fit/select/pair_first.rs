//! The pair look-ahead before the rivals' full fits: when the round's lead is kept but leaves
//! more than noise ([`super::lead`]), the lead is paired with its best coarse-fitted rivals on
//! its joints before any of them is fitted in full.
//!
//! The look-ahead ([`pair_lookahead`]) needs of a partner only its values, to start the joint
//! fit from, and its held-out figure, to rank it: the rival's coarse fit (on the screen's data)
//! gives both, the held-out figure by the one replay the held-out screen makes before a full
//! fit anyway. A pair that passes the look-ahead against the lead — the same tests as against
//! a round's winner: held-out beyond noise and by `pair_gain`, each member needed, BIC down,
//! beyond the model's discretisation — and leaves a white training residual on every fitted
//! joint is the round's best so far: its gain on the screen's data is the bar (`screen_share`)
//! every candidate still to be taken must reach to be fitted in full, and it is judged as a kept
//! candidate at the floor is (only aliases on its joints, of at most its parameters, are still
//! screened). At the end of the round the pair stands unless a single candidate fitted after it
//! leaves a held-out error the pair would not replace (below the pair's / `pair_gain`): then the
//! round ends as it would have without the early look-ahead. A pair short of the floor is not
//! taken: another pair of the round's full fits may explain more (on the arm3 conceal case of
//! armature + damping on the elbow, a delay + armature pair leaves a held-out error 3.4 × its
//! floor where the round's full fits find the true pair), so a pair whose coarse fit leaves
//! more on the screen's data than the floor allows on the whole training set is not fitted in
//! full ([`super::pair_reach`]: `tried` phase `pair_floor`).
//!
//! On arm2's delay + Coulomb pair the lead (the delay on both joints) leaves a training error
//! 15 times the pair's, which is at the floor: the singles' coarse fits all fall below the
//! pair's bar and none of the nine rivals is fitted in full.

use std::collections::BTreeMap;

use crate::fit::effects::Applied;
use crate::sim2real::recording::Recording;

use super::coarse::{self, Coarse};
use super::groups::Cand;
use super::pairs::{needless, pair_lookahead};
use super::verdict::verdict;
use super::{Errors, FitOutcome, Search, Selected};

type Evidence = BTreeMap<String, f64>;

/// A pair kept by the early look-ahead: its members (as the round returns them), its held-out
/// RMSE and its training RMSE on the screen's data.
pub(super) struct EarlyPair {
    pub(super) members: Vec<(Selected, Applied)>,
    pub(super) heldout_rmse: f64,
    pub(super) short_rmse: f64,
    /// Its training RMSE on the whole training set (a white residual on every fitted joint:
    /// [`super::Engine::at_floor`]).
    pub(super) train_rmse: f64,
    /// The model with the pair.
    pub(super) set: Vec<Applied>,
    /// `out.applied` and `out.selected` as the look-ahead left them (earlier effects re-fitted).
    after: (Vec<Applied>, Vec<Selected>),
    notes: Vec<String>,
    kept_logs: Vec<usize>,
}

/// The candidates of `cands` whose coarse fit (`coarse`, same order; not one deferred to its
/// plain variant's) passes `reaches` (given its RMSE on the screen's data), as fitted there,
/// best first, with their evidence.
pub(super) fn rivals(
    (cands, coarse): (&[Cand], &[Coarse]),
    reaches: impl Fn(f64) -> bool,
) -> Vec<(Applied, Evidence)> {
    let mut v: Vec<((Applied, Evidence), f64)> = cands
        .iter()
        .zip(coarse)
        .filter_map(|((e, g, ev), c)| {
            let c = c.clone()?;
            let ok = !coarse::is_deferred(&c) && c.1.is_finite() && reaches(c.1);
            ok.then(|| ((Applied { effect: *e, joints: g.clone(), params: c.0 }, ev.clone()), c.1))
        })
        .collect();
    v.sort_by(|a, b| a.1.total_cmp(&b.1));
    v.into_iter().map(|(a, _)| a).collect()
}

/// The look-ahead of `lead` (kept, on `applied`) with `rivals` (coarse fits on the screen's
/// data `short`, best first; those sharing none of the lead's joints are passed over): the
/// three best that lower the held-out error at their coarse fit (`ho_err`: without the
/// candidate) are its partners. `None` when no pair passes; `out` is then as it was, but for
/// the pairs logged in `tried`.
pub(super) fn early_pair(
    s: &Search,
    (short, applied): (&[Recording], &[Applied]),
    lead: &Selected,
    rivals: &[(Applied, Evidence)],
    ho_err: &Errors,
    (z, round): (f64, usize),
    out: &mut FitOutcome,
) -> Option<EarlyPair> {
    let engine = s.engine;
    engine.report(round, super::policy::Phase::EarlyPair, None);
    let policy = &engine.opts.policy;
    // (A lead that needs no partner is not paired: no rival is replayed for it.)
    if needless(engine.opts, lead) {
        return None;
    }
    let mut kept = vec![lead.clone()];
    for (a, ev) in rivals {
        // (The lead and its partners: as many as the look-ahead pairs.)
        if kept.len() >= policy.pair_candidates {
            break;
        }
        if !a.joints.iter().any(|j| lead.joints.contains(j)) {
            continue;
        }
        let mut t = applied.to_vec();
        t.push(a.clone());
        let Some(h) = engine.errors(s.heldout, &t) else { continue };
        let v = verdict(ho_err, &h, &a.joints, policy.gate_z(z));
        if v.rel <= 0.0 {
            continue;
        }
        let nan = (f64::NAN, f64::NAN);
        kept.push(Selected::new(a, ev.clone(), &v, ho_err.rmse(), h.rmse(), nan));
    }
    if kept.len() < 2 {
        return None;
    }
    // The look-ahead may carry re-fitted values into `out`, add notes and mark its choice
    // kept: all of that is held back until the round takes the pair ([`EarlyPair::take`]).
    let (applied0, selected0, notes0) =
        (out.applied.clone(), out.selected.clone(), out.notes.len());
    let logged0 = out.tried.len();
    let res = pair_lookahead(s, applied, &kept, lead, (z, round), true, out);
    let kept_logs: Vec<usize> = (logged0..out.tried.len()).filter(|&i| out.tried[i].kept).collect();
    kept_logs.iter().for_each(|&i| out.tried[i].kept = false);
    let notes = out.notes.split_off(notes0);
    let after = (
        std::mem::replace(&mut out.applied, applied0),
        std::mem::replace(&mut out.selected, selected0),
    );
    let members = res.filter(|r| r.len() == 2)?;
    let mut set = after.0.clone();
    set.extend(members.iter().map(|(_, a)| a.clone()));
    let short_rmse = engine.errors(short, &set)?.rmse();
    let t = engine.errors(s.train, &set)?;
    // A pair short of the floor leaves room for another pair (or a single and a later round)
    // that the round's full fits would find: the round goes on as without it.
    if !engine.at_floor(s.train, &set, &t) {
        return None;
    }
    let heldout_rmse = members[0].0.heldout_rmse_after;
    let train_rmse = t.rmse();
    Some(EarlyPair { members, heldout_rmse, short_rmse, train_rmse, set, after, notes, kept_logs })
}

impl EarlyPair {
    /// Its parameters and its joints (in the order of `joints`, as a candidate's group).
    pub(super) fn floored(&self, joints: &[String]) -> (usize, Vec<String>) {
        let k = self.members.iter().map(|(_, a)| a.effect.fitted()).sum();
        let on = |j: &String| self.members.iter().any(|(_, a)| a.joints.contains(j));
        (k, joints.iter().filter(|j| on(j)).cloned().collect())
    }

    /// Takes the pair as the round's result: `out` as the look-ahead left it; the members to add.
    pub(super) fn take(self, out: &mut FitOutcome) -> Vec<(Selected, Applied)> {
        (out.applied, out.selected) = self.after;
        out.notes.extend(self.notes);
        self.kept_logs.iter().for_each(|&i| out.tried[i].kept = true);
        self.members
    }
}
