//! Effects fitted together: the pair look-ahead after a round's winner, the known mimicking
//! pairs ([`effects::mimicking_pairs`]) when no single effect passes, and the joint re-fit of
//! several effects' parameters.

use std::collections::BTreeMap;

use crate::fit::effects::{self, Applied};
use crate::fit::stats::bic;
use crate::sim2real::recording::Recording;

use super::discretisation::{Judged, beyond_discretisation, pair_beyond_discretisation};
use super::engine::Engine;
use super::extension;
use super::pair_restart::{apply_restart, best_restart};
use super::policy::Phase;
use super::polish::{fit_jointly, fit_jointly_iters, polish_budget, polish_from, polish_set};
use super::screen::{Prediction, screen_data};
use super::verdict::{Verdict, verdict};
use super::{Errors, FitOutcome, Floor, Search, Selected, Tried, set_uncertainty, sync_selected};
use super::{pair_reach, pair_screen};

/// Look-ahead for two effects that only make sense together (extra inertia *and* damping: each
/// alone is mimicked by a delay or a gain error). The top four kept candidates of the round are
/// paired when they act on the same joints (not two friction models; one effect on a group and
/// on one of its members becomes the group with an exception; a candidate kept at its coarse
/// fit pairs only in those two ways, [`gated_at_coarse`]), each pair is fitted
/// jointly from the two single fits (coarsely first; fully when within 25 % of the best pair's
/// training RMSE), and the best pair replaces the single winner when it is
/// ≥ 10 % better on held-out (and beyond noise), and each member is needed in it (removing
/// either is worse beyond noise), and the pair still beats the winner alone with both replayed
/// at a finer timestep ([`pair_beyond_discretisation`]: a partner that only takes up the
/// model's own step beside the winner is a note). The pair with fewer parameters wins within 1 %. The winner
/// with the effects kept in earlier rounds on its joints re-fitted beside it
/// ([`with_kept_refitted`]) competes as a restart of the winner. With `to_floor` (the early
/// look-ahead, which keeps a pair only at the floor) a pair whose coarse fit cannot reach the
/// floor is not fitted in full; in either, one whose coarse fit leaves more on the screen's
/// data than `pair_gain` × the winner alone's RMSE, or does not lower the held-out error below
/// the winner's, is not ([`pair_reach`]).
pub(super) fn pair_lookahead(
    s: &Search,
    applied: &[Applied],
    kept: &[Selected],
    single: &Selected,
    (z, round): (f64, usize),
    to_floor: bool,
    out: &mut FitOutcome,
) -> Option<Vec<(Selected, Applied)>> {
    let Search { engine, train, heldout, allowed, .. } = *s;
    let opts = engine.opts;
    // The best kept candidates of the round, but not one gated at its coarse fit
    // ([`gated_at_coarse`]): it pairs only as a mimicking partner or a group's exception.
    let mut top: Vec<&Selected> = kept.iter().filter(|c| !gated_at_coarse(out, round, c)).collect();
    top.sort_by(|a, b| a.heldout_rmse_after.total_cmp(&b.heldout_rmse_after));
    top.truncate(opts.policy.pair_candidates);
    if needless(opts, single) {
        return None;
    }
    let as_applied = |s: &Selected| Applied {
        effect: effects::by_id(&s.effect).expect("known"),
        joints: s.joints.clone(),
        params: s.values.clone(),
    };
    let mut with_single = applied.to_vec();
    with_single.push(as_applied(single));
    // Nor does one that leaves a white training residual on every fitted joint: what is left
    // is noise, quantisation and command reconstruction (the floor that stops the rounds), and a
    // partner has nothing to explain. (The held-out test cannot show this: its improvement is
    // bounded by the same floor, e.g. 94 % on arm2's elbow damping.)
    let t_single = engine.errors(train, &with_single)?;
    if engine.at_floor(train, &with_single, &t_single) {
        return None;
    }
    let h_single = engine.errors(heldout, &with_single)?;
    let h_base = engine.errors(heldout, applied)?;
    let t_base = engine.errors(train, applied)?;
    let k_before: usize = applied.iter().map(|a| a.effect.fitted()).sum();
    // The round's floors (remembered per set: the greedy round measured them).
    let floors = engine.floors(train, applied, &t_base);
    let mut best: Option<(Vec<Applied>, f64, usize, usize)> = None;
    // (The early look-ahead's replays are booked apart: [`Phase::EarlyPair`].)
    let booked = if to_floor { Phase::EarlyPair } else { Phase::Pair };
    engine.report(round, booked, None);
    // The pairs of the top four, and any two kept candidates that mimic each other alone
    // ([`effects::mimicking_pairs`]) wherever they rank: a missing inertia and damping each
    // pass alone, and a third effect can outrank one of them (the pendulum's armature, fifth).
    // Likewise one effect kept on a joint and on a group holding it (a group with an exception).
    let mut pairs: Vec<(&Selected, &Selected)> = Vec::new();
    for i in 0..top.len() {
        for j in i + 1..top.len() {
            pairs.push((top[i], top[j]));
        }
    }
    let mimic = effects::mimicking_pairs();
    let inside = |a: &Selected, b: &Selected| {
        a.effect == b.effect
            && a.joints.len() < b.joints.len()
            && a.joints.iter().all(|j| b.joints.contains(j))
    };
    for a in kept {
        for b in kept {
            // (Also one effect on a joint and on a group holding it, wherever they rank.)
            let listed =
                mimic.iter().any(|(x, y)| x.id() == a.effect && y.id() == b.effect) || inside(a, b);
            let seen = pairs.iter().any(|(p, q)| {
                (std::ptr::eq(*p, a) && std::ptr::eq(*q, b))
                    || (std::ptr::eq(*p, b) && std::ptr::eq(*q, a))
            });
            if listed && !seen {
                pairs.push((a, b));
            }
        }
    }
    // The pairs as sets to fit: (first member, second member).
    let mut sets: Vec<(Applied, Applied)> = Vec::new();
    for (a, b) in pairs {
        if !a.joints.iter().any(|x| b.joints.contains(x)) {
            continue;
        }
        // One effect on a group and on one of its members: the group with an exception (its
        // own value on that member), e.g. damping on every joint and more on the elbow, which a
        // gain error on the elbow would otherwise mimic.
        let (a, b) = if a.effect == b.effect {
            let (small, big) = match (inside(a, b), inside(b, a)) {
                (true, _) => (a, b),
                (_, true) => (b, a),
                _ => continue,
            };
            let mut rest = as_applied(big);
            rest.joints.retain(|j| !small.joints.contains(j));
            (as_applied(small), rest)
        } else {
            // Two friction models are two descriptions of one loss, not a pair.
            if [&a.effect, &b.effect]
                .iter()
                .all(|id| effects::by_id(id).is_some_and(|e| e.friction()))
            {
                continue;
            }
            (as_applied(a), as_applied(b))
        };
        sets.push((a, b));
    }
    // A winner with two or more parameters can stand in for two one-parameter effects that
    // mimic each other alone (a servo gain error for damping + armature: its kd term is the
    // damping, its kp term the inertia; load-dependent friction for Coulomb friction + armature:
    // its load term follows the servo torque, hence the acceleration). Neither member needs to
    // have been kept, or even tried, on the winner's joints (the diagnosis may rank Coulomb
    // friction on another joint first), so the known mimicking pairs
    // ([`effects::mimicking_pairs`]) with at most one parameter more than the winner are also
    // fitted there, from fresh single fits, and compete with the winner.
    let k_single = effects::by_id(&single.effect).map_or(0, |e| e.fitted());
    if k_single >= 2 {
        let joints = &single.joints;
        let member = |e: &'static dyn effects::Effect| -> Option<Applied> {
            if let Some(k) = kept.iter().find(|k| k.effect == e.id() && &k.joints == joints) {
                return Some(as_applied(k));
            }
            // A richer model of a loss starts from its plain variant's fit taken over: the pair
            // is judged from its members' columns there and fitted from there, and the member's
            // own full fit (a simplex of 2 (k - 1) x `max_evals` whole-set replays; K7's
            // Stribeck friction on the ankle 6,114 s) would serve only as that start.
            if let Some(params) = extension::plain_start(s, (train, applied), (e, joints)) {
                return Some(Applied { effect: e, joints: joints.clone(), params });
            }
            let (params, f) = engine.fit_one(train, applied, e, joints);
            f.is_finite().then(|| Applied { effect: e, joints: joints.clone(), params })
        };
        for (ea, eb) in effects::mimicking_pairs() {
            let on = |x: &Applied, e: &'static dyn effects::Effect| {
                x.effect.id() == e.id() && &x.joints == joints
            };
            if ea.fitted() + eb.fitted() > k_single + 1
                || ![ea.id(), eb.id()].iter().all(|id| allowed.iter().any(|x| x == id))
                || sets.iter().any(|(a, b)| (on(a, ea) && on(b, eb)) || (on(a, eb) && on(b, ea)))
            {
                continue;
            }
            if let (Some(a), Some(b)) = (member(ea), member(eb)) {
                sets.push((a, b));
            }
        }
    }
    // Each pair is first fitted coarsely (two thirds of a single fit's budget) on the round's
    // screen data (the stretch of each training episode where the residual is largest); only
    // those within `pair_full_fit_within` of the best coarse RMSE there are fitted fully on the
    // whole training set. A pair of smooth effects is a least-squares problem in its own
    // parameters (Levenberg–Marquardt from the two single fits, the kept set held; k + 1
    // replays an iteration, stopping at the recordings' resolution); a pair with a non-smooth
    // member is polished with every kept parameter by the simplex.
    let n = applied.len();
    let smooth = |set: &[Applied]| set[n..].iter().all(|a| a.effect.smooth());
    let short = engine.screen_set(train, applied, || screen_data(engine, train, &t_base));
    let n_sets = sets.len();
    // What the floor allows on the whole training set ([`pair_reach`]), when the look-ahead
    // keeps only a pair at the floor.
    let allowance = to_floor.then(|| {
        let f_single = engine.floors(train, &with_single, &t_single);
        pair_reach::floor_allowance(engine, train, &[&floors, &f_single])
    });
    // The winner alone on the screen's data: a pair must fit them better ([`pair_reach`]).
    let f_single = engine.errors(&short, &with_single).map_or(f64::INFINITY, |e| e.rmse());
    let n_short = engine.errors(&short, applied).map_or(0, |e| e.n) as f64;
    // Best predicted first ([`pair_screen`]); a pair whose prediction cannot come within
    // `pair_full_fit_within` of the best coarse fit so far is not fitted, nor one whose
    // prediction, at the trust's edge, cannot pass the tests its coarse fit would take
    // ([`pair_reach`]: the floor's allowance, `pair_gain` × the winner there).
    let predicted = pair_screen::predicted(engine, &short, applied, &sets);
    let mut order: Vec<usize> = (0..n_sets).collect();
    let rank = |i: usize| predicted[i].map_or(0.0, |p| p.pair);
    order.sort_by(|&i, &j| rank(i).total_cmp(&rank(j)));
    let mut coarse: Vec<Option<(Vec<Applied>, f64)>> = vec![None; n_sets];
    let mut best_coarse = f64::INFINITY;
    for i in order {
        if predicted[i].is_some_and(|p| p.pair > opts.policy.pair_full_fit_within * best_coarse) {
            continue;
        }
        if let Some(p) = predicted[i] {
            // A pair that holds the winner reaches the winner's RMSE: its gain counts from there.
            let held = pair_screen::holds((&sets[i].0, &sets[i].1), &with_single[n]);
            let r = p.reach(held, f_single, &opts.policy);
            let phase = if allowance.is_some_and(|a| r * r * n_short > a) {
                Some(Phase::PairFloor)
            } else {
                (r >= opts.policy.pair_gain * f_single).then_some(Phase::PairScreen)
            };
            if let Some(phase) = phase {
                let (a, b) = &sets[i];
                let group: Vec<String> = a.joints.iter().chain(&b.joints).cloned().collect();
                out.tried.push(predicted_out((round, phase), (a, b), &group, p));
                continue;
            }
        }
        let (a, b) = &sets[i];
        engine.report(
            round,
            booked,
            Some((i + 1, n_sets, format!("coarse {} + {}", a.effect.id(), b.effect.id()))),
        );
        let mut set = applied.to_vec();
        set.push(a.clone());
        set.push(b.clone());
        let set = if smooth(&set) {
            let k: usize = set[n..].iter().map(|a| a.effect.fitted()).sum();
            let iters = (opts.policy.max_evals * 2 / 3 / (k + 2)).clamp(2, 12);
            fit_jointly_iters(engine, &short, set, n, iters)
        } else {
            polish_budget(
                engine,
                &short,
                heldout,
                set,
                opts.policy.coarse_polish_step,
                opts.policy.max_evals * 2 / 3,
            )
        };
        let f = engine.errors(&short, &set).map_or(f64::INFINITY, |e| e.rmse());
        best_coarse = best_coarse.min(f);
        coarse[i] = Some((set, f));
    }
    let mut restarts: Vec<Vec<Applied>> = Vec::new();
    for (i, ((a, b), c)) in sets.into_iter().zip(coarse).enumerate() {
        let Some((set, f)) = c else { continue };
        engine.report(
            round,
            booked,
            Some((i + 1, n_sets, format!("{} + {}", a.effect.id(), b.effect.id()))),
        );
        let group: Vec<String> = a.joints.iter().chain(&b.joints).cloned().collect();
        let full = f <= opts.policy.pair_full_fit_within * best_coarse;
        let judged = (&short[..], &set[..], f);
        if full
            && let Some(phase) = screened(s, judged, (&h_single, f_single), &group, z, allowance)
        {
            let params = set[n..]
                .iter()
                .flat_map(|x| x.params.iter().take(x.effect.fitted()).copied())
                .collect();
            let id = format!("{}+{}", a.effect.id(), b.effect.id());
            out.tried.push(Tried::not_tested(round, phase, &id, &group, params, f));
            continue;
        }
        let set = if full {
            if smooth(&set) {
                fit_jointly(engine, train, set, n)
            } else {
                polish_set(engine, train, heldout, set, opts.policy.polish_step)
            }
        } else {
            set
        };
        let (Some(h), Some(t)) = (engine.errors(heldout, &set), engine.errors(train, &set)) else {
            continue;
        };
        let k = a.effect.fitted() + b.effect.fitted();
        let v = verdict(&h_single, &h, &group, opts.policy.gate_z(z));
        let bic_ok = bic(t.n, t.sse, k_before + k) < bic(t_base.n, t_base.sse, k_before);
        // Each member needed: the pair beats the set without it beyond noise.
        let need: Vec<bool> = (0..2)
            .map(|m| {
                let mut wo = set.clone();
                wo.remove(applied.len() + m);
                engine.errors(heldout, &wo).is_some_and(|hw| {
                    let vw = verdict(&hw, &h, &set[applied.len() + m].joints, opts.policy.gate());
                    vw.significant && vw.rel >= opts.policy.min_rel_improvement
                })
            })
            .collect();
        let needed = need.iter().all(|&x| x);
        // One member not needed: the other, at the values the joint fit gave it, is a restart
        // of its single fit and competes with the winner as a single effect. So is the winner
        // itself at the values the pair gave it.
        let is_winner = |m: usize| {
            let a = &set[applied.len() + m];
            a.effect.id() == single.effect && a.joints == single.joints
        };
        for m in 0..2 {
            if (!need[m] && need[1 - m]) || is_winner(1 - m) {
                let mut wo = set.clone();
                wo.remove(applied.len() + m);
                restarts.push(wo);
            }
        }
        // A partner that only takes up the model's time discretisation beside the winner
        // does not improve on it at a finer step: the test a single candidate takes.
        let judged = Judged {
            base: applied,
            trial: &set,
            gate: opts.policy.gate_z(z),
            floors: &floors,
            round,
        };
        let ok = h.rmse() < opts.policy.pair_gain * h_single.rmse()
            && v.significant
            && bic_ok
            && needed
            && pair_beyond_discretisation(engine, heldout, &with_single[n], &judged, out);
        let logged = out.log(Tried {
            round,
            phase: Phase::Pair,
            effect: format!("{}+{}", a.effect.id(), b.effect.id()),
            joints: group.clone(),
            params: set[applied.len()..]
                .iter()
                .flat_map(|x| x.params.iter().take(x.effect.fitted()).copied())
                .collect(),
            train_rmse: t.rmse(),
            heldout_improvement: (h_base.rmse() - h.rmse()) / h_base.rmse().max(1e-300),
            significant: v.significant,
            bic_decreased: bic_ok,
            kept: false,
            predicted: None,
            simulated_s: None,
        });
        if !ok {
            continue;
        }
        if opts.policy.beats((h.rmse(), k), best.as_ref().map(|(_, r, kb, _)| (*r, *kb))) {
            best = Some((set, h.rmse(), k, logged));
        }
    }
    // The winner beside the effects kept in earlier rounds, each fitted without it: one on the
    // winner's joints may hold part of its signature (Coulomb friction fitted alone takes up
    // part of a delay's lag), which the winner's own fit cannot give back. Those effects are
    // re-fitted with the winner, coarsely on the screen's data; the set is a restart of the
    // winner (the same model at other values) and replaces it when better on both training
    // and held-out data. Otherwise the next round would hunt for what the biased value leaves.
    restarts.extend(with_kept_refitted(s, &short, applied, as_applied(single)));
    // A restart competes with the best pair by the same rule as two pairs: a single effect
    // that a failed pair re-fitted (a servo gain at 1.0 beside a 15 ms delay on Asimov's knee)
    // must not lose to a mimicking pair (damping + armature) it beats on held-out.
    let restart = best_restart(s, applied, single, (&h_base, &h_single), restarts, round, out);
    if let Some((rset, rh, rt, logged)) = restart {
        let kr = rset[n].effect.fitted();
        if opts.policy.beats((rh.rmse(), kr), best.as_ref().map(|(_, r, kb, _)| (*r, *kb))) {
            return apply_restart(
                s,
                applied,
                kept,
                single,
                (&h_base, &h_single, &t_base),
                (rset, rh, rt, logged),
                z,
                out,
            );
        }
    }
    let (set, rmse, _, logged) = best?;
    out.tried[logged].kept = true;
    let what = if set[n].effect.id() == set[n + 1].effect.id() {
        format!(
            "{} on {} with its own value and on {} with a shared one",
            set[n].effect.id(),
            set[n].joints.join(","),
            set[n + 1].joints.join(",")
        )
    } else {
        format!(
            "{} and {} on {} fitted together",
            set[n].effect.id(),
            set[n + 1].effect.id(),
            set[n].joints.join(",")
        )
    };
    out.notes.push(format!(
        "{what}: held-out RMSE {:.3e} rad, vs {:.3e} with {} alone",
        rmse,
        h_single.rmse(),
        single.effect
    ));
    let t_pair = engine.errors(train, &set)?;
    let h_pair = engine.errors(heldout, &set)?;
    let k_pair: usize = set.iter().map(|a| a.effect.fitted()).sum();
    let mut res = Vec::new();
    for m in 0..2 {
        let a = set[n + m].clone();
        let mut wo = set.clone();
        wo.remove(n + m);
        let (hw, tw) = (engine.errors(heldout, &wo)?, engine.errors(train, &wo)?);
        let v = verdict(&hw, &h_pair, &a.joints, opts.policy.gate());
        let evidence = kept
            .iter()
            .find(|s| s.effect == a.effect.id() && s.joints == a.joints)
            .map(|s| s.evidence.clone())
            .unwrap_or_default();
        let bics =
            (bic(tw.n, tw.sse, k_pair - a.effect.fitted()), bic(t_pair.n, t_pair.sse, k_pair));
        let s = Selected::new(&a, evidence, &v, hw.rmse(), rmse, bics);
        res.push((s, a));
    }
    // The polish may have moved the effects kept earlier: carry them over.
    out.applied[..n].clone_from_slice(&set[..n]);
    sync_selected(out);
    Some(res)
}

