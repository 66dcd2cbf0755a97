//! Occam's pass after the greedy rounds (drop effects no longer needed, swap one for a simpler
//! effect) and the joint polish of every kept effect's parameters.

use std::collections::BTreeMap;

use crate::fit::effects::{self, Applied};
use crate::fit::optim::{Bounds, NelderMeadOpts, nelder_mead};
use crate::fit::stats::bic;
use crate::sim2real::recording::Recording;

use super::engine::Engine;
use super::pairs::{fit_jointly, param_slots, with_params};
use super::verdict::verdict;
use super::{FitOutcome, Search, Selected, Tried, set_uncertainty, sync_selected};

/// Occam's pass over the kept effects, judged on the held-out set:
/// * **drop** an effect whose removal does not make the held-out error worse beyond noise (it
///   was needed only before a later effect explained the same thing);
/// * **swap** an effect for one with fewer parameters on the same joints (re-fitted, then all
///   parameters polished together) when the simpler set is not worse beyond noise: held-out
///   RMSE within min(1 % of it, 5 % of what the effect explains) and no significant paired
///   difference. Example: Stribeck friction with its velocity scale at the bound is Coulomb
///   friction; a servo gain error whose only change is kd is joint damping.
///
/// Returns `true` when the set changed.
pub(super) fn simplify(s: &Search, round: usize, out: &mut FitOutcome) -> bool {
    let mut changed = false;
    // Each swap removes at least one parameter, so this ends.
    loop {
        changed |= drop_pass(s, round, out);
        if !merge_pass(s, round, out)
            && !refit_drop_pass(s, round, out)
            && !swap_pass(s, round, out)
        {
            return changed;
        }
        changed = true;
    }
}

/// Merges one effect kept on two disjoint joint sets into one group sharing one parameter
/// vector when the data do not tell the two apart (a delay found on the shoulder, then on the
/// elbow, both 12 ms, is one delay on the arm): the group is fitted, all kept parameters
/// polished, and the merge kept on the same test as a swap (held-out RMSE within 5 %, not worse
/// beyond noise, a training BIC that is not higher). Returns `true` when a merge was made.
fn merge_pass(s: &Search, round: usize, out: &mut FitOutcome) -> bool {
    let Search { engine, train, heldout, .. } = *s;
    let opts = engine.opts;
    let n = out.applied.len();
    // Errors of the current set (held-out, training): the same for every candidate pair,
    // simulated once, when the first pair qualifies.
    let mut current = None;
    for (i, j) in (0..n).flat_map(|i| (i + 1..n).map(move |j| (i, j))) {
        let (a, b) = (&out.applied[i], &out.applied[j]);
        if a.effect.id() != b.effect.id() || a.joints.iter().any(|x| b.joints.contains(x)) {
            continue;
        }
        let effect = a.effect;
        // The group in the model's joint order.
        let joints: Vec<String> = engine
            .robot
            .joints
            .iter()
            .map(|x| &x.name)
            .filter(|n| a.joints.contains(n) || b.joints.contains(n))
            .cloned()
            .collect();
        let mut others = out.applied.clone();
        others.remove(j);
        others.remove(i);
        if !engine.shared_start(effect, &others, &joints) {
            continue;
        }
        let (Some(h_cur), Some(t_cur)) = current.get_or_insert_with(|| {
            (engine.errors(heldout, &out.applied), engine.errors(train, &out.applied))
        }) else {
            continue;
        };
        let (p, tr) = engine.fit_one(train, &others, effect, &joints);
        if p.is_empty() || !tr.is_finite() {
            continue;
        }
        let mut set = others.clone();
        set.push(Applied { effect, joints: joints.clone(), params: p });
        let set = if set.len() >= 2 { polish_set(engine, train, heldout, set, 0.02) } else { set };
        let (Some(h1), Some(t1), Some(h_wo), Some(t_wo)) = (
            engine.errors(heldout, &set),
            engine.errors(train, &set),
            engine.errors(heldout, &others),
            engine.errors(train, &others),
        ) else {
            continue;
        };
        let k_all: usize = out.applied.iter().map(|a| a.effect.fitted()).sum();
        let k_set = k_all - effect.fitted();
        let worse = verdict(&h1, h_cur, &joints, 2.0, f64::INFINITY);
        let bic_ok = bic(t1.n, t1.sse, k_set) <= bic(t_cur.n, t_cur.sse, k_all);
        let ok = h1.rmse() <= 1.05 * h_cur.rmse() && !worse.significant && bic_ok;
        let new = set.last().expect("pushed").clone();
        out.tried.push(Tried {
            round,
            phase: "merge",
            effect: effect.id().into(),
            joints: joints.clone(),
            params: new.params.clone(),
            train_rmse: t1.rmse(),
            heldout_improvement: (h_cur.rmse() - h1.rmse()) / h_cur.rmse().max(1e-300),
            significant: worse.significant,
            bic_decreased: bic_ok,
            kept: ok,
        });
        if !ok {
            continue;
        }
        out.warnings.push(format!(
            "{} on {} and on {} merged into one group (held-out RMSE {:.3e} → {:.3e} rad)",
            effect.id(),
            a.joints.join(","),
            b.joints.join(","),
            h_cur.rmse(),
            h1.rmse()
        ));
        out.selected.remove(j);
        let evidence = out.selected.remove(i).evidence;
        out.applied = set;
        sync_selected(out);
        let v = verdict(&h_wo, &h1, &joints, 2.0, opts.decisive_improvement);
        let bics = (bic(t_wo.n, t_wo.sse, k_set - effect.fitted()), bic(t1.n, t1.sse, k_set));
        let mut sel = Selected::new(&new, evidence, &v, h_wo.rmse(), h1.rmse(), bics);
        set_uncertainty(engine, train, &mut sel, &out.applied, &mut out.warnings);
        out.selected.push(sel);
        return true;
    }
    false
}

