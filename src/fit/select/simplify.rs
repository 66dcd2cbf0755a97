//! Occam's pass after the greedy rounds (drop effects no longer needed, swap one for a simpler
//! effect) and the joint polish of every kept effect's parameters.

use std::collections::BTreeMap;

use crate::fit::effects::{self, Applied, JointTarget, model_with};
use crate::fit::stats::bic;
use crate::model::Robot;

use super::policy::Phase;
use super::polish::polish_set;
use super::prune::{drop_pass, refit_drop_pass, simpler_set_ok, swap_pass};
use super::verdict::verdict;
use super::{Errors, FitOutcome, Search, Selected, Tried, set_uncertainty, sync_selected};
#[cfg(test)]
mod tests;

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
        // One parameter vector only over alike targets (a body effect: alike links).
        if !effects::alike_over(engine.robot, effect, &joints) {
            continue;
        }
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
            let set = if polish {
                polish_set(engine, train, heldout, set, engine.opts.policy.polish_step)
            } else {
                set
            };
            let r = Replacement {
                phase: Phase::Merge,
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
        let set = polish_set(engine, train, heldout, set, engine.opts.policy.polish_step);
        let mut evidence = out.selected[i].evidence.clone();
        evidence.insert(format!("absorbs_{}", b.effect.id()), 1.0);
        let message = format!(
            "{} on {} folded into {} on the same joints",
            b.effect.id(),
            b.joints.join(","),
            effect.id()
        );
        let r = Replacement {
            phase: Phase::Fold,
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

/// Replaces an effect kept beside its plain variant ([`Effect::plain_variant`]: a load-shaped
/// friction beside Coulomb friction) on the same joints by the plain variant alone, the joints getting a Coulomb value of their own: on a joint whose load
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
    let n = out.applied.len();
    let mut current = None;
    for i in 0..n {
        let a = &out.applied[i];
        let Some(plain) = a.effect.plain_variant() else { continue };
        let covered = a.joints.iter().all(|j| {
            out.applied.iter().any(|b| b.effect.id() == plain.id() && b.joints.contains(j))
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
            if b.effect.id() == plain.id() {
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
        let set = polish_set(engine, train, heldout, set, engine.opts.policy.polish_step);
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
        let (ok, worse, bic_ok) = simpler_set_ok(
            &engine.opts.policy,
            (&h1, &t1, k_set),
            (&*h_cur, &*t_cur, k_cur),
            &joints,
            true,
            false,
        );
        let new = set.last().expect("pushed").clone();
        out.tried.push(tested(
            round,
            Phase::PlainFriction,
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
            plain.id(),
            plain.id(),
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
        let v = verdict(&h_wo, &h1, &joints, engine.opts.policy.gate());
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
    phase: Phase,
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
    phase: Phase,
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
        predicted: None,
        simulated_s: None,
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
    let merge = r.phase == Phase::Merge;
    let (ok, worse, bic_ok) = simpler_set_ok(
        &engine.opts.policy,
        (&h1, &t1, k_set),
        (h_cur, t_cur, k_all),
        &new.joints,
        merge,
        merge && r.agree,
    );
    out.tried.push(tested(round, r.phase, &new, (&h1, &t1, h_cur), (ok, worse, bic_ok)));
    // (At dt / r² when it fails at dt: [`merged_at_finer_step`].)
    let ok = ok || (merge && merged_at_finer_step(s, round, out, &r, k_set));
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
    let v = verdict(&h_wo, &h1, &new.joints, engine.opts.policy.gate());
    let bics = (bic(t_wo.n, t_wo.sse, k_set - new.effect.fitted()), bic(t1.n, t1.sse, k_set));
    let mut sel = Selected::new(&new, r.evidence, &v, h_wo.rmse(), h1.rmse(), bics);
    set_uncertainty(engine, train, &mut sel, &out.applied, &mut out.warnings);
    out.selected.push(sel);
    true
}

/// A merge that failed its test at the model's timestep, tested again with both sets replayed
/// at `dt / r²` ([`SearchPolicy::discretisation_refine`]): two values of one effect that differ
/// only because the model's integrator needs a little more on one joint than on another are
/// one value in continuous time. (For a smooth effect not only when the discretisation floor
/// shows a part: values fitted at `dt` absorb it unevenly and the floor reads zero, see
/// `discretisation`.) A leg whose three motors all reflect 0.06 kg·m² of armature,
/// recorded in near-continuous time and replayed at 1 ms, fitted 0.0629 on the hip and 0.0612
/// on knee and ankle: one value was 15 % worse on held-out at 1 ms, 0.5 % at 0.25 ms. `true`
/// when the merge passes the same test there (logged, phase `discretisation`).
///
/// [`SearchPolicy::discretisation_refine`]: super::policy::SearchPolicy::discretisation_refine
fn merged_at_finer_step(
    s: &Search,
    round: usize,
    out: &mut FitOutcome,
    r: &Replacement,
    k_set: usize,
) -> bool {
    let Search { engine, train, heldout, .. } = *s;
    let effect = r.set.last().expect("a replacement set ends with its new effect").effect;
    if !effect.smooth() && !out.floors.iter().any(|f| f.discretisation > 0.0) {
        return false;
    }
    let refine = engine.opts.policy.discretisation_refine.max(2);
    let k = (refine * refine) as u32;
    let (Some(h1), Some(t1), Some(h_cur), Some(t_cur)) = (
        engine.errors_at(heldout, &r.set, k),
        engine.errors_at(train, &r.set, k),
        engine.errors_at(heldout, &out.applied, k),
        engine.errors_at(train, &out.applied, k),
    ) else {
        return false;
    };
    let new = r.set.last().expect("a replacement set ends with its new effect");
    let k_all: usize = out.applied.iter().map(|a| a.effect.fitted()).sum();
    let (ok, worse, bic_ok) = simpler_set_ok(
        &engine.opts.policy,
        (&h1, &t1, k_set),
        (&h_cur, &t_cur, k_all),
        &new.joints,
        true,
        r.agree,
    );
    let mut t = tested(round, r.phase, new, (&h1, &t1, &h_cur), (ok, worse, bic_ok));
    t.phase = Phase::Discretisation;
    out.tried.push(t);
    ok
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
