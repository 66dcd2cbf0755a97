//! Occam's pass after the greedy rounds (drop effects no longer needed, swap one for a simpler
//! effect) and the joint polish of every kept effect's parameters.

use std::collections::BTreeMap;

use crate::fit::effects::{self, Applied, JointTarget, model_with};
use crate::fit::optim::{Bounds, NelderMeadOpts, nelder_mead};
use crate::fit::stats::{bic, bic_pieces};
use crate::model::Robot;
use crate::sim2real::recording::Recording;

use super::engine::Engine;
use super::pairs::{fit_jointly, param_slots, with_params};
use super::verdict::verdict;
use super::{Errors, FitOutcome, Search, Selected, Tried, set_uncertainty, sync_selected};

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
            && !fold_pass(s, round, out)
            && !plain_friction_pass(s, round, out)
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
/// elbow, both 12 ms, is one delay on the arm). The group starts from the two fitted values
/// weighted by their joint counts, all kept parameters are polished, and the merge is kept on
/// the test of a swap (held-out RMSE within 5 %, not worse beyond noise, a training BIC that is
/// not higher; for a merge the BIC counts (episode, window, joint) windows, not samples:
/// [`bic_pieces`]; not asked when the two values agree within their standard errors,
/// [`values_agree`]). When that fails and every joint of the group starts from the same model value
/// (not each joint's own armature), a fresh fit of the group from that start is tried on the
/// same test: it finds the one value when the two fitted values are far apart. (The fresh fit
/// is not first: from its start it can stop short of values both groups agree on, 19.987 for
/// two stiffnesses at 20.000, and a shift that small already reads as worse beyond noise on
/// held-out.) Returns `true` when a merge was made.
fn merge_pass(s: &Search, round: usize, out: &mut FitOutcome) -> bool {
    let Search { engine, train, heldout, .. } = *s;
    let n = out.applied.len();
    // Errors of the current set (held-out, training): the same for every candidate pair,
    // simulated once, when the first pair qualifies.
    let mut current = None;
    for (i, j) in (0..n).flat_map(|i| (i + 1..n).map(move |j| (i, j))) {
        let (a, b) = (out.applied[i].clone(), out.applied[j].clone());
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
        let (Some(h_cur), Some(t_cur)) = current.get_or_insert_with(|| {
            (engine.errors(heldout, &out.applied), engine.errors(train, &out.applied))
        }) else {
            continue;
        };
        let cur = (&*h_cur, &*t_cur);
        let agree = values_agree(&a, &b, &out.selected[i].stderr, &out.selected[j].stderr);
        let message = format!(
            "{} on {} and on {} merged into one group{}",
            effect.id(),
            a.joints.join(","),
            b.joints.join(","),
            if agree { " (the two values agree within their standard errors)" } else { "" }
        );
        let attempt = |out: &mut FitOutcome, params: Vec<f64>, polish: bool| {
            let mut set = others.clone();
            set.push(Applied { effect, joints: joints.clone(), params });
            let set = if polish { polish_set(engine, train, heldout, set, 0.02) } else { set };
            let r = Replacement {
                phase: "merge",
                pair: (i, j),
                set,
                others: others.clone(),
                removed_k: effect.fitted(),
                evidence: out.selected[i].evidence.clone(),
                message: message.clone(),
                agree,
            };
            replace(s, round, out, cur, r)
        };
        let (na, nb) = (a.joints.len() as f64, b.joints.len() as f64);
        let mean =
            a.params.iter().zip(&b.params).map(|(x, y)| (na * x + nb * y) / (na + nb)).collect();
        if attempt(out, mean, true) {
            return true;
        }
        if engine.shared_start(effect, &others, &joints) {
            let (p, tr) = engine.fit_one(train, &others, effect, &joints);
            if !p.is_empty() && tr.is_finite() && attempt(out, p, !others.is_empty()) {
                return true;
            }
        }
    }
    false
}

