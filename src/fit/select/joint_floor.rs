//! After round 0, a candidate whose every joint is already at its floor is not screened.
//!
//! The search stops when the training residual of every fitted joint is within `white_ratio`
//! of its floor (white + reconstruction + discretisation, step 2 of docs/fitting.md): nothing is
//! left there that an effect could explain beyond noise. A round after round 0 runs because some
//! joint is still above its floor; a joint that is not has, by the same test, nothing left for
//! an effect on it alone to explain. An effect that changes the motion first at the joints it
//! is fitted on ([`Effect::joint_local`]: a torque, a transmission, a command or a reading of
//! those joints) and whose joints are all at their floor would have to explain another joint's
//! residual through the coupling of the chain while leaving its own joints' white residual
//! white. Such a candidate is left without a coarse fit (`tried`: phase `joint_floor`);
//! candidates on any joint above its floor, and the body effects and the ground contact (a
//! trunk's mass above the hip's axis loads the knee and the ankle, not the hip), are screened
//! as before. The round's z ([`SearchPolicy::z_needed`]) still counts them: they are
//! candidates the diagnosis named, judged on the same training data.
//!
//! Not in round 0: its floors are the nominal model's, where an error elsewhere in the chain
//! can still move a joint's residual; from round 1 on, the kept effects explain what the data
//! most showed, and a joint's floor test is the one that would end the search if every joint
//! met it. No new constant: `white_ratio` is the search's own stop.
//!
//! [`SearchPolicy::z_needed`]: super::policy::SearchPolicy::z_needed
//! [`Effect::joint_local`]: crate::fit::effects::Effect::joint_local

use super::groups::Cand;
use super::policy::Phase;
use super::screen::Screen;
use super::{FitOutcome, Floor, Tried};

/// After round 0, takes the candidates of a joint-local effect whose joints are all at their
/// floor out of `cands` ([`take_at_floor`], at the search's `white_ratio`) and logs each (`tried`: phase
/// `joint_floor`, with its linear prediction); `true` when none is left to screen.
pub(super) fn leave_at_floor(
    cands: &mut Vec<Cand>,
    (floors, ratio, round): (&[Floor], f64, usize),
    screen: &Screen,
    out: &mut FitOutcome,
) -> bool {
    for (e, g, _) in take_at_floor(cands, floors, ratio, round) {
        let t = Tried::not_tested(round, Phase::JointFloor, e.id(), &g, vec![], f64::NAN);
        out.tried.push(Tried { predicted: screen.predict(e.id(), &g), ..t });
    }
    cands.is_empty()
}

/// Whether every joint of `group` has a floor in `floors` that its residual has reached
/// (within `ratio`, [`Floor::reached`]); `false` for an empty group or a joint without one.
pub(super) fn all_at_floor(group: &[String], floors: &[Floor], ratio: f64) -> bool {
    !group.is_empty()
        && group.iter().all(|j| floors.iter().any(|f| f.joint == *j && f.reached(ratio)))
}

/// After round 0 (`round` > 0), the candidates of `cands` of a joint-local effect
/// ([`Effect::joint_local`]) whose joints are all at their floor ([`all_at_floor`]), taken out of
/// `cands` (whose order is kept) and returned; none in round 0.
///
/// [`Effect::joint_local`]: crate::fit::effects::Effect::joint_local
pub(super) fn take_at_floor(
    cands: &mut Vec<Cand>,
    floors: &[Floor],
    ratio: f64,
    round: usize,
) -> Vec<Cand> {
    if round == 0 {
        return vec![];
    }
    let (out, kept): (Vec<Cand>, Vec<Cand>) = std::mem::take(cands)
        .into_iter()
        .partition(|(e, g, _)| e.joint_local() && all_at_floor(g, floors, ratio));
    *cands = kept;
    out
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use super::*;
    use crate::fit::effects::{
        ActionDelay, Armature, Backlash, ComOffset, CoulombFriction, Effect, GainError,
        GroundContact, LinkInertia, LinkMass,
    };

    fn floor(joint: &str, ms: f64, white: f64) -> Floor {
        Floor { joint: joint.into(), ms, white, reconstruction: 0.1 * white, discretisation: 0.0 }
    }

    fn cand(e: &'static dyn Effect, joints: &[&str]) -> Cand {
        (e, joints.iter().map(|j| j.to_string()).collect(), BTreeMap::new())
    }

    #[test]
    fn a_joint_within_the_ratio_of_its_floor_is_at_it() {
        // Floor 1.1 (white 1 + reconstruction 0.1): 1.6 is within 1.5 x, 1.7 is not.
        let floors = [floor("hip", 1.6, 1.0), floor("knee", 1.7, 1.0)];
        assert!(all_at_floor(&["hip".into()], &floors, 1.5));
        assert!(!all_at_floor(&["knee".into()], &floors, 1.5));
        assert!(!all_at_floor(&["hip".into(), "knee".into()], &floors, 1.5));
        // A joint without a floor, or no joint, is never at one.
        assert!(!all_at_floor(&["ankle".into()], &floors, 1.5));
        assert!(!all_at_floor(&[], &floors, 1.5));
        // A stricter ratio leaves the hip above its floor.
        assert!(!all_at_floor(&["hip".into()], &floors, 1.4));
    }

    #[test]
    fn only_candidates_whose_joints_are_all_at_their_floor_are_taken_after_round_0() {
        let floors = [floor("hip", 1.0, 1.0), floor("knee", 9.0, 1.0), floor("ankle", 1.2, 1.0)];
        let all = vec![
            cand(&CoulombFriction, &["hip"]),
            cand(&Backlash, &["knee"]),
            cand(&Armature, &["hip", "knee", "ankle"]),
            cand(&ActionDelay, &["hip", "ankle"]),
            cand(&GainError, &["ankle"]),
        ];
        let ids = |c: &[Cand]| -> Vec<(String, Vec<String>)> {
            c.iter().map(|(e, g, _)| (e.id().to_string(), g.clone())).collect()
        };
        let mut cands = all.clone();
        assert!(take_at_floor(&mut cands, &floors, 1.5, 0).is_empty(), "round 0 screens all");
        assert_eq!(ids(&cands), ids(&all));
        let out = take_at_floor(&mut cands, &floors, 1.5, 1);
        assert_eq!(
            ids(&out),
            ids(&[all[0].clone(), all[3].clone(), all[4].clone()]),
            "the hip, the ankle and the two together are at their floors"
        );
        assert_eq!(ids(&cands), ids(&[all[1].clone(), all[2].clone()]), "order kept");
    }

    #[test]
    fn a_body_effect_or_the_ground_contact_is_screened_on_a_joint_at_its_floor() {
        // Every joint between a body and the base carries its mass, and the floor pushes on the
        // whole standing chain: the hip at its floor says nothing of the trunk's mass.
        let floors = [floor("hip", 1.0, 1.0), floor("knee", 9.0, 1.0)];
        let bodies: Vec<Cand> =
            [&LinkMass as &dyn Effect, &ComOffset, &LinkInertia, &GroundContact]
                .into_iter()
                .map(|e| cand(e, &["hip"]))
                .collect();
        let mut cands = bodies.clone();
        cands.push(cand(&Armature, &["hip"]));
        let out = take_at_floor(&mut cands, &floors, 1.5, 2);
        assert_eq!(out.len(), 1, "only the joint effect is left out");
        assert_eq!(out[0].0.id(), Armature.id());
        assert_eq!(cands.len(), bodies.len());
        assert!(cands.iter().all(|(e, ..)| !e.joint_local()));
    }
}
