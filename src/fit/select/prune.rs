//! Occam's removals after the greedy rounds: drop an effect no longer needed (alone, or with
//! the others re-fitted), swap one for a simpler effect on the same joints.

use std::collections::BTreeMap;

use crate::fit::effects::{self, Applied};
use crate::fit::stats::{bic, bic_pieces};

use super::policy::{Phase, SearchPolicy};
use super::polish::{fit_jointly, polish_set};
use super::reach::Reach;
use super::verdict::verdict;
use super::{Errors, FitOutcome, Search, Selected, Tried, set_uncertainty, sync_selected};

/// Drops, last kept first. Returns `true` when an effect was dropped.
pub(super) fn drop_pass(s: &Search, round: usize, out: &mut FitOutcome) -> bool {
    let Search { engine, train, heldout, .. } = *s;
    let opts = engine.opts;
    let mut changed = false;
    let mut i = out.applied.len();
    while i > 0 {
        i -= 1;
        let mut without = out.applied.clone();
        without.remove(i);
        let (Some(h_full), Some(h_wo), Some(t_full), Some(t_wo)) = (
            engine.errors(heldout, &out.applied),
            engine.errors(heldout, &without),
            engine.errors(train, &out.applied),
            engine.errors(train, &without),
        ) else {
            continue;
        };
        let a = &out.applied[i];
        let v = verdict(&h_wo, &h_full, &a.joints, opts.policy.gate());
        let k_full: usize = out.applied.iter().map(|a| a.effect.fitted()).sum();
        let bic_dec =
            bic(t_full.n, t_full.sse, k_full) < bic(t_wo.n, t_wo.sse, k_full - a.effect.fitted());
        let keep = v.significant && v.rel >= opts.policy.min_rel_improvement;
        out.tried.push(Tried {
            round,
            phase: Phase::Drop,
            effect: a.effect.id().into(),
            joints: a.joints.clone(),
            params: a.params.clone(),
            train_rmse: t_full.rmse(),
            heldout_improvement: v.rel,
            significant: v.significant,
            bic_decreased: bic_dec,
            kept: keep,
            predicted: None,
            simulated_s: None,
        });
        if !keep {
            out.notes.push(format!(
                "{} on {} dropped: with the other effects, removing it changes the held-out RMSE by {:+.1} % (not beyond noise)",
                a.effect.id(),
                a.joints.join(","),
                -100.0 * v.rel
            ));
            out.applied.remove(i);
            out.selected.remove(i);
            changed = true;
        }
    }
    changed
}