/// Folds a kept effect into another kept on the same joints of which it is a special case
/// ([`crate::fit::effects::Effect::absorb`]): Coulomb friction found first and Stribeck
/// friction after it on the same joints are one Stribeck friction whose two levels both carry
/// the Coulomb part. The greedy rounds cannot get there: the second effect is fitted with the
/// first held, and a Stribeck fit alone from its default start stops with v_s at a bound (the
/// reason Coulomb won the first round). The folded effect starts from the absorbed values, all
/// kept parameters are polished, and the fold is kept on the test of a merge (held-out RMSE
/// within 5 %, not worse beyond noise, a training BIC that is not higher).
/// Returns `true` when a fold was made.
fn fold_pass(s: &Search, round: usize, out: &mut FitOutcome) -> bool {
    let Search { engine, train, heldout, .. } = *s;
    let n = out.applied.len();
    let mut current = None;
    for (i, j) in (0..n).flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| (i, j))) {
        let (a, b) = (&out.applied[i], &out.applied[j]);
        let same =
            a.joints.len() == b.joints.len() && a.joints.iter().all(|x| b.joints.contains(x));
        if !same {
            continue;
        }
        let mut without_b = out.applied.clone();
        without_b.remove(j);
        let Some(absorbed) = absorbed_start(engine.robot, &without_b, a, b) else { continue };
        let (Some(h_cur), Some(t_cur)) = current.get_or_insert_with(|| {
            (engine.errors(heldout, &out.applied), engine.errors(train, &out.applied))
        }) else {
            continue;
        };
        let (effect, joints) = (a.effect, a.joints.clone());
        let mut others = out.applied.clone();
        others.remove(i.max(j));
        others.remove(i.min(j));
        let mut set = others.clone();
        set.push(Applied { effect, joints: joints.clone(), params: absorbed });
        let set = polish_set(engine, train, heldout, set, 0.02);
        let mut evidence = out.selected[i].evidence.clone();
        evidence.insert(format!("absorbs_{}", b.effect.id()), 1.0);
        let message = format!(
            "{} on {} folded into {} on the same joints",
            b.effect.id(),
            b.joints.join(","),
            effect.id()
        );
        let r = Replacement {
            phase: "fold",
            pair: (i, j),
            set,
            others,
            removed_k: b.effect.fitted(),
            evidence,
            message,
            agree: false,
        };
        if !replace(s, round, out, (h_cur, t_cur), r) {
            continue;
        }
        return true;
    }
    false
}

/// The friction model every other one elaborates; [`plain_friction_pass`] prefers it.
const PLAIN_FRICTION: &str = "coulomb_friction";

/// Replaces a load-shaped friction kept beside a Coulomb friction on the same joints by Coulomb
/// friction alone, the joints getting a Coulomb value of their own: on a joint whose load
/// hardly changes (a shoulder holding its arm against gravity) friction proportional to the
/// load is a constant, and the two together split one loss in two. An independent simulator's
/// arm with Coulomb friction 0.3 on three joints and 0.03 on the wrist came out as Coulomb
/// 0.030 on the shoulder (grouped with the wrist) plus external-load friction 0.080 × its
/// gravity load. Each friction effect (other than Coulomb) whose every joint also carries
/// Coulomb friction in some group is removed, its joints are taken out of their Coulomb groups
/// (the groups keep their values on their other joints) and given one Coulomb group of their
/// own, fitted and then polished with everything kept; the set is kept on the test of a merge
/// (held-out RMSE within 5 %, not worse beyond noise, training BIC per window not higher) —
/// the same number of parameters or fewer, one friction model per joint.
/// Returns `true` when a replacement was made.
fn plain_friction_pass(s: &Search, round: usize, out: &mut FitOutcome) -> bool {
    let Search { engine, train, heldout, .. } = *s;
    let Some(plain) = effects::by_id(PLAIN_FRICTION) else { return false };
    let n = out.applied.len();
    let mut current = None;
    for i in 0..n {
        let a = &out.applied[i];
        if !a.effect.friction() || a.effect.id() == PLAIN_FRICTION {
            continue;
        }
        let covered = a.joints.iter().all(|j| {
            out.applied.iter().any(|b| b.effect.id() == PLAIN_FRICTION && b.joints.contains(j))
        });
        if !covered {
            continue;
        }
        let (Some(h_cur), Some(t_cur)) = current.get_or_insert_with(|| {
            (engine.errors(heldout, &out.applied), engine.errors(train, &out.applied))
        }) else {
            return false;
        };
        let joints = a.joints.clone();
        // The kept set without `a`, its joints out of the Coulomb groups (index into the kept
        // set of each entry kept, for the records).
        let mut base: Vec<(usize, Applied)> = Vec::new();
        for (k, b) in out.applied.iter().enumerate() {
            if k == i {
                continue;
            }
            let mut b = b.clone();
            if b.effect.id() == PLAIN_FRICTION {
                b.joints.retain(|j| !joints.contains(j));
                if b.joints.is_empty() {
                    continue;
                }
            }
            base.push((k, b));
        }
        let others: Vec<Applied> = base.iter().map(|(_, b)| b.clone()).collect();
        let (p, tr) = engine.fit_one(train, &others, plain, &joints);
        if p.is_empty() || !tr.is_finite() {
            continue;
        }
        let mut set = others.clone();
        set.push(Applied { effect: plain, joints: joints.clone(), params: p });
        let set = polish_set(engine, train, heldout, set, 0.02);
        let (Some(h1), Some(t1), Some(h_wo), Some(t_wo)) = (
            engine.errors(heldout, &set),
            engine.errors(train, &set),
            engine.errors(heldout, &others),
            engine.errors(train, &others),
        ) else {
            continue;
        };
        let k_cur: usize = out.applied.iter().map(|a| a.effect.fitted()).sum();
        let k_set: usize = set.iter().map(|a| a.effect.fitted()).sum();
        let (ok, worse, bic_ok) =
            simpler_set_ok((&h1, &t1, k_set), (&*h_cur, &*t_cur, k_cur), &joints, true, false);
        let new = set.last().expect("pushed").clone();
        out.tried.push(tested(
            round,
            "plain_friction",
            &new,
            (&h1, &t1, &*h_cur),
            (ok, worse, bic_ok),
        ));
        if !ok {
            continue;
        }
        out.notes.push(format!(
            "{} on {} and the {} beside it replaced by {} with a value of its own on {} (one friction model \
             per joint; held-out RMSE {:.3e} → {:.3e} rad)",
            a.effect.id(),
            joints.join(","),
            PLAIN_FRICTION,
            PLAIN_FRICTION,
            joints.join(","),
            h_cur.rmse(),
            h1.rmse()
        ));
        let replaced = a.effect.id();
        // The records of the kept entries follow them (a Coulomb group that lost joints keeps
        // its record under its remaining joints).
        let mut selected: Vec<Selected> = base
            .iter()
            .map(|(k, b)| {
                let mut sel = out.selected[*k].clone();
                sel.joints = b.joints.clone();
                sel
            })
            .collect();
        out.applied = set;
        std::mem::swap(&mut out.selected, &mut selected);
        sync_selected(out);
        let v = verdict(&h_wo, &h1, &joints, 2.0, engine.opts.decisive_improvement);
        let bics = (bic(t_wo.n, t_wo.sse, k_set - plain.fitted()), bic(t1.n, t1.sse, k_set));
        let evidence = BTreeMap::from([(format!("replaces_{replaced}"), 1.0)]);
        let mut sel = Selected::new(&new, evidence, &v, h_wo.rmse(), h1.rmse(), bics);
        set_uncertainty(engine, train, &mut sel, &out.applied, &mut out.warnings);
        out.selected.push(sel);
        return true;
    }
    false
}

