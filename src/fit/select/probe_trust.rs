//! Round 0's trust, taken where the linear model was made: a smooth one-parameter candidate's
//! linear step replayed on the probes' data ([`out`]).
//!
//! Round 0 screens a smooth one-parameter candidate by secant Gauss–Newton steps on the screen's
//! data started from the screen's linear step ([`super::engine::Engine`]'s `fit_secant`): its
//! coarse fit stops at the first step whose replayed gain confirms the one its linear model
//! predicted ([`coarse::agrees`]: between `linear_trust` and its inverse times it, or both below
//! `min_rel_improvement`), and is then at most 1 / `linear_trust` times that prediction. That
//! model's columns and prediction are those of the probes' data (the screen's stretches of
//! largest residual, a fifth of its seconds), so the same step replayed there tests the model on
//! the data it was made on. Where it confirms it, the candidate is taken at its word, as a later
//! round takes a model round 0's coarse fit confirmed ([`super::trust::trust_out`]): when the
//! predicted gain divided by `linear_trust` stays below the round's bar, no coarse fit on the
//! screen's data is made (one replay of the probes' data for one or more of the screen's). A
//! step the probes' data does not confirm — a lightly damped servo whose fit gains many times
//! its prediction, a step across a kink — leaves the candidate to the screen as before.

use crate::fit::effects::{Applied, Effect, JointTarget, model_with};
use crate::sim2real::recording::Recording;

use super::coarse;
use super::engine::Engine;
use super::groups::same_data;
use super::screen::Screen;

/// In round 0, once a fit set the round's bar `cut` (a relative gain on the screen's data): `Some`
/// (the largest gain the linear model allows, its prediction / `linear_trust`) when `e` on `g` is
/// smooth with one fitted parameter, that gain stays below `cut`, and the screen's linear step
/// replayed once on the probes' data of `short` (with `applied`) achieves there a gain that
/// confirms what the columns predict for the step as replayed ([`coarse::agrees`]); the
/// candidate's linear model is then recorded as trusted for later rounds
/// ([`Engine::note_trust`]). `None` (screened as before) otherwise: no prediction, no probes'
/// data apart from `short`, a zero step, a failed replay, or a step not confirmed.
///
/// [`Engine::note_trust`]: super::engine::Engine
pub(super) fn out(
    engine: &Engine,
    screen: &Screen,
    (short, applied): (&[Recording], &[Applied]),
    (e, g): (&'static dyn Effect, &[String]),
    cut: f64,
) -> Option<f64> {
    let pol = &engine.opts.policy;
    if !e.smooth() || e.fitted() != 1 || !cut.is_finite() {
        return None;
    }
    let pred = screen.predict(e.id(), g)?;
    let base = screen.base_rmse();
    let upper = (1.0 - pred.train_rmse / base) / pol.linear_trust;
    if !(base > 0.0 && upper.is_finite() && upper < cut) {
        return None;
    }
    let probes = engine.probe_set_held(short, applied)?;
    if same_data(&probes, short) {
        return None;
    }
    let (p, f) = engine.at_linear_step(&probes, applied, (e, g), &[pred.step])?;
    let base_p = engine.score(&probes, applied);
    // The step as replayed (inside the bounds) from the effect's start.
    let t = JointTarget::of(engine.robot, g.first()?)?;
    let p0 = e.initial(&model_with(engine.robot, applied), &t);
    let step: Vec<f64> = p.iter().zip(&p0).map(|(a, b)| a - b).collect();
    let want = screen.gain_at(e.id(), g, &step)?;
    let ok = base_p > 0.0 && coarse::agrees(1.0 - f / base_p, want, pol);
    if ok {
        engine.note_trust((e, g), true);
    }
    ok.then_some(upper)
}

#[cfg(test)]
#[path = "probe_trust_tests.rs"]
mod tests;