/// Drops with a re-fit: of three or more kept effects, one can be needed only because the
/// others were fitted without the effect that came later (a servo gain error taken with an
/// armature before the friction was found absorbs part of the friction, and the drop test,
/// which keeps the others' values, still needs it). Each effect in turn is removed and the
/// rest fitted jointly again; the removal is made when that set is as good as the current one
/// on the test of a merge (held-out RMSE within 5 %, not worse beyond noise, training BIC
/// counted per window not higher, [`bic_pieces`]). Of several, the one with the lowest held-out RMSE. (With two kept effects the
/// re-fitted remainder is a single effect, which the greedy round already fitted.)
/// Returns `true` when an effect was dropped.
pub(super) fn refit_drop_pass(s: &Search, round: usize, out: &mut FitOutcome) -> bool {
    let Search { engine, train, heldout, .. } = *s;
    let n = out.applied.len();
    if n < 3 {
        return false;
    }
    let (Some(h_cur), Some(t_cur)) =
        (engine.errors(heldout, &out.applied), engine.errors(train, &out.applied))
    else {
        return false;
    };
    let k_all: usize = out.applied.iter().map(|a| a.effect.fitted()).sum();
    let mut best: Option<(usize, Vec<Applied>, f64)> = None;
    for i in (0..n).rev() {
        let cur = out.applied[i].clone();
        engine.report(round, Phase::DropRefit, Some((n - i, n, cur.effect.id().to_string())));
        let mut rest = out.applied.clone();
        rest.remove(i);
        let rest = fit_jointly(engine, train, rest, 0);
        let (Some(h1), Some(t1)) = (engine.errors(heldout, &rest), engine.errors(train, &rest))
        else {
            continue;
        };
        let k_rest = k_all - cur.effect.fitted();
        let (ok, worse, bic_ok) = simpler_set_ok(
            &engine.opts.policy,
            (&h1, &t1, k_rest),
            (&h_cur, &t_cur, k_all),
            &cur.joints,
            true,
            false,
        );
        out.tried.push(Tried {
            round,
            phase: Phase::DropRefit,
            effect: cur.effect.id().into(),
            joints: cur.joints.clone(),
            params: cur.params.clone(),
            train_rmse: t1.rmse(),
            heldout_improvement: (h_cur.rmse() - h1.rmse()) / h_cur.rmse().max(1e-300),
            significant: worse,
            bic_decreased: bic_ok,
            kept: !ok,
            predicted: None,
            simulated_s: None,
        });
        if ok && best.as_ref().is_none_or(|(_, _, r)| h1.rmse() < *r) {
            best = Some((i, rest, h1.rmse()));
        }
    }
    let Some((i, rest, rmse)) = best else { return false };
    let cur = &out.applied[i];
    out.notes.push(format!(
        "{} on {} dropped: the other effects, fitted again without it, explain the data as well (held-out RMSE {:.3e} → {:.3e} rad)",
        cur.effect.id(),
        cur.joints.join(","),
        h_cur.rmse(),
        rmse
    ));
    out.selected.remove(i);
    out.applied = rest;
    sync_selected(out);
    true
}

/// The test of a simpler set (a merge, fold or swap of two kept effects, or a drop with
/// re-fit) against the current one: the new set's `(held-out, training, fitted parameters)`
/// against the current set's, on `joints` (the new or dropped effect's). Held-out RMSE within
/// 5 %, not worse beyond noise, and a training BIC that is not higher — counted per window
/// ([`bic_pieces`]) when `per_window`, per sample otherwise, and not asked when `agree` (the
/// merged values agree within their standard errors). Per window for a merge and a drop with
/// re-fit: the question is whether the data need the extra parameter at all, and per sample a
/// parameter that follows a systematic hair reads as evidence (an external-load friction of
/// 0.037 invented next to a Coulomb friction on a wrist, recordings of an independent
/// simulator: held-out 0.5 % better with it, not beyond noise, training SSE 0.4 % lower).
/// Returns (made, worse beyond noise, BIC not higher).
pub(super) fn simpler_set_ok(
    p: &SearchPolicy,
    (h1, t1, k_new): (&Errors, &Errors, usize),
    (h_cur, t_cur, k_cur): (&Errors, &Errors, usize),
    joints: &[String],
    per_window: bool,
    agree: bool,
) -> (bool, bool, bool) {
    let worse = verdict(h1, h_cur, joints, p.noise_gate()).significant;
    let bic_ok = agree
        || if per_window {
            let m = t1.windows.len().min(t_cur.windows.len());
            bic_pieces(m, t1.n, t1.sse, k_new) <= bic_pieces(m, t_cur.n, t_cur.sse, k_cur)
        } else {
            bic(t1.n, t1.sse, k_new) <= bic(t_cur.n, t_cur.sse, k_cur)
        };
    (h1.rmse() <= p.simpler_within * h_cur.rmse() && !worse && bic_ok, worse, bic_ok)
}