/// A set that replaces two kept effects by one (a merge or a fold): `set` is `others` (the kept
/// set without the two) plus the new effect, last.
struct Replacement {
    phase: &'static str,
    /// Indices of the two replaced effects in the kept set.
    pair: (usize, usize),
    set: Vec<Applied>,
    others: Vec<Applied>,
    /// Fitted parameters the replacement removes.
    removed_k: usize,
    evidence: BTreeMap<String, f64>,
    /// What was done, for the warning (the held-out RMSEs are appended).
    message: String,
    /// A merge of two groups whose fitted values agree within their standard errors
    /// ([`values_agree`]): the training BIC is not asked.
    agree: bool,
}

/// `true` when every fitted parameter of `a` and `b` (one effect on two joint groups) differs
/// by at most twice the standard error of the difference, `√(se_a² + se_b²)`, both finite.
/// `sa`, `sb`: the kept effects' standard errors by parameter name.
fn values_agree(
    a: &Applied,
    b: &Applied,
    sa: &BTreeMap<String, f64>,
    sb: &BTreeMap<String, f64>,
) -> bool {
    let k = a.effect.fitted();
    k > 0
        && a.params.len() >= k
        && b.params.len() >= k
        && a.effect.params().iter().take(k).enumerate().all(|(i, d)| {
            let (Some(&ea), Some(&eb)) = (sa.get(d.name), sb.get(d.name)) else { return false };
            let se = (ea * ea + eb * eb).sqrt();
            se.is_finite() && se > 0.0 && (a.params[i] - b.params[i]).abs() <= 2.0 * se
        })
}

/// The record of a replacement set tested against the current one: its new effect `new`, the
/// set's held-out and training errors and the current held-out error, and
/// [`simpler_set_ok`]'s (made, worse beyond noise, BIC not higher).
fn tested(
    round: usize,
    phase: &'static str,
    new: &Applied,
    (h1, t1, h_cur): (&Errors, &Errors, &Errors),
    (ok, worse, bic_ok): (bool, bool, bool),
) -> Tried {
    Tried {
        round,
        phase,
        effect: new.effect.id().into(),
        joints: new.joints.clone(),
        params: new.params.clone(),
        train_rmse: t1.rmse(),
        heldout_improvement: (h_cur.rmse() - h1.rmse()) / h_cur.rmse().max(1e-300),
        significant: worse,
        bic_decreased: bic_ok,
        kept: ok,
    }
}

