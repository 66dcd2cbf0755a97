use super::Reach;
use crate::fit::effects::{Applied, CoulombFriction, Effect, StribeckFriction, ViscousDamping};
use crate::fit::select::{Engine, FitOptions, Search};

/// Beside a model at the floor of a damped pendulum servo, Coulomb friction is out of reach on
/// the probes' data, and Stribeck friction (which holds it as a special case) is judged from
/// that fit: out of reach too, as its own coarse fit there finds, for fewer replays than that
/// coarse fit. Where Coulomb friction is in the base on the joint, the richer model is left to
/// its own coarse fit.
#[test]
fn a_richer_friction_is_judged_from_the_plain_fit_out_of_reach() {
    let (robot, recs) =
        crate::synth::recorded::pendulum(Some((ViscousDamping.id(), vec![0.03])), 3, 7);
    let opts = FitOptions::default();
    let engine = Engine::new(&robot, &recs, &opts);
    let allowed: Vec<String> = [CoulombFriction.id(), StribeckFriction.id(), ViscousDamping.id()]
        .map(String::from)
        .to_vec();
    let s = Search { engine: &engine, train: &recs, heldout: &recs, allowed: &allowed };
    let g = vec!["servo".to_string()];
    let (p, _) = engine.fit_one(&recs, &[], &ViscousDamping, &g);
    let floor = [Applied { effect: &ViscousDamping, joints: g.clone(), params: vec![0.9 * p[0]] }];
    let probe = || vec![recs[0].clone()];
    engine.probe_set(&recs, &[], probe);
    let reach = Reach::new(&engine, &recs, &[], &floor).expect("probes held");
    let before = engine.rollout_stats().rollouts;
    assert!(reach.out_of_reach(&s, None, (&CoulombFriction, &g)).is_some());
    let (_, f) = reach.out_of_reach(&s, None, (&StribeckFriction, &g)).expect("out of reach");
    let judged = engine.rollout_stats().rollouts - before;
    assert!(f > reach.bar, "{f} vs {}", reach.bar);
    // The richer model's own coarse fit on the same probes' data, on an engine of its own.
    let other = Engine::new(&robot, &recs, &opts);
    let probes = other.probe_set(&recs, &[], probe);
    let at = other.rollout_stats().rollouts;
    let pol = &opts.policy;
    let (_, own_f) = other.fit_budget(&probes, &[], &StribeckFriction, &g, pol.screen_evals);
    let own = other.rollout_stats().rollouts - at;
    assert!(own_f > reach.bar, "its own coarse fit is out of reach too: {own_f}");
    assert!(judged < own, "plain fit and judgement {judged} rollouts, own coarse fit {own}");
    // Coulomb friction in the base on the joint: no judgement from a plain fit.
    let base = [Applied { effect: &CoulombFriction, joints: g.clone(), params: vec![0.01] }];
    let mut at_floor = base.to_vec();
    at_floor.extend(floor.iter().cloned());
    engine.probe_set(&recs, &base, probe);
    let reach = Reach::new(&engine, &recs, &base, &at_floor).expect("probes held");
    assert!(reach.extension_out(&s, None, (&StribeckFriction, &g)).is_none());
}
