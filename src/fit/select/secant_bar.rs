//! The bar for a full fit set, before a block's other coarse fits, by the block's secant coarse
//! fits.
//!
//! A coarse fit on the screen's data ([`coarse::fit_to`]) stops early where the round's bar for
//! a full fit is known: a point of a non-smooth candidate's fit on the probes' data whose replay
//! on the screen's data reaches the bar admits it and stands, and a smooth one whose
//! Gauss–Newton model at that point cannot reach the bar stands there too. Before any fit of
//! the round set the bar, every coarse fit runs to its end. Where no lead goes first
//! ([`super::lead`]: a round whose candidates all lie on one joint group — a single servo),
//! the first block's coarse fits are all made before any bar; yet the smooth one-parameter
//! candidates' coarse fits are the screen's linear step followed by secant steps
//! ([`coarse::secant`]), whose result does not depend on the bar, and they are made first in
//! [`coarse::fit_to`] anyway. So they are made first for the whole block: the best gain among
//! them sets the bar as a fit of the round sets it (`screen_share` × that gain, at least
//! `min_rel_improvement`), and the block's other one-parameter candidates are coarse-fitted
//! against it. The bar only rises as the round goes on (the round's best gain never falls), so
//! a candidate admitted by a point reaching it is judged as one admitted in a later block is; a
//! secant fit is the same simulations whether made before or inside [`coarse::fit_to`] (the
//! engine remembers them), so the block replays no more than before. Not a candidate of
//! several parameters: its coarse fit on the probes' data, stopped by the bar, can end below a
//! bar its fit on the screen's data reaches (the synth pendulum with 0.08 N·m of Coulomb
//! friction: the gain error 46.2 % against 46.9 %, a bar of 46.5 %). On the chain pendulum with
//! Coulomb friction, round 0: Coulomb friction's secant fit gains 91 % of the screen's
//! residual, the bar is 45 %, and the external-load friction's point on the probes' data,
//! replayed (48 %), stands instead of a grid on the screen's data that found the same point.

use std::ops::Range;

use rayon::prelude::*;

use crate::fit::effects::{Applied, Effect};
use crate::sim2real::recording::Recording;

use super::coarse::{self, Coarse};
use super::engine::Engine;
use super::groups::Cand;
use super::policy::{Phase, SearchPolicy};
use super::screen::Screen;
use super::{Search, swap};

/// A candidate left out by its trusted or held-out linear model ([`super::heldout_linear::out_of`]):
/// the largest training gain its model allows, why (the phase logged) and its held-out reach.
pub(super) type OutOf = Option<(f64, Phase, f64)>;

/// The coarse fits on the screen's data `short` of the block `range` of `cands` (the round's
/// candidates, `coarse` their coarse fits so far), in order: a richer model of a loss waits
/// for its plain variant ([`coarse::deferred`]); one out of reach on the probes' data
/// (`far`, [`super::reach`]) or left out by its trusted linear model (`out_of`) is a
/// stand-in judged when taken; a swap of a kept plain fit is judged from it
/// ([`swap::adds_nothing_to_kept`]); the others are coarse-fitted ([`coarse::fit_to`]) against
/// the bar `admits` (a relative gain on `short`; infinite before a fit of the round set it),
/// or, before any fit set it, a one-parameter candidate against the bar the block's secant
/// coarse fits set ([`bar`]).
pub(super) fn block_fits(
    s: &Search,
    screen: &Screen,
    (short, applied): (&[Recording], &[Applied]),
    (cands, coarse, range): (&[Cand], &[Coarse], Range<usize>),
    (out_of, far): (&[OutOf], &[Coarse]),
    admits: f64,
) -> Vec<(Vec<f64>, f64)> {
    let at = (short, applied);
    let pre: Vec<Coarse> = cands[range.clone()]
        .par_iter()
        .zip(out_of)
        .zip(far)
        .map(|(((e, g, _), out_of), far)| {
            let trust = || out_of.map(|_| (vec![], f64::INFINITY));
            coarse::deferred(s, (*e, g), cands, coarse)
                .or_else(|| far.clone().map(|(p, _)| (p, f64::INFINITY))) // judged when taken
                .or_else(trust) // judged when taken
                .or_else(|| swap::adds_nothing_to_kept(s, at, (*e, g)))
        })
        .collect();
    let secants = if admits.is_finite() {
        admits
    } else {
        let to_fit: Vec<(&'static dyn Effect, &[String])> = cands[range.clone()]
            .iter()
            .zip(&pre)
            .filter(|(_, p)| p.is_none())
            .map(|((e, g, _), _)| (*e, &g[..]))
            .collect();
        let base = s.engine.score(short, applied);
        bar(s.engine, screen, at, &to_fit, base)
    };
    // (A candidate of several parameters is fitted as before a bar: the secants' bar is one
    // for the one-parameter block they belong to.)
    cands[range]
        .par_iter()
        .zip(pre)
        .map(|((e, g, _), pre)| {
            let bar = if e.fitted() < 2 { secants } else { admits };
            pre.unwrap_or_else(|| coarse::fit_to(s.engine, screen, at, (*e, g), bar))
        })
        .collect()
}

/// The bar (a relative gain on the screen's data `short`, whose base RMSE is `base`) that the
/// secant coarse fits of `block` set: `screen_share` × the best of their gains, at least
/// `min_rel_improvement`; infinite when none gains anything (no fit set a bar).
pub(super) fn bar(
    engine: &Engine,
    screen: &Screen,
    (short, applied): (&[Recording], &[Applied]),
    block: &[(&'static dyn Effect, &[String])],
    base: f64,
) -> f64 {
    let gains: Vec<f64> = block
        .par_iter()
        .filter_map(|&(e, g)| coarse::secant(engine, screen, (short, applied), (e, g)))
        .map(|(_, f)| 1.0 - f / base)
        .collect();
    from_gains(&gains, &engine.opts.policy)
}

/// The bar that fits of these relative gains set (see [`bar`]).
fn from_gains(gains: &[f64], pol: &SearchPolicy) -> f64 {
    let best = gains.iter().copied().filter(|g| g.is_finite()).fold(0.0f64, f64::max);
    if best > 0.0 { (pol.screen_share * best).max(pol.min_rel_improvement) } else { f64::INFINITY }
}

#[cfg(test)]
#[path = "secant_bar_tests.rs"]
mod tests;