/// Tests a [`Replacement`] on the test of a swap (held-out RMSE within 5 % of the current
/// set's, not worse beyond noise, a training BIC that is not higher), records it in `tried`,
/// and makes it when it passes. `cur`: the current set's (held-out, training) errors.
/// Returns `true` when the replacement was made.
fn replace(
    s: &Search,
    round: usize,
    out: &mut FitOutcome,
    (h_cur, t_cur): (&Errors, &Errors),
    r: Replacement,
) -> bool {
    let Search { engine, train, heldout, .. } = *s;
    let new = r.set.last().expect("a replacement set ends with its new effect").clone();
    let (Some(h1), Some(t1), Some(h_wo), Some(t_wo)) = (
        engine.errors(heldout, &r.set),
        engine.errors(train, &r.set),
        engine.errors(heldout, &r.others),
        engine.errors(train, &r.others),
    ) else {
        return false;
    };
    let k_all: usize = out.applied.iter().map(|a| a.effect.fitted()).sum();
    let k_set = k_all - r.removed_k;
    // A merge asks whether two fitted values are one: counted per sample, two values that
    // differ by a systematic hair (two armature groups on the Asimov legs, both 0.1501 kg·m²
    // to four digits, merged: held-out +0.0 %) read as two. Counted per window, the one value
    // must cost no more than a parameter's worth of windows. A fold or swap keeps the
    // per-sample test.
    //
    // Two values that agree within their standard errors are one without asking the BIC: the
    // training error can step with a hair of the parameter (the Asimov legs' armature groups,
    // 0.150124 and 0.150064 ± 3e-5: one event in one training episode flips with a 1e-5
    // change, +2.5 % training SSE for any single value, truth included; held-out +0.0 %).
    let merge = r.phase == "merge";
    let (ok, worse, bic_ok) = simpler_set_ok(
        (&h1, &t1, k_set),
        (h_cur, t_cur, k_all),
        &new.joints,
        merge,
        merge && r.agree,
    );
    out.tried.push(tested(round, r.phase, &new, (&h1, &t1, h_cur), (ok, worse, bic_ok)));
    if !ok {
        return false;
    }
    out.notes.push(format!(
        "{} (held-out RMSE {:.3e} → {:.3e} rad)",
        r.message,
        h_cur.rmse(),
        h1.rmse()
    ));
    let (i, j) = r.pair;
    out.selected.remove(i.max(j));
    out.selected.remove(i.min(j));
    out.applied = r.set;
    sync_selected(out);
    let v = verdict(&h_wo, &h1, &new.joints, 2.0, engine.opts.decisive_improvement);
    let bics = (bic(t_wo.n, t_wo.sse, k_set - new.effect.fitted()), bic(t1.n, t1.sse, k_set));
    let mut sel = Selected::new(&new, r.evidence, &v, h_wo.rmse(), h1.rmse(), bics);
    set_uncertainty(engine, train, &mut sel, &out.applied, &mut out.warnings);
    out.selected.push(sel);
    true
}