/// Whether the kept candidate `c` was judged at its coarse fit in round `round` (`tried`: phase
/// `add_coarse`, [`super::winner::beaten_at_coarse`]): a kept candidate of the round left at
/// most (1 − `decisive_improvement`) × its held-out RMSE there. Such a rival is not among the
/// round's best that the look-ahead pairs whatever their effects: the greedy rounds find a
/// second effect that adds to the winner; what the look-ahead is for — effects that explain
/// the data only together — it still finds as a mimicking pair ([`effects::mimicking_pairs`])
/// or a group with an exception, wherever the members rank.
fn gated_at_coarse(out: &FitOutcome, round: usize, c: &Selected) -> bool {
    out.tried.iter().any(|t| {
        t.round == round
            && t.phase == Phase::AddCoarse
            && t.effect == c.effect
            && t.joints == c.joints
    })
}

/// A single effect that leaves under `pair_needless_improvement` of the held-out error needs
/// no partner.
pub(super) fn needless(opts: &super::FitOptions, single: &Selected) -> bool {
    single.heldout_improvement >= opts.policy.pair_needless_improvement
}

/// The `tried` entry of the pair `(a, b)` left out by its linear prediction `p`
/// ([`pair_screen`]) in phase `phase`, on `group`: not fitted (no training RMSE), its members'
/// single-fit values as its parameters and the predicted RMSE on the screen's data.
pub(super) fn predicted_out(
    (round, phase): (usize, Phase),
    (a, b): (&Applied, &Applied),
    group: &[String],
    p: pair_screen::PairPrediction,
) -> Tried {
    let id = format!("{}+{}", a.effect.id(), b.effect.id());
    let params = [a, b].into_iter().flat_map(|x| x.params.iter().take(x.effect.fitted()).copied());
    let mut t = Tried::not_tested(round, phase, &id, group, params.collect(), f64::NAN);
    t.predicted = Some(Prediction { train_rmse: p.pair, step: f64::NAN });
    t
}

