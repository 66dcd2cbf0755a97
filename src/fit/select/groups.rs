//! Joint groups of the candidates: a joint's left/right partner, a group already among the
//! candidates, and whether a screen set is the training set itself.

use std::collections::BTreeMap;

use crate::fit::diagnose::Candidate;
use crate::fit::effects::{self, Applied, Effect};
use crate::model::mirror::{leg_joint, mirror_in};
use crate::sim2real::recording::Recording;

use super::engine::Engine;

/// A candidate: effect, joint group, evidence.
pub(super) type Cand = (&'static dyn Effect, Vec<String>, BTreeMap<String, f64>);

/// A joint's left/right partner among the fitted joints, paired as lint pairs them
/// (`model::mirror::mirror_in`: `LL_`/`LR_` are a biped's legs only when both exist).
pub(super) fn partner(joint: &str, joints: &[String]) -> Option<String> {
    let has = |n: &str| joints.iter().any(|j| j == n);
    mirror_in(joint, None, has).map(|(_, m)| m).filter(|m| has(m))
}

/// Whether `a` holds the same recordings as `b` (a screen set that came back whole).
pub(super) fn same_data(a: &[Recording], b: &[Recording]) -> bool {
    a.len() == b.len()
        && a.iter().zip(b).all(|(x, y)| x.t.len() == y.t.len() && x.t.first() == y.t.first())
}

/// Whether `effect` on exactly `group` is already a candidate. Only an identical group is a
/// duplicate: a joint inside a family or all-joints group of the same effect still gets its own
/// candidate.
pub(super) fn has_group(cands: &[Cand], effect: &str, group: &[String]) -> bool {
    cands.iter().any(|(e, g, _)| e.id() == effect && g == group)
}

/// Whether `effect` acts on `joint` ([`Effect::acts_on`]; a joint the model does not have is
/// left to the callers' own checks).
pub(super) fn acts_on(robot: &crate::model::Robot, effect: &dyn Effect, joint: &str) -> bool {
    effects::JointTarget::of(robot, joint).is_none_or(|t| effect.acts_on(&t))
}

/// A joint and its left/right partner, in name order (the order groups are compared in).
pub(super) fn sorted_pair(j: &str, p: String) -> Vec<String> {
    let mut g = vec![j.to_string(), p];
    g.sort();
    g
}

/// The round's candidate (effect, joint group) list, best first: each diagnosed candidate on
/// its joint, with its left/right partner, its motor family, the same joint on every leg and
/// every recorded joint as further groups where they apply (`candidates_per_round` of the
/// diagnosis; with `every_effect`, the best joint of every other effect and every effect on
/// the top-ranked joint). Effects already applied on a joint are not candidates there.
pub(super) fn candidate_list(
    engine: &Engine,
    diag: &[Candidate],
    applied: &[Applied],
    allowed: &[String],
) -> Vec<Cand> {
    let opts = engine.opts;
    let robot = engine.robot;
    let covered = |id: &str, j: &str| {
        applied.iter().any(|a| a.effect.id() == id && a.joints.iter().any(|x| x == j))
    };
    let mut cands: Vec<Cand> = Vec::new();
    let push = |c: &Candidate, cands: &mut Vec<Cand>| {
        if covered(c.effect, &c.joint) || c.explained_rms <= 1e-9 {
            return;
        }
        let Some(e) = effects::by_id(c.effect) else { return };
        let group = vec![c.joint.clone()];
        // A group names only joints the effect acts on ([`Effect::acts_on`]): an actuator's
        // effect is not shared with the passive joints an equality or a tendon couples to it.
        let acts = |j: &String| acts_on(robot, e, j);
        // The joint and its left/right partner as one more group when the partner also ranks
        // high: both compete (one knee with a delay must not be smeared over both, and an
        // effect both sides have is fitted once).
        let pair: Option<Vec<String>> = partner(&c.joint, &engine.joints)
            .filter(|p| {
                !covered(c.effect, p)
                    && acts(p)
                    && effects::alike_over(robot, e, &[c.joint.clone(), p.clone()])
                    && diag
                        .iter()
                        .take(opts.policy.rank_window())
                        .any(|d| d.effect == c.effect && &d.joint == p)
            })
            .map(|p| sorted_pair(&c.joint, p));
        // Only an identical group is a duplicate: a joint inside a family or all-joints group
        // of the same effect still gets its own candidate (Coulomb friction on one knee when
        // the diagnosis ranked it first on a hip).
        let single_new = !has_group(cands, e.id(), &group);
        let pair = pair.filter(|g| !has_group(cands, e.id(), g));
        if !single_new && pair.is_none() {
            return;
        }
        let mut ev = c.evidence.clone();
        ev.insert("explained_rms".into(), c.explained_rms);
        ev.insert("residual_rms".into(), c.residual_rms);
        // The joint's motor family as one more group (shared parameters).
        let fam: Vec<String> = match opts.families.get(&c.joint) {
            Some(f) => engine
                .joints
                .iter()
                .filter(|j| opts.families.get(*j) == Some(f) && !covered(c.effect, j) && acts(j))
                .cloned()
                .collect(),
            None => vec![],
        };
        let fam_new = fam.len() >= opts.policy.min_group && !has_group(cands, e.id(), &fam);
        // The same joint on every leg of a quadruped (`FL_knee` … `RR_knee`) as one more group
        // when a joint of another leg pair (not the mirror: the pair covers that) also ranks
        // high for this effect: four knees with the same missing armature are one group, not
        // two pairs merged later.
        let legs: Vec<String> = match leg_joint(&c.joint) {
            Some(part) => engine
                .joints
                .iter()
                .filter(|j| leg_joint(j) == Some(part) && !covered(c.effect, j) && acts(j))
                .cloned()
                .collect(),
            None => vec![],
        };
        let mirror = partner(&c.joint, &engine.joints);
        let legs_new = legs.len() >= opts.policy.min_group
            && legs != fam
            && !has_group(cands, e.id(), &legs)
            && diag.iter().take(opts.policy.rank_window()).any(|d| {
                d.effect == c.effect
                    && d.joint != c.joint
                    && Some(&d.joint) != mirror.as_ref()
                    && legs.contains(&d.joint)
            })
            && engine.shared_start(e, applied, &legs);
        // Every recorded joint as one group sharing the parameters (an effect the whole robot
        // has, such as a missing damping or friction, a delay or a servo gain error, or one
        // armature of identical motors) — when the parameters mean the same on those joints
        // ([`Engine::shareable`]), even where the model gives each joint a value of its own:
        // a leg modelled with armature 0.04 / 0.03 / 0.012 whose three motors all reflect 0.06
        // came back as two groups when the one-value group was never a candidate.
        let all: Vec<String> =
            engine.joints.iter().filter(|j| !covered(c.effect, j) && acts(j)).cloned().collect();
        let all_new = all.len() >= 2
            && all.len() > pair.as_ref().map_or(1, |p| p.len())
            && all != fam
            && all != legs
            && !has_group(cands, e.id(), &all)
            && engine.shareable(e, &all);
        if single_new {
            cands.push((e, group, ev.clone()));
        }
        if let Some(p) = pair {
            cands.push((e, p, ev.clone()));
        }
        if fam_new {
            cands.push((e, fam, ev.clone()));
        }
        if legs_new {
            let mut ev = ev.clone();
            ev.insert("every_leg_group".into(), 1.0);
            cands.push((e, legs, ev));
        }
        if all_new {
            let mut ev = ev;
            ev.insert("all_joints_group".into(), 1.0);
            cands.push((e, all, ev));
        }
    };
    for c in diag {
        if cands.len() >= opts.policy.candidates_per_round {
            break;
        }
        push(c, &mut cands);
    }
    if opts.policy.every_effect {
        // The best-ranked joint of every other effect: the linearised ranking is only a guide
        // (a doubled inertia or a saturation is far from linear).
        // Effects whose best joint explains less than a tenth of the top candidate are left out.
        let top = diag
            .iter()
            .filter(|c| !covered(c.effect, &c.joint))
            .map(|c| c.explained_rms)
            .fold(0.0, f64::max);
        for id in allowed {
            if cands.iter().any(|(e, ..)| e.id() == id) {
                continue;
            }
            if let Some(c) = diag.iter().find(|c| {
                c.effect == id
                    && !covered(c.effect, &c.joint)
                    && c.explained_rms > 1e-9
                    && c.explained_rms >= opts.policy.minor_effect_share * top
            }) {
                push(c, &mut cands);
            }
        }
        // Where the error is, the ranking knows better than what it is: every effect is also
        // tried on the top-ranked joint. (A 1 N·m Coulomb friction on Asimov's left knee: the
        // linearised ranking put Coulomb friction first on a hip, whose fit explained nothing,
        // and the knee was left to a two-parameter friction model plus backlash.)
        let top_joint = diag
            .iter()
            .find(|c| !covered(c.effect, &c.joint) && c.explained_rms > 1e-9)
            .map(|c| c.joint.clone());
        if let Some(tj) = top_joint {
            for id in allowed {
                if has_group(&cands, id, std::slice::from_ref(&tj)) {
                    continue;
                }
                if let Some(c) = diag
                    .iter()
                    .find(|c| c.effect == id && c.joint == tj && !covered(c.effect, &c.joint))
                {
                    push(c, &mut cands);
                }
            }
        }
    }
    cands
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirror_partners() {
        let js = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let h = js(&["left_knee", "right_knee", "LL_HFE", "LR_HFE", "elbow_pitch"]);
        assert_eq!(partner("left_knee", &h).as_deref(), Some("right_knee"));
        assert_eq!(partner("LR_HFE", &h).as_deref(), Some("LL_HFE"));
        assert_eq!(partner("elbow_pitch", &h), None);
        // A quadruped's left-rear leg (`LF_` `LR_` `RF_` `RR_`) pairs with `RR_`, never `LL_`.
        let q = js(&["LF_KFE", "LR_KFE", "RF_KFE", "RR_KFE"]);
        assert_eq!(partner("LR_KFE", &q), None);
        assert_eq!(partner("LF_KFE", &q).as_deref(), Some("RF_KFE"));
        // Booster T1 and Unitree H1 spellings; a partner outside the fit is no partner.
        let t = js(&["Left_Knee_Pitch", "Right_Knee_Pitch", "right_knee_joint"]);
        assert_eq!(partner("Left_Knee_Pitch", &t).as_deref(), Some("Right_Knee_Pitch"));
        assert_eq!(partner("right_knee_joint", &t), None);
    }
}