/// Swaps for simpler effects. Returns `true` when a swap was made.
pub(super) fn swap_pass(s: &Search, round: usize, out: &mut FitOutcome) -> bool {
    let Search { engine, train, heldout, allowed } = *s;
    let opts = engine.opts;
    let mut changed = false;
    let mut i = 0;
    while i < out.applied.len() {
        let cur = out.applied[i].clone();
        let k_cur = cur.effect.fitted();
        let mut others = out.applied.clone();
        others.remove(i);
        let (Some(h_cur), Some(h_wo)) =
            (engine.errors(heldout, &out.applied), engine.errors(heldout, &others))
        else {
            i += 1;
            continue;
        };
        // Within 5 % of the current held-out RMSE, not worse beyond noise, and a training BIC
        // that is not higher (as in the greedy winner's choice): `simpler_set_ok`, per sample.
        let k_all: usize = out.applied.iter().map(|a| a.effect.fitted()).sum();
        let t_cur = engine.errors(train, &out.applied);
        let train_cur = t_cur.as_ref().map_or(f64::INFINITY, |e| e.rmse());
        // The screen's data for the set without `cur` (the coarse fits below are made there, on
        // the stretches `cur` had to explain; for the set a greedy round started from, they are
        // the round's own, and so are its coarse fits), and the current set's error there.
        let short_set = engine.screen_set(train, &others, || {
            match engine.errors(train, &others).or_else(|| t_cur.clone()) {
                Some(e) => super::screen::screen_data(engine, train, &e),
                None => train.to_vec(),
            }
        });
        let short = &short_set[..];
        let short_cur = engine.score(short, &out.applied);
        // At the floor, a simpler effect is first judged on the probes' data ([`Reach`]).
        let (cell, floored, current) =
            (std::cell::OnceCell::new(), out.stopped_at_floor, &out.applied);
        let current = current.clone();
        let reach = || {
            cell.get_or_init(|| floored.then(|| Reach::new(engine, short, &others, &current))?)
                .as_ref()
        };
        let mut best: Option<(Vec<Applied>, f64, usize, usize)> = None;
        for e in effects::all() {
            if !allowed.iter().any(|a| a == e.id())
                || e.id() == cur.effect.id()
                || e.fitted() >= k_cur
            {
                continue;
            }
            // On the joints of `cur` that `e` does not already act on (gain error on every
            // joint next to a damping on the elbow can become a damping on the other joints),
            // and only if `e` is a candidate on all of them (`Effect::acts_on`).
            let acts = |j: &String| {
                effects::JointTarget::of(engine.robot, j).is_none_or(|t| e.acts_on(&t))
            };
            let targets: Vec<String> = cur
                .joints
                .iter()
                .filter(|j| !others.iter().any(|a| a.effect.id() == e.id() && a.joints.contains(j)))
                .cloned()
                .collect();
            if targets.is_empty() || !cur.joints.iter().all(acts) {
                continue;
            }
            // Screen: a coarse fit (10 evaluations) of the simpler effect that leaves the
            // training error 1.5 times the current one cannot come within 5 % on held-out
            // (`tried`: phase "swap_screen"). Not when `e` already acts on some of the joints:
            // its kept parameters there only come right in the joint re-fit (polish) below.
            let partial = targets.len() < cur.joints.len();
            // (A full fit already made on this base, e.g. in round 1 when `others` is empty,
            // screens better than a coarse one and costs nothing.) Each error is compared with
            // the current set's on the same data.
            let known = engine.fit_known(train, &others, e, &targets);
            let far = (!partial && known.is_none()).then(reach).flatten();
            if let Some((p, f)) = far.and_then(|r| r.out_of_reach(s, None, (e, &targets))) {
                out.tried.push(Tried::not_tested(round, Phase::SwapScreen, e.id(), &targets, p, f));
                continue;
            }
            let (pc, fc, on) = match known {
                Some((p, f)) => (p, f, train_cur),
                None => {
                    let (p, f) =
                        engine.fit_budget(short, &others, e, &targets, opts.policy.screen_evals);
                    (p, f, short_cur)
                }
            };
            if !partial
                && (pc.is_empty() || !fc.is_finite() || fc > opts.policy.floor_screen_ratio * on)
            {
                out.tried.push(Tried::not_tested(
                    round,
                    Phase::SwapScreen,
                    e.id(),
                    &targets,
                    pc,
                    fc,
                ));
                continue;
            }
            let start = (!pc.is_empty() && fc.is_finite()).then_some(pc.as_slice());
            let (p, tr) = engine.fit_from(train, &others, (e, &targets), start);
            if p.is_empty() || !tr.is_finite() {
                continue;
            }
            let mut set = others.clone();
            set.push(Applied { effect: e, joints: targets.clone(), params: p });
            let Some(h0) = engine.errors(heldout, &set) else { continue };
            // Hopeless before polishing: skip the joint re-fit (unless `e` acts on other
            // joints too, whose kept parameters only come right in it).
            let set = if (partial || h0.rmse() <= h_cur.rmse() * opts.policy.swap_polish_within)
                && set.len() >= 2
            {
                polish_set(engine, train, heldout, set, engine.opts.policy.polish_step)
            } else {
                set
            };
            let Some(h1) = engine.errors(heldout, &set) else { continue };
            let k_set = k_all - k_cur + e.fitted();
            let t_set = engine.errors(train, &set);
            let (ok, worse, bic_ok) = match (&t_set, &t_cur) {
                (Some(t), Some(tc)) => simpler_set_ok(
                    &engine.opts.policy,
                    (&h1, t, k_set),
                    (&h_cur, tc, k_all),
                    &cur.joints,
                    false,
                    false,
                ),
                _ => (
                    false,
                    verdict(&h1, &h_cur, &cur.joints, opts.policy.noise_gate()).significant,
                    false,
                ),
            };
            let logged = out.log(Tried {
                round,
                phase: Phase::Swap,
                effect: e.id().into(),
                joints: targets.clone(),
                params: set.last().expect("pushed").params.clone(),
                // After the joint re-fit (what the BIC compares).
                train_rmse: t_set.as_ref().map_or(tr, |t| t.rmse()),
                heldout_improvement: (h_cur.rmse() - h1.rmse()) / h_cur.rmse().max(1e-300),
                significant: worse,
                bic_decreased: bic_ok,
                kept: false,
                predicted: None,
                simulated_s: None,
            });
            let better = match &best {
                None => true,
                Some((_, r, k, _)) => e.fitted() < *k || (e.fitted() == *k && h1.rmse() < *r),
            };
            if ok && better {
                best = Some((set, h1.rmse(), e.fitted(), logged));
            }
        }
        let Some((set, rmse_new, _, logged)) = best else {
            i += 1;
            continue;
        };
        let new = set.last().expect("non-empty").clone();
        out.tried[logged].kept = true;
        out.notes.push(format!(
            "{} on {} replaced by the simpler {} (held-out RMSE {:.3e} → {:.3e} rad)",
            cur.effect.id(),
            cur.joints.join(","),
            new.effect.id(),
            h_cur.rmse(),
            rmse_new
        ));
        let old = out.selected.remove(i);
        out.applied = set;
        sync_selected(out);
        let (Some(t_wo), Some(t_new), Some(h_new)) = (
            engine.errors(train, &others),
            engine.errors(train, &out.applied),
            engine.errors(heldout, &out.applied),
        ) else {
            // Cannot happen (both were just simulated); keep the old effect's record shape.
            out.selected.push(old);
            changed = true;
            continue;
        };
        let k_new: usize = out.applied.iter().map(|a| a.effect.fitted()).sum();
        let v = verdict(&h_wo, &h_new, &new.joints, opts.policy.gate());
        let evidence = BTreeMap::from([(format!("replaces_{}", cur.effect.id()), 1.0)]);
        let bics =
            (bic(t_wo.n, t_wo.sse, k_new - new.effect.fitted()), bic(t_new.n, t_new.sse, k_new));
        let mut s = Selected::new(&new, evidence, &v, h_wo.rmse(), h_new.rmse(), bics);
        set_uncertainty(engine, train, &mut s, &out.applied, &mut out.warnings);
        out.selected.push(s);
        changed = true;
        // `i` now holds the next effect; the new one (last) is revisited at the end.
    }
    changed
}
