//! A bound that leaves a deferred friction extension out before its judgement on the screen's
//! data.
//!
//! A richer model of a loss ([`extension`]) waiting on its plain variant's coarse fit is judged
//! from that fit on the screen's data ([`extension::could_reach`]: its starts, one replay per
//! fitted parameter for its columns at the best of them, the Gauss–Newton step predicted and
//! simulated — 4 to 9 replays of the screen's data), once the same judgement on the probes'
//! data found something there. The judgement's linear model on the probes' data (the
//! stretches of the screen's data where the base model is most wrong,
//! [`SearchPolicy::probe_seconds`] in all: 2 s of 10 by default) bounds it: the least SSE its
//! starts and its Gauss–Newton model allow there ([`extension::linear_least`]), as a relative
//! RMSE gain over the base model there, is what the screen takes a candidate's gain on the
//! screen's data to be (its linear model is made on the probes' data and scaled so,
//! [`super::screen`]); a fit is taken to gain at most 1 / `linear_trust` times what a linear
//! model predicts, as everywhere in the search. When that upper gain, applied to the base's SSE
//! on the screen's data, cannot reach the round's bar, the judgement there is not made and the
//! extension is logged `screen`, as the judgement would log it.
//!
//! **Why the extension's own columns, not the screen's.** The screen probes only an
//! extension's first parameter ([`Effect::screened`]: Stribeck friction's static level,
//! load-dependent friction's base level), at its own start on the base model, not at the plain
//! fit; a bound from those columns is no bound where the extra parameter's shape lies outside
//! them (load-dependent friction's load term). The columns here are every fitted parameter of
//! the extension moved one at a time at the best of its starts, so they hold each extra
//! parameter's shape; an effect that does not hold its plain variant as a special case
//! (external-load friction beside Coulomb friction: [`Effect::absorb`] gives nothing) is never
//! judged from the plain fit, and never bounded here.
//!
//! [`SearchPolicy::probe_seconds`]: super::policy::SearchPolicy::probe_seconds
//! [`Effect::screened`]: crate::fit::effects::Effect::screened
//! [`Effect::absorb`]: crate::fit::effects::Effect::absorb

use crate::fit::effects::{Applied, Effect};
use crate::sim2real::recording::Recording;

use super::Search;
use super::extension;
use super::groups::same_data;

/// The largest relative RMSE gain over the base model `applied` on the probes' data of `short`
/// that the judgement's linear model of `effect` near the plain variant's fit `pp` allows there
/// ([`extension::linear_least`]), taken at the trust's edge (divided by `linear_trust`); `None`
/// when the probes' data is not held or is `short` itself, or the model cannot be made.
fn upper_gain(
    s: &Search,
    (short, applied): (&[Recording], &[Applied]),
    (effect, group): (&'static dyn Effect, &[String]),
    pp: &[f64],
) -> Option<f64> {
    let engine = s.engine;
    let probes = engine.probe_set_held(short, applied).filter(|p| !same_data(p, short))?;
    let sse0 =
        engine.errors(&probes, applied).map(|e| e.sse).filter(|r| r.is_finite() && *r > 0.0)?;
    let least = extension::linear_least(s, (&probes, applied), (effect, group), pp)?;
    let upper = (1.0 - (least / sse0).sqrt()) / engine.opts.policy.linear_trust;
    upper.is_finite().then_some(upper)
}

/// The SSE a model leaves whose RMSE is `gain` below that of a reference SSE `sse0` (none past
/// a gain of 1).
fn after_gain(sse0: f64, gain: f64) -> f64 {
    sse0 * (1.0 - gain.min(1.0)).powi(2)
}

/// Whether a deferred extension judged from its plain variant's coarse fit `pp` cannot reach
/// the round's bar (`reaches`, of an SSE on `short`) by the bound (see the module docs), the
/// reference the base model `applied`. `false` whenever the bound cannot be made.
pub(super) fn short_of_bar(
    s: &Search,
    (short, applied): (&[Recording], &[Applied]),
    (effect, group): (&'static dyn Effect, &[String]),
    pp: &[f64],
    reaches: &dyn Fn(f64) -> bool,
) -> bool {
    let engine = s.engine;
    let Some(sse0) = engine.errors(short, applied).map(|e| e.sse).filter(|x| x.is_finite()) else {
        return false;
    };
    upper_gain(s, (short, applied), (effect, group), pp)
        .is_some_and(|up| !reaches(after_gain(sse0, up)))
}

#[cfg(test)]
#[path = "ext_bound_tests.rs"]
mod tests;