/// The phase a pair's coarse fit `set` (RMSE `f` on the screen's data `short`) is logged with
/// when it is not fitted in full ([`pair_reach`]): `pair_floor` when it leaves more there than
/// `allowance` (the floor's squared residual on the whole training set; `None`: no floor
/// asked), `pair_screen` when it leaves more there than `pair_gain` × the single winner's RMSE
/// at its values (`f_single`), `heldout_screen` when, replayed on the held-out set, it does not
/// lower the error below the single winner's (`h_single`) on the pair's joints `group`.
fn screened(
    s: &Search,
    (short, set, f): (&[Recording], &[Applied], f64),
    (h_single, f_single): (&Errors, f64),
    group: &[String],
    z: f64,
    allowance: Option<f64>,
) -> Option<Phase> {
    let engine = s.engine;
    if let Some(a) = allowance
        && engine.errors(short, set).is_none_or(|e| e.sse > a)
    {
        return Some(Phase::PairFloor);
    }
    if !(f < engine.opts.policy.pair_gain * f_single) {
        return Some(Phase::PairScreen);
    }
    let gate = engine.opts.policy.gate_z(z);
    let h = engine.errors(s.heldout, set);
    h.is_none_or(|h| verdict(h_single, &h, group, gate).rel <= 0.0).then_some(Phase::HeldoutScreen)
}

