//! The round's winner: its re-fit on the whole training set, and the notes naming its rivals.

use crate::fit::effects::{self, Applied, Effect};
use crate::fit::stats::bic;

use super::policy::SearchPolicy;
use super::verdict::{Gate, verdict};
use super::{Errors, Search, Selected};

/// A candidate's fit `p` on the screen's stretch, with its errors on the whole training set,
/// or `None` when it explains nothing there. A fit that leaves the whole training set worse
/// than without the candidate (`base_train`, its RMSE) was led by the stretch alone (a real
/// servo's load friction run to its bound on the stretches of largest residual): the
/// candidate gets a coarse fit (`screen_evals`) on the whole training set instead, and goes on
/// from it when that improves the set (the round's winner is re-fitted there in full, [`refine`]).
pub(super) fn on_whole_set(
    s: &Search,
    applied: &[Applied],
    (e, group): (&'static dyn Effect, &[String]),
    p: Vec<f64>,
    base_train: f64,
) -> Option<(Vec<f64>, Errors)> {
    let with = |p: &[f64]| {
        let mut trial = applied.to_vec();
        trial.push(Applied { effect: e, joints: group.to_vec(), params: p.to_vec() });
        trial
    };
    let tr = s.engine.errors(s.train, &with(&p))?;
    if tr.rmse() < base_train {
        return Some((p, tr));
    }
    let evals = s.engine.opts.policy.screen_evals;
    let (q, _) = s.engine.fit_budget(s.train, applied, e, group, evals);
    let t = s.engine.errors(s.train, &with(&q))?;
    (!q.is_empty() && t.rmse() < base_train).then_some((q, t))
}

/// Whether a candidate, replayed on the held-out set at its coarse fit (`at_coarse`: those
/// errors, and its joints), is beaten there decisively by a kept candidate of the round
/// (`kept`: its held-out errors after its fit, and its joints): the kept one's held-out RMSE
/// over all fitted joints is at most (1 − `decisive_improvement`) times the candidate's, and
/// on the windows of the two groups more than twice as many are better beyond `window_change`
/// as worse. Such a candidate is judged at its coarse fit and not fitted in full. A round's
/// winner has the lowest held-out RMSE, or is a simpler one within `simpler_within` of it; a
/// full fit goes on from the coarse fit on the same training data, and would have to halve
/// the held-out error the coarse fit leaves to come near the kept one (on the chain leg's
/// and pendulum's rivals, the full fit moved it by at most 8 %, either way), where noise cannot halve an unseen error either
/// (the gate's decisive improvement). Judged at its coarse fit, it is still gated where the
/// round's pair look-ahead could pair it, and when kept it partners the look-ahead
/// ([`super::rival`]).
pub(super) fn beaten_at_coarse(
    (kept, kept_joints): (&Errors, &[String]),
    (at_coarse, joints): (&Errors, &[String]),
    policy: &SearchPolicy,
) -> bool {
    let (best, mine) = (kept.rmse(), at_coarse.rmse());
    if !(best.is_finite() && mine.is_finite()) || best > (1.0 - policy.decisive_improvement) * mine
    {
        return false;
    }
    let mut group: Vec<String> = joints.to_vec();
    group.extend(kept_joints.iter().filter(|j| !joints.contains(j)).cloned());
    // Only the windows' majority is asked of the verdict (no z test).
    let gate = Gate { z: f64::INFINITY, ..policy.gate() };
    verdict(at_coarse, kept, &group, gate).significant
}

/// The round's winner `w`, fitted on the screen's data, fitted again on the whole training set
/// from those values; the refit replaces it when it lowers the training error (its held-out
/// figures are measured again).
pub(super) fn refine(
    s: &Search,
    applied: &[Applied],
    w: Selected,
    (tr, ho): (&Errors, &Errors),
    z: f64,
) -> Selected {
    let engine = s.engine;
    let Some(e) = effects::by_id(&w.effect) else { return w };
    let (p, f) = engine.fit_from(s.train, applied, (e, &w.joints), Some(&w.values));
    let mut trial = applied.to_vec();
    trial.push(Applied { effect: e, joints: w.joints.clone(), params: p });
    let (Some(tr_a), Some(ho_a)) =
        (engine.errors(s.train, &trial), engine.errors(s.heldout, &trial))
    else {
        return w;
    };
    let mut old = applied.to_vec();
    old.push(Applied { effect: e, joints: w.joints.clone(), params: w.values.clone() });
    if !f.is_finite() || engine.errors(s.train, &old).is_none_or(|t| tr_a.rmse() >= t.rmse()) {
        return w;
    }
    let k_before: usize = applied.iter().map(|a| a.effect.fitted()).sum();
    let v = verdict(ho, &ho_a, &w.joints, engine.opts.policy.gate_z(z));
    let bics = (bic(tr.n, tr.sse, k_before), bic(tr_a.n, tr_a.sse, k_before + e.fitted()));
    let a = trial.last().expect("pushed");
    Selected::new(a, w.evidence, &v, ho.rmse(), ho_a.rmse(), bics)
}

/// Notes naming the rivals of the round's winner `accepted[win]`: other effects on any of its
/// joints that explain the data as well (`same[i]`: within Occam's equivalence, see above). The
/// simpler one is kept, but the data do not rule the rival out — on a stiff servo a static
/// friction and a dead band both hold a joint near its command. The same effect on another
/// joint group is not a rival (the merge and the group search decide that).
pub(super) fn rival_notes(accepted: &[Selected], win: usize, same: &[bool]) -> Vec<String> {
    let w = &accepted[win];
    let show = |s: &Selected| {
        let p: Vec<String> =
            s.params.iter().map(|(k, v)| format!("{k} {}", effects::num(*v))).collect();
        format!("{} on {} ({})", s.effect, s.joints.join(","), p.join(", "))
    };
    accepted
        .iter()
        .enumerate()
        .filter(|&(i, s)| {
            i != win
                && same.get(i) == Some(&true)
                && s.effect != w.effect
                && s.joints.iter().any(|j| w.joints.contains(j))
                && !nested(&s.effect, &w.effect)
                && !nested(&w.effect, &s.effect)
        })
        .map(|(_, s)| {
            format!(
                "{} explains these recordings as well as the kept {} (held-out RMSE {:.3e} vs \
                 {:.3e} rad, no difference beyond noise; kept as the simpler or better one): the \
                 data do not tell them apart",
                show(s),
                show(w),
                s.heldout_rmse_after,
                w.heldout_rmse_after
            )
        })
        .collect()
}

/// Whether effect `outer` contains effect `inner` as a special case ([`Effect::absorb`]):
/// Stribeck friction that fits as well as the kept Coulomb friction is no rival of it.
fn nested(outer: &str, inner: &str) -> bool {
    let (Some(o), Some(i)) = (effects::by_id(outer), effects::by_id(inner)) else {
        return false;
    };
    let mine: Vec<f64> = o.params().iter().map(|p| p.default).collect();
    o.absorb(i, &mine, &vec![0.0; i.params().len()]).is_some()
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use super::*;
    use crate::fit::effects::{
        Armature, Backlash, CoulombFriction, StribeckFriction, ViscousDamping,
    };

    fn sel(effect: &str, joints: &[&str], p: &[(&str, f64)], heldout: f64) -> Selected {
        Selected {
            effect: effect.into(),
            joints: joints.iter().map(|j| j.to_string()).collect(),
            params: p.iter().map(|(k, v)| (k.to_string(), *v)).collect(),
            stderr: BTreeMap::new(),
            identifiable: true,
            unidentified: vec![],
            evidence: BTreeMap::new(),
            heldout_improvement: 0.9,
            heldout_rmse_before: 0.014,
            heldout_rmse_after: heldout,
            window_improvement: 0.0,
            window_improvement_se: 0.0,
            bic_before: 0.0,
            bic_after: 0.0,
            values: vec![],
        }
    }

    /// Held-out errors with these per-window RMSEs on joint `j` (one sample per window).
    fn errs(j: &str, w: &[f64]) -> Errors {
        Errors {
            sse: w.iter().map(|v| v * v).sum(),
            n: w.len(),
            windows: w.iter().map(|v| (j.to_string(), *v)).collect(),
            eps: vec![],
        }
    }

    #[test]
    fn a_candidate_is_beaten_at_its_coarse_fit_only_decisively_and_on_most_windows() {
        let p = SearchPolicy::default();
        let knee = vec!["knee".to_string()];
        let coarse = errs("knee", &[4.0, 4.0, 4.0, 4.0, 4.0, 4.0]);
        // Less than half the candidate's error on every window: it cannot come near.
        let kept = errs("knee", &[1.5, 1.5, 1.5, 1.5, 1.5, 1.5]);
        assert!(beaten_at_coarse((&kept, &knee), (&coarse, &knee), &p));
        // 60 % of it: a full fit could close that.
        let near = errs("knee", &[2.4, 2.4, 2.4, 2.4, 2.4, 2.4]);
        assert!(!beaten_at_coarse((&near, &knee), (&coarse, &knee), &p));
        // Half the RMSE, but from one window, the others worse: not most windows better.
        let one = errs("knee", &[0.1, 4.2, 4.2, 4.2, 4.2, 4.2]);
        let coarse1 = errs("knee", &[40.0, 4.0, 4.0, 4.0, 4.0, 4.0]);
        assert!(one.rmse() <= 0.5 * coarse1.rmse());
        assert!(!beaten_at_coarse((&one, &knee), (&coarse1, &knee), &p));
        // A replay that failed proves nothing.
        let failed = Errors { n: 0, ..errs("knee", &[]) };
        assert!(!beaten_at_coarse((&kept, &knee), (&failed, &knee), &p));
    }

    #[test]
    fn an_equally_good_rival_on_the_winners_joint_is_named() {
        let acc = vec![
            sel(
                StribeckFriction.id(),
                &["left_knee"],
                &[("static", 2.0), ("dynamic", 1.0)],
                7.0e-4,
            ),
            sel(Backlash.id(), &["left_knee"], &[(Backlash.id(), 0.0369)], 7.3e-4),
            // Equivalent but on another joint: not a rival of the knee's friction.
            sel(Armature.id(), &["right_knee"], &[(Armature.id(), 0.02)], 7.2e-4),
            // On the knee, but worse beyond noise (not in Occam's set).
            sel(ViscousDamping.id(), &["left_knee"], &[("damping", 3.0)], 9.0e-4),
            // The same effect on a group with the knee: a group question, not a rival.
            sel(Backlash.id(), &["left_knee", "right_knee"], &[(Backlash.id(), 0.03)], 7.1e-4),
            // Another effect on a group that contains the knee: a rival.
            sel(
                CoulombFriction.id(),
                &["left_knee", "right_knee"],
                &[("frictionloss", 1.5)],
                7.1e-4,
            ),
        ];
        let same = [true, true, true, false, true, true];
        let n = rival_notes(&acc, 1, &same);
        assert_eq!(n.len(), 2, "{n:#?}");
        assert!(n[0].starts_with("stribeck_friction on left_knee (dynamic 1, static 2) explains"));
        assert!(n[0].contains("the kept backlash on left_knee (backlash 0.0369)"), "{}", n[0]);
        assert!(n[0].contains("7.000e-4 vs 7.300e-4 rad"), "{}", n[0]);
        assert!(n[1].starts_with("coulomb_friction on left_knee,right_knee (frictionloss 1.5)"));
        // Stribeck friction as good as the kept Coulomb friction contains it: no rival.
        let nest = vec![
            sel(CoulombFriction.id(), &["left_knee"], &[("frictionloss", 1.5)], 7.0e-4),
            sel(StribeckFriction.id(), &["left_knee"], &[("static", 1.5)], 6.9e-4),
            sel(Backlash.id(), &["left_knee"], &[(Backlash.id(), 0.03)], 7.1e-4),
        ];
        let n = rival_notes(&nest, 0, &[true, true, true]);
        assert_eq!(n.len(), 1, "{n:#?}");
        assert!(n[0].starts_with("backlash on left_knee"), "{}", n[0]);
        assert_eq!(rival_notes(&nest, 1, &[true, true, false]), Vec::<String>::new());
        // Nothing equivalent: no note.
        assert!(rival_notes(&acc, 1, &[false, true, false, false, false, false]).is_empty());
    }
}