/// `a`'s parameters when it takes over `b`, kept on the same joints (`without_b`: the kept
/// set without `b`): `b`'s change from its start on the model without it (for a MuJoCo-native
/// parameter, the model's own value) absorbed by [`crate::fit::effects::Effect::absorb`] and
/// clamped to `a`'s bounds. `None` when `a` cannot take `b` over.
fn absorbed_start(
    robot: &Robot,
    without_b: &[Applied],
    a: &Applied,
    b: &Applied,
) -> Option<Vec<f64>> {
    let t = JointTarget::of(robot, b.joints.first()?)?;
    let ta = JointTarget::of(robot, a.joints.first()?)?;
    let m0 = model_with(robot, without_b);
    let delta: Vec<f64> =
        b.params.iter().zip(b.effect.initial(&m0, &t)).map(|(p, p0)| p - p0).collect();
    let absorbed = a.effect.absorb(b.effect, &a.params, &delta)?;
    let (lo, hi) = a.effect.bounds(&m0, &ta);
    Some(
        absorbed
            .iter()
            .enumerate()
            .map(|(k, v)| if k < lo.len() && k < hi.len() { v.clamp(lo[k], hi[k]) } else { *v })
            .collect(),
    )
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
        let (ok, worse, bic_ok) =
            simpler_set_ok((&h1, &t1, k_rest), (&h_cur, &t_cur, k_all), &cur.joints, true, false);
        out.tried.push(Tried {
            round,
            phase: "drop_refit",
            effect: cur.effect.id().into(),
            joints: cur.joints.clone(),
            params: cur.params.clone(),
            train_rmse: t1.rmse(),
            heldout_improvement: (h_cur.rmse() - h1.rmse()) / h_cur.rmse().max(1e-300),
            significant: worse,
            bic_decreased: bic_ok,
            kept: !ok,
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
fn simpler_set_ok(
    (h1, t1, k_new): (&Errors, &Errors, usize),
    (h_cur, t_cur, k_cur): (&Errors, &Errors, usize),
    joints: &[String],
    per_window: bool,
    agree: bool,
) -> (bool, bool, bool) {
    let worse = verdict(h1, h_cur, joints, 2.0, f64::INFINITY).significant;
    let bic_ok = agree
        || if per_window {
            let m = t1.windows.len().min(t_cur.windows.len());
            bic_pieces(m, t1.n, t1.sse, k_new) <= bic_pieces(m, t_cur.n, t_cur.sse, k_cur)
        } else {
            bic(t1.n, t1.sse, k_new) <= bic(t_cur.n, t_cur.sse, k_cur)
        };
    (h1.rmse() <= 1.05 * h_cur.rmse() && !worse && bic_ok, worse, bic_ok)
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
        // that is not higher (as in the greedy winner's choice): `simpler_set_ok`, per sample.
        let k_all: usize = out.applied.iter().map(|a| a.effect.fitted()).sum();
        let t_cur = engine.errors(train, &out.applied);
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
            let k_set = k_all - k_cur + e.fitted();
            let t_set = engine.errors(train, &set);
            let (ok, worse, bic_ok) = match (&t_set, &t_cur) {
                (Some(t), Some(tc)) => {
                    simpler_set_ok((&h1, t, k_set), (&h_cur, tc, k_all), &cur.joints, false, false)
                }
                _ => (
                    false,
                    verdict(&h1, &h_cur, &cur.joints, 2.0, f64::INFINITY).significant,
                    false,
                ),
            };
            out.tried.push(Tried {
                round,
                phase: "swap",
                effect: e.id().into(),
                joints: targets.clone(),
                params: set.last().expect("pushed").params.clone(),
                // After the joint re-fit (what the BIC compares).
                train_rmse: t_set.as_ref().map_or(tr, |t| t.rmse()),
                heldout_improvement: (h_cur.rmse() - h1.rmse()) / h_cur.rmse().max(1e-300),
                significant: worse,
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

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;
    use std::path::Path;

    use super::*;
    use crate::fit::effects::by_id;
    use crate::fit::select::FitOptions;
    use crate::fit::split::split;
    use crate::model::source::SourceMap;
    use crate::sim2real::recording::read_csv;
    use crate::synth::{self, Settings, truth::Hidden};

    type Pass = fn(&Search, usize, &mut FitOutcome) -> bool;

    /// arm3 (each joint's armature 0.01 kg·m², no frictionloss; `attrs` sets one joint
    /// attribute each) with `hidden`, recorded by the independent synth and read back from CSV.
    fn recorded(
        tag: &str,
        attrs: &[(&str, &str, f64)],
        hidden: &[(&str, &str, &[f64])],
    ) -> (Robot, Vec<Recording>) {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut xml = std::fs::read_to_string(root.join("fixtures/gap/arm3.xml")).expect("arm3");
        for (j, attr, v) in attrs {
            let from = format!("<joint name=\"{j}\"/>");
            assert!(xml.contains(&from), "{from}");
            xml = xml.replace(&from, &format!("<joint name=\"{j}\" {attr}=\"{v}\"/>"));
        }
        let dir =
            std::env::temp_dir().join(format!("modellint_simplify_{tag}_{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join("arm3.xml");
        std::fs::write(&path, xml).expect("write model");
        let robot = crate::model::load(&mut SourceMap::default(), &path, None).expect("arm3");
        let joints: Vec<String> =
            ["shoulder_pitch", "elbow_pitch", "wrist_pitch"].map(String::from).to_vec();
        let hidden: Vec<Hidden> = hidden
            .iter()
            .map(|(e, j, p)| Hidden {
                effect: by_id(e).expect("effect").id(),
                joint: (*j).into(),
                params: p.to_vec(),
            })
            .collect();
        let s = Settings {
            episodes: 8,
            duration_s: 4.0,
            amplitude: 0.5,
            seed: 7,
            ..Settings::default()
        };
        let ds = synth::generate(&robot, &joints, &hidden, &s, &|_, _| {}).expect("synth");
        let files = synth::write::write(&ds, &dir.join("rec")).expect("write");
        let recs = files.iter().map(|f| read_csv(f).expect("read")).collect();
        let _ = std::fs::remove_dir_all(&dir);
        (robot, recs)
    }

    fn applied(id: &str, joints: &[&str], params: &[f64]) -> Applied {
        Applied {
            effect: by_id(id).expect("effect"),
            joints: joints.iter().map(|j| j.to_string()).collect(),
            params: params.to_vec(),
        }
    }

    /// Runs `pass` on the kept set `start`; returns the outcome and whether the set changed.
    fn run(
        pass: Pass,
        robot: &Robot,
        recs: &[Recording],
        start: Vec<Applied>,
    ) -> (FitOutcome, bool) {
        let opts = FitOptions::default();
        let engine = Engine::new(robot, recs, &opts);
        let sp = split(recs, opts.holdout);
        let allowed: Vec<String> = effects::all().iter().map(|e| e.id().to_string()).collect();
        let s =
            Search { engine: &engine, train: &sp.train, heldout: &sp.heldout, allowed: &allowed };
        let h = engine.errors(&sp.heldout, &start).expect("replay");
        let mut out = FitOutcome::empty(String::new());
        for a in &start {
            let v = verdict(&h, &h, &a.joints, 2.0, 0.5);
            out.selected.push(Selected::new(a, BTreeMap::new(), &v, 1.0, 1.0, (0.0, 0.0)));
        }
        out.applied = start;
        let changed = pass(&s, 2, &mut out);
        (out, changed)
    }

    fn near(got: &[f64], truth: &[f64], rel: f64) -> bool {
        got.len() == truth.len()
            && got.iter().zip(truth).all(|(g, t)| (g - t).abs() <= rel * t.abs())
    }

    const STRIBECK: [f64; 3] = [0.3, 0.1, 0.2];

    /// The Asimov failure, on arm3: Coulomb friction taken first, then a Stribeck friction with
    /// its levels short by the Coulomb part. The fold gives one Stribeck friction at the truth.
    #[test]
    fn coulomb_next_to_stribeck_folds_into_stribeck() {
        // The model's own frictionloss on the elbow is 0.2 N·m (the truth adds the Stribeck
        // friction to it): the fold must take only the Coulomb part above it.
        let (robot, recs) = recorded(
            "fold",
            &[("elbow_pitch", "frictionloss", 0.2)],
            &[("stribeck_friction", "elbow_pitch", &STRIBECK)],
        );
        let t = JointTarget::of(&robot, "elbow_pitch").expect("elbow");
        let c0 =
            by_id("coulomb_friction").expect("coulomb").initial(&model_with(&robot, &[]), &t)[0];
        assert!((c0 - 0.2).abs() < 1e-12, "model frictionloss {c0}");
        // Coulomb took 0.12 N·m above the model's frictionloss, Stribeck a part of the rest:
        // folded, (0.22, 0.12, 0.14) is 20–30 % off the truth; the polish must bring it there.
        // (Adding the whole 0.32 instead would start at (0.42, 0.32, 0.14).)
        let start = vec![
            applied("coulomb_friction", &["elbow_pitch"], &[c0 + 0.12]),
            applied("stribeck_friction", &["elbow_pitch"], &[0.10, 0.0, 0.14]),
        ];
        // The folded start, by hand: 0.10 + 0.12, 0.0 + 0.12, 0.14.
        let got = absorbed_start(&robot, &start[1..], &start[1], &start[0]).expect("absorbs");
        assert!(near(&got, &[0.22, 0.12, 0.14], 1e-9), "folded start {got:?}");
        let (out, folded) = run(fold_pass, &robot, &recs, start);
        assert!(folded, "no fold; tried {:?}", out.tried);
        assert_eq!(out.applied.len(), 1, "{:?}", out.applied);
        let a = &out.applied[0];
        assert_eq!(a.effect.id(), "stribeck_friction");
        assert!(near(&a.params, &STRIBECK, 0.05), "fitted {:?} for {STRIBECK:?}", a.params);
        assert_eq!(out.selected.len(), 1);
        assert!(out.selected[0].evidence.contains_key("absorbs_coulomb_friction"));
        assert!(out.tried.iter().any(|t| t.phase == "fold" && t.kept));
    }

    /// Must not fire: the two frictions on different joints are not one effect.
    #[test]
    fn frictions_on_different_joints_do_not_fold() {
        let (robot, recs) =
            recorded("apart", &[], &[("stribeck_friction", "elbow_pitch", &STRIBECK)]);
        let start = vec![
            applied("coulomb_friction", &["shoulder_pitch"], &[0.05]),
            applied("stribeck_friction", &["elbow_pitch"], &STRIBECK),
        ];
        let (out, folded) = run(fold_pass, &robot, &recs, start);
        assert!(!folded);
        assert_eq!(out.applied.len(), 2);
        assert!(out.tried.iter().all(|t| t.phase != "fold"));
    }

    /// Armature 0.04 kg·m² on the three joints, whose model values differ (shoulder 0.02, the
    /// others 0.01): found as a group of two (0.047) and on the elbow alone (0.022), the two
    /// are one group at the truth. The start, weighted by joint count, is 0.0387 (3.3 % off;
    /// unweighted 0.0345): the polish must bring it within 2 %.
    #[test]
    fn armatures_from_different_model_values_merge() {
        let (robot, recs) = recorded(
            "merge",
            &[("shoulder_pitch", "armature", 0.02)],
            &[
                ("armature", "shoulder_pitch", &[0.04]),
                ("armature", "elbow_pitch", &[0.04]),
                ("armature", "wrist_pitch", &[0.04]),
            ],
        );
        let start = vec![
            applied("armature", &["shoulder_pitch", "wrist_pitch"], &[0.047]),
            applied("armature", &["elbow_pitch"], &[0.022]),
        ];
        let (out, merged) = run(merge_pass, &robot, &recs, start);
        assert!(merged, "no merge; tried {:?}", out.tried);
        assert_eq!(out.applied.len(), 1, "{:?}", out.applied);
        let a = &out.applied[0];
        assert_eq!(a.joints, ["shoulder_pitch", "elbow_pitch", "wrist_pitch"]);
        eprintln!("merged: {:?}", a.params);
        assert!(near(&a.params, &[0.04], 0.02), "fitted {:?} for 0.04", a.params);
        assert!(out.tried.iter().any(|t| t.phase == "merge" && t.kept));
    }

    /// Armature 0.04 kg·m² on the shoulder and wrist, 0.0402 on the elbow (0.5 % apart):
    /// fitted as two groups, each at its training optimum, the two values are a hair apart and
    /// the per-sample BIC reads them as two parameters (the Asimov legs' two armature groups,
    /// both 0.1501 kg·m² to four digits, were kept apart so). Counted per window they are one:
    /// the merge is made, within 1 % of both values. Fails if the merge goes back to the
    /// per-sample BIC; `different_armatures_do_not_merge` is the other side.
    #[test]
    fn armatures_a_hair_apart_merge() {
        let (robot, recs) = recorded(
            "hair",
            &[],
            &[
                ("armature", "shoulder_pitch", &[0.04]),
                ("armature", "elbow_pitch", &[0.0402]),
                ("armature", "wrist_pitch", &[0.04]),
            ],
        );
        let opts = FitOptions::default();
        let engine = Engine::new(&robot, &recs, &opts);
        let sp = split(&recs, opts.holdout);
        let start = vec![
            applied("armature", &["shoulder_pitch", "wrist_pitch"], &[0.04]),
            applied("armature", &["elbow_pitch"], &[0.04]),
        ];
        let start = polish_budget(&engine, &sp.train, &sp.train, start, 0.02, 400);
        let (a, b) = (start[0].params[0], start[1].params[0]);
        assert!(near(&[a, b], &[0.04, 0.0402], 0.002), "two groups {a}, {b}");
        // The case is the one claimed: the one value costs more than a parameter per sample,
        // less than one per window.
        let one = vec![applied(
            "armature",
            &["shoulder_pitch", "elbow_pitch", "wrist_pitch"],
            &[(2.0 * a + b) / 3.0],
        )];
        let one = polish_budget(&engine, &sp.train, &sp.train, one, 0.02, 400);
        let (t1, t2) = (
            engine.errors(&sp.train, &one).expect("replay"),
            engine.errors(&sp.train, &start).expect("replay"),
        );
        let m = t2.windows.len();
        assert!(bic(t1.n, t1.sse, 1) > bic(t2.n, t2.sse, 2), "per sample the two are one");
        assert!(bic_pieces(m, t1.n, t1.sse, 1) <= bic_pieces(m, t2.n, t2.sse, 2));
        let (out, merged) = run(merge_pass, &robot, &recs, start);
        assert!(merged, "no merge; tried {:?}", out.tried);
        assert_eq!(out.applied.len(), 1, "{:?}", out.applied);
        let g = &out.applied[0];
        assert_eq!(g.joints, ["shoulder_pitch", "elbow_pitch", "wrist_pitch"]);
        assert!(near(&g.params, &[0.0401], 0.01), "merged at {:?}", g.params);
    }

    /// Two groups' values agree when they differ by at most 2 standard errors of the
    /// difference: the Asimov legs' armatures (0.150124 and 0.150064, ± 3e-5 each: 1.4) do,
    /// 0.03 and 0.06 ± 1e-4 do not, nor do values without a finite standard error. Every fitted
    /// parameter must agree (a Stribeck friction whose velocity scales differ does not).
    #[test]
    fn values_agree_within_their_standard_errors() {
        let se = |v: &[(&str, f64)]| -> BTreeMap<String, f64> {
            v.iter().map(|(k, x)| (k.to_string(), *x)).collect()
        };
        let name = |id: &str, k: usize| by_id(id).unwrap().params()[k].name;
        let arm = name("armature", 0);
        let (a, b) =
            (applied("armature", &["a"], &[0.150124]), applied("armature", &["b"], &[0.150064]));
        let s3 = se(&[(arm, 3e-5)]);
        assert!(values_agree(&a, &b, &s3, &s3));
        assert!(!values_agree(&a, &b, &se(&[(arm, 1e-5)]), &se(&[(arm, 1e-5)])));
        let (c, d) = (applied("armature", &["a"], &[0.03]), applied("armature", &["b"], &[0.06]));
        let s4 = se(&[(arm, 1e-4)]);
        assert!(!values_agree(&c, &d, &s4, &s4));
        assert!(!values_agree(&a, &b, &se(&[(arm, f64::INFINITY)]), &s3));
        assert!(!values_agree(&a, &b, &se(&[(arm, f64::NAN)]), &s3));
        assert!(!values_agree(&a, &b, &se(&[]), &s3));
        // Two parameters: one level agrees, the velocity scale does not.
        let st = by_id("stribeck_friction").unwrap();
        let k = st.fitted();
        assert!(k >= 2, "stribeck fits {k}");
        let names: Vec<&str> = (0..k).map(|i| name("stribeck_friction", i)).collect();
        let pa: Vec<f64> = (0..k).map(|i| 0.1 + i as f64).collect();
        let mut pb = pa.clone();
        let sab = se(&names.iter().map(|n| (*n, 0.01)).collect::<Vec<_>>());
        let (x, y) =
            (applied("stribeck_friction", &["a"], &pa), applied("stribeck_friction", &["b"], &pb));
        assert!(values_agree(&x, &y, &sab, &sab));
        pb[k - 1] += 0.5;
        let y = applied("stribeck_friction", &["b"], &pb);
        assert!(!values_agree(&x, &y, &sab, &sab));
    }

    /// The drop with re-fit counts the training BIC per window: 400 windows of 100 samples,
    /// held-out unchanged, the remainder's training SSE 0.6 % higher with one parameter fewer
    /// is a drop (per sample, 240 of likelihood against ln 40000 = 10.6 of penalty, it was
    /// not); 5 % higher is not (19.5 against ln 400 = 6.0), nor is a held-out error worse
    /// beyond noise.
    #[test]
    fn drop_refit_counts_the_bic_per_window() {
        let errs = |w: &[f64], scale: f64| {
            let w: Vec<f64> = w.iter().map(|v| v * scale).collect();
            Errors {
                sse: w.iter().map(|v| v * v * 100.0).sum(),
                n: 100 * w.len(),
                windows: w.iter().map(|v| ("j".to_string(), *v)).collect(),
                eps: vec![],
            }
        };
        let base: Vec<f64> = (0..400).map(|i| 1e-3 * (1.0 + 0.3 * ((i * 7) % 11) as f64)).collect();
        let (h, t) = (errs(&base, 1.0), errs(&base, 1.0));
        let j = ["j".to_string()];
        let t_hair = errs(&base, 1.006f64.sqrt());
        assert!(bic(t_hair.n, t_hair.sse, 2) > bic(t.n, t.sse, 3), "per sample: kept");
        assert_eq!(
            simpler_set_ok((&h, &t_hair, 2), (&h, &t, 3), &j, true, false),
            (true, false, true)
        );
        let t_more = errs(&base, 1.05f64.sqrt());
        assert_eq!(
            simpler_set_ok((&h, &t_more, 2), (&h, &t, 3), &j, true, false),
            (false, false, false)
        );
        let h_worse = errs(&base, 1.03);
        let (ok, worse, _) = simpler_set_ok((&h_worse, &t_hair, 2), (&h, &t, 3), &j, true, false);
        assert!(!ok && worse);
    }

    /// Joint stiffness 10 N·m/rad on the three joints (every joint starts from the model's 0,
    /// so the group has a start of its own), found as two groups that agree exactly: merged at
    /// those values the model is the same with one parameter fewer, so the merge must be made
    /// and its training error must not be above the two groups' (a fresh fit from 0 that stops
    /// short of them, as at 19.987 for 20.000 on the Asimov legs, loses the BIC test).
    #[test]
    fn equal_stiffnesses_merge_at_their_own_value() {
        let k = [10.0];
        let (robot, recs) = recorded(
            "stiff",
            &[],
            &[
                ("joint_stiffness", "shoulder_pitch", &k),
                ("joint_stiffness", "elbow_pitch", &k),
                ("joint_stiffness", "wrist_pitch", &k),
            ],
        );
        let start = vec![
            applied("joint_stiffness", &["shoulder_pitch", "wrist_pitch"], &k),
            applied("joint_stiffness", &["elbow_pitch"], &k),
        ];
        let opts = FitOptions::default();
        let engine = Engine::new(&robot, &recs, &opts);
        let sp = split(&recs, opts.holdout);
        let t_cur = engine.errors(&sp.train, &start).expect("replay").rmse();
        let (out, merged) = run(merge_pass, &robot, &recs, start);
        assert!(merged, "no merge; tried {:?}", out.tried);
        assert_eq!(out.applied.len(), 1, "{:?}", out.applied);
        let a = &out.applied[0];
        assert_eq!(a.joints, ["shoulder_pitch", "elbow_pitch", "wrist_pitch"]);
        assert!(near(&a.params, &k, 0.01), "fitted {:?} for {k:?}", a.params);
        let t_new = engine.errors(&sp.train, &out.applied).expect("replay").rmse();
        assert!(
            t_new <= t_cur * (1.0 + 1e-12),
            "training RMSE {t_new} > {t_cur} of the two groups"
        );
    }

    /// Must not fire: stiffnesses 4 and 12 N·m/rad are two values, not one, from the mean
    /// start (6.67, weighted by joint count) or a fresh fit alike.
    #[test]
    fn different_stiffnesses_do_not_merge() {
        let (robot, recs) = recorded(
            "stiffapart",
            &[],
            &[
                ("joint_stiffness", "shoulder_pitch", &[4.0]),
                ("joint_stiffness", "wrist_pitch", &[4.0]),
                ("joint_stiffness", "elbow_pitch", &[12.0]),
            ],
        );
        let start = vec![
            applied("joint_stiffness", &["shoulder_pitch", "wrist_pitch"], &[4.0]),
            applied("joint_stiffness", &["elbow_pitch"], &[12.0]),
        ];
        let (out, merged) = run(merge_pass, &robot, &recs, start);
        assert!(!merged, "merged: {:?}", out.applied);
        assert_eq!(out.applied.len(), 2);
        // Both starts were tried: the weighted mean and the group's own start.
        let n = out.tried.iter().filter(|t| t.phase == "merge" && !t.kept).count();
        assert_eq!(n, 2, "{:?}", out.tried);
    }

    /// Must not fire: armatures 0.03 and 0.06 are two values, not one.
    #[test]
    fn different_armatures_do_not_merge() {
        let (robot, recs) = recorded(
            "nomerge",
            &[("shoulder_pitch", "armature", 0.02)],
            &[("armature", "shoulder_pitch", &[0.03]), ("armature", "elbow_pitch", &[0.06])],
        );
        let start = vec![
            applied("armature", &["shoulder_pitch"], &[0.03]),
            applied("armature", &["elbow_pitch"], &[0.06]),
        ];
        let (out, merged) = run(merge_pass, &robot, &recs, start);
        assert!(!merged, "merged: {:?}", out.applied);
        assert_eq!(out.applied.len(), 2);
        assert!(out.tried.iter().any(|t| t.phase == "merge" && !t.kept), "{:?}", out.tried);
    }
}
