//! Restarts from the pair look-ahead: a single effect that a failed pair re-fitted (its
//! partner not needed), or the winner at the values a pair or the kept effects' re-fit gave
//! it, competing with the round's winner as a single effect.

use crate::fit::effects::{self, Applied};
use crate::fit::stats::bic;

use super::policy::Phase;
use super::verdict::{at_bound, verdict};
use super::{Errors, FitOutcome, Search, Selected, Tried, sync_selected};

/// The best restart that passes, as (set, held-out errors, training errors); `tried` gets phase
/// "pair_restart" for each one evaluated.
///
/// A restart is a single effect that a failed pair re-fitted (its partner not needed): the
/// look-ahead's joint polish restarts its single fit. It passes when its parameters are inside
/// their bounds and it beats the round's winner beyond noise (paired test, z = 2), by ≥ 5 %
/// held-out RMSE, with a lower training BIC. (Asimov's knee Stribeck friction, 12-bit: the
/// single fit stops at v_s's lower bound, where Coulomb friction wins; the Stribeck + backlash
/// pair reaches (1.95, 0.97, 0.203) for (2, 1, 0.2) with a 0.9 mrad backlash that is not
/// needed.) The winner itself at the values a pair gave it is the same model and passes when
/// it is better on both training and held-out data (Asimov's knee load-dependent friction,
/// 12-bit: (0.567, 0.053) alone, (0.500, 0.097) beside a delay, for (0.5, 0.1)).
pub(super) fn best_restart(
    s: &Search,
    applied: &[Applied],
    single: &Selected,
    (h_base, h_single): (&Errors, &Errors),
    restarts: Vec<Vec<Applied>>,
    round: usize,
    out: &mut FitOutcome,
) -> Option<(Vec<Applied>, Errors, Errors, usize)> {
    if restarts.is_empty() {
        return None;
    }
    let engine = s.engine;
    let opts = engine.opts;
    let n = applied.len();
    let k_before: usize = applied.iter().map(|a| a.effect.fitted()).sum();
    let k_single = effects::by_id(&single.effect).map_or(0, |e| e.fitted());
    let t_single = {
        let mut w = applied.to_vec();
        w.push(Applied {
            effect: effects::by_id(&single.effect).expect("known"),
            joints: single.joints.clone(),
            params: single.values.clone(),
        });
        engine.errors(s.train, &w)?
    };
    let bic_single = bic(t_single.n, t_single.sse, k_before + k_single);
    let mut best: Option<(Vec<Applied>, Errors, Errors, usize)> = None;
    for set in restarts {
        let a = &set[n];
        if at_bound(engine, &set[..n], a) {
            continue;
        }
        let (Some(h), Some(t)) = (engine.errors(s.heldout, &set), engine.errors(s.train, &set))
        else {
            continue;
        };
        let group: Vec<String> = a.joints.iter().chain(&single.joints).cloned().collect();
        let vs = verdict(h_single, &h, &group, opts.policy.gate());
        let bic_a = bic(t.n, t.sse, k_before + a.effect.fitted());
        // The winner at other values is the same model: a better optimum on the training data
        // that is also better on held-out replaces it. Another effect must beat it beyond noise.
        let same = a.effect.id() == single.effect && a.joints == single.joints;
        let ok = if same {
            t.rmse() < t_single.rmse() && h.rmse() < h_single.rmse()
        } else {
            vs.significant
                && h.rmse() <= opts.policy.restart_gain * h_single.rmse()
                && bic_a < bic_single
        };
        let logged = out.log(Tried {
            round,
            phase: Phase::PairRestart,
            effect: a.effect.id().into(),
            joints: a.joints.clone(),
            params: a.params.iter().take(a.effect.fitted()).copied().collect(),
            train_rmse: t.rmse(),
            heldout_improvement: (h_base.rmse() - h.rmse()) / h_base.rmse().max(1e-300),
            significant: vs.significant,
            bic_decreased: bic_a < bic_single,
            kept: false,
            predicted: None,
            simulated_s: None,
        });
        if ok && best.as_ref().is_none_or(|(_, hb, ..)| h.rmse() < hb.rmse()) {
            best = Some((set, h, t, logged));
        }
    }
    best
}

/// Keeps the restart `(set, h, t)` from [`best_restart`] in place of the round's winner (and of
/// a pair that passed, when the restart beats it by the rule pairs compete by, [`SearchPolicy::beats`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn apply_restart(
    s: &Search,
    applied: &[Applied],
    kept: &[Selected],
    single: &Selected,
    (h_base, h_single, t_base): (&Errors, &Errors, &Errors),
    (set, h, t, logged): (Vec<Applied>, Errors, Errors, usize),
    z: f64,
    out: &mut FitOutcome,
) -> Option<Vec<(Selected, Applied)>> {
    let opts = s.engine.opts;
    let n = applied.len();
    let k_before: usize = applied.iter().map(|a| a.effect.fitted()).sum();
    let a = set[n].clone();
    let label = a.effect.id();
    out.tried[logged].kept = true;
    // Re-fitted beside the effects kept before it (their values moved), or in a pair whose
    // partner was not needed.
    let how = if set[..n].iter().zip(applied).any(|(x, y)| x.params != y.params) {
        "with the effects kept before it"
    } else {
        "in a pair whose partner was not needed"
    };
    out.notes.push(format!(
        "{} on {} re-fitted {how}: held-out RMSE {:.3e} rad, vs {:.3e} with {} alone",
        label,
        a.joints.join(","),
        h.rmse(),
        h_single.rmse(),
        single.effect
    ));
    let v = verdict(h_base, &h, &a.joints, opts.policy.gate_z(z));
    let evidence = kept
        .iter()
        .find(|k| k.effect == label && k.joints == a.joints)
        .map(|k| k.evidence.clone())
        .unwrap_or_else(|| single.evidence.clone());
    let bics = (bic(t_base.n, t_base.sse, k_before), bic(t.n, t.sse, k_before + a.effect.fitted()));
    let sel = Selected::new(&a, evidence, &v, h_base.rmse(), h.rmse(), bics);
    // The polish may have moved the effects kept earlier: carry them over.
    out.applied[..n].clone_from_slice(&set[..n]);
    sync_selected(out);
    Some(vec![(sel, a)])
}
