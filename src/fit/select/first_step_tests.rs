//! The first iteration of a full fit, made before it ([`short_after_first_step`]), on the
//! pendulum servo recorded by the synth (4 × 3 s: three episodes to train on, the last held
//! out), judged by replays and fits it does not make.

use super::short_after_first_step;
use crate::fit::effects::{Applied, Effect, GainError};
use crate::fit::select::verdict::verdict;
use crate::fit::select::{Engine, FitOptions};
use crate::model::Robot;
use crate::sim2real::recording::Recording;
use crate::synth::recorded::pendulum;

const E: &dyn Effect = &GainError;

fn split(hidden: Option<Vec<f64>>, seed: u64) -> (Robot, Vec<Recording>, Vec<Recording>) {
    let (robot, mut recs) = pendulum(hidden.map(|p| (GainError.id(), p)), 4, seed);
    let held = recs.split_off(3);
    (robot, recs, held)
}

fn set(p: &[f64]) -> Vec<Applied> {
    vec![Applied { effect: E, joints: vec!["servo".into()], params: p.to_vec() }]
}

fn seconds(recs: &[Recording]) -> f64 {
    recs.iter().map(|r| r.t.last().unwrap() - r.t[0]).sum()
}

/// The iteration made first is the full fit's own: a full fit from the same point after it
/// replays none of it again — the two together cost what the full fit alone costs, plus at most
/// the one held-out replay of the step — and ends where the full fit alone ends.
#[test]
fn the_first_iteration_is_the_full_fits_own() {
    let (robot, train, held) = split(Some(vec![0.9, 1.4]), 11);
    let opts = FitOptions::default();
    let g = vec!["servo".to_string()];
    let e: &'static dyn Effect = &GainError;
    let (p0, gate) = ([1.0, 1.1], opts.policy.gate());
    let alone = Engine::new(&robot, &train, &opts);
    let (q_alone, f_alone) = alone.fit_from(&train, &[], (e, &g), Some(&p0));
    let cost_alone = alone.rollout_stats().simulated_s;
    let both = Engine::new(&robot, &train, &opts);
    let ho = both.errors(&held, &[]).expect("replay");
    let before = both.rollout_stats().simulated_s;
    let short = short_after_first_step(&both, (&held, &train), (&[], &set(&p0)), &ho, gate);
    assert_eq!(short, None, "a gain error that is there is fitted on");
    let (q, f) = both.fit_from(&train, &[], (e, &g), Some(&p0));
    let cost = both.rollout_stats().simulated_s - before;
    assert!(cost <= cost_alone + seconds(&held) + 1e-9, "{cost} s for {cost_alone} s alone");
    assert!(cost >= cost_alone - 1e-9, "{cost} s for {cost_alone} s alone");
    assert_eq!((q, f), (q_alone, f_alone));
}

/// Where the servo's gains are off (kp × 0.9 and kd × 1.4; kp × 1.12 and kd × 0.75), the fit
/// goes on from any start that leaves them off — also under a gate no point passes at the
/// trust's edge when the step gains on the held-out episode (it is judged there only when the
/// iteration confirms its model: a strict gate stops it only then).
#[test]
fn a_gain_error_that_is_there_is_fitted_on() {
    for (p, seed) in [(vec![0.9, 1.4], 11), (vec![1.12, 0.75], 5)] {
        let (robot, train, held) = split(Some(p.clone()), seed);
        let opts = FitOptions::default();
        let engine = Engine::new(&robot, &train, &opts);
        let ho = engine.errors(&held, &[]).expect("replay");
        for p0 in [[1.0, 1.0], [1.0, 1.1], [0.95, 1.2]] {
            let got = short_after_first_step(
                &engine,
                (&held, &train),
                (&[], &set(&p0)),
                &ho,
                opts.policy.gate(),
            );
            assert_eq!(got, None, "{p:?} from {p0:?}");
        }
    }
}

/// Where the gains are right (nothing missing; three synth seeds) and the fit starts off them,
/// its first step goes back towards them and gains nothing beyond noise on the held-out
/// episode: the fit is not continued — and the full fit, made here, is not kept by the gate
/// either (not beyond noise, or under `min_rel_improvement`).
#[test]
fn a_gain_error_that_is_not_there_stops_after_its_first_step_as_its_full_fit_fails() {
    let mut stopped = 0;
    for seed in [3, 7, 21] {
        let (robot, train, held) = split(None, seed);
        let opts = FitOptions::default();
        let pol = &opts.policy;
        let engine = Engine::new(&robot, &train, &opts);
        let ho = engine.errors(&held, &[]).expect("replay");
        let g = vec!["servo".to_string()];
        let e: &'static dyn Effect = &GainError;
        for p0 in [[1.04, 0.9], [0.97, 1.08]] {
            let at = (&[][..], &set(&p0)[..]);
            let got = short_after_first_step(&engine, (&held, &train), at, &ho, pol.gate());
            let (q, _) = engine.fit_from(&train, &[], (e, &g), Some(&p0));
            let after = engine.errors(&held, &set(&q)).expect("replay");
            let v = verdict(&ho, &after, &g, pol.gate());
            assert!(!(v.significant && v.rel >= pol.min_rel_improvement), "seed {seed}: {q:?}");
            if let Some(rel) = got {
                assert!(rel.is_finite(), "seed {seed} from {p0:?}");
                stopped += 1;
            }
        }
    }
    assert!(stopped >= 1, "stopped {stopped} of 6");
}

/// A step confirms its model by the trust's ratio alone: achieved within `linear_trust` of the
/// prediction, the prediction within it of the model's optimum — however small the gains (BAM
/// kp-400's round-2 motor constants: 0.19 % achieved for 0.95 % predicted is no confirmation,
/// though both are under `min_rel_improvement`).
#[test]
fn a_step_confirms_its_model_by_the_trusts_ratio_however_small() {
    use super::believed;
    use crate::fit::select::SearchPolicy;
    let pol = SearchPolicy::default();
    let (lt, small) = (pol.linear_trust, pol.min_rel_improvement);
    assert!(0.0095 < small);
    assert!(!believed((0.0019, 0.0095, 0.0095), &pol));
    assert!(believed((0.009, 0.0095, 0.0095), &pol));
    assert!(believed((0.0095 * lt, 0.0095, 0.0095 / lt), &pol));
    assert!(!believed((0.0095 * lt * 0.99, 0.0095, 0.0095), &pol));
    assert!(!believed((0.0095 / (lt * 0.99), 0.0095, 0.0095), &pol));
    // Short of the model's optimum: the fit goes further than the step.
    assert!(!believed((0.05, 0.05, 0.05 / (lt * 0.99)), &pol));
    // No predicted gain, or a loss: nothing to confirm.
    assert!(!believed((0.0, 0.0, 0.0), &pol) && !believed((-0.01, -0.01, 0.0), &pol));
    assert!(!believed((f64::NAN, 0.01, 0.01), &pol));
    assert!(believed((0.1, 0.1, 0.1), &pol));
}
