//! A later round's probes of an effect with several probe values ([`Effect::probes`]: a
//! `torque_limit` at its signature's level and at the 95th and 99th percentiles of the servo
//! torque) start from the value the earlier round's screen kept.
//!
//! The several values are there to find a level at which the limit acts on the probes' data: a
//! limit reached by the top 1 % of torques acts only after each saturation, one above every
//! torque changes nothing. Round 0 replayed each and kept the one that explained most; the model
//! a later round screens differs from it by the effects kept since, which explain part of the
//! residual and move the forces little. A later round probes that value alone; where it gives no
//! column there (the limit no longer acts: a move judged to change nothing
//! ([`Effect::unmoved`]), a replay as the base's or one that failed), the candidate is probed at
//! each of its own values as before. No constant: the test is the one every probe meets, a
//! column that is not zero.
//!
//! [`Effect::probes`]: crate::fit::effects::Effect::probes
//! [`Effect::unmoved`]: crate::fit::effects::Effect::unmoved

use std::collections::BTreeMap;

use crate::fit::diagnose::Candidate;
use crate::fit::effects::{self, JointTarget};

use super::probe::{CHOSEN_PROBE, Probe};
use super::{Engine, entries};

/// Gives each uncovered entry of `diag` whose effect has more than one probe value at its
/// start in `m0`, and that `earlier` (an earlier round's screened diagnosis) names a best probe
/// for inside the parameter's bounds, that value as its chosen probe ([`CHOSEN_PROBE`]);
/// returns the entries seeded. An entry that names its chosen probe already is left as it is.
pub(super) fn seed(
    engine: &Engine,
    m0: &mujoco_rs::prelude::MjModel,
    diag: &mut [Candidate],
    covered: &(dyn Fn(&str, &str) -> bool + Sync),
    earlier: &[Candidate],
) -> Vec<usize> {
    let mut out = Vec::new();
    for (i, c) in diag.iter_mut().enumerate() {
        if covered(c.effect, &c.joint) || c.evidence.contains_key(CHOSEN_PROBE) {
            continue;
        }
        let Some(v) = earlier
            .iter()
            .find(|e| e.effect == c.effect && e.joint == c.joint)
            .and_then(|e| e.evidence.get(CHOSEN_PROBE).copied())
            .filter(|v| v.is_finite())
        else {
            continue;
        };
        let (Some(effect), Some(t)) =
            (effects::by_id(c.effect), JointTarget::of(engine.robot, &c.joint))
        else {
            continue;
        };
        let (p0, (lo, hi)) = (effect.initial(m0, &t), effect.bounds(m0, &t));
        let (Some(&s), Some(&l), Some(&h)) = (p0.first(), lo.first(), hi.first()) else {
            continue;
        };
        if effect.probes(s, l, h, &c.evidence).len() > 1 && v > l && v <= h && v != s {
            c.evidence.insert(CHOSEN_PROBE.into(), v);
            out.push(i);
        }
    }
    out
}

/// The entries of effect `id` among `seeded` whose probes `found` hold no column of the first
/// parameter: their seeded value is dropped ([`CHOSEN_PROBE`]), so that they are probed at their
/// own values.
pub(super) fn unanswered(
    id: &str,
    diag: &mut [Candidate],
    covered: &(dyn Fn(&str, &str) -> bool + Sync),
    seeded: &[usize],
    found: &BTreeMap<usize, Vec<Option<Probe>>>,
) -> Vec<usize> {
    let again: Vec<usize> = entries(id, diag, covered)
        .into_iter()
        .filter(|i| seeded.contains(i))
        .filter(|i| !matches!(found.get(i).and_then(|p| p.first()), Some(Some(_))))
        .collect();
    for &i in &again {
        diag[i].evidence.remove(CHOSEN_PROBE);
    }
    again
}

