//! A smooth candidate's fallback from its probes' fit: the Gauss–Newton step of the model at
//! the probes' point ([`super::further::Model::step`]), replayed once, before any coarse fit of
//! `screen_evals` replays on the screen's data.

use super::{further, on_probes};
use crate::fit::effects::{Effect, GainError, model_with};
use crate::fit::select::engine::{neutral_params, with_candidate};
use crate::fit::select::{Engine, FitOptions, SearchPolicy};
use crate::sim2real::recording::Recording;

/// Recording seconds of a dataset.
fn seconds(r: &[Recording]) -> f64 {
    r.iter().map(|x| x.t.last().unwrap() - x.t[0]).sum::<f64>()
}

/// The pendulum servo whose real gains are kp × 0.9, kd × 1.4 (synth, 3 × 3 s), and options with
/// a linear trust of 1: no gain is confirmed but a replay's own, so the probes' fit of a gain
/// error, replayed on the screen's data, never stands by its own gain there.
fn gain_error_case() -> (crate::model::Robot, Vec<Recording>, FitOptions) {
    let (robot, recs) =
        crate::synth::recorded::pendulum(Some((GainError.id(), vec![0.9, 1.4])), 3, 7);
    let policy = SearchPolicy { linear_trust: 1.0, ..SearchPolicy::default() };
    (robot, recs, FitOptions { policy, ..FitOptions::default() })
}

/// What the fallback sees, measured on an engine of its own: the screen's base RMSE; the probes'
/// fit and its RMSE on the screen's data; the Gauss–Newton model there; the step's RMSE.
struct Seen {
    base: f64,
    q: Vec<f64>,
    fs: f64,
    model: further::Model,
    fx: f64,
}

fn seen(robot: &crate::model::Robot, recs: &[Recording], opts: &FitOptions) -> Seen {
    let engine = Engine::new(robot, recs, opts);
    let g = vec!["servo".to_string()];
    let probes = engine.probe_set(recs, &[], || vec![recs[1].clone()]);
    let base = engine.errors_held(recs, &[]).expect("replay").rmse();
    let _ = engine.errors_held(&probes, &[]).expect("replay");
    let (q, _) = engine.fit_budget(&probes, &[], &GainError, &g, opts.policy.screen_evals);
    let m0 = model_with(robot, &[]);
    let neutral = neutral_params(robot, &m0, (&GainError, &g));
    let at = |p: Vec<f64>| with_candidate(&[], (&GainError, &g), p, neutral.as_deref());
    let fs = engine.score(recs, &at(q.clone()));
    let model =
        further::model_at(&engine, (recs, &[]), (&GainError, &g), (&q, fs)).expect("modelled");
    let (x, _) = model.step.clone().expect("a step");
    let fx = engine.score(recs, &at(x));
    Seen { base, q, fs, model, fx }
}

/// A fresh engine with the probes' data made, as a round's screen leaves it.
fn screened<'a>(
    robot: &'a crate::model::Robot,
    recs: &[Recording],
    opts: &'a FitOptions,
) -> Engine<'a> {
    let engine = Engine::new(robot, recs, opts);
    let probes = engine.probe_set(recs, &[], || vec![recs[1].clone()]);
    let _ = engine.errors_held(recs, &[]).expect("replay");
    let _ = engine.errors_held(&probes, &[]).expect("replay");
    engine
}

/// Where the probes' fit neither confirms nor reaches the bar but its Gauss–Newton model could,
/// the model's step is replayed once, and where it reaches the bar it is the coarse fit: no
/// Levenberg–Marquardt replay on the screen's data — the probes' fit, its replay, one replay per
/// parameter for the model and one for the step are all it costs. It gains what the coarse fit
/// on the screen's data from the effect's start gains, within a fifth.
#[test]
fn a_gauss_newton_step_that_reaches_the_bar_is_the_coarse_fit() {
    let (robot, recs, opts) = gain_error_case();
    let g = vec!["servo".to_string()];
    let s = seen(&robot, &recs, &opts);
    let (x, _) = s.model.step.clone().unwrap();
    let (reached, reach, stepped) =
        (1.0 - s.fs / s.base, 1.0 - s.model.least / s.base, 1.0 - s.fx / s.base);
    assert!(stepped > reached + 1e-3 && reach > reached + 1e-3, "{reached} {stepped} {reach}");
    let bar = 0.5 * (reached + stepped.min(reach));
    let engine = screened(&robot, &recs, &opts);
    let probes = engine.probe_set_held(&recs, &[]).expect("held");
    let before = engine.rollout_stats().simulated_s;
    let got = on_probes(&engine, (&recs, &[]), (&GainError, &g), bar);
    let cost = engine.rollout_stats().simulated_s - before;
    assert_eq!(got, Some((x, s.fx)), "from the probes' {:?}", s.q);
    let k = GainError.fitted() as f64;
    let budget = opts.policy.screen_evals as f64 * seconds(&probes) + (k + 2.0) * seconds(&recs);
    assert!(cost <= budget + 1e-9, "{cost} s replayed for {budget}");
    let (_, fr) = engine.fit_budget(&recs, &[], &GainError, &g, opts.policy.screen_evals);
    let fitted = 1.0 - fr / s.base;
    assert!(stepped >= 0.8 * fitted, "the step gains {stepped}, the coarse fit {fitted}");
}

/// Where the step gains less than the bar (and, under a trust of 1, does not confirm the model),
/// the coarse fit on the screen's data follows from the step (it improved on the probes' point
/// and on the base): it is the fit a fresh engine makes from there, kept where better than the
/// step, and at least as good as the step.
#[test]
fn a_step_short_of_the_bar_starts_the_coarse_fit() {
    let (robot, recs, opts) = gain_error_case();
    let g = vec!["servo".to_string()];
    let s = seen(&robot, &recs, &opts);
    let (x, _) = s.model.step.clone().unwrap();
    let (reach, stepped) = (1.0 - s.model.least / s.base, 1.0 - s.fx / s.base);
    assert!(s.fx < s.fs && s.fx < s.base, "{} {} {}", s.fx, s.fs, s.base);
    // A bar above the step's gain, within the model's reach (the model at the probes' point
    // is nearly exact here: its step leaves 2e-5 of the base's RMSE more than it allows).
    assert!(reach > stepped, "the model reaches {reach}, the step {stepped}");
    let bar = 0.5 * (stepped + reach);
    let engine = screened(&robot, &recs, &opts);
    let before = engine.rollout_stats().simulated_s;
    let got = on_probes(&engine, (&recs, &[]), (&GainError, &g), bar);
    let cost = engine.rollout_stats().simulated_s - before;
    let fresh = screened(&robot, &recs, &opts);
    let evals = opts.policy.screen_evals;
    let (q, fq) = fresh.fit_budget_from(&recs, &[], (&GainError, &g), evals, &x);
    let (p, f) = got.expect("fitted");
    assert_eq!((p, f), if s.fx < fq { (x, s.fx) } else { (q, fq) });
    assert!(f <= s.fx);
    // The probes' point, the model's two differences, the step, and the fit's replays.
    assert!(cost > 5.0 * seconds(&recs), "{cost} s: no fit on the screen's data");
}
