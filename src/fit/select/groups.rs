//! Joint groups of the candidates: a joint's left/right partner, a group already among the
//! candidates, and whether a screen set is the training set itself.

use std::collections::BTreeMap;

use crate::fit::effects::Effect;
use crate::model::mirror::mirror_in;
use crate::sim2real::recording::Recording;

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

/// A joint and its left/right partner, in name order (the order groups are compared in).
pub(super) fn sorted_pair(j: &str, p: String) -> Vec<String> {
    let mut g = vec![j.to_string(), p];
    g.sort();
    g
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
