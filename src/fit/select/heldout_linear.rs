//! Which candidates of a block of the screen are taken without a coarse fit ([`out_of`]): in
//! round 0, once a fit set the bar, those whose linear step the probes' data confirms
//! ([`probe_trust::out`]); after round 0, those round 0's trust leaves out ([`trust_out`]) and
//! those the held-out set's own linear model leaves out ([`heldout_out`]), that model's effects
//! probed only for the candidates it is asked about ([`HeldoutScreen::ensure`]), and the smooth
//! candidates of several parameters whose held-out optimum at their start cannot lower the
//! held-out RMSE by the trust's edge of `min_rel_improvement` ([`start_bound::short_at_start`]:
//! `heldout_bound`).

use rayon::prelude::*;

use crate::fit::effects::Applied;
use crate::sim2real::recording::Recording;

use super::coarse::{self, Coarse};
use super::groups::Cand;
use super::policy::Phase;
use super::probe_trust;
use super::screen::{HeldoutScreen, Screen};
use super::start_bound;
use super::trust::{heldout_out, plain_needed, train_reach, trust_out};
use super::{Errors, Search};

/// Per candidate of `block` (of `cands`, whose coarse fits so far are `coarse`) in round
/// `round` with the bar `cut` (`set`: a fit of the round set it): why it is taken without a
/// coarse fit — (the largest training gain its linear model allows, the phase logged, the
/// held-out reach; NaN for round 0's trust; the held-out optimum's relative improvement for
/// [`start_bound`], against the round's held-out errors `ho_err`) — or `None`
/// (screened as usual). In round 0 only
/// once a fit set the bar, by the probes' data's test ([`probe_trust::out`], on the screen's
/// data `short`); never the plain variant of another candidate on its joints ([`plain_needed`]); a candidate that waits for its plain variant's
/// fit ([`coarse::deferred`]) takes that fit's stand-in whatever this says, and is not asked
/// about on the held-out set: only the effects of the candidates asked about are probed there
/// ([`HeldoutScreen::ensure`], booked to `heldout_linear` with the held-out replays that
/// confirm a linear model).
pub(super) fn out_of(
    s: &Search,
    (round, cut, set): (usize, f64, bool),
    (screen, ho): (&Screen, &mut Option<HeldoutScreen>),
    (short, applied, ho_err): (&[Recording], &[Applied], &Errors),
    covered: &(dyn Fn(&str, &str) -> bool + Sync),
    (cands, coarse, block): (&[Cand], &[Coarse], &[Cand]),
) -> Vec<Option<(f64, Phase, f64)>> {
    let engine = s.engine;
    if round == 0 {
        let at = (short, applied);
        let out = |(e, g, _): &Cand| {
            let own = plain_needed(cands, (*e, g))
                || coarse::deferred(s, (*e, g), cands, coarse).is_some();
            let u = (set && !own).then(|| probe_trust::out(engine, screen, at, (*e, g), cut));
            u.flatten().map(|u| (u, Phase::TrustScreen, f64::NAN))
        };
        return block.par_iter().map(out).collect();
    }
    engine.report(round, Phase::HeldoutLinear, None);
    let lt = engine.opts.policy.linear_trust;
    let trusted = |(e, g, _): &Cand| {
        if plain_needed(cands, (*e, g)) {
            return None;
        }
        Some(trust_out(engine, screen, (*e, g), cut).map(|u| (u, Phase::TrustScreen, f64::NAN)))
    };
    let asked = |c: &Cand| {
        matches!(trusted(c), Some(None))
            && coarse::deferred(s, (c.0, &c.1), cands, coarse).is_none()
    };
    if let Some(h) = ho.as_mut() {
        let these: Vec<(&'static str, &[String])> =
            block.iter().filter(|c| asked(c)).map(|c| (c.0.id(), &c.1[..])).collect();
        h.ensure(engine, &these, covered);
    }
    let ho = ho.as_ref().and_then(|h| h.screen());
    block
        .par_iter()
        .map(|c| {
            if let Some(t) = trusted(c)? {
                return Some(t);
            }
            if !asked(c) {
                return None;
            }
            let (e, g) = (c.0, &c.1);
            let upper = train_reach(screen, (e, g), lt);
            let linear =
                ho.and_then(|ho| heldout_out(engine, (screen, ho), (s.heldout, applied), (e, g)));
            if let Some(h) = linear {
                return Some((upper, Phase::HeldoutLinear, h));
            }
            // A several-parameter smooth one: the held-out bound of its full fit, at its start.
            let at = (s.heldout, short, applied, ho_err);
            let h = start_bound::short_at_start(engine, at, (e, g), round)?;
            Some((upper, Phase::HeldoutBound, h))
        })
        .collect()
}