/// The training RMSE of `applied` + `winner` re-fitted as [`with_kept_refitted`] does, when that
/// leaves a white residual on every fitted joint ([`Engine::at_floor`]); `None` otherwise or when
/// no kept effect shares a joint with the winner. The same re-fit in the look-ahead is answered
/// by the rollout memo when the winner's values did not move.
pub(super) fn refitted_at_floor(
    s: &Search,
    short: &[Recording],
    applied: &[Applied],
    winner: &Applied,
) -> Option<f64> {
    let set = with_kept_refitted(s, short, applied, winner.clone())?;
    let t = s.engine.errors(s.train, &set)?;
    s.engine.at_floor(s.train, &set, &t).then(|| t.rmse())
}

/// `applied` + `winner` with the winner and the kept effects that share a joint with it fitted
/// together on `short` (the round's screen data), from their values, with a pair's coarse budget
/// (Levenberg–Marquardt when all of them are smooth, else the simplex); the kept effects on
/// other joints stay as they are. `None` when no kept effect shares a joint with the winner.
fn with_kept_refitted(
    s: &Search,
    short: &[Recording],
    applied: &[Applied],
    winner: Applied,
) -> Option<Vec<Applied>> {
    let (engine, policy) = (s.engine, &s.engine.opts.policy);
    let n = applied.len();
    let shares = |a: &Applied| a.joints.iter().any(|j| winner.joints.contains(j));
    let (free, fixed): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| shares(&applied[i]));
    if free.is_empty() {
        return None;
    }
    // The fixed effects first, then the freed ones and the winner (fitted from `first`).
    let order: Vec<usize> = fixed.iter().chain(&free).copied().collect();
    let mut set: Vec<Applied> = order.iter().map(|&i| applied[i].clone()).collect();
    set.push(winner);
    let first = fixed.len();
    let set = if set[first..].iter().all(|a| a.effect.smooth()) {
        let k: usize = set[first..].iter().map(|a| a.effect.fitted()).sum();
        let iters = (policy.max_evals * 2 / 3 / (k + 2)).clamp(2, 12);
        fit_jointly_iters(engine, short, set, first, iters)
    } else {
        let budget = (policy.coarse_polish_step, policy.max_evals * 2 / 3);
        polish_from(engine, (short, s.heldout), set, first, budget)
    };
    // Back in the kept order, the winner last.
    let mut back: Vec<Option<Applied>> = vec![None; n];
    for (k, &i) in order.iter().enumerate() {
        back[i] = Some(set[k].clone());
    }
    let mut out: Vec<Applied> = back.into_iter().collect::<Option<_>>()?;
    out.push(set[n].clone());
    Some(out)
}