#[cfg(test)]
mod tests {
    use super::CHOSEN_PROBE;
    use crate::fit::diagnose::{Candidate, diagnose};
    use crate::fit::effects::{Effect, JointTarget, TorqueLimit, ViscousDamping, model_with};
    use crate::fit::select::screen::Screen;
    use crate::fit::select::{Engine, FitOptions};
    use crate::sim2real::recording::Recording;

    /// A later screen of a torque limit (several probe values) probes the value the earlier one
    /// kept, alone; a value that acts no more (above every torque) is replaced by the probes of
    /// the candidate's own values, which choose as a screen without an earlier one does; an
    /// effect of one probe value keeps its own whatever the earlier screen names.
    #[test]
    fn a_later_screen_probes_the_earlier_best_value_alone_while_it_acts() {
        let (robot, recs) = crate::synth::recorded::pendulum(None, 3, 11);
        let opts = FitOptions::default();
        let allowed = vec![TorqueLimit.id().to_string(), ViscousDamping.id().to_string()];
        let secs = |r: &[Recording]| r.iter().map(|x| x.t.last().unwrap() - x.t[0]).sum::<f64>();
        // A screen on an engine of its own: its diagnosis, cost and probes' seconds.
        let screen = |earlier: &[Candidate]| {
            let engine = Engine::new(&robot, &recs, &opts);
            let base = engine.errors_held(&recs, &[]).expect("replay");
            let mut diag =
                diagnose(&robot, &recs, &base.eps, &engine.joints, &allowed, opts.gap_mask_s);
            let before = engine.rollout_stats().simulated_s;
            let _ = Screen::build_after(
                &engine,
                (&recs, &[], &base),
                &mut diag,
                &|_, _| false,
                earlier,
            );
            let cost = engine.rollout_stats().simulated_s - before;
            let probes = engine.probe_set_held(&recs, &[]).expect("made by the screen");
            let unprobed = engine.unprobed().len();
            (diag, cost, secs(&probes), unprobed)
        };
        let chosen = |d: &[Candidate], e: &dyn Effect| {
            d.iter().find(|c| c.effect == e.id()).expect("diagnosed").evidence[CHOSEN_PROBE]
        };
        let (plain, plain_cost, s, plain_unprobed) = screen(&[]);
        let limit = plain.iter().find(|c| c.effect == TorqueLimit.id()).expect("diagnosed");
        let m0 = model_with(&robot, &[]);
        let t = JointTarget::of(&robot, "servo").expect("servo");
        let (p0, (lo, hi)) = (TorqueLimit.initial(&m0, &t), TorqueLimit.bounds(&m0, &t));
        let own = TorqueLimit.probes(p0[0], lo[0], hi[0], &limit.evidence);
        assert!(own.len() >= 2, "{own:?}");
        let best = chosen(&plain, &TorqueLimit);
        assert!(own.contains(&best), "{best} of {own:?}");
        // The earlier best value alone: the torque limit's other values are not replayed.
        let (seeded, cost, _, unprobed) = screen(&plain);
        assert_eq!(chosen(&seeded, &TorqueLimit), best);
        let saved = (own.len() - 1 - (plain_unprobed - unprobed)) as f64 * s;
        assert!(saved >= s, "{own:?}: {plain_unprobed} / {unprobed} left out");
        assert!((plain_cost - cost - saved).abs() < 1e-6, "{plain_cost} → {cost}, {s} s each");
        // A value above every torque acts no more: the candidate's own values, as without one;
        // the viscous damping's probe is its own, not the earlier screen's.
        let mut earlier = plain.clone();
        for c in &mut earlier {
            let v =
                if c.effect == TorqueLimit.id() { hi[0] } else { 2.0 * c.evidence[CHOSEN_PROBE] };
            c.evidence.insert(CHOSEN_PROBE.into(), v);
        }
        let (again, cost, ..) = screen(&earlier);
        assert_eq!(chosen(&again, &TorqueLimit), best);
        assert_eq!(chosen(&again, &ViscousDamping), chosen(&plain, &ViscousDamping));
        assert!(cost >= plain_cost - 1e-6, "{cost} of {plain_cost}");
    }
}
