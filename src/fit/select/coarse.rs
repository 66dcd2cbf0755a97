//! A candidate's coarse fit on the screen's data: what it is, when it can wait, and the
//! screen's linear step replayed where it alone would admit a candidate to a full fit.

use crate::fit::effects::{Applied, Effect};
use crate::sim2real::recording::Recording;

use super::engine::Engine;
use super::groups::Cand;
use super::screen::Screen;
use super::{Search, extension};

/// A point of a candidate's parameters and its training RMSE on the screen's data.
pub(super) type Point = (Vec<f64>, f64);

/// A candidate's coarse fit: its parameters and training RMSE on the screen's data.
pub(super) type Coarse = Option<Point>;

/// The coarse fit of `e` on `g` on `short` (`screen_evals` replays): a smooth one-parameter
/// candidate goes on from the screen's linear step by secant steps (one replay each).
pub(super) fn fit(
    engine: &Engine,
    screen: &Screen,
    (short, applied): (&[Recording], &[Applied]),
    (e, g): (&'static dyn Effect, &[String]),
) -> (Vec<f64>, f64) {
    let linear = screen.predict(e.id(), g).and_then(|p| {
        let gain = 1.0 - p.train_rmse / screen.base_rmse();
        engine.fit_secant(short, applied, (e, g), (p.step, gain))
    });
    linear
        .unwrap_or_else(|| engine.fit_budget(short, applied, e, g, engine.opts.policy.screen_evals))
}

/// A richer model of a loss whose plain variant ([`Effect::plain_variant`]) is a candidate on
/// the same joints in `cands`, coarse-fitted already, waits for its own coarse fit: it is
/// judged first from the plain variant's full fit ([`extension::adds_nothing`]), where its fit
/// starts anyway. Its stand-in (no parameters, the plain variant's coarse RMSE, which the
/// plain fit taken over reaches) orders it right after the plain variant.
pub(super) fn deferred(
    s: &Search,
    (e, g): (&'static dyn Effect, &[String]),
    cands: &[Cand],
    coarse: &[Coarse],
) -> Option<(Vec<f64>, f64)> {
    let f = plain_coarse(s, (e, g), cands, coarse)?.1;
    f.is_finite().then(|| (vec![], f))
}

/// The coarse fit of the plain variant of `e` (one the search may fit) on `g`, when that is a
/// candidate in `cands` and was coarse-fitted.
fn plain_coarse(
    s: &Search,
    (e, g): (&'static dyn Effect, &[String]),
    cands: &[Cand],
    coarse: &[Coarse],
) -> Option<(Vec<f64>, f64)> {
    let plain = e.plain_variant()?;
    if !s.allowed.iter().any(|id| id == plain.id()) {
        return None;
    }
    let i = cands.iter().position(|(p, pg, _)| p.id() == plain.id() && pg.as_slice() == g)?;
    coarse.get(i)?.clone().filter(|c| !is_deferred(c))
}

/// Whether a coarse fit is [`deferred`]'s stand-in (a fit that failed has an infinite RMSE).
pub(super) fn is_deferred(c: &(Vec<f64>, f64)) -> bool {
    c.0.is_empty() && c.1.is_finite()
}

/// A deferred candidate when it is taken: `None` (logged without a fit) when the plain variant
/// was fitted in full on the screen's data and its fit leaves nothing the extension's extra
/// parameters pay for ([`extension::adds_nothing`]), or when it was not and nothing near its
/// coarse fit taken over reaches the round's bar for a full fit (`reaches`, of an SSE on the
/// screen's data; [`extension::could_reach`]: its coarse fit could not admit it either, unless
/// the extra parameters explain what the plain fit leaves); else its coarse fit, as any
/// other candidate's, and in the second case the best point that judgement simulated, which
/// stands in for its linear step (the step of its columns there, replayed).
pub(super) fn when_taken(
    s: &Search,
    screen: &Screen,
    (short, applied): (&[Recording], &[Applied]),
    (e, g): (&'static dyn Effect, &[String]),
    (cands, coarse): (&[Cand], &[Coarse]),
    reaches: &dyn Fn(f64) -> bool,
) -> Option<(Point, Option<Point>)> {
    let mut stepped = None;
    if plain_fitted(s, (short, applied), (e, g)) {
        if extension::adds_nothing(s, short, applied, (e, g)) {
            return None;
        }
    } else if let Some((pp, _)) = plain_coarse(s, (e, g), cands, coarse) {
        let (could, least) = extension::could_reach(s, (short, applied), (e, g), &pp, reaches);
        if !could {
            return None;
        }
        stepped = least;
    }
    Some((fit(s.engine, screen, (short, applied), (e, g)), stepped))
}

/// Whether the plain variant of `e` was fitted in full on `g` on the screen's data this round.
/// A deferred candidate whose plain variant was is judged from that fit even once a kept
/// candidate left a white residual: its extra parameters are fitted only where they pay
/// ([`extension::adds_nothing`]), as Occam's nesting rule asks of them.
pub(super) fn plain_fitted(
    s: &Search,
    (short, applied): (&[Recording], &[Applied]),
    (e, g): (&'static dyn Effect, &[String]),
) -> bool {
    e.plain_variant().is_some_and(|p| s.engine.fit_known(short, applied, p, g).is_some())
}

/// The screen's linear step of `e` on `g` replayed on `short` (one replay; none when the
/// candidate's coarse fit began there): its parameters and RMSE. Where only the linear model
/// would admit a smooth candidate to a full fit, the step as simulated stands in for the
/// prediction. (Not a non-smooth one: a torque limit's column is that of a kink, and its step
/// can miss a narrow basin that the full fit finds — a heavy knee's 60 N·m limit.)
pub(super) fn replayed_step(
    engine: &Engine,
    screen: &Screen,
    (short, applied): (&[Recording], &[Applied]),
    (e, g): (&'static dyn Effect, &[String]),
) -> Option<(Vec<f64>, f64)> {
    let x = screen.steps(e.id(), g)?;
    engine.at_linear_step(short, applied, (e, g), &x)
}
