//! Beside a kept lead, a smooth rival of several parameters judged out of reach by the
//! Gauss–Newton model at its replayed linear step on the probes' data, before a coarse fit
//! there ([`super::reach::Reach::beside_lead`]).
//!
//! The reach leaves out a rival whose coarse fit on the probes' data leaves more than the
//! reach's bar there. For a smooth rival of several parameters, every one probed (a gain
//! error), that coarse fit is the screen's linear step replayed once when the gain it achieves
//! confirms the prediction ([`super::coarse`]`::agrees`), else Levenberg–Marquardt of
//! `screen_evals` replays — on chainsim's leg whose motors lack rotor inertia, 7–10 replays of
//! the probes' 2 s for the gain error on one joint or on all, which were out of reach. Each
//! Levenberg–Marquardt iteration steps to the minimum of the Gauss–Newton model of the
//! residual at its point; the model at the replayed step ([`further::model_at`] on the probes'
//! data: a forward difference per free parameter, the fit's own step, and the secant from the
//! base model, whose replay the reach holds) predicts the least RMSE any step from there
//! reaches, unbounded by the box and a trust region (both only shorten the step). When even
//! that stays above the reach's bar, the rival is out of reach at the replayed step, for one
//! replay per free parameter instead of the fit: the judgement the screen makes of a smooth
//! candidate's point on its own data ([`further`]), made here on the probes' data against the
//! reach's bar. No constant. Where the model can reach the bar the coarse fit follows as
//! before (its differences then cost k replays more). *Limit:* like [`further`]'s, the model is
//! that of one step from the replayed point, not a proof about a fit from the effect's start.

use crate::fit::effects::{Applied, Effect};
use crate::sim2real::recording::Recording;

use super::coarse;
use super::engine::Engine;
use super::further;
use super::screen::Screen;

/// `Some` (the replayed linear step and its RMSE on `probes`) when `e` on `g` — smooth, of
/// several parameters, every one probed — has a linear step in `screen` whose replay on
/// `probes` (the data `screen` was made on, with the base `base`) does not confirm its
/// prediction, and the Gauss–Newton model there predicts no RMSE on `probes` down to `bar`
/// [rad]. `None` otherwise: the rival's coarse fit judges it (a confirmed step is that fit).
pub(super) fn beyond(
    engine: &Engine,
    screen: &Screen,
    (probes, base): (&[Recording], &[Applied]),
    (e, g): (&'static dyn Effect, &[String]),
    bar: f64,
) -> Option<(Vec<f64>, f64)> {
    // (The candidates whose coarse fit starts from a replayed linear step of every parameter:
    // one parameter goes on by secant steps instead.)
    if !e.smooth() || e.fitted() < 2 || e.stepped().max(e.screened()) < e.fitted() {
        return None;
    }
    let (pred, x) = screen.steps(e.id(), g)?;
    let want = 1.0 - pred.train_rmse / screen.base_rmse();
    let (p, f) = engine.at_linear_step(probes, base, (e, g), &x)?;
    let f0 = engine.score(probes, base);
    if !(f0 > 0.0) || coarse::agrees(1.0 - f / f0, want, &engine.opts.policy) {
        return None;
    }
    let m = further::model_at(engine, (probes, base), (e, g), (&p, f))?;
    (m.least > bar).then_some((p, f))
}

#[cfg(test)]
#[path = "reach_model_tests.rs"]
mod tests;
