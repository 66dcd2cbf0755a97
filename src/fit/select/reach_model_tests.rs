//! The reach's Gauss–Newton judgement of a smooth rival of several parameters
//! ([`super::beyond`]): it leaves out only a rival whose coarse fit on the probes' data ends
//! above the bar too, never one that fit brings down to it, and costs less than that fit.

use super::beyond;
use crate::fit::diagnose::diagnose;
use crate::fit::effects::{Backlash, Effect, GainError, ViscousDamping, all};
use crate::fit::select::further::model_at;
use crate::fit::select::policy::SearchPolicy;
use crate::fit::select::screen::Screen;
use crate::fit::select::{Engine, FitOptions};

/// A servo whose gains are off (kp × 0.9, kd × 1.4), recorded by the synth, screened in round
/// 0 (its probes' data made). A trust of 1 confirms no gain but itself: the gain error's linear
/// step is not its coarse fit, which is Levenberg–Marquardt on the probes' data. At every bar
/// that fit reaches the judgement leaves the gain error in (it would pass the reach and could
/// win the round); at a bar it leaves out, that fit ends above the bar too, for fewer replays.
/// A one-parameter rival and a non-smooth one are left to their coarse fits.
#[test]
fn a_rival_is_left_out_only_where_its_coarse_fit_ends_above_the_bar() {
    let (robot, recs) =
        crate::synth::recorded::pendulum(Some((GainError.id(), vec![0.9, 1.4])), 3, 7);
    let policy = SearchPolicy { linear_trust: 1.0, ..SearchPolicy::default() };
    let opts = FitOptions { policy, ..FitOptions::default() };
    let screened = |engine: &Engine| {
        let base = engine.errors_held(&recs, &[]).expect("replay");
        let allowed: Vec<String> = all().iter().map(|e| e.id().to_string()).collect();
        let mut diag =
            diagnose(&robot, &recs, &base.eps, &engine.joints, &allowed, opts.gap_mask_s);
        let screen = Screen::build(engine, &recs, &[], &base, &mut diag, &|_, _| false);
        let probes = engine.probe_set_held(&recs, &[]).expect("made by the screen");
        (screen, probes)
    };
    let g = vec!["servo".to_string()];
    let e: &'static dyn Effect = &GainError;
    // The coarse fit the judgement stands in for, and what it costs, on an engine of its own.
    let fitter = Engine::new(&robot, &recs, &opts);
    let (_, probes_f) = screened(&fitter);
    let at = fitter.rollout_stats().simulated_s;
    let (q, fq) = fitter.fit_budget(&probes_f, &[], e, &g, opts.policy.screen_evals);
    let fit_cost = fitter.rollout_stats().simulated_s - at;
    assert!(!q.is_empty() && fq.is_finite(), "{q:?} {fq}");
    let engine = Engine::new(&robot, &recs, &opts);
    let (screen, probes) = screened(&engine);
    let f0 = engine.score(&probes, &[]);
    assert!(fq < 0.9 * f0, "the fit finds the gains on the probes' data: {fq} of {f0}");
    // The model at the replayed step, which the judgement compares with the bar.
    let (_, x) = screen.steps(e.id(), &g).expect("modelled");
    let (p, f) = engine.at_linear_step(&probes, &[], (e, &g), &x).expect("a step");
    let least = model_at(&engine, (&probes, &[]), (e, &g), (&p, f)).expect("modelled").least;
    assert!(least < f, "the model steps further: {least} from {f}");
    let before = engine.rollout_stats().simulated_s;
    let mut left_out = 0;
    for k in 0..=40 {
        let bar = f0 * 0.025 * k as f64;
        match beyond(&engine, &screen, (&probes, &[]), (e, &g), bar) {
            Some((pp, ff)) => {
                assert!(fq > bar, "left out at {bar}, which its coarse fit reaches ({fq})");
                assert!(ff > bar && pp == p && ff == f, "{pp:?} {ff}: the replayed step");
                left_out += 1;
            }
            None => assert!(least <= bar, "left in at {bar} above the model's {least}"),
        }
    }
    assert!(left_out > 0, "no bar left it out: least {least}, fit {fq}, base {f0}");
    let cost = engine.rollout_stats().simulated_s - before;
    assert!(cost < fit_cost, "the judgement {cost} s, the coarse fit {fit_cost} s");
    // Not a one-parameter rival nor a non-smooth one: nothing replayed, left to the coarse fit.
    let before = engine.rollout_stats().simulated_s;
    for other in [&ViscousDamping as &'static dyn Effect, &Backlash] {
        assert!(beyond(&engine, &screen, (&probes, &[]), (other, &g), 0.0).is_none());
    }
    assert_eq!(engine.rollout_stats().simulated_s, before);
    // Under the default trust the step, where it confirms its prediction, is the coarse fit.
    let defaults = FitOptions::default();
    let engine = Engine::new(&robot, &recs, &defaults);
    let (screen, probes) = screened(&engine);
    let (pred, x) = screen.steps(e.id(), &g).expect("modelled");
    let want = 1.0 - pred.train_rmse / screen.base_rmse();
    let (_, f) = engine.at_linear_step(&probes, &[], (e, &g), &x).expect("a step");
    let got = 1.0 - f / engine.score(&probes, &[]);
    let pol = SearchPolicy::default();
    if crate::fit::select::coarse::agrees(got, want, &pol) {
        assert!(beyond(&engine, &screen, (&probes, &[]), (e, &g), 0.0).is_none());
    }
}
