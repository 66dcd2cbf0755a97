//! A gain error's coarse fit from the screen's two columns (kp and kd): its least-squares step,
//! replayed once, instead of a Levenberg–Marquardt fit of `screen_evals` replays; its rank and
//! prediction from kp's column alone (`Effect::screened`, `Effect::stepped`).

use crate::fit::diagnose::diagnose;
use crate::fit::effects::{Effect, GainError};
use crate::fit::select::screen::Screen;
use crate::fit::select::{Engine, FitOptions};
use crate::sim2real::recording::Recording;

/// The pendulum servo (kp 2, kv 0.0335) whose real gains are kp × `sp`, kv × `sd`, recorded by
/// the synth (3 × 3 s): MuJoCo's replay of the model with those gains, noise and all.
fn pendulum_with_gains(sp: f64, sd: f64) -> (crate::model::Robot, Vec<Recording>) {
    crate::synth::recorded::pendulum(Some((GainError.id(), vec![sp, sd])), 3, 7)
}

/// Real gains kp × 0.9, kd × 1.4: both columns are probed, the screen's step moves both (kd up,
/// kp down), and the coarse fit is that step replayed once on the screen's data — one replay's
/// seconds, not `screen_evals` replays' — leaving less than half the residual. With kp alone
/// probed, the step could not confirm (kd is what the recordings ask for) and the coarse fit
/// would cost the Levenberg–Marquardt fit's replays. The rank and the prediction are kp's
/// column's alone: they leave more of the residual than the two columns' step.
#[test]
fn a_gain_error_coarse_fit_is_its_two_column_step_replayed_once() {
    let (robot, recs) = pendulum_with_gains(0.9, 1.4);
    let opts = FitOptions::default();
    let engine = Engine::new(&robot, &recs, &opts);
    let g = vec!["servo".to_string()];
    let secs = |r: &[Recording]| r.iter().map(|x| x.t.last().unwrap() - x.t[0]).sum::<f64>();
    let base = engine.errors_held(&recs, &[]).expect("replay");
    let allowed = vec![GainError.id().to_string()];
    let mut diag = diagnose(&robot, &recs, &base.eps, &engine.joints, &allowed, opts.gap_mask_s);
    let screen = Screen::build(&engine, &recs, &[], &base, &mut diag, &|_, _| false);
    let (two, steps) = screen.steps(GainError.id(), &g).expect("modelled");
    assert_eq!(steps.len(), 2, "{steps:?}");
    let kp = screen.predict(GainError.id(), &g).expect("modelled");
    assert!(kp.train_rmse > 1.05 * two.train_rmse, "kp alone {kp:?}, both {two:?}");
    assert!(steps[0] < 0.0 && steps[1] > 0.0, "{steps:?}");
    let before = engine.rollout_stats().simulated_s;
    let (p, f) = super::fit(&engine, &screen, (&recs, &[]), (&GainError, &g));
    let cost = engine.rollout_stats().simulated_s - before;
    assert!(cost <= secs(&recs) + 1e-9, "{cost} s replayed for one replay of {}", secs(&recs));
    assert_eq!(p, vec![1.0 + steps[0], 1.0 + steps[1]]);
    assert!(f < 0.5 * base.rmse(), "{p:?}: {f} of {}", base.rmse());
}