/// When no single candidate passed the held-out gate: fit the pairs of effects that mimic each
/// other alone but not together ([`effects::mimicking_pairs`]) whose members were
/// both fitted on the same joint group this round, jointly from their single fits, and keep the
/// best pair that passes the gate as a whole (beyond noise against the model without it, BIC
/// down) with each member needed (removing either is worse beyond noise), and the pair physics
/// beyond the model's time discretisation ([`beyond_discretisation`], the test a single smooth
/// candidate takes: a gain error and a delay fitted together can stand in for the integrator's
/// phase lag).
#[allow(clippy::too_many_arguments)]
pub(super) fn joint_pairs(
    engine: &Engine,
    (short, train, heldout): (&[Recording], &[Recording], &[Recording]),
    (applied, fitted): (&[Applied], &[Applied]),
    (tr_err, ho_err): (&Errors, &Errors),
    floors: &[Floor],
    z: f64,
    round: usize,
    out: &mut FitOutcome,
) -> bool {
    let opts = engine.opts;
    let n = applied.len();
    let k_before: usize = applied.iter().map(|a| a.effect.fitted()).sum();
    let bic_before = bic(tr_err.n, tr_err.sse, k_before);
    let mut best: Option<(Vec<Applied>, Errors, Verdict, f64, usize)> = None;
    engine.report(round, Phase::JointPair, None);
    let mut sets: Vec<(Applied, Applied)> = Vec::new();
    for (ea, eb) in effects::mimicking_pairs().into_iter().map(|(a, b)| (a.id(), b.id())) {
        for a in fitted.iter().filter(|x| x.effect.id() == ea) {
            if let Some(b) = fitted.iter().find(|x| x.effect.id() == eb && x.joints == a.joints) {
                sets.push((a.clone(), b.clone()));
            }
        }
    }
    // Judged first from the members' own fits ([`pair_screen`]): a pair whose linear
    // prediction, at the trust's edge, does not lower its better member's RMSE on the screen's
    // data by `min_rel_improvement` has a member that is not needed, and is not fitted.
    let predicted = pair_screen::predicted(engine, short, applied, &sets);
    for ((a, b), p) in sets.iter().zip(predicted) {
        if let Some(p) = p.filter(|p| p.adds_nothing(&opts.policy)) {
            out.tried.push(predicted_out((round, Phase::PairScreen), (a, b), &a.joints, p));
            continue;
        }
        let (ea, eb) = (a.effect.id(), b.effect.id());
        let mut set = applied.to_vec();
        set.push(a.clone());
        set.push(b.clone());
        let set = fit_jointly(engine, train, set, n);
        let (Some(h), Some(t)) = (engine.errors(heldout, &set), engine.errors(train, &set)) else {
            continue;
        };
        let k = a.effect.fitted() + b.effect.fitted();
        let v = verdict(ho_err, &h, &a.joints, opts.policy.gate_z(z));
        let bic_after = bic(t.n, t.sse, k_before + k);
        let needed = (0..2).all(|m| {
            let mut wo = set.clone();
            wo.remove(n + m);
            engine.errors(heldout, &wo).is_some_and(|hw| {
                let vw = verdict(&hw, &h, &a.joints, opts.policy.gate());
                vw.significant && vw.rel >= opts.policy.min_rel_improvement
            })
        });
        let judged =
            |set| Judged { base: applied, trial: set, gate: opts.policy.gate_z(z), floors, round };
        let ok = v.significant
            && v.rel >= opts.policy.min_rel_improvement
            && bic_after < bic_before
            && needed
            && beyond_discretisation(engine, heldout, &judged(&set), out);
        let logged = out.log(Tried {
            round,
            phase: Phase::JointPair,
            effect: format!("{ea}+{eb}"),
            joints: a.joints.clone(),
            params: set[n..]
                .iter()
                .flat_map(|x| x.params.iter().take(x.effect.fitted()).copied())
                .collect(),
            train_rmse: t.rmse(),
            heldout_improvement: v.rel,
            significant: v.significant,
            bic_decreased: bic_after < bic_before,
            kept: false,
            predicted: None,
            simulated_s: None,
        });
        if ok && best.as_ref().is_none_or(|(_, hb, ..)| h.rmse() < hb.rmse()) {
            best = Some((set, h, v, bic_after, logged));
        }
    }
    let Some((set, h, v, bic_after, logged)) = best else { return false };
    out.tried[logged].kept = true;
    out.notes.push(format!(
        "no single effect passed; {} and {} on {} pass together: held-out RMSE {:.3e} → {:.3e} rad",
        set[n].effect.id(),
        set[n + 1].effect.id(),
        set[n].joints.join(","),
        ho_err.rmse(),
        h.rmse()
    ));
    for m in 0..2 {
        let a = set[n + m].clone();
        let mut sel = Selected::new(
            &a,
            BTreeMap::new(),
            &v,
            ho_err.rmse(),
            h.rmse(),
            (bic_before, bic_after),
        );
        out.applied.push(a);
        set_uncertainty(engine, train, &mut sel, &out.applied, &mut out.warnings);
        out.selected.push(sel);
    }
    true
}