/// Drops, last kept first. Returns `true` when an effect was dropped.
fn drop_pass(s: &Search, round: usize, out: &mut FitOutcome) -> bool {
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
        let v = verdict(&h_wo, &h_full, &a.joints, 2.0, opts.decisive_improvement);
        let k_full: usize = out.applied.iter().map(|a| a.effect.fitted()).sum();
        let bic_dec =
            bic(t_full.n, t_full.sse, k_full) < bic(t_wo.n, t_wo.sse, k_full - a.effect.fitted());
        let keep = v.significant && v.rel >= opts.min_rel_improvement;
        out.tried.push(Tried {
            round,
            phase: "drop",
            effect: a.effect.id().into(),
            joints: a.joints.clone(),
            params: a.params.clone(),
            train_rmse: t_full.rmse(),
            heldout_improvement: v.rel,
            significant: v.significant,
            bic_decreased: bic_dec,
            kept: keep,
        });
        if !keep {
            out.warnings.push(format!(
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
/// on the test of a swap (held-out RMSE within 5 %, not worse beyond noise, training BIC not
/// higher). Of several, the one with the lowest held-out RMSE. (With two kept effects the
/// re-fitted remainder is a single effect, which the greedy round already fitted.)
/// Returns `true` when an effect was dropped.
fn refit_drop_pass(s: &Search, round: usize, out: &mut FitOutcome) -> bool {
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
    let bic_cur = bic(t_cur.n, t_cur.sse, k_all);
    let mut best: Option<(usize, Vec<Applied>, f64)> = None;
    for i in (0..n).rev() {
        let cur = out.applied[i].clone();
        engine.report(round, "drop with re-fit", Some((n - i, n, cur.effect.id().to_string())));
        let mut rest = out.applied.clone();
        rest.remove(i);
        let rest = fit_jointly(engine, train, rest, 0);
        let (Some(h1), Some(t1)) = (engine.errors(heldout, &rest), engine.errors(train, &rest))
        else {
            continue;
        };
        let k_rest = k_all - cur.effect.fitted();
        let worse = verdict(&h1, &h_cur, &cur.joints, 2.0, f64::INFINITY);
        let bic_ok = bic(t1.n, t1.sse, k_rest) <= bic_cur;
        let ok = h1.rmse() <= 1.05 * h_cur.rmse() && !worse.significant && bic_ok;
        out.tried.push(Tried {
            round,
            phase: "drop_refit",
            effect: cur.effect.id().into(),
            joints: cur.joints.clone(),
            params: cur.params.clone(),
            train_rmse: t1.rmse(),
            heldout_improvement: (h_cur.rmse() - h1.rmse()) / h_cur.rmse().max(1e-300),
            significant: worse.significant,
            bic_decreased: bic_ok,
            kept: !ok,
        });
        if ok && best.as_ref().is_none_or(|(_, _, r)| h1.rmse() < *r) {
            best = Some((i, rest, h1.rmse()));
        }
    }
    let Some((i, rest, rmse)) = best else { return false };
    let cur = &out.applied[i];
    out.warnings.push(format!(
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

/// Swaps for simpler effects. Returns `true` when a swap was made.
fn swap_pass(s: &Search, round: usize, out: &mut FitOutcome) -> bool {
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
        // that is not higher (as in the greedy winner's choice).
        let tol = 0.05 * h_cur.rmse();
        let k_all: usize = out.applied.iter().map(|a| a.effect.fitted()).sum();
        let t_cur = engine.errors(train, &out.applied);
        let bic_cur = t_cur.as_ref().map_or(f64::NEG_INFINITY, |e| bic(e.n, e.sse, k_all));
        let train_cur = t_cur.as_ref().map_or(f64::INFINITY, |e| e.rmse());
        let mut best: Option<(Vec<Applied>, f64, usize)> = None;
        for e in effects::all() {
            if !allowed.iter().any(|a| a == e.id())
                || e.id() == cur.effect.id()
                || e.fitted() >= k_cur
            {
                continue;
            }
            // On the joints of `cur` that `e` does not already act on (gain error on every
            // joint next to a damping on the elbow can become a damping on the other joints).
            let targets: Vec<String> = cur
                .joints
                .iter()
                .filter(|j| !others.iter().any(|a| a.effect.id() == e.id() && a.joints.contains(j)))
                .cloned()
                .collect();
            if targets.is_empty() {
                continue;
            }
            // Screen: a coarse fit (10 evaluations) of the simpler effect that leaves the
            // training error 1.5 times the current one cannot come within 5 % on held-out
            // (`tried`: phase "swap_screen"). Not when `e` already acts on some of the joints:
            // its kept parameters there only come right in the joint re-fit (polish) below.
            let partial = targets.len() < cur.joints.len();
            // (A full fit already made on this base, e.g. in round 1 when `others` is empty,
            // screens better than a coarse one and costs nothing.)
            let (pc, fc) = engine
                .fit_known(train, &others, e, &targets)
                .unwrap_or_else(|| engine.fit_budget(train, &others, e, &targets, 10));
            if !partial && (pc.is_empty() || !fc.is_finite() || fc > 1.5 * train_cur) {
                out.tried.push(Tried::not_tested(round, "swap_screen", e.id(), &targets, pc, fc));
                continue;
            }
            let (p, tr) = engine.fit_one(train, &others, e, &targets);
            if p.is_empty() || !tr.is_finite() {
                continue;
            }
            let mut set = others.clone();
            set.push(Applied { effect: e, joints: targets.clone(), params: p });
            let Some(h0) = engine.errors(heldout, &set) else { continue };
            // Hopeless before polishing: skip the joint re-fit (unless `e` acts on other
            // joints too, whose kept parameters only come right in it).
            let set = if (partial || h0.rmse() <= h_cur.rmse() * 1.10) && set.len() >= 2 {
                polish_set(engine, train, heldout, set, 0.02)
            } else {
                set
            };
            let Some(h1) = engine.errors(heldout, &set) else { continue };
            // Is the current set better than the swap beyond noise?
            let worse = verdict(&h1, &h_cur, &cur.joints, 2.0, f64::INFINITY);
            let k_set = k_all - k_cur + e.fitted();
            let t_set = engine.errors(train, &set);
            let bic_ok = t_set.as_ref().is_some_and(|t| bic(t.n, t.sse, k_set) <= bic_cur);
            let ok = h1.rmse() <= h_cur.rmse() + tol && !worse.significant && bic_ok;
            out.tried.push(Tried {
                round,
                phase: "swap",
                effect: e.id().into(),
                joints: targets.clone(),
                params: set.last().expect("pushed").params.clone(),
                // After the joint re-fit (what the BIC compares).
                train_rmse: t_set.as_ref().map_or(tr, |t| t.rmse()),
                heldout_improvement: (h_cur.rmse() - h1.rmse()) / h_cur.rmse().max(1e-300),
                significant: worse.significant,
                bic_decreased: bic_ok,
                kept: false,
            });
            let better = match &best {
                None => true,
                Some((_, r, k)) => e.fitted() < *k || (e.fitted() == *k && h1.rmse() < *r),
            };
            if ok && better {
                best = Some((set, h1.rmse(), e.fitted()));
            }
        }
        let Some((set, rmse_new, _)) = best else {
            i += 1;
            continue;
        };
        let new = set.last().expect("non-empty").clone();
        if let Some(t) =
            out.tried.iter_mut().rev().find(|t| {
                t.phase == "swap" && t.effect == new.effect.id() && t.joints == new.joints
            })
        {
            t.kept = true;
        }
        out.warnings.push(format!(
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
        let v = verdict(&h_wo, &h_new, &new.joints, 2.0, opts.decisive_improvement);
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

/// Joint re-fit of every kept effect's fitted parameters (Nelder–Mead from the greedy values);
/// kept only when both the training and the held-out RMSE do not get worse.
pub(super) fn polish(s: &Search, out: &mut FitOutcome) {
    let applied = std::mem::take(&mut out.applied);
    out.applied = polish_set(s.engine, s.train, s.heldout, applied, 0.02);
    sync_selected(out);
}

pub(super) fn polish_set(
    engine: &Engine,
    train: &[Recording],
    heldout: &[Recording],
    applied: Vec<Applied>,
    step: f64,
) -> Vec<Applied> {
    polish_budget(engine, train, heldout, applied, step, engine.opts.max_evals * 2)
}

/// [`polish_set`] with a budget of `max_evals` objective evaluations.
pub(super) fn polish_budget(
    engine: &Engine,
    train: &[Recording],
    heldout: &[Recording],
    applied: Vec<Applied>,
    step: f64,
    max_evals: usize,
) -> Vec<Applied> {
    let Some(slots) = param_slots(engine, &applied, 0, |ai| ai) else { return applied };
    let make = |x: &[f64]| with_params(&applied, &slots, x);
    let x0: Vec<f64> = slots.iter().map(|&(ai, k, ..)| applied[ai].params[k]).collect();
    let b =
        Bounds { lo: slots.iter().map(|s| s.2).collect(), hi: slots.iter().map(|s| s.3).collect() };
    let obj = |x: &[f64]| engine.errors(train, &make(x)).map_or(f64::INFINITY, |e| e.rmse());
    let f0 = obj(&x0);
    let o = NelderMeadOpts { max_evals, xtol: 1e-4, ftol: 1e-12, initial_step: step };
    let r = nelder_mead(&obj, &x0, &b, &o);
    if r.f.is_nan() || r.f >= f0 {
        return applied;
    }
    let new = make(&r.x);
    let (Some(h0), Some(h1)) = (engine.errors(heldout, &applied), engine.errors(heldout, &new))
    else {
        return applied;
    };
    if h1.rmse() > h0.rmse() {
        return applied;
    }
    new
}
