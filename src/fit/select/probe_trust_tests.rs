//! Round 0's trust from the probes' data ([`super::out`]): a smooth one-parameter candidate's
//! linear step replayed on the probes' data, the candidate left out only where that replay
//! confirms the prediction and the prediction at the trust's edge cannot reach the bar.

use super::out;
use crate::fit::diagnose::diagnose;
use crate::fit::effects::{ActionDelay, Backlash, CoulombFriction, Effect, GainError};
use crate::fit::effects::{ViscousDamping, all};
use crate::fit::select::coarse;
use crate::fit::select::screen::Screen;
use crate::fit::select::{Engine, FitOptions};
use crate::sim2real::recording::Recording;

/// Recording seconds of a dataset.
fn seconds(r: &[Recording]) -> f64 {
    r.iter().map(|x| x.t.last().unwrap() - x.t[0]).sum::<f64>()
}

/// The pendulum servo with `truth` hidden (synth, 3 × 3 s), an engine on it and its round-0
/// screen of every effect (the probes' data made).
fn screened(
    truth: (&'static dyn Effect, Vec<f64>),
    opts: &FitOptions,
    run: impl FnOnce(&Engine, &Screen, &[Recording]),
) {
    let (robot, recs) = crate::synth::recorded::pendulum(Some((truth.0.id(), truth.1)), 3, 7);
    let engine = Engine::new(&robot, &recs, opts);
    let base = engine.errors_held(&recs, &[]).expect("replay");
    let allowed: Vec<String> = all().iter().map(|e| e.id().to_string()).collect();
    let mut diag = diagnose(&robot, &recs, &base.eps, &engine.joints, &allowed, opts.gap_mask_s);
    let screen = Screen::build(&engine, &recs, &[], &base, &mut diag, &|_, _| false);
    run(&engine, &screen, &recs);
}

/// The relative gain on `recs` of `e`'s coarse fit there.
fn coarse_gain(
    engine: &Engine,
    screen: &Screen,
    recs: &[Recording],
    e: &'static dyn Effect,
) -> f64 {
    let g = vec!["servo".to_string()];
    let (_, f) = coarse::fit(engine, screen, (recs, &[]), (e, &g));
    1.0 - f / engine.score(recs, &[])
}

/// A lightly damped servo's friction or damping, where the recordings hold it: the fit gains
/// far more than the linear step predicts, which the step replayed on the probes' data shows,
/// so the candidate is never left out, whatever the bar; beside it a smooth rival whose step
/// the probes' data confirms is left out at a bar above its prediction at the trust's edge
/// (its coarse fit there gains no more), for one replay of the probes' seconds and its linear
/// model recorded as trusted, and is screened (nothing replayed) at a bar it could reach.
#[test]
fn a_rival_is_left_out_only_where_the_probes_confirm_its_step() {
    let opts = FitOptions::default();
    let lt = opts.policy.linear_trust;
    let g = vec!["servo".to_string()];
    for (truth, v) in [(&CoulombFriction as &'static dyn Effect, 0.03), (&ViscousDamping, 0.02)] {
        screened((truth, vec![v]), &opts, |engine, screen, recs| {
            let pred = screen.predict(truth.id(), &g).expect("modelled");
            let want = 1.0 - pred.train_rmse / screen.base_rmse();
            assert!(out(engine, screen, (recs, &[]), (truth, &g), 10.0).is_none());
            let got = coarse_gain(engine, screen, recs, truth);
            assert!(got > want / lt, "{}: {got} for {want} predicted", truth.id());
        });
    }
    screened((&CoulombFriction, vec![0.03]), &opts, |engine, screen, recs| {
        let e: &'static dyn Effect = &ActionDelay;
        let pred = screen.predict(e.id(), &g).expect("modelled");
        let upper = (1.0 - pred.train_rmse / screen.base_rmse()) / lt;
        assert!(upper > opts.policy.min_rel_improvement, "{upper}");
        let before = engine.rollout_stats().simulated_s;
        assert!(out(engine, screen, (recs, &[]), (e, &g), upper).is_none());
        assert_eq!(engine.rollout_stats().simulated_s, before, "nothing replayed");
        assert_eq!(engine.trusted((e, &g)), None);
        let bar = 1.5 * upper;
        let got = out(engine, screen, (recs, &[]), (e, &g), bar);
        let probes = engine.probe_set_held(recs, &[]).expect("made by the screen");
        let cost = engine.rollout_stats().simulated_s - before;
        assert_eq!(got, Some(upper));
        assert!(cost <= seconds(&probes) + 1e-9, "{cost} s for {}", seconds(&probes));
        assert_eq!(engine.trusted((e, &g)), Some(true));
        let fit = coarse_gain(engine, screen, recs, e);
        assert!(fit <= upper && fit < bar, "{fit} above {upper}");
    });
}

/// Only a smooth one-parameter candidate is judged so, and only once a fit set the bar: a play
/// (a grid) and a gain error (two parameters) are screened as before at any bar, and with no bar
/// (∞) neither is anything else; none of those replays anything.
#[test]
fn only_a_smooth_one_parameter_rival_below_a_set_bar_is_judged() {
    let opts = FitOptions::default();
    let g = vec!["servo".to_string()];
    screened((&Backlash, vec![0.04]), &opts, |engine, screen, recs| {
        let before = engine.rollout_stats().simulated_s;
        for e in [&Backlash as &'static dyn Effect, &GainError] {
            assert!(screen.predict(e.id(), &g).is_some(), "{}", e.id());
            assert!(out(engine, screen, (recs, &[]), (e, &g), 10.0).is_none(), "{}", e.id());
        }
        for e in all().into_iter().filter(|e| e.smooth() && e.fitted() == 1) {
            assert!(out(engine, screen, (recs, &[]), (e, &g), f64::INFINITY).is_none());
        }
        assert_eq!(engine.rollout_stats().simulated_s, before, "nothing replayed");
    });
}
